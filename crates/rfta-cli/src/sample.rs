//! `rfta sample`: the exact signed distance of a mesh on a regular grid.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta_geom::Aabb;
use rfta_geom::{Grid, TriMesh, glam::DVec3, shapes};
use rfta_io::GridBounds;
use rfta_mesh::{MeshSdf, Topology};

use crate::ui::{Ui, parse_bounds};

/// Built-in shapes for trying rfta without data.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub(crate) enum Shape {
    /// Unit-diameter sphere (radius 0.5), genus 0.
    Sphere,
    /// Torus with R = 0.6, r = 0.25 about the z axis, genus 1.
    Torus,
    /// Box with half-extents 0.6 x 0.4 x 0.3 (sharp edges), genus 0.
    Box,
}

impl Shape {
    fn mesh(self) -> TriMesh {
        match self {
            Shape::Sphere => shapes::icosphere(0.5, 5),
            Shape::Torus => shapes::torus(0.6, 0.25, 256, 128),
            Shape::Box => shapes::cuboid(DVec3::new(0.6, 0.4, 0.3)),
        }
    }
}

#[derive(Debug, clap::Args)]
pub(crate) struct Args {
    /// The mesh (.obj .off .ply .stl .glb); or use --shape.
    #[arg(required_unless_present = "shape", conflicts_with = "shape")]
    mesh: Option<PathBuf>,
    /// Use a built-in shape instead of a mesh file.
    #[arg(long, value_enum)]
    shape: Option<Shape>,
    /// Cells per axis: the grid has N + 1 samples per axis, as numpy.linspace(lo, hi, N + 1).
    #[arg(long, value_name = "N")]
    res: usize,
    /// Corner sample positions (default -1,-1,-1,1,1,1); "lo,hi" for a cube.
    #[arg(long, value_name = "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX", value_parser = parse_bounds)]
    bounds: Option<GridBounds>,
    /// Output grid: .npy (float64, with a .json sidecar holding the bounds) or .exr (float32).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the input mesh here (useful with --shape).
    #[arg(long, value_name = "MESH")]
    save_mesh: Option<PathBuf>,
}

/// Readies a mesh whose signed distance is to be measured (`sample`, `reconstruct --from-mesh`):
/// an inside-out closed mesh is flipped so that inside is negative (a grid of "outside" would
/// describe no surface, hostile test D5), and a mesh that is not watertight is warned about.
pub(crate) fn as_sdf_source(mesh: &mut TriMesh, name: &str, ui: &Ui) {
    let topo = Topology::of(mesh);
    // An inside-out closed mesh has winding number -1 inside: every sample would come out
    // positive, a grid of "outside" that describes no surface (hostile test D5). Its volume is
    // measured near the unit: at 1e-300 it would underflow to zero, at 1e155 overflow.
    let scale = rfta_mesh::unit_scale(mesh);
    let volume = if scale == 1.0 {
        mesh.signed_volume()
    } else {
        rfta_mesh::scaled(mesh, scale).signed_volume()
    };
    if topo.is_watertight() && volume < 0.0 {
        ui.say(format!(
            "warning: {name} is inside out (its faces enclose a negative volume): sampled with its faces flipped, so that inside is negative"
        ));
        mesh.flip();
    }
    if !topo.is_watertight() {
        ui.say(format!(
            "warning: {name} is not watertight ({} boundary, {} non-manifold edges): the sign comes from the winding number, which is only approximate near holes",
            topo.boundary_edges, topo.nonmanifold_edges
        ));
    }
}

pub(crate) fn run(args: Args, ui: &Ui) -> Result<()> {
    if args.res == 0 {
        bail!("--res must be at least 1 (the grid has res + 1 samples per axis)");
    }
    let mut files = crate::paths::Files::new();
    if let Some(mesh) = &args.mesh {
        files.read("the mesh", mesh);
    }
    files.write("the output (-o)", &args.output);
    if rfta_io::extension_of(&args.output).as_deref() == Some("npy") {
        files.write("the output's sidecar", &rfta_io::sidecar_path(&args.output));
    }
    if let Some(path) = &args.save_mesh {
        files.write("--save-mesh", path);
    }
    files.check()?;
    let (mut mesh, name) = match (&args.mesh, args.shape) {
        (Some(path), _) => (rfta_io::read_mesh(path)?, path.display().to_string()),
        (None, Some(shape)) => (shape.mesh(), format!("built-in {shape:?}").to_lowercase()),
        (None, None) => bail!("give a mesh file or --shape"),
    };
    if let Some(path) = &args.save_mesh {
        rfta_io::write_mesh(path, &mesh)?;
        ui.say(format!("wrote {}", path.display()));
    }
    as_sdf_source(&mut mesh, &name, ui);
    let t0 = Instant::now();
    let sdf = MeshSdf::new(&mesh).with_context(|| format!("{name}: cannot measure distances"))?;
    ui.detail(format!(
        "index over {} triangles built in {:.3} s",
        mesh.n_faces(),
        t0.elapsed().as_secs_f64()
    ));
    let bounds = match args.bounds {
        Some(b) => b,
        None => default_bounds(sdf.bounds(), &name, ui),
    };
    let grid =
        Grid::from_bounds([args.res + 1; 3], bounds.min, bounds.max).context("invalid grid")?;
    let n = grid.len();
    // Refuse grids that cannot fit in memory before allocating (8 bytes per value, 24 per
    // position), against the memory available now (16 GiB where it cannot be read).
    let bytes = n.checked_mul(32).context("grid too large")? as u64;
    let limit = rfta::available_memory().unwrap_or(16 << 30);
    if bytes > limit {
        bail!(
            "a {}^3 grid needs about {} but {} is available; choose a smaller --res",
            args.res + 1,
            rfta::format_bytes(bytes),
            rfta::format_bytes(limit)
        );
    }
    let t1 = Instant::now();
    let bar = ui.progress(grid.dims()[0] as u64, "sampling");
    let values = sdf.signed_distance_grid(&grid, &|| bar.inc(1));
    bar.finish_and_clear();
    let n_inside = values.iter().filter(|v| **v < 0.0).count();
    ui.detail(format!(
        "sampled {n} points in {:.3} s",
        t1.elapsed().as_secs_f64()
    ));
    if n_inside == 0 {
        ui.say(format!(
            "warning: no sample is inside {name}: the grid describes no surface (is the shape inside --bounds, and larger than a spacing?)"
        ));
    }
    rfta_io::write_sdf_grid(&args.output, &grid, &values)?;
    ui.say(format!(
        "wrote {} ({}^3 samples over [{}, {}], {} inside, {} outside)",
        args.output.display(),
        args.res + 1,
        fmt_vec(bounds.min),
        fmt_vec(bounds.max),
        n_inside,
        n - n_inside
    ));
    Ok(())
}

/// The cube a mesh is sampled in when no box is given, here and by `reconstruct --from-mesh`:
/// centred on the mesh's box, its side the box's longest side grown by a tenth on each end
/// (one spacing for every axis: a box stretched to the mesh would give each axis its own).
pub(crate) fn cube_around(mesh: Aabb) -> Aabb {
    let centre = (mesh.min + mesh.max) / 2.0;
    let side = (mesh.max - mesh.min).max_element().max(f64::MIN_POSITIVE);
    let half = DVec3::splat(0.6 * side);
    Aabb::new(centre - half, centre + half)
}

/// `[-1, 1]^3` (the paper's box) when the mesh lies in it; otherwise [`cube_around`] the mesh,
/// said aloud: the default box would cut the shape (hostile test E17: a mesh spanning -5 to 10
/// was sampled in [-1, 1]^3 without a word).
fn default_bounds(mesh: Aabb, name: &str, ui: &Ui) -> GridBounds {
    let unit = GridBounds::default();
    if mesh.min.cmpge(unit.min).all() && mesh.max.cmple(unit.max).all() {
        return unit;
    }
    let cube = cube_around(mesh);
    ui.say(format!(
        "note: {name} spans [{}, {}], beyond the default box [-1, 1]^3; sampling the cube [{}, {}] around it (--bounds chooses the box)",
        fmt_vec(mesh.min),
        fmt_vec(mesh.max),
        fmt_vec(cube.min),
        fmt_vec(cube.max)
    ));
    GridBounds {
        min: cube.min,
        max: cube.max,
    }
}

pub(crate) fn fmt_vec(v: DVec3) -> String {
    format!("({}, {}, {})", num(v.x), num(v.y), num(v.z))
}

/// A coordinate or length as people read it: four decimals near the unit, scientific notation
/// far from it (a box at 1e155 printed 160 digits a number).
pub(crate) fn num(x: f64) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
        format!("{x:.4}")
    } else {
        format!("{x:.4e}")
    }
}
