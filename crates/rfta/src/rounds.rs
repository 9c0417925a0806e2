//! Steps 4 and 5: screened Poisson reconstruction of the tangency points, then fine-tuning of the
//! points against that surface, `rounds` times.

use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::{OrientedPoints, SphereSet};
use rfta_sphere_tree::SphereTree;
use rfta_spsr::{SidePoint, SideSet, SpsrParams};

use crate::Stage;
use crate::params::Seeds;
use crate::plan::Plan;
use crate::report::{Journal, RoundsReport, counted};

/// The fine-tuning rounds on `cloud` (step 5, with step 4's solve in each), stopping early (and
/// saying why in the report) when a solve fails or fewer than 3 points remain, and with
/// [`crate::Error::Cancelled`] when `go_on` says so before a round. Returns the points the final
/// solve takes.
pub(crate) fn fine_tune(
    plan: &Plan<'_>,
    mut cloud: TangentPoints,
    journal: &mut Journal,
    progress: &mut (dyn FnMut(Stage) + Send),
    go_on: &dyn Fn() -> crate::Result<()>,
) -> crate::Result<(TangentPoints, RoundsReport)> {
    let (unit, params) = (&plan.unit, &plan.params);
    let n = unit.len();
    let mut report = RoundsReport {
        spsr_depth: plan.final_spsr.depth,
        round_spsr_depth: plan.round_spsr.depth,
        ..RoundsReport::default()
    };
    // Without batching every round tests against the same tree: built once. On fine grids a
    // round's batch is drawn from the spheres the initial points draw instead of from every
    // sphere: of the 2.1 million of a 129^3 grid 92% are farther out, so a batch of all held
    // about 260 spheres that can meet a tangency point, and the large ones it held instead made
    // every query visit most of the tree.
    let mut all = None;
    let mut pool = None;
    if plan.rounds > 0 && params.batch_holds_all(n) {
        all = Some(SphereTree::new(unit));
    } else if plan.fine_rounds {
        pool = Some(
            (0..n as u32)
                .filter(|&i| unit.radius(i as usize) < plan.raster_radius)
                .collect::<Vec<u32>>(),
        );
    }
    for round in 1..=plan.rounds {
        go_on()?;
        progress(Stage::FineTune {
            round,
            of: plan.rounds,
        });
        report.points_per_round.push(cloud.len());
        crate::pool::waiters_back();
        let t = Instant::now();
        let batch;
        let tree = match &all {
            Some(t) => t,
            None => {
                let seed = Seeds(params.seed).round_batch(round);
                batch = match &pool {
                    None => SphereTree::batch(unit, params.batch_size, seed),
                    Some(pool) => SphereTree::with_indices(
                        unit,
                        &crate::initial::draw_batch(pool, params.batch_size, seed),
                    ),
                };
                &batch
            }
        };
        // A round's surface only guides the next moves: no side constraints (measured in
        // docs/faithfulness.md).
        let mesh = match solve(&cloud, &[] as &[SidePoint; 0], &plan.round_spsr) {
            Ok(r) => r.mesh,
            Err(e) => {
                report.stopped_early = Some(format!("round {round}: {e}"));
                break;
            }
        };
        journal.timed(crate::Step::RoundSolve(round), t);
        crate::pool::waiters_back();
        let t = Instant::now();
        // From the second round on, with every tree holding all spheres, the points were
        // tested against this same set last round.
        let tested = if round > 1 && all.is_some() {
            rfta_feasible::Tested::AgainstThisTree
        } else {
            rfta_feasible::Tested::No
        };
        let next = counted(n, progress, |done| {
            rfta_feasible::fine_tune(
                unit,
                &unit.values,
                &mesh,
                &cloud,
                tested,
                tree,
                &plan.feasible,
                Some(done),
            )
        });
        journal.timed(crate::Step::RoundTune(round), t);
        if next.len() < 3 {
            report.stopped_early = Some(format!(
                "round {round}: only {} feasible points remained",
                next.len()
            ));
            break;
        }
        cloud = next;
    }
    // The points the final solve takes.
    report.points_per_round.push(cloud.len());
    Ok((cloud, report))
}

/// Screened Poisson reconstruction of the tangency points, re-solved where it puts one of
/// `sides` on the wrong side ([`rfta_spsr::reconstruct_with_sides`]; none: one solve).
pub(crate) fn solve(
    cloud: &TangentPoints,
    sides: &dyn SideSet,
    spsr: &SpsrParams,
) -> std::result::Result<rfta_spsr::Reconstruction, rfta_spsr::Error> {
    let pts = OrientedPoints::new(cloud.points.clone(), cloud.normals.clone(), None)
        .map_err(|e| rfta_spsr::Error::DegenerateInput(format!("tangency points: {e}")))?;
    rfta_spsr::reconstruct_with_sides(&pts, sides, spsr)
}
