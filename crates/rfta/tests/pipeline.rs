//! The pipeline on analytic SDF grids: determinism and the errors of degenerate input.

use rfta::geom::{Grid, SdfSamples};
use rfta::{Params, reconstruct};
use rfta_testkit::Analytic;

fn grid_samples(shape: Analytic, n: usize) -> SdfSamples {
    let grid = Grid::cube(n, -1.0, 1.0).expect("grid");
    let values = (0..grid.len())
        .map(|i| shape.sdf(grid.position(i)))
        .collect();
    SdfSamples::grid(grid, values).expect("samples")
}

#[test]
fn same_mesh_at_one_and_two_threads() {
    let sphere = Analytic::Sphere { radius: 0.55 };
    let samples = grid_samples(sphere, 10);
    let p = Params {
        k_max: 2,
        ..Params::default()
    };
    let one = reconstruct(
        &samples,
        &Params {
            threads: Some(1),
            ..p.clone()
        },
    )
    .expect("1");
    let two = reconstruct(
        &samples,
        &Params {
            threads: Some(2),
            ..p
        },
    )
    .expect("2");
    assert_eq!(one.mesh.vertices, two.mesh.vertices);
    assert_eq!(one.mesh.faces, two.mesh.faces);
}

#[test]
fn a_single_negative_sample_gives_a_finite_mesh_or_an_error_never_a_panic() {
    // One negative sample in a 3^3 grid (gpytoolbox issue 147's situation): the call must end
    // in a finite mesh or an error that says something, never a panic.
    let grid = Grid::cube(2, -1.0, 1.0).expect("grid");
    let mut values = vec![1.0; grid.len()];
    values[13] = -0.2;
    let samples = SdfSamples::grid(grid, values).expect("samples");
    match reconstruct(
        &samples,
        &Params {
            k_max: 1,
            ..Params::default()
        },
    ) {
        Ok(out) => assert!(out.mesh.vertices.iter().all(|v| v.is_finite())),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}
