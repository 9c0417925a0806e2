//! The shapes an evaluation runs on: prepared inputs (`NAME/gt.obj`, `NAME/sdf_n{N}.npy`) as
//! they are, or raw meshes normalised as the paper prepares them, and each shape's grid at a
//! resolution.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use rfta_geom::{Grid, Layout, TriMesh, glam::DMat3, glam::DVec3, rng};
use rfta_mesh::MeshIndex;

/// Where the shapes come from (default: the shared data's prepared inputs).
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Source {
    /// Prepared inputs (`NAME/gt.obj`, `NAME/sdf_n{N}.npy`), taken as they are; a missing grid
    /// is sampled from `gt.obj`.
    #[arg(long, value_name = "DIR", conflicts_with = "meshes")]
    pub(crate) inputs: Option<PathBuf>,
    /// Raw meshes: each normalised (box centred, longest side 1, a rotation seeded by its name)
    /// and its SDF sampled on `linspace(-1, 1, N + 1)^3` with `rfta sample`'s code.
    #[arg(long, value_name = "DIR")]
    pub(crate) meshes: Option<PathBuf>,
}

impl Source {
    /// The shapes that load, and `(name, reason)` for those that do not.
    pub(crate) fn load(&self) -> Result<Loaded> {
        match (&self.inputs, &self.meshes) {
            (_, Some(dir)) => load_meshes(dir),
            (Some(dir), None) => load_inputs(dir),
            (None, None) => load_inputs(&crate::data_dir().join("inputs")),
        }
    }
}

/// One shape of the evaluation.
pub(crate) struct Shape {
    pub(crate) name: String,
    pub(crate) gt: TriMesh,
    /// Where prepared grids live (`--inputs`), if any.
    dir: Option<PathBuf>,
}

/// Keeps only the shape with the fewest faces (a quick run's).
pub(crate) fn smallest(shapes: &mut Vec<Shape>) {
    shapes.sort_by_key(|s| s.gt.n_faces());
    shapes.truncate(1);
}

/// The grid of a shape at resolution `n`: the prepared `sdf_n{n}.npy` if present, else sampled.
pub(crate) fn grid_for(shape: &Shape, gt: &MeshIndex, n: usize) -> Result<(Grid, Vec<f64>)> {
    if let Some(dir) = &shape.dir {
        let path = dir.join(format!("sdf_n{n}.npy"));
        if path.is_file() {
            let raw = rfta_io::read_sdf(&path, None)?;
            if let Layout::Grid(g) = raw.layout {
                return Ok((g, raw.values));
            }
        }
    }
    let grid = Grid::cube(n, -1.0, 1.0)?;
    let values = gt.signed_distances(
        &(0..grid.len())
            .map(|i| grid.position(i))
            .collect::<Vec<_>>(),
    );
    Ok((grid, values))
}

/// Shapes that load, and `(name, reason)` for those that do not.
type Loaded = (Vec<Shape>, Vec<(String, String)>);

pub(crate) fn load_inputs(dir: &Path) -> Result<Loaded> {
    let mut shapes = Vec::new();
    let mut unreadable = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("gt.obj").is_file())
        .collect();
    entries.sort();
    for p in entries {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        match rfta_io::read_mesh(&p.join("gt.obj")) {
            Ok(gt) => shapes.push(Shape {
                name,
                gt,
                dir: Some(p),
            }),
            Err(e) => unreadable.push((name, e.to_string())),
        }
    }
    Ok((shapes, unreadable))
}

pub(crate) fn load_meshes(dir: &Path) -> Result<Loaded> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| rfta_io::MeshFormat::from_path(p).is_ok())
        .collect();
    files.sort();
    let mut shapes = Vec::new();
    let mut unreadable = Vec::new();
    for p in files {
        let name = p
            .file_stem()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        match rfta_io::read_mesh(&p) {
            Ok(mut gt) if !gt.is_empty() => {
                normalize(&mut gt, &name);
                shapes.push(Shape {
                    name,
                    gt,
                    dir: None,
                });
            }
            Ok(_) => unreadable.push((name, "the mesh has no triangles".into())),
            Err(e) => unreadable.push((name, e.to_string())),
        }
    }
    Ok((shapes, unreadable))
}

/// The paper's preparation: bounding box centred at the origin, longest side 1, then a rotation
/// about a random axis by a random angle, seeded by the shape's name (Sellán et al. 2024, §5).
fn normalize(mesh: &mut TriMesh, name: &str) {
    let b = mesh.bounds();
    let (center, scale) = (b.center(), b.longest_side().max(f64::MIN_POSITIVE));
    let seed = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, c| {
        (h ^ c as u64).wrapping_mul(0x100_0000_01b3)
    });
    let mut r = rng::Rng::new(seed);
    let axis = DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()).normalize_or(DVec3::Z);
    let rot = DMat3::from_axis_angle(axis, r.next_f64() * std::f64::consts::TAU);
    mesh.map_vertices(|v| rot * ((v - center) / scale));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalize_centres_scales_and_rotates_by_name() {
        let mut a = rfta_geom::shapes::cuboid(DVec3::new(2.0, 1.0, 0.5));
        a.map_vertices(|v| v + DVec3::new(5.0, -3.0, 1.0));
        let mut b = a.clone();
        normalize(&mut a, "box");
        normalize(&mut b, "box");
        assert_eq!(a, b, "the rotation is seeded by the name");
        // Rotation keeps the centre at the origin and the longest edge (4 units, scaled to 1) at 1.
        let c = a.vertices.iter().copied().sum::<DVec3>() / a.n_vertices() as f64;
        assert!(c.length() < 1e-12);
        let longest = (0..a.n_vertices()).flat_map(|i| (0..a.n_vertices()).map(move |j| (i, j)));
        let diag = longest
            .map(|(i, j)| a.vertices[i].distance(a.vertices[j]))
            .fold(0.0, f64::max);
        // The box's diagonal sqrt(16 + 4 + 1) / 4.
        assert!((diag - 21f64.sqrt() / 4.0).abs() < 1e-12, "{diag}");
        let mut other = b.clone();
        normalize(&mut other, "another name");
        assert_ne!(other, b);
    }
}
