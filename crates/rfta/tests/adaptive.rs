//! Adaptive reconstruction (`rfta::adaptive`) against analytic shapes: accuracy against the grid
//! of as many evaluations, topology, the budget, determinism at any thread count, and the
//! oracle's failures.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use rfta::adaptive::{
    AdaptiveReconstruction, Budget, MIN_BUDGET, OracleError, reconstruct_adaptive,
};
use rfta::geom::glam::DVec3;
use rfta::geom::{Aabb, Analytic, Grid, SdfSamples, TriMesh};
use rfta::{Error, Params};

/// A torus whose tube (0.16 across) is barely more than one spacing of a 15^3 grid over
/// [-1, 1]^3 (0.14): the grid hardly resolves it, the surface is where the samples are needed.
const TORUS: Analytic = Analytic::Torus {
    major: 0.6,
    minor: 0.08,
};

fn cube() -> Aabb {
    Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0))
}

fn params(threads: usize) -> Params {
    Params {
        rounds: Some(3),
        threads: Some(threads),
        ..Params::default()
    }
}

fn run(shape: Analytic, budget: usize, params: &Params) -> rfta::Result<AdaptiveReconstruction> {
    let mut oracle = |p: &[DVec3]| -> Result<Vec<f64>, OracleError> {
        Ok(p.iter().map(|&q| shape.sdf(q)).collect())
    };
    reconstruct_adaptive(
        &mut oracle,
        cube(),
        Budget::evaluations(budget),
        params,
        &mut |_| {},
        &mut |_| {},
        &AtomicBool::new(false),
    )
}

/// Mean distance of the mesh's vertices to the true surface.
fn vertex_error(shape: Analytic, mesh: &TriMesh) -> f64 {
    mesh.vertices
        .iter()
        .map(|&v| shape.sdf(v).abs())
        .sum::<f64>()
        / mesh.n_vertices() as f64
}

/// With the evaluations of a 15^3 grid, the adaptive samples give a thin torus closer to the true
/// surface than rfta on that grid (and within a small fraction of the tube), with its genus, in
/// one watertight piece, no sample on the wrong side, the budget kept.
#[test]
fn a_torus_from_as_many_evaluations_as_a_grid_is_closer_than_the_grids() {
    let budget = 15usize.pow(3);
    let params = params(2);
    let out = run(TORUS, budget, &params).expect("adaptive");
    let report = &out.report;
    assert!(
        report.evaluations <= budget,
        "{} > {budget}",
        report.evaluations
    );
    assert!(report.passes.len() >= 2, "{:?}", report.passes);
    assert_eq!(
        out.samples.len(),
        report.passes.last().map_or(0, |p| p.samples)
    );
    let mesh = &out.reconstruction.mesh;
    let r = &out.reconstruction.report;
    assert!(r.mesh.watertight && r.mesh.components == 1, "{:?}", r.mesh);
    assert_eq!(rfta_mesh::Topology::of(mesh).genus(), Some(1));
    assert_eq!(r.consistency.sign_errors, 0);
    // The final solve has two cells per finest spacing (FINAL_CELLS_PER_SPACING), where a
    // grid's has four: on the box of side 2, a cell of 3.2 * 2 / 2^depth is at most half the
    // spacing and more than a quarter of it.
    let cell = 3.2 * 2.0 / f64::from(1u32 << r.rounds.spsr_depth);
    assert!(
        2.0 * cell <= report.finest_spacing && 4.0 * cell > report.finest_spacing,
        "depth {} for the finest spacing {}",
        r.rounds.spsr_depth,
        report.finest_spacing
    );

    let grid = Grid::cube(14, -1.0, 1.0).expect("grid");
    let values = (0..grid.len())
        .map(|i| TORUS.sdf(grid.position(i)))
        .collect();
    let on_grid = rfta::reconstruct(&SdfSamples::grid(grid, values).expect("grid"), &params)
        .expect("grid reconstruction");
    let (adaptive, gridded) = (
        vertex_error(TORUS, mesh),
        vertex_error(TORUS, &on_grid.mesh),
    );
    assert!(
        adaptive < gridded,
        "adaptive {adaptive:.5} against the grid's {gridded:.5}"
    );
    // A twentieth of the tube's radius.
    assert!(adaptive < 0.004, "{adaptive}");
}

/// The same oracle asked on 1 and 2 threads: the same samples in the same order, the same mesh.
#[test]
fn the_samples_and_the_mesh_do_not_depend_on_the_thread_count() {
    let one = run(Analytic::TwoTori, 2_000, &params(1)).expect("1 thread");
    let two = run(Analytic::TwoTori, 2_000, &params(2)).expect("2 threads");
    assert_eq!(one.samples, two.samples);
    assert_eq!(one.reconstruction.mesh, two.reconstruction.mesh);
}

/// The adaptive passes keep every sphere as an owner whatever the owner band, while the same
/// samples reconstructed as scattered samples keep the spheres beyond their own band as
/// constraints only.
#[test]
fn the_adaptive_passes_keep_every_sphere_as_an_owner() {
    let out = run(TORUS, 2_000, &params(2)).expect("adaptive");
    assert_eq!(out.reconstruction.report.final_solve.far_spheres, 0);
    let again = rfta::reconstruct(&out.samples, &params(2)).expect("scattered");
    let far = again.report.final_solve.far_spheres;
    assert!(far > 0 && far < out.samples.len(), "{far} far");
}

/// The oracle is asked exactly as often as the report says, never beyond the budget.
#[test]
fn the_report_counts_every_evaluation() {
    let calls = AtomicUsize::new(0);
    let mut oracle = |p: &[DVec3]| -> Result<Vec<f64>, OracleError> {
        calls.fetch_add(p.len(), Ordering::Relaxed);
        Ok(p.iter().map(|&q| TORUS.sdf(q)).collect())
    };
    let out = reconstruct_adaptive(
        &mut oracle,
        cube(),
        Budget::evaluations(1_500),
        &params(2),
        &mut |_| {},
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .expect("adaptive");
    // Every point the oracle saw, the final pass's questions included, is in the report.
    assert_eq!(out.report.evaluations, calls.load(Ordering::Relaxed));
    assert!(out.report.evaluations <= 1_500);
}

/// A fixed way of answering, for the failure cases.
type Answer = dyn Fn(&[DVec3]) -> Result<Vec<f64>, OracleError> + Sync;

/// An oracle's error ends the run as `Error::Oracle` carrying it; a NaN, an infinite value or the
/// wrong number of values is `Error::OracleAnswer` naming the batch; a budget too small, a flat
/// box and a cancelled run are refused.
#[test]
fn a_failing_oracle_is_an_error_naming_the_batch() {
    #[derive(Debug)]
    struct Down;
    impl std::fmt::Display for Down {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "the model server is down")
        }
    }
    impl std::error::Error for Down {}
    let ask = |answer: &Answer, budget: usize, bounds: Aabb, cancel: bool| {
        let mut oracle = |p: &[DVec3]| answer(p);
        reconstruct_adaptive(
            &mut oracle,
            bounds,
            Budget::evaluations(budget),
            &params(1),
            &mut |_| {},
            &mut |_| {},
            &AtomicBool::new(cancel),
        )
    };
    let exact = |p: &[DVec3]| -> Result<Vec<f64>, OracleError> {
        Ok(p.iter().map(|&q| TORUS.sdf(q)).collect())
    };
    match ask(&|_| Err(Box::new(Down)), 1_000, cube(), false) {
        Err(Error::Oracle { batch: 1, source }) => {
            assert!(source.downcast_ref::<Down>().is_some(), "{source}");
        }
        other => panic!("{other:?}"),
    }
    let nan = |p: &[DVec3]| -> Result<Vec<f64>, OracleError> {
        let mut v: Vec<f64> = p.iter().map(|&q| TORUS.sdf(q)).collect();
        v[7] = f64::NAN;
        Ok(v)
    };
    match ask(&nan, 1_000, cube(), false) {
        Err(e @ Error::OracleAnswer { batch: 1, .. }) => {
            assert!(e.to_string().contains("point 7"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    let short = |p: &[DVec3]| -> Result<Vec<f64>, OracleError> {
        Ok(p.iter().skip(1).map(|&q| TORUS.sdf(q)).collect())
    };
    match ask(&short, 1_000, cube(), false) {
        Err(e @ Error::OracleAnswer { batch: 1, .. }) => {
            assert!(e.to_string().contains("values for"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        ask(&exact, MIN_BUDGET - 1, cube(), false),
        Err(Error::InvalidParams(_))
    ));
    let flat = Aabb::new(DVec3::splat(-1.0), DVec3::new(1.0, 1.0, -1.0));
    assert!(matches!(
        ask(&exact, 1_000, flat, false),
        Err(Error::InvalidParams(_))
    ));
    assert!(matches!(
        ask(&exact, 1_000, cube(), true),
        Err(Error::Cancelled)
    ));
}
