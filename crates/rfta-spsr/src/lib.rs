//! Screened Poisson surface reconstruction (Kazhdan and Hoppe, "Screened Poisson Surface
//! Reconstruction", ACM TOG 2013): oriented points in, a watertight triangle mesh out.
//!
//! The input is mapped into a cube ([`SpsrParams::box_scale`] times its bounding box), points
//! that share a finest cell are merged, and a density estimate gives every sample a depth and the
//! surface area it stands for, so sparse regions get coarser, smoother support
//! ([`SpsrParams::samples_per_node`]). The inward normal field is splatted into an adaptive
//! octree that is refined only near samples and graded so that every depth's hats overlap active
//! hats one depth coarser. The indicator function, a sum of trilinear hats over all depths
//! (degree-1 B-splines, the basis PoissonRecon uses by default and Reach for the Arcs runs),
//! minimises `∫|∇χ - V|² + α Σ w (χ(p) - 1/2)²` with natural (Neumann) or zero (Dirichlet)
//! boundary conditions. It is solved by a cascadic multigrid pass: conjugate gradients on the
//! coarsest complete grids, then a few multi-colour Gauss-Seidel sweeps per depth with the
//! coarser solution moved to the right-hand side. The iso-value is the weighted mean of `χ` at
//! the samples, and the surface is extracted crack-free over the adaptive leaves.
//!
//! Everything is deterministic: the same input and parameters give the same mesh, bit for bit,
//! whatever the number of threads. The work runs on the caller's rayon pool (the global one, or
//! one the caller installs: `pool.install(|| reconstruct(..))`).
//!
//! # Example
//! ```
//! use rfta_spsr::{OrientedPoints, SpsrParams, glam::DVec3, reconstruct};
//!
//! // 4,000 points on the unit sphere (a Fibonacci spiral), normals pointing out.
//! let n = 4000;
//! let pts: Vec<DVec3> = (0..n)
//!     .map(|i| {
//!         let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
//!         let r = (1.0 - z * z).sqrt();
//!         let phi = i as f64 * 2.399963229728653;
//!         DVec3::new(r * phi.cos(), r * phi.sin(), z)
//!     })
//!     .collect();
//! let cloud = OrientedPoints::new(pts.clone(), pts, None)?;
//! let params = SpsrParams { depth: 6, ..SpsrParams::default() };
//! let out = reconstruct(&cloud, &params)?;
//! // Closed and outward: the volume is close to 4/3 pi.
//! let v = out.mesh.signed_volume();
//! assert!((v - 4.18879).abs() < 0.1, "{v}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// Stencil code indexes several fixed-size arrays with one loop variable; iterators would hide that.
#![allow(clippy::needless_range_loop)]

mod basis;
mod extract;
mod keys;
mod solve;
mod tree;

use std::time::{Duration, Instant};

use rayon::prelude::*;

/// The types of this crate's API, so that depending on `rfta-spsr` alone is enough.
pub use rfta_geom::{OrientedPoints, TriMesh, glam};

/// Errors of the reconstruction. Each says what is wrong with the input or the parameters.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Fewer points than a surface needs.
    #[error("screened Poisson needs at least 3 oriented points, got {found}")]
    TooFewPoints {
        /// Number of points given.
        found: usize,
    },
    /// The input describes no surface (for example, all points are identical).
    #[error("{0}")]
    DegenerateInput(String),
    /// A parameter is out of its range.
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// The solved function has no iso-surface inside the cube.
    #[error(
        "the reconstructed function has no iso-surface (iso-value {iso}); the normals may be inconsistent"
    )]
    NoSurface {
        /// The iso-value that was looked for.
        iso: f64,
    },
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, Error>;

/// B-spline degree of the finite elements.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Degree {
    /// Trilinear hats on cell corners (27-entry rows): PoissonRecon's default since version 11 and
    /// what Reach for the Arcs runs. Degree 2 is not implemented.
    #[default]
    One,
}

/// Boundary condition on the faces of the reconstruction cube.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Boundary {
    /// Natural boundary (zero normal derivative): PoissonRecon's default.
    #[default]
    Neumann,
    /// The function is zero on the cube's faces.
    Dirichlet,
}

/// Parameters. The defaults are PoissonRecon 18's (`--depth 8 --pointWeight 2 --degree 1
/// --bType 3 --scale 1.1 --samplesPerNode 1.5 --fullDepth 5 --iters 8`);
/// [`SpsrParams::rfta_reference`] is the setting Reach for the Arcs uses.
#[derive(Debug, Clone, PartialEq)]
pub struct SpsrParams {
    /// Maximum octree depth: the finest cell is `box_scale * extent / 2^depth`. An upper bound:
    /// where samples are sparse the tree stops coarser. 1 to 16.
    pub depth: u32,
    /// Screening weight α (`--pointWeight`): how strongly the function is pulled to the iso-value
    /// at the samples, scaled internally by the average sample area so it does not depend on the
    /// number of points. 0 gives the unscreened Poisson reconstruction of 2006.
    pub screening: f64,
    /// Finite-element degree.
    pub degree: Degree,
    /// Boundary condition.
    pub boundary: Boundary,
    /// Side of the reconstruction cube over the largest side of the points' bounding box (≥ 1).
    pub box_scale: f64,
    /// Target number of samples per node in the density-adaptive depth; raise it (15-20) for
    /// noisy input.
    pub samples_per_node: f64,
    /// Depth up to which the tree is complete (a regular grid); the depths below it are solved by
    /// conjugate gradients.
    pub full_depth: u32,
    /// Gauss-Seidel sweeps per depth from `full_depth` up.
    pub iterations: usize,
    /// Conjugate-gradient iterations cap per depth below `full_depth`.
    pub base_iterations: usize,
}

impl Default for SpsrParams {
    fn default() -> Self {
        Self {
            depth: 8,
            screening: 2.0,
            degree: Degree::One,
            boundary: Boundary::Neumann,
            box_scale: 1.1,
            samples_per_node: 1.5,
            full_depth: 5,
            iterations: 8,
            base_iterations: 200,
        }
    }
}

impl SpsrParams {
    /// The setting of the Reach for the Arcs reference implementation (its `point_cloud_to_mesh`):
    /// depth 10, screening 10, degree 1, Neumann, and a cube 3.2 times the cloud's extent.
    pub fn rfta_reference() -> Self {
        Self {
            depth: 10,
            screening: 10.0,
            box_scale: 3.2,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        if !(1..=16).contains(&self.depth) {
            return Err(Error::InvalidParams(format!(
                "depth must be 1 to 16, got {}",
                self.depth
            )));
        }
        if !(self.screening >= 0.0 && self.screening.is_finite()) {
            return Err(Error::InvalidParams(format!(
                "screening weight must be finite and >= 0, got {}",
                self.screening
            )));
        }
        if !(self.box_scale >= 1.0 && self.box_scale.is_finite()) {
            return Err(Error::InvalidParams(format!(
                "box scale must be finite and >= 1, got {}",
                self.box_scale
            )));
        }
        if !(self.samples_per_node > 0.0 && self.samples_per_node.is_finite()) {
            return Err(Error::InvalidParams(format!(
                "samples per node must be finite and > 0, got {}",
                self.samples_per_node
            )));
        }
        Ok(())
    }
}

/// What a reconstruction did, for logs and benchmarks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SpsrReport {
    /// Input points.
    pub points: usize,
    /// Samples after merging points per finest cell.
    pub samples: usize,
    /// Active hat functions (unknowns) per depth, coarsest first.
    pub nodes_per_depth: Vec<usize>,
    /// Octree cells per depth.
    pub cells_per_depth: Vec<usize>,
    /// The iso-value (weighted mean of the function at the samples).
    pub iso_value: f64,
    /// With side points ([`reconstruct_with_sides`]): how many were on the wrong side after each
    /// solve, the last entry for the surface returned. Empty without them.
    pub side_errors: Vec<usize>,
    /// Leaves whose face segments did not close into loops (always 0 unless there is a bug; the
    /// mesh is then not watertight there).
    pub broken_leaves: usize,
    /// Time to merge samples, estimate density and build the octree.
    pub tree_time: Duration,
    /// Time to splat normals and assemble the per-depth systems.
    pub system_time: Duration,
    /// Time of the multigrid solve and the iso-value.
    pub solve_time: Duration,
    /// Time of the iso-surface extraction.
    pub extract_time: Duration,
}

/// A reconstructed surface.
#[derive(Debug, Clone)]
pub struct Reconstruction {
    /// The mesh, in the input's coordinates, triangles oriented outward (along the normals).
    pub mesh: TriMesh,
    /// Statistics and timings.
    pub report: SpsrReport,
}

/// Reconstruct a surface from oriented points.
///
/// # Errors
/// [`Error::TooFewPoints`] below 3 points, [`Error::DegenerateInput`] when all points coincide,
/// [`Error::InvalidParams`], [`Error::NoSurface`] when the normals are so inconsistent that the
/// solution has no level set.
pub fn reconstruct(points: &OrientedPoints, params: &SpsrParams) -> Result<Reconstruction> {
    params.validate()?;
    Ok(run(points, params, &[], None, Keep::Nothing)?.0)
}

/// A point the surface must leave on one side: inside (`inside: true`) or outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SidePoint {
    /// Where, in the points' coordinates.
    pub position: glam::DVec3,
    /// Whether it lies inside the surface.
    pub inside: bool,
}

/// Re-solves after the first at most, in [`reconstruct_with_sides`].
pub const SIDE_PASSES: usize = 4;

/// A side point counts as wrong unless the function is at least this far on its side of the
/// iso-value (in the indicator's units: 1 inside, 0 outside): the extracted surface follows the
/// function only approximately, and a point right at the iso-value is on neither side.
pub const SIDE_MARGIN: f64 = 0.02;

/// Between the first solve and the last, only the side points within this of being wrong after
/// the first solve (in the indicator's units, beyond [`SIDE_MARGIN`]) are evaluated again; the
/// solve whose surface is returned is checked at every side point. A re-solve changes the
/// function near the points it adds, which lie near the surface; far from it the indicator stays
/// near its far value (at 129^3 samples of a shape, 2,071 of 2.1 million side points are within
/// 0.1 after the first solve, 2.0 million within 0.3).
pub const SIDE_RECHECK: f64 = 0.1;

/// A wrong side point is screened toward the iso-value plus (inside) or minus (outside) this: a
/// target just past the surface moves it no farther than needed (measured on the Reach for the
/// Arcs dev set, docs/faithfulness.md: targets of 1/2 past it, the indicator's own values,
/// dig pits and tunnels around the points).
pub const SIDE_TARGET: f64 = 0.1;

/// Weight of a side constraint in its first re-solve, in units of the mean screening weight of
/// one merged sample; each later re-solve that still finds it wrong multiplies it by
/// [`SIDE_WEIGHT_GROWTH`].
pub const SIDE_WEIGHT: f64 = 1.0;

/// Growth of a still-wrong side constraint's weight from one re-solve to the next.
pub const SIDE_WEIGHT_GROWTH: f64 = 4.0;

/// Gauss-Seidel sweeps per depth of a re-solve with side points. A re-solve runs on the same
/// octree with a few more screening terms, so it starts from the solution before it (exactly
/// the same nodes) and needs fewer sweeps than a cold solve ([`SpsrParams::iterations`]).
/// Measured in the Reach for the Arcs pipeline (docs/speed.md): the dev set's mean Chamfer at
/// N = 10, 20, 30 the same or lower than with cold 8-sweep re-solves, and the final solve of
/// the 129^3 bunny 29% shorter.
pub const SIDE_RESOLVE_SWEEPS: usize = 2;

/// [`reconstruct`], with points known to lie inside or outside the surface.
///
/// The screened Poisson energy pulls the indicator function toward 1/2 at the samples. Here,
/// after the first solve, every side point where the function is not at least [`SIDE_MARGIN`]
/// on its side of the iso-value becomes a screening term of its own, with the target
/// iso ± [`SIDE_TARGET`] and weight [`SIDE_WEIGHT`], and the system is solved again on the same
/// octree, starting from the solution before ([`SIDE_RESOLVE_SWEEPS`] sweeps); up to
/// [`SIDE_PASSES`] times, each adding the points still wrong and multiplying the
/// weight of those that stay wrong by [`SIDE_WEIGHT_GROWTH`]. This is the screening term with a
/// target per point, in the spirit of the envelope constraints of Kazhdan, Chuang, Rusinkiewicz
/// and Hoppe ("Poisson Surface Reconstruction with Envelope Constraints", SGP 2020), applied only
/// where the plain solution disagrees. A wrong side point whose cell the octree does not refine
/// to its finest depth gets its cell refined (the octree rebuilt as if a sample were there): a
/// constraint on coarse depths alone is undone by the finer hats beside it. Side points outside
/// the reconstruction cube are ignored, and re-solves whose surface reaches the cube's faces
/// (where it would come out open) are dropped for the first solve's surface when that one stays
/// inside.
/// [`SpsrReport::side_errors`] says how many were wrong after each solve whose surface it
/// returns.
///
/// ```
/// use rfta_spsr::{OrientedPoints, SidePoint, SpsrParams, glam::DVec3, reconstruct_with_sides};
///
/// // Points on two spheres of radius 0.5 whose centres are 1.05 apart: a 0.05 gap that the
/// // smooth solution bridges at depth 5; the gap's centre is outside.
/// let mut pts = Vec::new();
/// let mut nrm = Vec::new();
/// for c in [-0.525, 0.525] {
///     for i in 0..1500 {
///         let z = 1.0 - 2.0 * (i as f64 + 0.5) / 1500.0;
///         let phi = i as f64 * 2.399963229728653;
///         let s = (1.0 - z * z).sqrt();
///         let n = DVec3::new(z, s * phi.cos(), s * phi.sin());
///         pts.push(DVec3::new(c, 0.0, 0.0) + 0.5 * n);
///         nrm.push(n);
///     }
/// }
/// let cloud = OrientedPoints::new(pts, nrm, None)?;
/// let sides = [SidePoint { position: DVec3::ZERO, inside: false }];
/// let params = SpsrParams { depth: 5, ..SpsrParams::default() };
/// let out = reconstruct_with_sides(&cloud, &sides, &params)?;
/// // Wrong after the first solve, right after the last.
/// assert_eq!(out.report.side_errors.first(), Some(&1));
/// assert_eq!(out.report.side_errors.last(), Some(&0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`reconstruct`].
pub fn reconstruct_with_sides(
    points: &OrientedPoints,
    sides: &[SidePoint],
    params: &SpsrParams,
) -> Result<Reconstruction> {
    params.validate()?;
    Ok(run(points, params, sides, None, Keep::Nothing)?.0)
}

/// What one reconstruction leaves for the next, for clouds that change little from one solve to
/// the next (the fine-tuning rounds of Reach for the Arcs move every point by a small step).
///
/// Each solve after the first starts its Gauss-Seidel relaxation from the previous solve's
/// coefficients at the nodes both octrees share, so the same sweeps
/// ([`SpsrParams::iterations`]) land nearer the converged solution. The octree itself is rebuilt every time: moving points change its
/// refinement (measured on the rounds at 21^3: 2% to 8% of the refined cells are new each
/// round), and a tree kept from before would no longer be the one the density estimate asks
/// for. Results depend only on the sequence of inputs, never on the thread count.
///
/// The Reach for the Arcs pipeline measured it and solves cold: at 4 sweeps a warm start left
/// the dev set's mean Chamfer and CPU time unchanged and put more samples on the wrong side of
/// the mesh (docs/speed.md).
///
/// ```
/// use rfta_spsr::{OrientedPoints, SpsrParams, Workspace, glam::DVec3};
///
/// let sphere = |r: f64| {
///     let pts: Vec<DVec3> = (0..2000)
///         .map(|i| {
///             let z = 1.0 - 2.0 * (i as f64 + 0.5) / 2000.0;
///             let phi = i as f64 * 2.399963229728653;
///             let s = (1.0 - z * z).sqrt();
///             DVec3::new(s * phi.cos(), s * phi.sin(), z)
///         })
///         .collect();
///     OrientedPoints::new(pts.iter().map(|p| r * *p).collect(), pts, None)
/// };
/// let params = SpsrParams { depth: 6, iterations: 2, ..SpsrParams::default() };
/// let mut ws = Workspace::new();
/// for r in [1.0, 1.01, 1.02] {
///     let out = ws.reconstruct(&sphere(r)?, &params)?;
///     let v = out.mesh.signed_volume();
///     assert!((v - 4.18879 * r * r * r).abs() < 0.15, "{v}");
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    last: Option<solve::WarmStart>,
}

impl Workspace {
    /// An empty workspace: its first solve starts cold, as [`reconstruct`] does.
    pub fn new() -> Self {
        Self::default()
    }

    /// Reconstruct `points`, starting from this workspace's previous solution, and keep this
    /// solution for the next call.
    ///
    /// # Errors
    /// As [`reconstruct`]; a failed solve leaves the previous solution in place.
    pub fn reconstruct(
        &mut self,
        points: &OrientedPoints,
        params: &SpsrParams,
    ) -> Result<Reconstruction> {
        params.validate()?;
        let (out, warm) = run(points, params, &[], self.last.as_ref(), Keep::Coefficients)?;
        self.last = warm;
        Ok(out)
    }

    /// Forget the previous solution: the next solve starts cold.
    pub fn clear(&mut self) {
        self.last = None;
    }
}

/// What a solve keeps for the next one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Keep {
    /// Nothing: a cold solve.
    Nothing,
    /// Its coefficients and the octree's node index ([`Workspace`]).
    Coefficients,
}

/// The solve's result before extraction: the solution and its iso-value, the first pass's (while
/// side re-solves ran) with the octree it was solved on when the octree was refined since, the
/// side points on the wrong side after each pass, and the time spent so far.
struct Solved {
    sol: solve::Solution,
    iso: f64,
    first: Option<(solve::Solution, f64)>,
    first_levels: Option<Vec<tree::Level>>,
    side_errors: Vec<usize>,
    tree_time: Duration,
    system_time: Duration,
    solve_time: Duration,
}

/// The three phases: the octree over the merged samples, the solve (re-solved while side points
/// are on the wrong side), the extraction ([`extract_surface`]).
fn run(
    points: &OrientedPoints,
    params: &SpsrParams,
    sides: &[SidePoint],
    warm: Option<&solve::WarmStart>,
    keep: Keep,
) -> Result<(Reconstruction, Option<solve::WarmStart>)> {
    if points.len() < 3 {
        return Err(Error::TooFewPoints {
            found: points.len(),
        });
    }
    let t0 = Instant::now();
    let frame = tree::Frame::around(points, params.box_scale)?;
    let depth = params.depth;
    let base = params.full_depth.min(depth);
    let mut samples = tree::merge(points, &frame, depth);
    if samples.len() < 3 {
        return Err(Error::DegenerateInput(format!(
            "the points fall into {} cell(s) of the depth-{depth} grid (or have zero weight): too few to define a surface",
            samples.len()
        )));
    }
    tree::estimate_density(&mut samples, params, base);
    let mut levels = tree::build_levels(&samples, &[], depth, base);
    let mut tree_time = t0.elapsed();

    let t1 = Instant::now();
    let total_w: f64 = samples.iter().map(|s| s.weight).sum();
    let total_a: f64 = samples.iter().map(|s| s.area).sum();
    let alpha = params.screening * total_a / total_w;
    // The normal field's terms and the first pass's systems (no value constraints yet) do not
    // depend on each other: built side by side.
    let ((mut v, mut down), first_systems) = rayon::join(
        || {
            let v = solve::splat_normals(&levels, &samples);
            let down = solve::down_pass(&levels, &v);
            (v, down)
        },
        || solve::build_systems(&levels, &samples, &[], params, alpha),
    );
    let mut first_systems = Some(first_systems);
    // Side points in the cube, with the value of their side.
    let sides: Vec<(glam::DVec3, bool)> = sides
        .iter()
        .map(|s| (frame.to_unit(s.position), s.inside))
        .filter(|(u, _)| u.cmpge(glam::DVec3::ZERO).all() && u.cmplt(glam::DVec3::ONE).all())
        .collect();
    let mut constraints: Vec<solve::ValueConstraint> = Vec::new();
    // Per side point, its constraint's index once it has one.
    let mut active: Vec<Option<u32>> = vec![None; sides.len()];
    let mut side_errors = Vec::new();
    // The side points the re-solves between the first and the last look at again.
    let mut recheck: Option<Vec<usize>> = None;
    let mut system_time = t1.elapsed();
    let mut solve_time = Duration::ZERO;
    // The first solve's solution and iso-value, kept while re-solves run.
    let mut first: Option<(solve::Solution, f64)> = None;
    // Side points the octree was refined around, and its first version when it was.
    let mut seeds: Vec<glam::DVec3> = Vec::new();
    let mut first_levels: Option<Vec<tree::Level>> = None;
    // Whether the warm start's nodes are those of an octree rebuilt since.
    let mut stale_nodes = false;
    // A re-solve's start: the previous solve's coefficients on the same nodes.
    let mut resolve: Option<solve::WarmStart> = None;
    let resolve_params = SpsrParams {
        iterations: SIDE_RESOLVE_SWEEPS.min(params.iterations),
        ..params.clone()
    };
    let (sol, iso) = loop {
        let t1 = Instant::now();
        let systems = match first_systems.take() {
            Some(systems) => systems,
            None => solve::build_systems(&levels, &samples, &constraints, params, alpha),
        };
        let last = sides.is_empty() || side_errors.len() == SIDE_PASSES;
        system_time += t1.elapsed();
        let t2 = Instant::now();
        let sol = match &resolve {
            Some(start) => solve::solve(
                &levels,
                &systems,
                &v,
                &down,
                &resolve_params,
                base,
                Some(start),
            ),
            None => solve::solve(&levels, &systems, &v, &down, params, base, warm),
        };
        drop(systems);
        let at = |p: glam::DVec3| solve::evaluate(&levels, &sol, p, base);
        let vals: Vec<f64> = samples.par_iter().map(|s| at(s.pos)).collect();
        let (mut num, mut den) = (0.0, 0.0);
        for (s, f) in samples.iter().zip(&vals) {
            num += s.weight * f;
            den += s.weight;
        }
        let iso = num / den;
        if sides.is_empty() {
            solve_time += t2.elapsed();
            break (sol, iso);
        }
        // How far each side point is on its side beyond the margin (negative: wrong).
        let slack = |i: usize| {
            let (p, inside) = sides[i];
            let f = at(p);
            if inside {
                f - iso - SIDE_MARGIN
            } else {
                iso - SIDE_MARGIN - f
            }
        };
        let every = || -> Vec<f64> { (0..sides.len()).into_par_iter().map(slack).collect() };
        let wrong: Vec<usize> = match &recheck {
            None => {
                let all = every();
                recheck = Some(
                    (0..sides.len())
                        .filter(|&i| all[i] < SIDE_RECHECK)
                        .collect(),
                );
                (0..sides.len()).filter(|&i| all[i] < 0.0).collect()
            }
            Some(near) => {
                let w: Vec<usize> = near
                    .par_iter()
                    .copied()
                    .filter(|&i| slack(i) < 0.0)
                    .collect();
                if last || w.is_empty() {
                    // The surface returned: its count over every side point.
                    let all = every();
                    (0..sides.len()).filter(|&i| all[i] < 0.0).collect()
                } else {
                    w
                }
            }
        };
        side_errors.push(wrong.len());
        solve_time += t2.elapsed();
        if last || wrong.is_empty() {
            break (sol, iso);
        }
        // The octree stays (unless refined below): its node index is copied once, the
        // coefficients each pass.
        let start = resolve.get_or_insert_with(|| solve::WarmStart {
            nodes: levels.iter().map(|l| l.node_index.clone()).collect(),
            x: Vec::new(),
        });
        if std::mem::take(&mut stale_nodes) {
            start.nodes = levels.iter().map(|l| l.node_index.clone()).collect();
        }
        // A wrong side point in a cell the octree does not refine to its finest depth: its
        // constraint would act on the depths whose cells hold it, while the finer depths' hats
        // that reach it (around the finer cells beside it) are solved without it and undo it. The
        // octree is rebuilt with such points refined as the samples are; the next solve starts
        // from this one's coefficients on the nodes both octrees share.
        let finest = &levels[depth as usize];
        let coarse: Vec<glam::DVec3> = wrong
            .iter()
            .map(|&i| sides[i].0)
            .filter(|&p| {
                let c = tree::cell_of(p, depth);
                finest
                    .cell([i64::from(c[0]), i64::from(c[1]), i64::from(c[2])])
                    .is_none()
            })
            .collect();
        if first.is_none() {
            start.x = sol.x.clone();
            first = Some((sol, iso));
        } else {
            start.x = sol.x;
        }
        for i in wrong {
            match active[i] {
                Some(c) => constraints[c as usize].weight *= SIDE_WEIGHT_GROWTH,
                None => {
                    active[i] = Some(constraints.len() as u32);
                    let (pos, inside) = sides[i];
                    constraints.push(solve::ValueConstraint {
                        pos,
                        target: if inside {
                            iso + SIDE_TARGET
                        } else {
                            iso - SIDE_TARGET
                        },
                        weight: SIDE_WEIGHT * total_w / samples.len() as f64,
                    });
                }
            }
        }
        if !coarse.is_empty() {
            let t = Instant::now();
            seeds.extend(coarse);
            let old = std::mem::replace(
                &mut levels,
                tree::build_levels(&samples, &seeds, depth, base),
            );
            first_levels.get_or_insert(old);
            tree_time += t.elapsed();
            let t = Instant::now();
            v = solve::splat_normals(&levels, &samples);
            down = solve::down_pass(&levels, &v);
            stale_nodes = true;
            system_time += t.elapsed();
        }
    };

    drop((v, down));
    let solved = Solved {
        sol,
        iso,
        first,
        first_levels,
        side_errors,
        tree_time,
        system_time,
        solve_time,
    };
    extract_surface(points, &frame, &samples, levels, solved, keep)
}

/// The surface of `solved` on `levels` (the first pass's, when a re-solve pulled it out of the
/// cube and the first pass's stayed inside), in world coordinates, with the report; and what
/// `keep` asks for the next solve.
fn extract_surface(
    points: &OrientedPoints,
    frame: &tree::Frame,
    samples: &[tree::Sample],
    mut levels: Vec<tree::Level>,
    solved: Solved,
    keep: Keep,
) -> Result<(Reconstruction, Option<solve::WarmStart>)> {
    let Solved {
        sol,
        iso,
        first,
        first_levels,
        mut side_errors,
        tree_time,
        system_time,
        solve_time,
    } = solved;
    let t3 = Instant::now();
    let solve::Solution { x, u } = sol;
    let mut values = extract::final_values(&levels, &u);
    drop(u);
    // Only the coefficients outlive the extraction, and only when the next solve will use them.
    let kept_x = (keep == Keep::Coefficients).then_some(x);
    let mut iso = iso;
    // A re-solve that pulls the surface out of the cube (where it would come out open) while the
    // first solve's stayed inside is dropped for the first solve's surface.
    let mut on_first = false;
    if let Some((sol, first_iso)) = first
        && extract::leaves_cube(&levels, &values, iso)
    {
        let lv = first_levels.as_deref().unwrap_or(&levels);
        let plain = extract::final_values(lv, &sol.u);
        if !extract::leaves_cube(lv, &plain, first_iso) {
            values = plain;
            iso = first_iso;
            side_errors.truncate(1);
            on_first = true;
        }
    }
    let surface_levels = match &first_levels {
        Some(lv) if on_first => lv,
        _ => &levels,
    };
    let mut ex = extract::extract(surface_levels, &values, iso);
    if ex.faces.is_empty() || !iso.is_finite() {
        return Err(Error::NoSurface { iso });
    }
    extract::to_world(frame, &mut ex.vertices);
    let next = kept_x.map(|x| solve::WarmStart {
        nodes: levels
            .iter_mut()
            .map(|l| std::mem::take(&mut l.node_index))
            .collect(),
        x,
    });
    let extract_time = t3.elapsed();
    let mesh = TriMesh {
        vertices: ex.vertices,
        faces: ex.faces,
    };
    let report = SpsrReport {
        points: points.len(),
        samples: samples.len(),
        nodes_per_depth: levels.iter().map(|l| l.nodes.len()).collect(),
        cells_per_depth: levels.iter().map(|l| l.cells.len()).collect(),
        iso_value: iso,
        side_errors,
        broken_leaves: ex.broken_leaves,
        tree_time,
        system_time,
        solve_time,
        extract_time,
    };
    Ok((Reconstruction { mesh, report }, next))
}
