//! Steps 4 and 5: screened Poisson reconstruction of the tangency points, then fine-tuning of the
//! points against that surface, `rounds` times.

use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::OrientedPoints;
use rfta_sphere_tree::SphereTree;
use rfta_spsr::{SidePoint, SideSet, SpsrParams};

use crate::normalize::UnitBox;
use crate::params::Seeds;
use crate::report::{Journal, RoundsReport, counted};
use crate::{Params, Stage};

/// What lives across the rounds: the current tangency points and the settings of both stages.
pub(crate) struct Rounds {
    /// The tangency points, sorted by owner.
    pub(crate) cloud: TangentPoints,
    /// The screened Poisson setting of the solves inside the rounds.
    pub(crate) spsr: SpsrParams,
    feasible: rfta_feasible::Params,
    /// The tree of every sphere, when every round tests against all of them (no batching).
    all: Option<SphereTree>,
    /// The spheres the batches are drawn from: every sphere, or on fine grids the drawn ones
    /// ([`Rounds::batch_pool`]).
    pool: Option<Vec<u32>>,
}

impl Rounds {
    pub(crate) fn new(unit: &UnitBox, params: &Params, cloud: TangentPoints) -> Self {
        Self {
            cloud,
            spsr: params.round_spsr_params(Some(unit.spacing())),
            feasible: params.feasible_params(
                unit.len(),
                unit.owner_radius(params),
                unit.owner_scale(),
            ),
            all: None,
            pool: None,
        }
    }

    /// Runs the fine-tuning rounds, stopping early (and saying why in the report) when a solve
    /// fails or fewer than 3 points remain, and with [`crate::Error::Cancelled`] when `go_on`
    /// says so before a round.
    pub(crate) fn run(
        &mut self,
        unit: &UnitBox,
        params: &Params,
        journal: &mut Journal,
        progress: &mut (dyn FnMut(Stage) + Send),
        go_on: &dyn Fn() -> crate::Result<()>,
    ) -> crate::Result<RoundsReport> {
        let n = unit.len();
        let mut report = RoundsReport {
            spsr_depth: params.spsr_params(Some(unit.spacing())).depth,
            round_spsr_depth: self.spsr.depth,
            ..RoundsReport::default()
        };
        // Without batching every round tests against the same tree: built once.
        if params.rounds > 0 && params.batch_holds_all(n) {
            self.all = Some(SphereTree::new(&unit.spheres));
        } else if params.fine_rounds(Some(unit.spacing())) {
            self.pool = Some(Self::batch_pool(unit, params));
        }
        for round in 1..=params.rounds {
            go_on()?;
            progress(Stage::FineTune {
                round,
                of: params.rounds,
            });
            report.points_per_round.push(self.cloud.len());
            crate::pool::waiters_back();
            let t = Instant::now();
            let batch;
            let tree = match &self.all {
                Some(t) => t,
                None => {
                    let seed = Seeds(params.seed).round_batch(round);
                    batch = match &self.pool {
                        None => SphereTree::batch(&unit.spheres, params.batch_size, seed),
                        Some(pool) => SphereTree::with_indices(
                            &unit.spheres,
                            &crate::initial::draw_batch(pool, params.batch_size, seed),
                        ),
                    };
                    &batch
                }
            };
            // A round's surface only guides the next moves: no side constraints (measured in
            // docs/faithfulness.md).
            let mesh = match solve(&self.cloud, &[] as &[SidePoint; 0], &self.spsr) {
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
            let tested = if round > 1 && self.all.is_some() {
                rfta_feasible::Tested::AgainstThisTree
            } else {
                rfta_feasible::Tested::No
            };
            let next = counted(n, progress, |done| {
                rfta_feasible::fine_tune(
                    &unit.spheres,
                    &unit.values,
                    &mesh,
                    &self.cloud,
                    tested,
                    tree,
                    &self.feasible,
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
            self.cloud = next;
        }
        // The points the final solve takes.
        report.points_per_round.push(self.cloud.len());
        Ok(report)
    }

    /// On fine grids ([`Params::fine_rounds`]) a round's feasibility batch is drawn
    /// from the spheres the initial points draw ([`UnitBox::raster_radius`]) instead of from
    /// every sphere: of the 2.1 million of a 129^3 grid 92% are farther out, so a batch of all
    /// held about 260 spheres that can meet a tangency point, and the large ones it held instead
    /// made every query visit most of the tree.
    fn batch_pool(unit: &UnitBox, params: &Params) -> Vec<u32> {
        let reach = unit.raster_radius(params);
        (0..unit.len() as u32)
            .filter(|&i| unit.spheres[i as usize].radius < reach)
            .collect()
    }
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
