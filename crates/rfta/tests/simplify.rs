//! The pipeline's simplification (`rfta::Params::simplify`): on analytic shapes the simplified
//! mesh keeps every sample's verdict and the topology, stays within the tolerance of the mesh
//! it simplifies and of the true surface, and is much lighter; off, the mesh is the repaired one.

use rfta::geom::{Grid, SdfSamples, TriMesh};
use rfta::{Params, reconstruct};
use rfta_mesh::{MeshIndex, Topology};
use rfta_testkit::Analytic;

const TORUS: Analytic = Analytic::Torus {
    major: 0.55,
    minor: 0.22,
};

fn torus_samples(n: usize) -> SdfSamples {
    let grid = Grid::cube(n, -1.0, 1.0).expect("grid");
    let values = (0..grid.len())
        .map(|i| TORUS.sdf(grid.position(i)))
        .collect();
    SdfSamples::grid(grid, values).expect("samples")
}

fn genus_and_pieces(mesh: &TriMesh) -> (Option<i64>, usize, usize) {
    let t = Topology::of(mesh);
    (
        t.genus(),
        t.components,
        t.boundary_edges + t.nonmanifold_edges,
    )
}

/// The default reconstruction without simplification.
fn unsimplified(samples: &SdfSamples) -> rfta::Reconstruction {
    let params = Params {
        simplify: false,
        ..Params::default()
    };
    reconstruct(samples, &params).expect("unsimplified")
}

/// The largest distance from `a`'s vertices to `b`.
fn one_way(a: &TriMesh, b: &TriMesh) -> f64 {
    let index = MeshIndex::new(b).expect("faces");
    a.vertices
        .iter()
        .map(|&v| index.unsigned_distance(v))
        .fold(0.0, f64::max)
}

#[test]
fn the_default_mesh_is_lighter_and_keeps_every_verdict() {
    let samples = torus_samples(24);
    let h = samples.spacing();
    let full = unsimplified(&samples);
    let out = reconstruct(&samples, &Params::default()).expect("simplified");
    let (r, r0) = (&out.report, &full.report);
    // Off, nothing is simplified; on, the report counts the faces it started from.
    assert_eq!(r0.simplify.faces_before, full.mesh.n_faces());
    assert_eq!(r0.simplify.largest_deviation, 0.0);
    assert_eq!(r.simplify.faces_before, full.mesh.n_faces());
    assert!(
        out.mesh.n_faces() * 5 < full.mesh.n_faces(),
        "{} of {} faces",
        out.mesh.n_faces(),
        full.mesh.n_faces()
    );
    // Same topology, closed, no sample on another side, no sphere newly entered.
    assert_eq!(genus_and_pieces(&out.mesh), (Some(1), 1, 0));
    assert_eq!(genus_and_pieces(&full.mesh), (Some(1), 1, 0));
    assert_eq!(r.consistency.sign_errors, r0.consistency.sign_errors);
    assert!(r.consistency.entered <= r0.consistency.entered);
    // Within the default tolerance (0.8 / 24 spacings: the samples are 24 spacings across) of
    // the unsimplified mesh at the vertices, both ways, and about as close to the true torus.
    let spacings = 0.8 / 24.0;
    let tol = spacings * h + 1e-9;
    assert!(r.simplify.largest_deviation <= spacings + 1e-9);
    assert!(one_way(&full.mesh, &out.mesh) <= tol);
    assert!(one_way(&out.mesh, &full.mesh) <= tol);
    let worst = |m: &TriMesh| {
        m.vertices
            .iter()
            .map(|&v| TORUS.sdf(v).abs())
            .fold(0.0, f64::max)
    };
    assert!(worst(&out.mesh) <= worst(&full.mesh) + tol);
}

#[test]
fn a_face_budget_and_a_tolerance_are_honoured() {
    let samples = torus_samples(20);
    let h = samples.spacing();
    let budget = Params {
        faces: Some(600),
        ..Params::default()
    };
    let out = reconstruct(&samples, &budget).expect("to 600 faces");
    assert!(out.mesh.n_faces() <= 600, "{}", out.mesh.n_faces());
    assert_eq!(genus_and_pieces(&out.mesh), (Some(1), 1, 0));
    assert_eq!(out.report.consistency.sign_errors, 0);
    // The budget is below what the default tolerance keeps, so it is what stopped the run.
    let default = reconstruct(&samples, &Params::default()).expect("default");
    assert!(default.mesh.n_faces() > 600, "{}", default.mesh.n_faces());
    // A tighter tolerance keeps more faces and stays within it.
    let tight = Params {
        simplify_tolerance: Some(0.01),
        ..Params::default()
    };
    let close = reconstruct(&samples, &tight).expect("tight");
    assert!(close.mesh.n_faces() > default.mesh.n_faces());
    assert!(close.report.simplify.largest_deviation <= 0.01 + 1e-9);
    let full = unsimplified(&samples);
    assert!(one_way(&full.mesh, &close.mesh) <= 0.01 * h + 1e-9);
}

#[test]
fn a_bad_tolerance_is_refused_by_name() {
    let samples = torus_samples(8);
    for t in [-0.1, f64::NAN, f64::INFINITY] {
        let e = reconstruct(
            &samples,
            &Params {
                simplify_tolerance: Some(t),
                ..Params::default()
            },
        );
        let msg = e.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(msg.contains("simplify_tolerance"), "{t}: {msg}");
    }
}
