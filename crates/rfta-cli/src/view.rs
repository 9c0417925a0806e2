//! `rfta view` (a mesh, and what its SDF samples say of it, as one HTML page) and the page
//! `rfta reconstruct --html` writes: the scene `rfta_view` draws.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use rfta::geom::{SdfSamples, TriMesh};
use rfta_view::{Found, Scene};

use crate::ui::{Ui, parse_bounds};

#[derive(Debug, clap::Args)]
pub(crate) struct Args {
    /// The mesh (.obj .off .ply .stl .glb).
    mesh: PathBuf,
    /// SDF samples the mesh was made from (as for `reconstruct`): samples on the wrong side and
    /// spheres entered are marked, and marching cubes' mesh of a grid is a layer to compare.
    #[arg(long, value_name = "SDF")]
    sdf: Option<PathBuf>,
    /// Grid bounds for an .npy grid, overriding its sidecar (as for `sample`).
    #[arg(long, value_name = "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX", value_parser = parse_bounds)]
    bounds: Option<rfta_io::GridBounds>,
    /// The page (.html).
    #[arg(short, long)]
    output: PathBuf,
}

pub(crate) fn run(args: Args, ui: &Ui) -> Result<()> {
    let mut files = crate::paths::Files::new();
    files
        .read("the mesh", &args.mesh)
        .write("the page (-o)", &args.output);
    if let Some(sdf) = &args.sdf {
        files.read_sdf("--sdf", sdf);
    }
    files.check()?;
    let mesh = rfta_io::read_mesh(&args.mesh)?;
    let samples = match &args.sdf {
        Some(path) => Some(rfta_io::read_sdf(path, args.bounds)?.validate(path)?),
        None => None,
    };
    let topology = rfta_mesh::Topology::of(&mesh);
    let mut figures = vec![
        ("vertices".to_string(), mesh.n_vertices().to_string()),
        ("faces".into(), mesh.n_faces().to_string()),
        ("components".into(), topology.components.to_string()),
        ("watertight".into(), topology.is_watertight().to_string()),
        (
            "genus".into(),
            topology.genus().map_or("-".into(), |g| g.to_string()),
        ),
    ];
    // The samples are walked once: the marks, and the figures counted from them (the same
    // samples rfta::consistency::measure counts).
    let found = match &samples {
        Some(s) => Some(Found::of(s, &mesh, None)?),
        None => None,
    };
    if let (Some(s), Some(f)) = (&samples, &found) {
        figures.extend([
            ("samples".to_string(), s.len().to_string()),
            ("on the wrong side".into(), f.wrong_side.len().to_string()),
            ("spheres entered".into(), f.entered.len().to_string()),
            ("thin loops".into(), f.thin_loops.len().to_string()),
        ]);
    }
    let title = args.mesh.display().to_string();
    let scene = rfta_view::reconstruction(&title, &mesh, found.as_ref(), figures);
    write(&args.output, &scene)?;
    ui.say(format!("wrote {}", args.output.display()));
    Ok(())
}

/// The page of `mesh` ([`rfta_view::reconstruction`]); with `samples`, what they find
/// ([`Found::of`]).
pub(crate) fn scene(
    title: &str,
    mesh: &TriMesh,
    samples: Option<&SdfSamples>,
    clamp: Option<f64>,
    figures: Vec<(String, String)>,
) -> Result<Scene> {
    let found = match samples {
        Some(s) => Some(Found::of(s, mesh, clamp)?),
        None => None,
    };
    Ok(rfta_view::reconstruction(
        title,
        mesh,
        found.as_ref(),
        figures,
    ))
}

/// Writes the page atomically.
pub(crate) fn write(path: &Path, scene: &Scene) -> Result<()> {
    let page = rfta_view::html(scene);
    rfta_io::write_atomic(path, |w| w.write_all(page.as_bytes()))
        .with_context(|| format!("{}: cannot write the page", path.display()))?;
    Ok(())
}
