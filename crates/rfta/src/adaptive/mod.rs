//! Reconstruction from an SDF that can be asked: the samples chosen where the current
//! reconstruction is least determined by them, under a budget of evaluations (issue 37).
//!
//! [`reconstruct_adaptive`] starts from a coarse grid over the box, reconstructs, then asks the
//! oracle where the mesh and the function disagree, and refines there:
//!
//! 1. the base grid (about a sixth of the budget) is evaluated and reconstructed;
//! 2. every leaf cell of the octree (`lattice.rs`) that the surface may cross (no corner's empty
//!    ball holds it) is probed at its centre, coarsest cells first: the function's value there
//!    against the current mesh's signed distance is the mesh's error at that point, a quantity
//!    neither the samples nor the reconstruction can tell without asking;
//! 3. the cells with the largest errors are refined (the 19 points of their subdivision that are
//!    not known), with the cells whose corners the mesh disagrees with: thin parts the grid
//!    missed, handles and gaps the coarse samples closed, curved parts, the surface between grid
//!    points; cells whose probe finds the mesh right are left coarse;
//! 4. reconstruct and repeat, each pass spending up to one and a half times as many evaluations
//!    as all before it (`SPEND_PER_PASS`), until the budget is spent or no
//!    probed cell is off by more than [`Budget::tolerance`]. Each pass starts from the tangency
//!    points the pass before ended with, those no new sample's sphere holds; only the spheres
//!    left without one get initial points of their own.
//!
//! The passes before the last only say where to ask: they reconstruct with at most
//! `GUIDE_ROUNDS` (3) fine-tuning rounds and end at the final solve with the components the
//! samples contradict removed (no spheres cleared, no cavities opened, no verdict). The last
//! runs the caller's [`Params`], at the depth of `FINAL_CELLS_PER_SPACING` (2.0) unless one is set.
//! In every pass whose final solve is at depth 10 or more the rounds solve two depths coarser
//! (`coarser_rounds`).
//! A pass that would leave less than a quarter of the samples so far for another takes the
//! rest of the budget itself. A last pass whose mesh enters the samples' spheres or leaves one
//! on the wrong side is weighed against the samples' zero set when their spheres are bounds
//! (a CSG tree, a smooth blend: `bounds.rs`). Every choice is a function of
//! the values asked for (sorted lattice keys, errors ordered with ties broken by key), so a
//! deterministic oracle gives the same samples and the same mesh on any number of threads.
//! The oracle's time is measured apart from rfta's ([`AdaptiveReport`]).

mod bounds;
mod bridge;
mod lattice;
mod level_set;
mod settle;

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use rfta_geom::glam::DVec3;
use rfta_geom::{Aabb, SdfSamples};
use rfta_mesh::MeshIndex;

use rfta_feasible::TangentPoints;
use rfta_geom::TriMesh;

use crate::plan::with_plan;
use crate::{Error, Params, Reconstruction, Result, Stage, finish, initial, rounds};
use lattice::{Cell, Lattice};

/// What an oracle's failure carries back: the caller's own error.
pub type OracleError = Box<dyn std::error::Error + Send + Sync>;

/// An SDF that can be asked: the values at a batch of points, in order, or the caller's error.
pub type Oracle<'a> = dyn FnMut(&[DVec3]) -> std::result::Result<Vec<f64>, OracleError> + Send + 'a;

/// The fewest evaluations a budget may allow: the smallest base grid (5^3 points).
pub const MIN_BUDGET: usize = 125;

/// Fine-tuning rounds of the passes before the last (their meshes only guide the next samples).
pub(crate) const GUIDE_ROUNDS: usize = 3;

/// The passes' [`Params::owner_band`]: none, every sphere owns points. The band in each sample's
/// own spacing that scattered samples get (docs/speed.md, item 50) made the dev set's mean
/// Chamfer 2.3% lower at 30,000 evaluations, but at 5,000 the knight came out genus 1 (true 0)
/// and thingi54725 13 (true 11; 9 before): one shape fewer right.
const OWNER_BAND: Option<f64> = None;

/// How much an adaptive run may ask.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// The most evaluations of the oracle (at least [`MIN_BUDGET`]).
    pub evaluations: usize,
    /// Stop early once no probed cell's error (the function's value at its centre against the
    /// mesh's signed distance, in the samples' units) exceeds this: nothing left undecided at
    /// that tolerance. `None`: spend the budget.
    pub tolerance: Option<f64>,
}

impl Budget {
    /// A budget of `evaluations`, spent in full.
    pub fn evaluations(evaluations: usize) -> Self {
        Self {
            evaluations,
            tolerance: None,
        }
    }
}

/// One pass: what was asked and what it cost.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Pass {
    /// Samples the pass reconstructed from.
    pub samples: usize,
    /// Cells probed at their centre after the reconstruction.
    pub probes: usize,
    /// Cells refined after the probes.
    pub refined: usize,
    /// The largest error a probe found (samples' units; 0 before any probe).
    pub largest_error: f64,
    /// Leaf cells the surface may still cross whose probe found an error above the tolerance
    /// (or that were not probed) when the pass ended.
    pub undecided: usize,
    /// Seconds in the oracle during the pass.
    pub oracle_seconds: f64,
    /// Seconds in rfta's own work during the pass (reconstruction, probes' mesh distances).
    pub rfta_seconds: f64,
}

/// The adaptive run's own report, beside the final reconstruction's.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct AdaptiveReport {
    /// Evaluations of the oracle in all (the final sample count).
    pub evaluations: usize,
    /// The budget.
    pub budget: usize,
    /// The finest sample spacing reached (near the surface).
    pub finest_spacing: f64,
    /// Seconds in the oracle.
    pub oracle_seconds: f64,
    /// Seconds in rfta's own work.
    pub rfta_seconds: f64,
    /// The passes, in order; the last one's mesh is the result.
    pub passes: Vec<Pass>,
}

/// The result of [`reconstruct_adaptive`].
#[derive(Debug, Clone)]
pub struct AdaptiveReconstruction {
    /// The final reconstruction, from every sample asked for.
    pub reconstruction: Reconstruction,
    /// The samples asked for, in the order asked (scattered, with the finest spacing stated).
    pub samples: SdfSamples,
    /// Evaluations, passes and the time in the oracle and in rfta.
    pub report: AdaptiveReport,
}

/// Reconstructs the surface of the signed distance function `oracle` (negative inside) over
/// `bounds`, asking it at most `budget.evaluations` times, in batches: `oracle` takes a slice of
/// points and returns their values, or an error that ends the run.
///
/// `progress` hears each stage of each pass's reconstruction, `on_pass` each finished pass;
/// `cancel` is read between batches and stages.
///
/// # Errors
/// [`Error::InvalidParams`] for a budget under [`MIN_BUDGET`] or an empty or non-finite box;
/// [`Error::Oracle`] when the oracle fails, [`Error::OracleAnswer`] when it answers with the wrong
/// number of values or a value that is not finite (nothing is reconstructed from such a batch);
/// [`Error::Cancelled`]; otherwise as [`crate::reconstruct`].
pub fn reconstruct_adaptive(
    oracle: &mut Oracle<'_>,
    bounds: Aabb,
    budget: Budget,
    params: &Params,
    progress: &mut (dyn FnMut(Stage) + Send),
    on_pass: &mut dyn FnMut(&Pass),
    cancel: &AtomicBool,
) -> Result<AdaptiveReconstruction> {
    validate(params, bounds, budget)?;
    let extent = bounds.max - bounds.min;
    // What the budget's samples would need, before the first evaluation (hostile test E15: a
    // budget of 1e11 ran on for minutes): an adaptive run holds at least what a grid of as many
    // samples does.
    crate::check_memory(budget.evaluations, params)?;
    let mut asker = Asker {
        oracle,
        batches: 0,
        asked: 0,
        seconds: 0.0,
        cancel,
    };
    let mut lattice = Lattice::new(bounds, base_cells(budget.evaluations));
    let corners = lattice.missing_corners();
    if corners.len() > budget.evaluations {
        return Err(Error::InvalidParams(format!(
            "a budget of {} evaluations cannot sample a {:?} box's base grid ({} points); give a larger budget or a less elongated box",
            budget.evaluations,
            extent.to_array(),
            corners.len()
        )));
    }
    asker.ask(&mut lattice, &corners)?;
    // A function whose values fall short of its zero set is refined by sign and read as a level
    // set (`level_set.rs`); the base grid says which.
    if let Some(base) = level_set::base_if_level_set(&lattice, params)? {
        let n = budget.evaluations;
        return level_set::refine_and_read(base, &mut asker, n, params, progress, on_pass);
    }
    let guide = Params {
        // The rounds of scattered samples (the passes' samples are), at most GUIDE_ROUNDS.
        rounds: Some(params.rounds_for(false, None).min(GUIDE_ROUNDS)),
        owner_band: OWNER_BAND,
        ..params.clone()
    };
    let mut report = AdaptiveReport {
        budget: budget.evaluations,
        ..AdaptiveReport::default()
    };
    // Kept for the final pass's questions about thin handles.
    let reserve = (budget.evaluations as f64 * HANDLE_SHARE) as usize;
    let usable = budget
        .evaluations
        .saturating_sub(reserve)
        .max(lattice.len());
    // Each pass starts from the tangency points the one before ended with.
    let mut seeds: Option<rfta_feasible::TangentPoints> = None;
    loop {
        // A pass spends up to one and a half times what all before it did.
        let mut spend = (usable - lattice.len())
            .min(((SPEND_PER_PASS * lattice.len() as f64) as usize).max(MIN_BUDGET));
        if usable - lattice.len() - spend < lattice.len() / 4 {
            // What would be left after this pass is too little for a pass of its own.
            spend = usable - lattice.len();
        }
        if spend < MIN_BUDGET / 5 {
            break;
        }
        let t = Instant::now();
        let oracle_before = asker.seconds;
        let samples = lattice.samples()?;
        let (mesh, points) = guide_pass(&samples, &guide, seeds.as_ref(), progress, cancel)?;
        let mut pass = Pass {
            samples: samples.len(),
            ..Pass::default()
        };
        let index = MeshIndex::new(&mesh)?;
        let done = refine_where_wrong(&mut lattice, &index, &mut asker, spend, budget, &mut pass)?;
        pass.oracle_seconds = asker.seconds - oracle_before;
        pass.rfta_seconds = t.elapsed().as_secs_f64() - pass.oracle_seconds;
        on_pass(&pass);
        report.passes.push(pass);
        if done {
            // Nothing left undecided, or nothing left to refine.
            break;
        }
        seeds = Some(points);
    }
    let left = budget.evaluations - lattice.len();
    let read = final_pass(
        &lattice, &mut asker, left, params, seeds, report, progress, on_pass,
    )?;
    // A function whose spheres are bounds is read again on a dense grid (`bounds.rs`).
    bounds::read_again_if_bounds(read, &lattice, params, progress, asker.cancel)
}

/// [`Error::InvalidParams`] for invalid `params`, a box that is not finite with positive extent,
/// a budget under [`MIN_BUDGET`].
fn validate(params: &Params, bounds: Aabb, budget: Budget) -> Result<()> {
    params.validate()?;
    let extent = bounds.max - bounds.min;
    if !(bounds.min.is_finite() && bounds.max.is_finite() && extent.min_element() > 0.0) {
        return Err(Error::InvalidParams(format!(
            "the box must be finite with positive extent on every axis, not {:?} to {:?}",
            bounds.min.to_array(),
            bounds.max.to_array()
        )));
    }
    if budget.evaluations < MIN_BUDGET {
        return Err(Error::InvalidParams(format!(
            "the budget must allow at least {MIN_BUDGET} evaluations, not {}",
            budget.evaluations
        )));
    }
    Ok(())
}

/// A pass before the last: the stages up to the fine-tuning rounds, started from `seeds`, then
/// the guide surface ([`finish::guide`]); the surface and the rounds' points in the caller's
/// coordinates (the next pass starts from them).
fn guide_pass(
    samples: &SdfSamples,
    params: &Params,
    seeds: Option<&TangentPoints>,
    progress: &mut (dyn FnMut(Stage) + Send),
    cancel: &AtomicBool,
) -> Result<(TriMesh, TangentPoints)> {
    let go_on = || crate::go_on(cancel);
    with_plan(samples, params, |mut plan, mut journal| {
        go_on()?;
        coarser_rounds(&mut plan);
        let (cloud, _) = initial::initial_points(&plan, seeds, &mut journal, progress)?;
        let (cloud, _) = rounds::fine_tune(&plan, cloud, &mut journal, progress, &go_on)?;
        go_on()?;
        let mesh = finish::guide(&plan, &cloud, &mut journal, progress)?;
        let points = plan.unit.points_to_input(cloud);
        let out = plan.to_caller(Reconstruction {
            mesh,
            points,
            report: crate::Report::default(),
        });
        Ok((out.mesh, out.points))
    })
}

/// The adaptive passes' fine-tuning rounds solve [`ROUND_DEPTHS_COARSER`] depths below a final
/// solve of depth [`COARSER_ROUNDS_FROM`] or more (about half a cell per finest sample spacing at
/// the last pass's [`FINAL_CELLS_PER_SPACING`]) instead of the grid pipeline's one below depth 11
/// and none below that ([`Params::round_spsr_params`]): a round's surface only guides the next
/// moves, and the adaptive samples put a tangency point on the surface per sample, so ten rounds
/// solving at the final depth cost about five final solves (docs/speed.md, "Adaptive runs").
fn coarser_rounds(plan: &mut crate::plan::Plan<'_>) {
    if plan.final_spsr.depth >= COARSER_ROUNDS_FROM {
        plan.round_spsr.depth = plan.final_spsr.depth - ROUND_DEPTHS_COARSER;
    }
}

/// See [`coarser_rounds`]: below depth 10 a round's solve is cheap, and one depth coarser lost
/// the knight's one piece at a third of MISE's evaluations (depth 9).
const COARSER_ROUNDS_FROM: u32 = 10;

/// See [`coarser_rounds`].
const ROUND_DEPTHS_COARSER: u32 = 2;

/// A pass before the last asks up to this many times the samples it starts from: more of the
/// cells the surface may cross refined a level before any goes two, nearer MISE's level at a time
/// (Mescheder et al., "Occupancy Networks", CVPR 2019), the ranking by error deciding less. At 1
/// the passes went deeper in fewer places. Mean Chamfer over the dev set (docs/eval/adaptive.md)
/// at 1, 1.5 and 2: 0.00437, 0.00425, 0.00473 at 5,000 evaluations; 0.00253, 0.00232, 0.00236
/// at 10,000; 0.00110, 0.00109, 0.00109 at 30,000; at a third of MISE's evaluations 0.00191,
/// 0.00182, 0.00181 (MISE 0.00185); at MISE's 0.000878, 0.000898, 0.000898 (the knight and
/// thingi44395 lose 10% to 17% there).
pub(crate) const SPEND_PER_PASS: f64 = 1.5;

/// The share of the budget kept for the final pass's questions about small components and thin
/// handles (`settle.rs`). At 1% the CSG trees asked as functions at 30,000 evaluations kept
/// handles their zero sets lack (the box bitten by a ball and united with a torus genus 5, the
/// rounded cube genus 1; docs/eval/inexact.md); at 3% genus 1 and 0, for about 1% of mean
/// Chamfer on the exact dev shapes (docs/eval/adaptive.md).
pub(crate) const HANDLE_SHARE: f64 = 0.03;

/// The last pass: the caller's parameters on every sample, the small components and thin handles
/// settled by asking the function at most `left` times (`settle.rs`).
#[allow(clippy::too_many_arguments)]
fn final_pass(
    lattice: &Lattice,
    asker: &mut Asker<'_>,
    left: usize,
    params: &Params,
    seeds: Option<rfta_feasible::TangentPoints>,
    mut report: AdaptiveReport,
    progress: &mut (dyn FnMut(Stage) + Send),
    on_pass: &mut dyn FnMut(&Pass),
) -> Result<AdaptiveReconstruction> {
    let t = Instant::now();
    let oracle_before = asker.seconds;
    let samples = lattice.samples()?;
    // Loops up to THIN_LOOP base cells long: the coarsest spacing any part of the surface may
    // have been left at.
    let bound = crate::consistency::THIN_LOOP * lattice.base_spacing();
    let gap = rfta_repair::CUT_GAP * lattice.finest_spacing();
    let small = lattice.base_spacing();
    let cancel = asker.cancel;
    let params = Params {
        spsr_depth: params.spsr_depth.or(Some(final_depth(lattice))),
        owner_band: OWNER_BAND,
        ..params.clone()
    };
    let go_on = || crate::go_on(cancel);
    let rec = with_plan(&samples, &params, |mut plan, mut journal| {
        go_on()?;
        coarser_rounds(&mut plan);
        let seeds = seeds.as_ref();
        let (cloud, initial) = initial::initial_points(&plan, seeds, &mut journal, progress)?;
        let (cloud, rounds) = rounds::fine_tune(&plan, cloud, &mut journal, progress, &go_on)?;
        go_on()?;
        let (mesh, mut final_solve) = finish::final_solve(&plan, &cloud, &mut journal, progress)?;
        let (mut mesh, mut repair) =
            finish::repair(&plan, &cloud, mesh, &mut final_solve, &mut journal)?;
        // The small components and thin handles settled by asking the function, in its own
        // coordinates.
        plan.in_caller_scale(&mut mesh, |mesh| {
            let mut ask = |p: &[DVec3]| asker.values(p);
            let (asked, removed) =
                settle::settle_components(mesh, &samples, small, left, &mut ask)?;
            repair.small_components_asked = asked;
            repair.small_components_removed = removed;
            let oracle = crate::finish::handles::Oracle {
                ask: &mut ask,
                max_asks: left - 2 * asked,
            };
            let s = crate::finish::handles::settle(mesh, &samples, bound, gap, Some(oracle))?;
            repair.thin_handles_asked = s.asked;
            repair.thin_handles_cut = s.cut.len();
            repair.thin_handle_loops = s.cut.iter().map(|l| l / lattice.finest_spacing()).collect();
            repair.cavities = rfta_mesh::cavities(mesh).len();
            Ok::<_, Error>(())
        })?;
        // Simplified at the finest level's spacing, where the surface is.
        let finest = lattice.finest_spacing();
        let (mesh, simplify) = finish::simplify(&plan, mesh, finest, &mut journal)?;
        let report = crate::Report {
            input: plan.input.clone(),
            initial,
            rounds,
            final_solve,
            repair,
            simplify,
            ..crate::Report::default()
        };
        finish::verdict(&plan, mesh, cloud, report, journal)
    })?;
    let oracle_seconds = asker.seconds - oracle_before;
    let pass = Pass {
        samples: samples.len(),
        oracle_seconds,
        rfta_seconds: t.elapsed().as_secs_f64() - oracle_seconds,
        ..Pass::default()
    };
    on_pass(&pass);
    report.passes.push(pass);
    report.evaluations = asker.asked;
    report.finest_spacing = lattice.finest_spacing();
    report.oracle_seconds = report.passes.iter().map(|p| p.oracle_seconds).sum();
    report.rfta_seconds = report.passes.iter().map(|p| p.rfta_seconds).sum();
    Ok(AdaptiveReconstruction {
        reconstruction: rec,
        samples,
        report,
    })
}

/// Cells of the final pass's finest Poisson depth per finest sample spacing (a grid's solves have
/// `CELLS_PER_SPACING`; [`Params::spsr_depth`], when set, rules instead): the finest spacing is
/// reached only near the hardest parts, and a depth matched to it costs time for no accuracy
/// (docs/eval/adaptive.md).
pub(crate) const FINAL_CELLS_PER_SPACING: f64 = 2.0;

/// The final pass's screened Poisson depth: [`FINAL_CELLS_PER_SPACING`] cells per finest
/// spacing, on the box of the samples (the unit box the pipeline solves in).
fn final_depth(lattice: &Lattice) -> u32 {
    let h = lattice.finest_spacing() / lattice.extent();
    crate::spsr_depth_for(h * crate::CELLS_PER_SPACING / FINAL_CELLS_PER_SPACING)
}

/// Cells of the base grid along the box's longest side for a budget: its points about a sixth of
/// the budget, 4 to 64 cells.
fn base_cells(evaluations: usize) -> u32 {
    let per_axis = rfta_geom::math::cbrt(evaluations as f64 / 6.0).floor() - 1.0;
    per_axis.clamp(4.0, 64.0) as u32
}

/// The oracle with its bookkeeping: batches counted from 1, the time spent in it, the answers
/// checked.
struct Asker<'a> {
    oracle: &'a mut Oracle<'a>,
    batches: usize,
    /// Points asked for in all.
    asked: usize,
    seconds: f64,
    cancel: &'a AtomicBool,
}

impl Asker<'_> {
    /// Asks for `keys` in one batch and records the answers.
    fn ask(&mut self, lattice: &mut Lattice, keys: &[[u32; 3]]) -> Result<()> {
        if keys.is_empty() {
            return Ok(());
        }
        let points: Vec<DVec3> = keys.iter().map(|&k| lattice.position(k)).collect();
        let values = self.values(&points)?;
        lattice.insert(keys, &values);
        Ok(())
    }

    /// The oracle's values at `points`, in one batch, checked.
    fn values(&mut self, points: &[DVec3]) -> Result<Vec<f64>> {
        if points.is_empty() {
            return Ok(Vec::new());
        }
        if self.cancel.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(Error::Cancelled);
        }
        self.batches += 1;
        let batch = self.batches;
        let t = Instant::now();
        let answer = (self.oracle)(points);
        self.seconds += t.elapsed().as_secs_f64();
        let values = answer.map_err(|source| Error::Oracle { batch, source })?;
        if values.len() != points.len() {
            return Err(Error::OracleAnswer {
                batch,
                reason: format!("{} values for {} points", values.len(), points.len()),
            });
        }
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            let p = points[i];
            return Err(Error::OracleAnswer {
                batch,
                reason: format!("the value at point {i} ({}, {}, {}) is {v}", p.x, p.y, p.z),
            });
        }
        self.asked += points.len();
        Ok(values)
    }
}

/// Probes the cells the surface may cross and refines those where the mesh is most wrong,
/// spending at most `spend` evaluations. Returns whether nothing is left to refine (every probe
/// within the tolerance, or no cell left above the finest level).
fn refine_where_wrong(
    lattice: &mut Lattice,
    index: &MeshIndex,
    asker: &mut Asker<'_>,
    spend: usize,
    budget: Budget,
    pass: &mut Pass,
) -> Result<bool> {
    let candidates: Vec<Cell> = lattice
        .leaves()
        .iter()
        .copied()
        .filter(|&c| c.level < lattice::FINEST && lattice.may_hold_surface(c))
        .collect();
    if candidates.is_empty() {
        return Ok(true);
    }
    // Probes: the centres not known yet, coarsest cells first, at most half the pass.
    let mut unprobed: Vec<Cell> = candidates
        .iter()
        .copied()
        .filter(|c| lattice.value(c.centre()).is_none())
        .collect();
    unprobed.sort_by_key(|c| (c.level, c.corner));
    unprobed.truncate(spend / 2);
    let probes: Vec<[u32; 3]> = unprobed.iter().map(|c| c.centre()).collect();
    asker.ask(lattice, &probes)?;
    pass.probes = probes.len();
    // Each candidate's error: at its centre and its corners, the function's value against the
    // mesh's signed distance. Unprobed cells rank by their corners alone.
    let points: Vec<[u32; 3]> = {
        let mut all: Vec<[u32; 3]> = candidates
            .iter()
            .flat_map(|c| c.corners().chain(std::iter::once(c.centre())))
            .filter(|&k| lattice.value(k).is_some())
            .collect();
        all.sort_unstable();
        all.dedup();
        all
    };
    let positions: Vec<DVec3> = points.iter().map(|&k| lattice.position(k)).collect();
    let mesh_distance = index.signed_distances(&positions);
    let error_at = |k: [u32; 3]| -> Option<f64> {
        let i = points.binary_search(&k).ok()?;
        Some((lattice.value(k)? - mesh_distance[i]).abs())
    };
    let mut scored: Vec<(f64, Cell)> = candidates
        .iter()
        .map(|&c| {
            let e = c
                .corners()
                .chain(std::iter::once(c.centre()))
                .filter_map(error_at)
                .fold(0.0, f64::max);
            (e, c)
        })
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    pass.largest_error = scored.first().map_or(0.0, |s| s.0);
    let tolerance = budget.tolerance.unwrap_or(0.0);
    let above: Vec<(f64, Cell)> = scored.into_iter().filter(|s| s.0 > tolerance).collect();
    if above.is_empty() {
        return Ok(true);
    }
    // Refine in order of error while the pass's evaluations last.
    let mut left = spend.saturating_sub(probes.len());
    let mut chosen: Vec<Cell> = Vec::new();
    let mut asked: std::collections::HashSet<[u32; 3]> = std::collections::HashSet::new();
    for &(_, cell) in &above {
        let new: Vec<[u32; 3]> = lattice
            .refinement_points(&[cell])
            .into_iter()
            .filter(|k| !asked.contains(k))
            .collect();
        if new.len() > left {
            continue;
        }
        left -= new.len();
        asked.extend(new);
        chosen.push(cell);
    }
    pass.undecided = above.len() - chosen.len();
    let keys = lattice.refinement_points(&chosen);
    asker.ask(lattice, &keys)?;
    lattice.refine(&chosen);
    pass.refined = chosen.len();
    Ok(chosen.is_empty())
}
