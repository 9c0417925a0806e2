//! rfta in the browser: the pipeline and marching cubes on a built-in shape or an `.npy` grid,
//! with the pages `rfta reconstruct --html` writes (`rfta_view`), and the program
//! (`src/main.rs`) that the demo page runs as WebAssembly.
//!
//! The program is built for `wasm32-wasip1`: a request on standard input, the answer on
//! standard output, so the page needs no bindings generator, only a few WASI calls of its own
//! (`page/index.html`: standard input and output, the clock, random bytes). WebAssembly has no
//! threads there; rayon then runs every loop on the calling thread, and the results are those of
//! a native run on one thread (the pipeline's results never depend on the thread count).
//! `cargo xtask web` builds the page; `cargo xtask web --check` opens it in headless Chromium.
//!
//! # Example
//! ```
//! let out = rfta_web::run(&rfta_web::Input::Shape { name: "two-tori".into(), cells: 10 })?;
//! assert_eq!(out.summary["rfta"]["genus"], 2);
//! assert!(out.rfta_page.starts_with("<!DOCTYPE html>"));
//! # Ok::<(), String>(())
//! ```

use std::time::Instant;

use rfta_geom::{Analytic, Grid, SdfSamples, TriMesh, glam::DVec3};
use rfta_view::Found;
use serde_json::json;

/// The built-in shapes: name, label, shape.
pub const SHAPES: [(&str, &str, Analytic); 4] = [
    ("two-tori", "two tori (genus 2)", Analytic::TwoTori),
    (
        "torus",
        "torus (genus 1)",
        Analytic::Torus {
            major: 0.6,
            minor: 0.25,
        },
    ),
    ("sphere", "sphere", Analytic::Sphere { radius: 0.5 }),
    (
        "box",
        "box (sharp edges)",
        Analytic::Box {
            half: DVec3::new(0.6, 0.4, 0.3),
        },
    ),
];

/// The most cells per axis a built-in shape is sampled with (65^3 samples).
pub(crate) const MAX_CELLS: usize = 64;

/// What to reconstruct.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// A built-in shape ([`SHAPES`]) sampled exactly on `linspace(-1, 1, cells + 1)^3`.
    Shape {
        /// Its name.
        name: String,
        /// Grid cells per axis (2 to `MAX_CELLS` (64)).
        cells: usize,
    },
    /// An `.npy` grid (bounds `[-1, 1]^3`: a page has no sidecar).
    Npy(Vec<u8>),
}

/// The answer: figures, and the page of each method's mesh.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// What was read and each method's figures (vertices, faces, genus, components, milliseconds,
    /// the mesh's [`mesh_hash`], samples on the wrong side, spheres entered, thin loops).
    pub summary: serde_json::Value,
    /// rfta's mesh with what the samples find on it, marching cubes' as a hidden layer.
    pub rfta_page: String,
    /// Marching cubes' mesh with what the samples find on it, rfta's as a hidden layer.
    pub mc_page: String,
    /// rfta's mesh.
    pub mesh: TriMesh,
}

/// The samples of `input` and a line saying what they are.
///
/// # Errors
/// An unknown shape, a resolution out of range, an `.npy` file that is not a valid 3D grid.
pub fn samples(input: &Input) -> Result<(SdfSamples, String), String> {
    match input {
        Input::Shape { name, cells } => {
            let (_, label, shape) = SHAPES
                .iter()
                .find(|s| s.0 == name)
                .ok_or_else(|| format!("no built-in shape {name:?}"))?;
            if !(2..=MAX_CELLS).contains(cells) {
                return Err(format!(
                    "the resolution must be 2 to {MAX_CELLS} cells, not {cells}"
                ));
            }
            let grid = Grid::cube(*cells, -1.0, 1.0).map_err(|e| e.to_string())?;
            let values = (0..grid.len())
                .map(|i| shape.sdf(grid.position(i)))
                .collect();
            let s = SdfSamples::grid(grid, values).map_err(|e| e.to_string())?;
            Ok((s, format!("{label} on a {0}^3 grid", cells + 1)))
        }
        Input::Npy(bytes) => {
            let path = std::path::Path::new("dropped.npy");
            let raw = rfta_io::decode_sdf(bytes, rfta_io::SdfFormat::Npy, path, None)
                .map_err(|e| e.to_string())?;
            if !matches!(raw.layout, rfta_geom::Layout::Grid(_)) {
                return Err(
                    "dropped.npy: the demo takes grids (an (nx, ny, nz) array), not rows".into(),
                );
            }
            let description = raw.description.clone();
            let s = raw.validate(path).map_err(|e| e.to_string())?;
            Ok((s, format!("{description} over [-1, 1]^3")))
        }
    }
}

/// Reconstructs `input` with the default preset and marching cubes, and makes their pages.
///
/// # Errors
/// As [`samples`]; the pipeline's error, as text.
pub fn run(input: &Input) -> Result<Outcome, String> {
    let (samples, what) = samples(input)?;
    let grid = *samples.as_grid().ok_or("not a grid")?;
    let params = rfta::Params::default();
    let t = Instant::now();
    let out = rfta::reconstruct(&samples, &params).map_err(|e| e.to_string())?;
    let rfta_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let mc = rfta_mc::marching_cubes(&grid, samples.values(), 0.0);
    let mc_ms = t.elapsed().as_secs_f64() * 1e3;
    let clamp = out.report.input.clamp;
    // Each page shows the other method's mesh as a hidden layer.
    let found = Found {
        compare: Some(("marching cubes (same samples)".into(), mc.clone())),
        ..Found::marks(&samples, &out.mesh, clamp).map_err(|e| e.to_string())?
    };
    let mc_found = Found {
        compare: Some(("rfta (same samples)".into(), out.mesh.clone())),
        ..Found::marks(&samples, &mc, clamp).map_err(|e| e.to_string())?
    };
    let figures = |mesh: &TriMesh, f: &Found, ms: f64| {
        let t = rfta_mesh::Topology::of(mesh);
        json!({
            "vertices": mesh.n_vertices(),
            "faces": mesh.n_faces(),
            "genus": t.genus(),
            "components": t.components,
            "watertight": t.is_watertight(),
            "milliseconds": ms,
            "hash": mesh_hash(mesh),
            "wrong_side": f.wrong_side.len(),
            "entered": f.entered.len(),
            "thin_loops": f.thin_loops.len(),
        })
    };
    let summary = json!({
        "input": what,
        "samples": samples.len(),
        "rfta": figures(&out.mesh, &found, rfta_ms),
        "mc": figures(&mc, &mc_found, mc_ms),
    });
    let mut rfta_figures = rfta_view::report_figures(&out.report);
    rfta_figures.insert(0, ("milliseconds".into(), format!("{rfta_ms:.0}")));
    let rfta_page = rfta_view::html(&rfta_view::reconstruction(
        &format!("rfta: {what}"),
        &out.mesh,
        Some(&found),
        rfta_figures,
    ));
    let mc_figures = vec![
        ("milliseconds".to_string(), format!("{mc_ms:.1}")),
        ("vertices".into(), mc.n_vertices().to_string()),
        ("faces".into(), mc.n_faces().to_string()),
        (
            "on the wrong side".into(),
            mc_found.wrong_side.len().to_string(),
        ),
        ("spheres entered".into(), mc_found.entered.len().to_string()),
        ("thin loops".into(), mc_found.thin_loops.len().to_string()),
    ];
    let mc_page = rfta_view::html(&rfta_view::reconstruction(
        &format!("marching cubes: {what}"),
        &mc,
        Some(&mc_found),
        mc_figures,
    ));
    Ok(Outcome {
        summary,
        rfta_page,
        mc_page,
        mesh: out.mesh,
    })
}

/// A 64-bit FNV-1a hash of a mesh's vertex coordinates (their bits) and face indices, in
/// order, as 16 hex digits: equal meshes, equal hashes, on any machine.
pub fn mesh_hash(mesh: &TriMesh) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for v in &mesh.vertices {
        for c in v.to_array() {
            eat(&c.to_bits().to_le_bytes());
        }
    }
    for f in &mesh.faces {
        for i in f {
            eat(&i.to_le_bytes());
        }
    }
    format!("{h:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hash_sees_every_coordinate_and_index() {
        let mesh = rfta_geom::shapes::octahedron(1.0);
        let h = mesh_hash(&mesh);
        let mut moved = mesh.clone();
        moved.vertices[3].y = f64::from_bits(moved.vertices[3].y.to_bits() ^ 1);
        let mut flipped = mesh.clone();
        flipped.flip();
        assert_ne!(h, mesh_hash(&moved));
        assert_ne!(h, mesh_hash(&flipped));
        assert_eq!(h, mesh_hash(&mesh.clone()));
    }

    #[test]
    fn a_dropped_npy_grid_is_the_same_as_the_shape_it_samples() {
        let (shape, _) = samples(&Input::Shape {
            name: "two-tori".into(),
            cells: 10,
        })
        .expect("a built-in shape");
        let mut npy = Vec::new();
        rfta_io::write_npy_f64(&mut npy, &[11, 11, 11], shape.values()).expect("in memory");
        let dropped = run(&Input::Npy(npy)).expect("reconstructs");
        let built_in = run(&Input::Shape {
            name: "two-tori".into(),
            cells: 10,
        })
        .expect("too");
        assert_eq!(mesh_hash(&dropped.mesh), mesh_hash(&built_in.mesh));
        assert_eq!(dropped.summary["rfta"]["genus"], 2);
        assert!(
            dropped.summary["input"]
                .as_str()
                .unwrap_or("")
                .contains("npy grid")
        );
    }

    #[test]
    fn bad_requests_are_errors_that_say_why() {
        let shape = |name: &str, cells| Input::Shape {
            name: name.into(),
            cells,
        };
        assert!(
            samples(&shape("teapot", 20))
                .expect_err("refused")
                .contains("no built-in shape")
        );
        assert!(
            samples(&shape("torus", 1))
                .expect_err("refused")
                .contains("2 to 64")
        );
        assert!(samples(&Input::Npy(b"not numpy".to_vec())).is_err());
        let rows = {
            let mut b = Vec::new();
            rfta_io::write_npy_f64(&mut b, &[2, 4], &[0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 0.0, 1.0])
                .expect("in memory");
            b
        };
        assert!(
            samples(&Input::Npy(rows))
                .expect_err("refused")
                .contains("takes grids")
        );
    }
}
