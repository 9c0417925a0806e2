//! [`Params`]: every setting of a reconstruction, and the stage settings derived from it.
//!
//! Each stage crate has its own parameter type; this module is the one place that fills them
//! ([`Params::raster_params`], [`Params::feasible_params`], [`Params::spsr_params`]), so a setting
//! has one owner and the pipeline never assembles stage parameters by hand.

use rfta_geom::rng::hash;
use rfta_spsr::SpsrParams;
use serde::{Deserialize, Deserializer, Serialize};

use crate::field::Field;
use crate::{Error, Result};

/// The most worker threads [`Params::threads`] may ask for.
pub(crate) const MAX_THREADS: usize = 4096;

/// Parameters. Lengths (`transport_step`, `tolerance`) are in the normalized unit box, as in the
/// reference. The paper's symbols are given for each.
///
/// Its serde form is the one table of setting names behind every front end: the Python
/// package's keywords, the command line's options (`--max-points-per-sphere`, ...) and
/// [`Params::with_options`] all use these field names (`spsr_depth` as `depth`); a missing field
/// is the default's, an unknown one an error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Params {
    /// Fine-tuning rounds, the paper's `k_max`. `None`: 10, or 3 on grids of more than 80 cells
    /// along their longest side ([`Params::rounds_for`]).
    pub rounds: Option<usize>,
    /// Maximum tangency points per sphere, the paper's `n_max` (3).
    pub max_points_per_sphere: usize,
    /// Spheres in each feasibility batch, drawn with replacement, the paper's `b` (10^4; 0 = all).
    pub batch_size: usize,
    /// Screening weight of the Poisson solves, in `rfta-spsr`'s units (30), at depths up to 9;
    /// each depth beyond halves it ([`screening_at`]). The reference runs PoissonRecon with 10,
    /// for which our solver needs about 30 on the same points (docs/spsr.md).
    pub screening: f64,
    /// Octree depth of the Poisson solves, on a box 3.2 times the unit box as in the reference;
    /// `None` matches it to the sample spacing ([`spsr_depth_for`]). The reference always runs 10.
    #[serde(rename = "depth")]
    pub spsr_depth: Option<u32>,
    /// Moves of the feasibility local search (20).
    pub local_search_moves: usize,
    /// Arc length of one transport step, the paper's `tau` (0.01).
    pub transport_step: f64,
    /// Tolerance of the inside tests (1e-4).
    pub tolerance: f64,
    /// Rasterization resolution; `None` for the paper's `64 ceil(n^(1/3) / 16)`.
    pub raster_resolution: Option<usize>,
    /// The SDF was clamped at this magnitude: samples at or beyond it get no tangency point and
    /// their spheres are shrunk to this radius (the surface is at least that far). `None`: no
    /// clamp unless [`Params::check`] detects one.
    pub clamp: Option<f64>,
    /// Inspect the samples first ([`crate::check::inspect`]): refuse values that are not a
    /// distance (more than [`Params::max_inconsistent`] of the samples overlap a sample of the
    /// other sign by more than `SEVERE_RATIO` (1.25), or a value exceeds the samples'
    /// extent), warn about milder violations, and detect clamping when `clamp` is `None`.
    /// Default `true`.
    pub check: bool,
    /// The fraction of severely inconsistent samples above which [`Params::check`] refuses (0.25).
    pub max_inconsistent: f64,
    /// Refuse, before any work, inputs whose [`crate::estimate_peak_memory`] exceeds this many
    /// bytes (`None`: no limit; the command-line tool passes the memory available).
    pub memory_limit: Option<u64>,
    /// Seed of every random choice (raster jitter, batches); see [`Seeds`].
    pub seed: u64,
    /// Rasterize on the GPU when the crate is built with feature `gpu` and an adapter exists.
    pub gpu: bool,
    /// Worker threads (`None`: rayon's global pool). The mesh does not depend on it.
    pub threads: Option<usize>,
    /// Spheres farther from the surface than this many sample spacings (`|s| >= owner_band h`)
    /// own no tangency point; they stay constraints, in the rasterization and in every
    /// feasibility test. On a grid `h` is the grid's spacing; scattered samples' spacing varies,
    /// so each sphere has its own, the distance from its centre to the fourth nearest other
    /// sample (one spacing on a grid; `LOCAL_SPACING_NEIGHBOUR`): where samples near the surface
    /// are sparse the far spheres keep their points (a band of the mean spacing left 5,500
    /// samples of a sphere, four in five far from it, with a mean vertex error 4x larger).
    /// Default `OWNER_BAND` (3.0). `None`: every sphere owns points, as in the reference. In the
    /// serde form 0 is `None` too.
    #[serde(deserialize_with = "zero_is_none")]
    pub owner_band: Option<f64>,
    /// Closed components (other than the largest) whose bounding-box diagonal is below this many
    /// sample spacings stay only where the samples witness them: a sample inside of the sign their
    /// orientation gives their inside, or a sample whose sphere reaches them while the largest
    /// component is farther from it than its value (it would have a gap without them); 0 keeps
    /// them all. Screened Poisson leaves small closed islands next to outlying tangency points
    /// (the reference's outputs have them too); a thin part the grid resolves only in pieces
    /// leaves small islands around its inside samples or between them where the samples' spheres
    /// touch it, and those stay, if at least a spacing across (smaller ones, with no sample in
    /// them, are below what the samples resolve and go unless [`Params::keep_thin_handles`]).
    /// Size alone removes nothing. Default 2.
    pub min_island: f64,
    /// The shape's genus, when the caller knows it (a scanned organ: 0): the output is made one
    /// surface of at most this genus. Every other component is joined to the largest by a tube
    /// between their nearest faces, and while the genus is higher the shortest loop around a
    /// handle is cut and both sides capped (`rfta_mesh::short_loops`, `rfta_mesh::cut_along`),
    /// thinnest handle first: a bar cut through, or a tunnel filled. Handles the mesh lacks are
    /// not added. `None` (the default): the topology is the reconstruction's; handles thinner
    /// than the samples resolve are reported ([`crate::Consistency::thin_loops`]).
    pub genus: Option<usize>,
    /// Keep the cavities a grid's samples leave open instead of opening them. By default a
    /// cavity the surface seals around outside samples, where an outside sample in it is next to
    /// an outside sample beyond the surface on the grid (a gap or a hole the surface closed: the
    /// wall between them holds no inside sample), is opened: the final solve is run again with a
    /// point in each such gap kept outside ([`rfta_repair::cavity_openings`]). A cavity walled in
    /// by inside samples all round (a hollow ball) is kept either way. Scattered samples: kept.
    /// In 2D the same for the holes of the curve ([`crate::plane`], `rfta_plane::holes`).
    pub keep_cavities: bool,
    /// Keep the handles thinner than the samples resolve that no sample confirms, and the small
    /// parts less than a spacing across that no sample lies in ([`Params::min_island`]). By default,
    /// on a grid, a handle whose loop is shorter than `THIN_LOOP` (pi) spacings (a bar or a tunnel
    /// less than about a spacing across) is cut along its loop and both sides capped unless a
    /// sample of its side lies next to its centre (material in a bar, empty space in a tunnel):
    /// the samples cannot tell it from none, and marching cubes of the same samples makes none
    /// ([`crate::RepairReport::thin_handle_loops`]). Scattered samples: kept; an adaptive run
    /// asks its function instead.
    pub keep_thin_handles: bool,
    /// Where the initial tangency points come from: on grids, by default, the closest surface
    /// point each sample's gradient points to ([`InitialPoints::Gradient`]); the paper's
    /// rasterized empty space ([`InitialPoints::Raster`], always for scattered samples).
    pub initial: InitialPoints,
    /// How the samples are read: as distances (the paper's spheres) or as a level set whose zero
    /// set is the surface; by default ([`Field::Auto`]) a grid whose values fall short of their
    /// zero set is read as a level set ([`crate::field`]).
    pub field: Field,
    /// Simplify the repaired mesh (default `true`): edges collapsed by quadric error while the
    /// surface stays within [`Params::simplify_tolerance`] of the unsimplified one, every sample
    /// keeps its side, no sphere is entered deeper than the consistency check allows, and the
    /// mesh keeps its topology ([`rfta_simplify`]). `false` returns the repaired mesh as it is.
    pub simplify: bool,
    /// How far, in sample spacings, the simplified surface may lie from the unsimplified one.
    /// On samples at least 100 spacings across, the final solve's extraction also takes the
    /// cells whose surface is flat within it (at most the default) whole, so the surface the
    /// collapses start from lies within twice it of the full extraction's
    /// (`Params::flat_spacings`). `None`: [`rfta_simplify::default_tolerance`], `0.8 h / L`
    /// spacings (`h` the spacing, `L` the samples' longest extent: 0.04 at N = 20, 0.016 at
    /// N = 50) within 0.008 to 0.06, or one spacing when [`Params::faces`] is set (a budget of
    /// faces may cost accuracy, not what the samples resolve).
    pub simplify_tolerance: Option<f64>,
    /// Simplify to at most this many faces, as far as the samples, the topology and the
    /// tolerance allow (`None`: as far as they allow).
    pub faces: Option<usize>,
}

/// The source of the initial tangency points ([`Params::initial`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InitialPoints {
    /// On grids, for each sample `p` near the surface, `p - s grad S / |grad S|` (central
    /// differences of the grid's values): for an exact SDF the closest surface point, which
    /// touches the sample's sphere. Those outside every other sphere of the sign are the empty
    /// space the initial points start from, in place of a raster of the whole box (issue 41).
    /// Scattered samples are rasterized.
    #[default]
    Gradient,
    /// The paper's: rasterize each sign's spheres, take the empty-space sample nearest to each
    /// centre (steps 2 and 3).
    Raster,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            rounds: None,
            max_points_per_sphere: 3,
            batch_size: 10_000,
            screening: 30.0,
            spsr_depth: None,
            local_search_moves: 20,
            transport_step: 0.01,
            tolerance: 1e-4,
            raster_resolution: None,
            clamp: None,
            check: true,
            max_inconsistent: 0.25,
            memory_limit: None,
            seed: 3452,
            gpu: false,
            threads: None,
            owner_band: Some(OWNER_BAND),
            min_island: 2.0,
            genus: None,
            keep_cavities: false,
            keep_thin_handles: false,
            initial: InitialPoints::Gradient,
            field: Field::Auto,
            simplify: true,
            simplify_tolerance: None,
            faces: None,
        }
    }
}

/// `owner_band`'s serde form: a number of spacings, `0` or `null` for none.
fn zero_is_none<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Option<f64>, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.filter(|&b| b != 0.0))
}

/// Cells of the finest octree depth per sample spacing that [`spsr_depth_for`] aims at: fewer
/// lose accuracy, more cost time for none (measured in docs/speed.md).
pub(crate) const CELLS_PER_SPACING: f64 = 4.0;

/// The default [`Params::owner_band`]: spheres within 3 sample spacings of the surface own points;
/// the far ones' points only repeat, less precisely, what the near ones say (docs/speed.md; on
/// scattered samples uniform in their box, mean Chamfer 26% lower in a sixth of the CPU time at
/// 29,791 samples, 37% lower in an eighth at 103,823).
pub(crate) const OWNER_BAND: f64 = 3.0;

/// With an owner band, only spheres smaller than this many owner radii are rasterized for the
/// empty space: a far sphere only fills what lies between nearer ones (docs/speed.md).
pub(crate) const RASTER_REACH: f64 = 3.0;

/// The fewest spacings across the samples' longest extent at which the final solve's flat cells
/// are extracted whole ([`Params::flat_spacings`]), where the full extraction is six times the
/// simplified mesh and its simplification most of a run's last steps. Measured (docs/speed.md):
/// on the 129^3 grids of bunny, fandisk and knight, within the default tolerance, 11% to 34%
/// fewer faces before simplification and mean Chamfer +0.2% (within twice it, +2.4% on the
/// bunny); on the dev set at N = 10 to 50 the same rule gave mean Chamfer -0.5%, +1.4%, +0.7%,
/// +0.7%, 3holes at N = 20 lost a hole and thingi54725 entered 14 spheres instead of 7, where
/// the simplification took 5% to 8% of a run without it.
const FLAT_FROM: f64 = 100.0;

/// The simplification's tolerance, in sample spacings, when only [`Params::faces`] is given.
const FACES_TOLERANCE: f64 = 1.0;

/// The box of the Poisson solves, in unit boxes (the reference's `point_cloud_to_mesh`).
const SPSR_BOX: f64 = 3.2;

/// Depth up to which the Poisson octree is a complete grid: in the reference's 3.2 box the cloud
/// spans 2.5 cells at depth 3, and a deeper complete grid was most of a small input's time
/// (docs/speed.md).
pub(crate) const SPSR_FULL_DEPTH: u32 = 3;

/// Gauss-Seidel sweeps per depth of the rounds' solves (the final solve keeps PoissonRecon's 8):
/// a round's surface only guides the next moves (docs/speed.md).
pub(crate) const ROUND_SWEEPS: usize = 4;

/// The deepest Poisson solve that runs the full [`Params::screening`]; each depth beyond halves
/// it ([`screening_at`]), so that fine solves do not follow a stray point into a fin or a thin
/// handle (docs/faithfulness.md, "weaker screening on fine grids").
pub(crate) const SCREENING_FULL_DEPTH: u32 = 9;

/// The screening weight the solves at `depth` run for a [`Params::screening`] of `screening`:
/// itself up to `SCREENING_FULL_DEPTH` (9), halved for each depth beyond.
pub fn screening_at(screening: f64, depth: u32) -> f64 {
    let beyond = depth.saturating_sub(SCREENING_FULL_DEPTH);
    screening / f64::from(1u32 << beyond.min(16))
}

/// The fine-tuning rounds of the paper (`k_max`), unless [`Params::rounds`] says otherwise.
pub(crate) const ROUNDS: usize = 10;

/// The fine-tuning rounds on grids whose final solve is deeper than [`ROUND_FULL_DEPTH`] (10: more
/// than 80 cells along the longest side), unless [`Params::rounds`] says otherwise. There the
/// samples' gradients start the points close to where the rounds leave them (on the 129^3 bunny
/// nine points in ten no longer move after the third round), and three rounds hold the ten's
/// accuracy and topology on the dev shapes: mean Chamfer 0.000906 against 0.000905 at 101^3,
/// 0.000615 against 0.000612 at 129^3, 0.000258 against 0.000259 at 257^3 (bunny, fandisk,
/// knight), every genus right in one piece, nothing on the wrong side, no sphere entered (ten
/// rounds entered one at 101^3), in about a third less time (docs/speed.md, item 45). On all
/// eight dev shapes at 257^3 one shape was worse: thingi54725's repaired mesh entered 42 wide
/// spheres by at most 0.114 spacings where ten rounds (and one or two) entered none, which the
/// verdict now clears (docs/speed.md, 2026-12-07, night and late night). On coarser grids fewer
/// rounds lost accuracy and topology (51^3 and below), so they keep ten.
pub(crate) const FINE_GRID_ROUNDS: usize = 3;

/// The deepest Poisson solve whose rounds run as the reference's; beyond it they solve one depth
/// coarser ([`Params::round_spsr_params`]) and draw their batches from the spheres near the surface
/// (`RASTER_REACH` owner radii): a round's surface only guides the next moves (docs/speed.md,
/// item 33).
pub(crate) const ROUND_FULL_DEPTH: u32 = 10;

/// Handles whose loop is shorter than this many of the final solve's finest cells are cut
/// ([`crate::RepairReport::sub_cell_handles_cut`]): a thread or pinhole of the extraction at a
/// saddle, not a feature (docs/faithfulness.md, "handles narrower than a cell").
pub(crate) const SUB_CELL_LOOP: f64 = 2.0;

/// The screened Poisson depth whose finest cell, on the reference's box of 3.2 unit boxes, is at
/// most `1 / CELLS_PER_SPACING` of the sample spacing `h` (in the unit box), within 5 to 12.
pub fn spsr_depth_for(h: f64) -> u32 {
    let cells = SPSR_BOX * CELLS_PER_SPACING / h.max(1e-9);
    (rfta_geom::math::log2(cells).ceil() as i64).clamp(5, 12) as u32
}

/// The names of the presets [`Params::preset`] knows, in one place for every front end.
pub const PRESETS: [&str; 3] = ["default", "paper", "fast"];

impl Params {
    /// The preset named `name`: `default` ([`Params::default`], the paper's defaults), `paper`
    /// ([`Params::paper_table`], its Table 2) or `fast` ([`Params::fast`], gpytoolbox's
    /// defaults); `None` for another name ([`PRESETS`] lists them).
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "default" => Some(Self::default()),
            "paper" => Some(Self::paper_table()),
            "fast" => Some(Self::fast()),
            _ => None,
        }
    }

    /// `self` with the settings `options` names (the serde field names; `null` is `None`): an
    /// unknown name or a value of the wrong type is [`Error::InvalidParams`] naming it. The
    /// values are not checked here; [`crate::reconstruct`] checks them.
    pub fn with_options(
        &self,
        options: serde_json::Map<String, serde_json::Value>,
    ) -> Result<Self> {
        let merged = |options: serde_json::Map<String, serde_json::Value>| {
            let mut all = match serde_json::to_value(self)? {
                serde_json::Value::Object(all) => all,
                _ => serde_json::Map::new(),
            };
            all.extend(options);
            serde_json::from_value::<Self>(serde_json::Value::Object(all))
        };
        merged(options.clone()).map_err(|e| {
            // serde names an unknown field but not the field whose value is wrong: found alone.
            let culprit = options.iter().find(|(k, v)| {
                merged([((*k).clone(), (*v).clone())].into_iter().collect()).is_err()
            });
            Error::InvalidParams(match culprit {
                Some((k, _)) if !e.to_string().contains(k.as_str()) => format!("{k}: {e}"),
                _ => e.to_string(),
            })
        })
    }

    /// The setting of the paper's Table 2 (its evaluation script): 20 rounds, 30 points per sphere.
    pub fn paper_table() -> Self {
        Self {
            rounds: Some(20),
            max_points_per_sphere: 30,
            ..Self::default()
        }
    }

    /// gpytoolbox's defaults (`reach_for_the_arcs` in gpytoolbox 0.3): 3 rounds, 3 points per
    /// sphere; the setting of the shared reference results' `rfta` rows.
    pub fn fast() -> Self {
        Self {
            rounds: Some(3),
            ..Self::default()
        }
    }

    /// The rasterizer's settings for one sign set (`negative` or not) at `resolution`.
    pub fn raster_params(&self, resolution: usize, negative: bool) -> rfta_raster::RasterParams {
        rfta_raster::RasterParams {
            res: resolution,
            seed: Seeds(self.seed).raster(negative),
        }
    }

    /// The rasterization resolution for `n` samples.
    pub fn raster_resolution_for(&self, n: usize) -> usize {
        self.raster_resolution
            .unwrap_or_else(|| rfta_raster::default_resolution(n))
    }

    /// The tangency-point settings for `n` samples, where spheres of radius `owner_radius` and
    /// larger own no point (unit box; clamped or beyond [`Params::owner_band`]) and a sphere's own
    /// points lie at `owner_scale` times its radius (1; above 1 for spheres shrunk by noise,
    /// [`crate::InputReport::radius_scale`]).
    pub fn feasible_params(
        &self,
        n: usize,
        owner_radius: f64,
        owner_scale: f64,
    ) -> rfta_feasible::Params {
        rfta_feasible::Params {
            tol: self.tolerance,
            local_search_iters: self.local_search_moves,
            k_search: rfta_feasible::Params::k_search_for(n),
            tau: self.transport_step,
            n_max: self.max_points_per_sphere,
            owner_radius,
            owner_scale,
            ..rfta_feasible::Params::default()
        }
    }

    /// The screened Poisson settings the pipeline runs, for samples `spacing` apart in the unit
    /// box (`None`: unknown, depth 10 as the reference): the reference's box and degree, our
    /// screening at that depth ([`screening_at`]), [`Params::spsr_depth`] or the depth matched to
    /// the spacing, complete grids up to depth `SPSR_FULL_DEPTH` (3), and, when the mesh is
    /// simplified, flat cells taken whole (`Params::flat_spacings`). `rfta psr --preset rfta`
    /// runs the same (with no spacing, every leaf).
    pub fn spsr_params(&self, spacing: Option<f64>) -> SpsrParams {
        let depth = self
            .spsr_depth
            .unwrap_or_else(|| spacing.map_or(10, spsr_depth_for));
        SpsrParams {
            depth,
            screening: screening_at(self.screening, depth),
            box_scale: SPSR_BOX,
            full_depth: SPSR_FULL_DEPTH,
            flat_tolerance: spacing.and_then(|h| self.flat_spacings(1.0 / h).map(|t| t * h)),
            ..SpsrParams::rfta_reference()
        }
    }

    /// The settings of the solves inside the fine-tuning rounds: [`Params::spsr_params`] with
    /// `ROUND_SWEEPS` (4) Gauss-Seidel sweeps per depth, one depth coarser beyond
    /// `ROUND_FULL_DEPTH` (10) (the screening weight stays the final depth's). The adaptive
    /// passes' rounds solve coarser still from a final depth of 10 (`adaptive::coarser_rounds`).
    pub fn round_spsr_params(&self, spacing: Option<f64>) -> SpsrParams {
        let last = self.spsr_params(spacing);
        SpsrParams {
            iterations: ROUND_SWEEPS,
            depth: last.depth - u32::from(self.fine_rounds(spacing)),
            flat_tolerance: None,
            ..last
        }
    }

    /// The fine-tuning rounds of a run: [`Params::rounds`] when set, else 3 (`FINE_GRID_ROUNDS`)
    /// on a grid (`grid`) whose final solve is deeper than depth 10 at sample spacing `spacing`
    /// (in the unit box: more than 80 cells along the longest side), else the paper's 10.
    pub fn rounds_for(&self, grid: bool, spacing: Option<f64>) -> usize {
        match self.rounds {
            Some(k) => k,
            None if grid && self.fine_rounds(spacing) => FINE_GRID_ROUNDS,
            None => ROUNDS,
        }
    }

    /// Whether the final solve is deeper than [`ROUND_FULL_DEPTH`]: the rounds then solve one
    /// depth coarser and draw their feasibility batches from the spheres near the surface.
    pub(crate) fn fine_rounds(&self, spacing: Option<f64>) -> bool {
        self.spsr_params(spacing).depth > ROUND_FULL_DEPTH
    }

    /// Whether every fine-tuning round tests feasibility against all spheres (no batching).
    pub(crate) fn batch_holds_all(&self, n: usize) -> bool {
        self.batch_size == 0 || self.batch_size >= n
    }

    /// The simplification's tolerance in sample spacings when it does not depend on the samples
    /// ([`Params::simplify_tolerance`], or one spacing for [`Params::faces`]); `None`: the
    /// default for the samples' size, [`rfta_simplify::default_tolerance`].
    pub(crate) fn simplify_tolerance_set(&self) -> Option<f64> {
        self.simplify_tolerance
            .or_else(|| self.faces.map(|_| FACES_TOLERANCE))
    }

    /// The simplification's tolerance in sample spacings for samples `per_axis` spacings across
    /// their longest extent; `None` when the mesh is not simplified.
    pub(crate) fn simplify_spacings(&self, per_axis: f64) -> Option<f64> {
        self.simplify.then(|| {
            self.simplify_tolerance_set()
                .unwrap_or_else(|| rfta_simplify::default_tolerance(per_axis))
        })
    }

    /// How far, in sample spacings, the crossings in a refined cell of the final solve may lie
    /// from a plane for the extraction to take the cell whole
    /// (`rfta_spsr::SpsrParams::flat_tolerance`), for samples `per_axis` spacings across: the
    /// simplification's tolerance, at most the default one (a budget of faces or a loose
    /// tolerance may cost accuracy, not the extraction's topology), from `FLAT_FROM` spacings
    /// across; `None` below, or when the mesh is not simplified (the full extraction's).
    pub(crate) fn flat_spacings(&self, per_axis: f64) -> Option<f64> {
        if per_axis < FLAT_FROM {
            return None;
        }
        let at_most = rfta_simplify::default_tolerance(per_axis);
        self.simplify_spacings(per_axis).map(|t| t.min(at_most))
    }

    pub(crate) fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParams(m));
        if self.max_points_per_sphere == 0 {
            return bad("max_points_per_sphere must be at least 1".into());
        }
        if !(self.transport_step > 0.0 && self.transport_step.is_finite()) {
            return bad(format!(
                "transport_step must be finite and > 0, got {}",
                self.transport_step
            ));
        }
        if !(self.tolerance >= 0.0 && self.tolerance.is_finite()) {
            return bad(format!(
                "tolerance must be finite and >= 0, got {}",
                self.tolerance
            ));
        }
        if let Some(c) = self.clamp
            && (c.is_nan() || c <= 0.0)
        {
            return bad(format!("clamp must be > 0, got {c}"));
        }
        if !(0.0..=1.0).contains(&self.max_inconsistent) {
            return bad(format!(
                "max_inconsistent must be in [0, 1], got {}",
                self.max_inconsistent
            ));
        }
        if self.threads == Some(0) {
            return bad("threads must be at least 1".into());
        }
        if let Some(t) = self.threads.filter(|&t| t > MAX_THREADS) {
            return bad(format!(
                "threads must be at most {MAX_THREADS}, got {t} (a pool that size takes minutes to \
                 start, and results do not depend on the count)"
            ));
        }
        if !(self.min_island >= 0.0 && self.min_island.is_finite()) {
            return bad(format!(
                "min_island must be finite and >= 0, got {}",
                self.min_island
            ));
        }
        if let Some(b) = self.owner_band
            && !(b > 0.0 && b.is_finite())
        {
            return bad(format!("owner_band must be finite and > 0, got {b}"));
        }
        if let Some(t) = self.simplify_tolerance
            && !(t >= 0.0 && t.is_finite())
        {
            return bad(format!(
                "simplify_tolerance must be finite and >= 0 (sample spacings), got {t}"
            ));
        }
        if let Some(d) = self.spsr_depth
            && !(1..=16).contains(&d)
        {
            return bad(format!("spsr_depth must be 1 to 16, got {d}"));
        }
        Ok(())
    }
}

/// The named random streams of a run, each derived from [`Params::seed`]: one per use, so that
/// adding a stream never shifts another.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Seeds(pub u64);

impl Seeds {
    /// Jitter of the empty-space samples of one sign set.
    pub fn raster(self, negative: bool) -> u64 {
        hash(self.0, if negative { 2 } else { 1 })
    }

    /// The feasibility batch of the initial points of one sign set.
    pub fn initial_batch(self, negative: bool) -> u64 {
        hash(self.0, if negative { 12 } else { 11 })
    }

    /// The feasibility batch of fine-tuning round `round` (1-based).
    pub fn round_batch(self, round: usize) -> u64 {
        hash(self.0, 100 + round as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn screening_halves_with_each_depth_beyond_the_full_one() {
        // 30 up to depth 9 (N = 30 and coarser), then 15, 7.5 (N = 100, the 129^3 grid), 3.75.
        for (depth, want) in [(5, 30.0), (9, 30.0), (10, 15.0), (11, 7.5), (12, 3.75)] {
            assert_eq!(screening_at(30.0, depth), want, "depth {depth}");
        }
        let p = Params::default();
        assert_eq!(p.spsr_params(Some(1.0 / 30.0)).screening, 30.0);
        assert_eq!(p.spsr_params(Some(1.0 / 100.0)).screening, 7.5);
        assert_eq!(p.round_spsr_params(Some(1.0 / 100.0)).screening, 7.5);
        assert_eq!(screening_at(1.0, 60), 1.0 / 65536.0);
    }

    #[test]
    fn rounds_solve_one_depth_coarser_beyond_the_full_depth() {
        // h = 1/50: depth 10 (N = 50), the rounds too; h = 1/128: 11, the rounds 10; an
        // explicit depth 12: the rounds 11. The rest of the settings as the final solve's.
        let p = Params::default();
        for (params, h, last, rounds) in [
            (p.clone(), 1.0 / 30.0, 9, 9),
            (p.clone(), 1.0 / 50.0, 10, 10),
            (p.clone(), 1.0 / 128.0, 11, 10),
            (
                Params {
                    spsr_depth: Some(12),
                    ..p.clone()
                },
                1.0 / 30.0,
                12,
                11,
            ),
        ] {
            let (final_solve, round) = (
                params.spsr_params(Some(h)),
                params.round_spsr_params(Some(h)),
            );
            assert_eq!((final_solve.depth, round.depth), (last, rounds), "h = {h}");
            assert_eq!(round.screening, final_solve.screening);
            assert_eq!(round.iterations, ROUND_SWEEPS);
        }
    }

    #[test]
    fn fine_grids_take_three_rounds_unless_told() {
        // The final depth is the first with 12.8 / h cells or more (4 per spacing in the 3.2
        // box): h = 1/80 gives 1024 cells, depth 10, so ten rounds; h = 1/81 gives 1036.8 cells,
        // depth 11, so three. Scattered samples, and any rounds asked for, are not changed.
        let p = Params::default();
        for (params, grid, h, rounds) in [
            (p.clone(), true, 1.0 / 20.0, 10),
            (p.clone(), true, 1.0 / 80.0, 10),
            (p.clone(), true, 1.0 / 81.0, 3),
            (p.clone(), true, 1.0 / 256.0, 3),
            (p.clone(), false, 1.0 / 256.0, 10),
            (
                Params {
                    spsr_depth: Some(10),
                    ..p.clone()
                },
                true,
                1.0 / 256.0,
                10,
            ),
            (
                Params {
                    rounds: Some(10),
                    ..p.clone()
                },
                true,
                1.0 / 256.0,
                10,
            ),
            (Params::fast(), true, 1.0 / 20.0, 3),
            (Params::paper_table(), true, 1.0 / 256.0, 20),
        ] {
            assert_eq!(
                params.rounds_for(grid, Some(h)),
                rounds,
                "h = {h}, grid {grid}"
            );
        }
    }

    #[test]
    fn flat_cells_are_taken_whole_within_the_simplification_tolerance_on_fine_grids_only() {
        let p = Params::default();
        // 128 spacings across: the default tolerance is its floor, 0.008 spacings (0.8 / 128 is
        // less); the final solve's cells within 0.008 spacings of a plane are taken whole, the
        // rounds' never.
        let h = 1.0 / 128.0;
        assert_eq!(p.flat_spacings(128.0), Some(0.008));
        assert_eq!(p.spsr_params(Some(h)).flat_tolerance, Some(0.008 * h));
        assert_eq!(p.round_spsr_params(Some(h)).flat_tolerance, None);
        // A tighter tolerance is the flat one; a looser one or a budget of faces stops at the
        // default.
        let tight = Params {
            simplify_tolerance: Some(0.004),
            ..p.clone()
        };
        assert_eq!(tight.flat_spacings(128.0), Some(0.004));
        let budget = Params {
            faces: Some(1000),
            ..p.clone()
        };
        assert_eq!(budget.flat_spacings(128.0), Some(0.008));
        // Below 100 spacings across, without simplification, or with no spacing: every leaf.
        assert_eq!(p.flat_spacings(50.0), None);
        assert_eq!(p.spsr_params(Some(1.0 / 50.0)).flat_tolerance, None);
        let full = Params {
            simplify: false,
            ..p.clone()
        };
        assert_eq!(full.flat_spacings(128.0), None);
        assert_eq!(p.spsr_params(None).flat_tolerance, None);
    }

    #[test]
    fn the_depth_puts_four_finest_cells_in_a_sample_spacing() {
        // The finest cell of depth d on the 3.2 box is 3.2 / 2^d; four of them fit in h when
        // 2^d >= 12.8 / h. h = 0.1 (N = 10): 128 -> 7. h = 0.05: 256 -> 8. h = 1/30: 384 -> 9
        // (2^8 = 256 is too few). h = 1/50: 640 -> 10. h = 1/128: 1638.4 -> 11.
        for (h, d) in [
            (0.1, 7),
            (0.05, 8),
            (1.0 / 30.0, 9),
            (1.0 / 50.0, 10),
            (1.0 / 128.0, 11),
        ] {
            assert_eq!(spsr_depth_for(h), d, "h = {h}");
        }
        assert_eq!(spsr_depth_for(1.0), 5);
        assert_eq!(spsr_depth_for(1e-6), 12);
        assert_eq!(spsr_depth_for(0.0), 12);
    }

    #[test]
    fn the_rounds_solve_with_fewer_sweeps_and_otherwise_the_same_setting() {
        let p = Params::default();
        let (round, last) = (p.round_spsr_params(Some(0.05)), p.spsr_params(Some(0.05)));
        // The final solve keeps PoissonRecon's 8 sweeps; the rounds take half.
        assert_eq!((round.iterations, last.iterations), (4, 8));
        assert_eq!(
            SpsrParams {
                iterations: last.iterations,
                ..round
            },
            last
        );
    }

    #[test]
    fn an_explicit_depth_wins_and_an_unknown_spacing_is_the_reference_depth() {
        let p = Params::default();
        assert_eq!(p.spsr_params(Some(0.05)).depth, 8);
        assert_eq!(p.spsr_params(None).depth, 10);
        let fixed = Params {
            spsr_depth: Some(6),
            ..Params::default()
        };
        assert_eq!(fixed.spsr_params(Some(0.05)).depth, 6);
        assert!(
            Params {
                spsr_depth: Some(0),
                ..Params::default()
            }
            .validate()
            .is_err()
        );
    }

    #[test]
    fn seed_streams_are_distinct() {
        let s = Seeds(3452);
        let mut all = vec![
            s.raster(false),
            s.raster(true),
            s.initial_batch(false),
            s.initial_batch(true),
        ];
        all.extend((1..=30).map(|r| s.round_batch(r)));
        let n = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), n);
    }

    /// Options by the serde names: each lands in its field (`depth` in `spsr_depth`, an owner
    /// band of 0 is none), the rest stay the preset's; a name that is no field, or a value of the
    /// wrong type, is refused naming it.
    #[test]
    fn options_by_name_override_a_preset() {
        let options = |v: serde_json::Value| match v {
            serde_json::Value::Object(m) => m,
            _ => unreachable!("an object"),
        };
        let fast = Params::fast();
        let p = fast
            .with_options(options(serde_json::json!({
                "rounds": 7, "depth": 9, "owner_band": 0, "clamp": 0.25, "genus": 1, "check": false
            })))
            .expect("valid");
        let expect = Params {
            rounds: Some(7),
            spsr_depth: Some(9),
            owner_band: None,
            clamp: Some(0.25),
            genus: Some(1),
            check: false,
            ..Params::fast()
        };
        assert_eq!(p, expect);
        for name in PRESETS {
            let p = Params::preset(name).expect("a preset");
            assert_eq!(p.with_options(serde_json::Map::new()).expect("same"), p);
        }
        let Err(Error::InvalidParams(why)) =
            fast.with_options(options(serde_json::json!({"iters": 3})))
        else {
            panic!("an unknown name is refused");
        };
        assert!(why.contains("iters"), "{why}");
        let Err(Error::InvalidParams(why)) =
            fast.with_options(options(serde_json::json!({"rounds": "many"})))
        else {
            panic!("a wrong type is refused");
        };
        assert!(why.starts_with("rounds: ") && why.contains("many"), "{why}");
    }
}
