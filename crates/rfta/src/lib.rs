//! Reach for the Arcs (Sellán, Ren, Batty and Stein, "Reach For the Arcs: Reconstructing Surfaces
//! from SDFs via Tangent Points", SIGGRAPH 2024): a triangle mesh from signed distance samples.
//!
//! Every sample `(p_i, s_i)` is a sphere of radius `|s_i|` that the surface touches without
//! entering. [`reconstruct`] normalizes the samples into the unit box, samples empty space next to
//! the spheres of each sign by rasterization ([`raster`]), places one feasible tangency point per
//! sphere ([`feasible::initial_points`]), then runs `k_max` rounds of screened Poisson
//! reconstruction ([`spsr`]) and fine-tuning ([`feasible::fine_tune`]), and a final screened
//! Poisson solve, whose mesh is mapped back to the input's coordinates.
//!
//! The defaults are the paper's ([`Params::default`]); [`Params::paper_table`] is the setting of
//! its Table 2. Results are deterministic for a given seed, whatever the thread count.
//!
//! Before any of that, the values are checked ([`check`]): fields that are not a distance
//! (occupancy, random, rescaled, sentinel values) are refused with [`Error::NotADistance`], a
//! clamped SDF is detected and treated as such, and [`Params::memory_limit`] refuses inputs too
//! large for the machine by [`estimate_peak_memory`]. The mesh is checked before it is returned
//! ([`MeshCheck`]), and the [`Report`] lists what the caller should know in `warnings`.
//!
//! # Example
//! ```
//! use rfta::{Params, reconstruct};
//! use rfta::geom::{Grid, SdfSamples};
//!
//! // A sphere of radius 0.5 sampled on a 13^3 grid over [-1, 1]^3.
//! let grid = Grid::cube(12, -1.0, 1.0)?;
//! let values = (0..grid.len()).map(|i| grid.position(i).length() - 0.5).collect();
//! let samples = SdfSamples::grid(grid, values)?;
//! let params = Params { k_max: 2, ..Params::default() };
//! let out = reconstruct(&samples, &params)?;
//! let v = out.mesh.signed_volume();
//! assert!((v - 0.5236).abs() < 0.05, "volume {v}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod check;

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

pub use rfta_feasible as feasible;
pub use rfta_geom as geom;
pub use rfta_raster as raster;
pub use rfta_sphere_tree as sphere_tree;
pub use rfta_spsr as spsr;

use rfta_feasible::TangentPoints;
use rfta_geom::glam::DVec3;
use rfta_geom::rng::hash;
use rfta_geom::{OrientedPoints, SdfSamples, Sphere, TriMesh};
use rfta_sphere_tree::SphereTree;
use rfta_spsr::SpsrParams;

/// Errors of a reconstruction.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Too few spheres admit a feasible tangency point to define a surface.
    #[error(
        "only {feasible} of {spheres} spheres admit a tangency point, too few for a surface (are the values a signed distance?)"
    )]
    TooFewPoints {
        /// Feasible points found.
        feasible: usize,
        /// Spheres (samples).
        spheres: usize,
    },
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// The values do not behave like a signed distance (see [`check`]): reconstructing from them
    /// would give a wrong mesh. [`Params::check`] set to `false` reconstructs anyway.
    #[error("the samples are not a signed distance function: {0}")]
    NotADistance(String),
    /// The input needs more memory than [`Params::memory_limit`] allows.
    #[error(
        "{samples} samples need about {} of memory by rfta's estimate, more than the limit of {}; use fewer samples (a coarser grid) or raise the limit",
        format_bytes(*needed),
        format_bytes(*limit)
    )]
    TooLarge {
        /// Samples given.
        samples: usize,
        /// The estimate, bytes ([`estimate_peak_memory`]).
        needed: u64,
        /// The limit, bytes.
        limit: u64,
    },
    /// The reconstructed mesh has a non-finite vertex (a bug; reported instead of written).
    #[error("the reconstructed mesh has a non-finite vertex ({0}); please report this input")]
    NonFiniteOutput(usize),
    /// Empty-space rasterization failed.
    #[error("rasterization: {0}")]
    Raster(#[from] rfta_raster::Error),
    /// The final screened Poisson solve failed.
    #[error("screened Poisson: {0}")]
    Spsr(#[from] rfta_spsr::Error),
    /// The thread pool could not be created.
    #[error("could not start {threads} threads: {reason}")]
    ThreadPool {
        /// Requested threads.
        threads: usize,
        /// Why.
        reason: String,
    },
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, Error>;

/// Parameters. Lengths (`tau`, `tol`) are in the normalized unit box, as in the reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// Fine-tuning rounds (10).
    pub k_max: usize,
    /// Maximum tangency points per sphere (3).
    pub n_max: usize,
    /// Spheres in each feasibility batch, drawn with replacement (10^4; 0 = all).
    pub batch: usize,
    /// Screening weight of the Poisson solves, in `rfta-spsr`'s units (30). The reference runs
    /// PoissonRecon with 10; on the same tangency points in the reference's setting (depth 10,
    /// box 3.2) our solver needs about 30 for the same fit (bunny, N = 30: PoissonRecon at 10
    /// reaches Chamfer 0.00717, ours 0.00905 at 10 and 0.00679 at 30; see docs/spsr.md).
    pub screening: f64,
    /// Depth of the Poisson solves (10, on a box 3.2 times the cloud, as the reference).
    pub spsr_depth: u32,
    /// Moves of the feasibility local search (20).
    pub local_search_iters: usize,
    /// Arc length of a transport step (0.01).
    pub tau: f64,
    /// Tolerance of the inside tests (1e-4).
    pub tol: f64,
    /// Rasterization resolution; `None` for the paper's `64 ceil(n^(1/3) / 16)`.
    pub raster_res: Option<usize>,
    /// The SDF was clamped at this magnitude: samples at or beyond it get no tangency point and
    /// their spheres are shrunk to this radius (the surface is at least that far). `None`: no
    /// clamp unless [`Params::check`] detects one.
    pub clamp: Option<f64>,
    /// Inspect the samples first ([`check::inspect`]): refuse values that are not a distance
    /// (more than [`Params::max_inconsistent`] of the samples overlap a sample of the other sign
    /// by more than [`check::SEVERE_RATIO`], or a value exceeds the samples' extent), warn about
    /// milder violations, and detect clamping when `clamp` is `None`. Default `true`.
    pub check: bool,
    /// The fraction of severely inconsistent samples above which [`Params::check`] refuses (0.25).
    pub max_inconsistent: f64,
    /// Refuse, before any work, inputs whose [`estimate_peak_memory`] exceeds this many bytes
    /// (`None`: no limit; the command-line tool passes the memory available).
    pub memory_limit: Option<u64>,
    /// Seed of every random choice (raster jitter, batches).
    pub seed: u64,
    /// Rasterize on the GPU when the crate is built with feature `gpu` and an adapter exists.
    pub gpu: bool,
    /// Worker threads (`None`: rayon's global pool). The mesh does not depend on it.
    pub threads: Option<usize>,
    /// Connected components whose bounding-box diagonal is below this fraction of the sample
    /// spacing are removed (0 keeps everything). Screened Poisson leaves small closed islands next
    /// to outlying tangency points (the reference's outputs have them too); a part that small
    /// cannot be witnessed by the samples. Default 0.5.
    pub min_island: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            k_max: 10,
            n_max: 3,
            batch: 10_000,
            screening: 30.0,
            spsr_depth: 10,
            local_search_iters: 20,
            tau: 0.01,
            tol: 1e-4,
            raster_res: None,
            clamp: None,
            check: true,
            max_inconsistent: 0.25,
            memory_limit: None,
            seed: 3452,
            gpu: false,
            threads: None,
            min_island: 0.5,
        }
    }
}

impl Params {
    /// The setting of the paper's Table 2 (its evaluation script): 20 rounds, 30 points per sphere.
    pub fn paper_table() -> Self {
        Self {
            k_max: 20,
            n_max: 30,
            ..Self::default()
        }
    }

    /// gpytoolbox's defaults (`reach_for_the_arcs` in gpytoolbox 0.3): 3 rounds, 3 points per
    /// sphere; the setting of the shared reference results' `rfta` rows.
    pub fn fast() -> Self {
        Self {
            k_max: 3,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParams(m));
        if self.n_max == 0 {
            return bad("n_max must be at least 1".into());
        }
        if !(self.tau > 0.0 && self.tau.is_finite()) {
            return bad(format!("tau must be finite and > 0, got {}", self.tau));
        }
        if !(self.tol >= 0.0 && self.tol.is_finite()) {
            return bad(format!("tol must be finite and >= 0, got {}", self.tol));
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
        if !(self.min_island >= 0.0 && self.min_island.is_finite()) {
            return bad(format!(
                "min_island must be finite and >= 0, got {}",
                self.min_island
            ));
        }
        Ok(())
    }
}

/// A pipeline stage, for progress reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Stage {
    /// Empty-space sampling and initial tangency points.
    Initial,
    /// Fine-tuning round `round` (1-based) of `of`.
    FineTune {
        /// This round.
        round: usize,
        /// All rounds.
        of: usize,
    },
    /// The final screened Poisson solve.
    Final,
    /// Progress within the current stage: `done` of `of` spheres, reported about twice a second
    /// while a stage runs longer than that.
    Progress {
        /// Spheres finished.
        done: usize,
        /// Spheres in the stage.
        of: usize,
    },
}

/// Runs `work` with a counter of finished spheres, reporting it through `progress` from a
/// monitor thread every half second until `work` returns (the result does not depend on it).
fn counted<T>(
    of: usize,
    progress: &mut (dyn FnMut(Stage) + Send),
    work: impl FnOnce(&AtomicUsize) -> T,
) -> T {
    let done = AtomicUsize::new(0);
    let finished = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let monitor = scope.spawn(|| {
            let mut last = 0;
            loop {
                std::thread::park_timeout(Duration::from_millis(500));
                if finished.load(Ordering::Acquire) {
                    break;
                }
                let d = done.load(Ordering::Relaxed);
                if d != last {
                    progress(Stage::Progress { done: d, of });
                    last = d;
                }
            }
        });
        let out = work(&done);
        finished.store(true, Ordering::Release);
        monitor.thread().unpark();
        let _ = monitor.join();
        out
    })
}

/// What a reconstruction did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Report {
    /// Samples (spheres).
    pub samples: usize,
    /// Samples with `s < 0` and `s >= 0`.
    pub negative: usize,
    /// Samples with `s >= 0`.
    pub non_negative: usize,
    /// Rasterization resolution used.
    pub raster_res: usize,
    /// Empty-space points sampled (both signs).
    pub empty_space_points: usize,
    /// Spheres with a feasible initial tangency point.
    pub feasible_initial: usize,
    /// Tangency points before each fine-tuning round and at the end (`k_max + 1` entries unless
    /// stopped early).
    pub points_per_round: Vec<usize>,
    /// Spheres without a tangency point at the end (clamped and zero-radius ones included).
    pub spheres_without_point: usize,
    /// Small closed islands removed from the final mesh (see [`Params::min_island`]).
    pub islands_removed: usize,
    /// Why fine-tuning stopped before `k_max` rounds, if it did.
    pub stopped_early: Option<String>,
    /// Samples that overlap a sample of the other sign (see [`check`]; 0 when not checked).
    pub inconsistent_samples: usize,
    /// The clamp used: [`Params::clamp`], or the one [`Params::check`] detected.
    pub clamp: Option<f64>,
    /// What the output mesh is like (checked before it is returned).
    pub mesh: MeshCheck,
    /// Things the caller should know: inconsistent samples, a detected clamp, more than 5% of the
    /// spheres without a point, a mesh that is not watertight.
    pub warnings: Vec<String>,
    /// Wall time of each stage, in order.
    pub timings: Vec<(String, Duration)>,
}

/// Checks of the output mesh.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MeshCheck {
    /// Faces with a repeated vertex index (none unless the extraction has a bug).
    pub degenerate_faces: usize,
    /// Faces of zero area left in the mesh (distinct vertices at one position or on one line).
    pub zero_area_faces: usize,
    /// Every edge has exactly two faces.
    pub watertight: bool,
    /// Edges with one face.
    pub boundary_edges: usize,
    /// Edges with more than two faces.
    pub nonmanifold_edges: usize,
    /// Connected components.
    pub components: usize,
}

/// A reconstructed mesh and how it was made.
#[derive(Debug, Clone)]
pub struct Reconstruction {
    /// The mesh, in the samples' coordinates, outward-oriented.
    pub mesh: TriMesh,
    /// The final tangency points, in the samples' coordinates.
    pub points: TangentPoints,
    /// Counts and timings.
    pub report: Report,
}

/// Reconstruct a mesh from signed distance samples (negative inside).
///
/// # Errors
/// [`Error::InvalidParams`], [`Error::TooLarge`] above [`Params::memory_limit`],
/// [`Error::NotADistance`] when [`Params::check`] finds the values are not a distance,
/// [`Error::TooFewPoints`] when fewer than 3 spheres admit a tangency point, [`Error::Raster`],
/// [`Error::Spsr`] when the final solve fails, [`Error::ThreadPool`], [`Error::NonFiniteOutput`].
pub fn reconstruct(samples: &SdfSamples, params: &Params) -> Result<Reconstruction> {
    reconstruct_with_progress(samples, params, &mut |_| {})
}

/// [`reconstruct`], calling `progress` as each stage starts.
///
/// # Errors
/// As [`reconstruct`].
pub fn reconstruct_with_progress(
    samples: &SdfSamples,
    params: &Params,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<Reconstruction> {
    params.validate()?;
    check_memory(samples.len(), params)?;
    match params.threads {
        None => run(samples, params, progress),
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .map_err(|e| Error::ThreadPool {
                threads: t,
                reason: e.to_string(),
            })?
            .install(|| run(samples, params, progress)),
    }
}

/// An upper estimate of the peak resident memory, in bytes, of reconstructing from `n` samples
/// (the samples included): a fixed 256 MiB (the depth-10 screened Poisson octree, thread stacks,
/// the binary) plus 1 KiB per sample (positions, spheres, sphere tree, k-d trees, tangency points
/// and their octree cells, the empty-space samples of a raster that grows with `n^(1/3)`), plus
/// 200 B per sample for each tangency point allowed beyond 3 per sphere.
///
/// Checked against `/usr/bin/time -v` peaks of `rfta reconstruct` on the bunny's SDF at 33^3, 65^3
/// and 129^3 samples (185, 444 and 1409 MiB; the estimate is 1.6, 1.2 and 1.7 times these; see
/// docs/hardening.md).
pub fn estimate_peak_memory(n: usize, params: &Params) -> u64 {
    const BASE: u64 = 256 << 20;
    const PER_SAMPLE: u64 = 1024;
    const PER_EXTRA_POINT: u64 = 200;
    let extra_points = params.n_max.saturating_sub(3) as u64;
    BASE.saturating_add(
        (n as u64).saturating_mul(PER_SAMPLE.saturating_add(extra_points * PER_EXTRA_POINT)),
    )
}

/// Whether `n` samples fit in [`Params::memory_limit`] by [`estimate_peak_memory`]: callers
/// that know `n` before loading the samples (from a file header) can refuse early.
///
/// # Errors
/// [`Error::TooLarge`] with the estimate and the limit.
pub fn check_memory(n: usize, params: &Params) -> Result<()> {
    match params.memory_limit {
        Some(limit) if estimate_peak_memory(n, params) > limit => Err(Error::TooLarge {
            samples: n,
            needed: estimate_peak_memory(n, params),
            limit,
        }),
        _ => Ok(()),
    }
}

/// Bytes as "1.5 GiB".
pub fn format_bytes(bytes: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = bytes as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{bytes} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}

/// The reference's normalization: subtract the per-axis minimum, divide by the largest extent.
struct Normalization {
    trans: DVec3,
    scale: f64,
}

fn run(
    samples: &SdfSamples,
    params: &Params,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<Reconstruction> {
    let mut report = Report {
        samples: samples.len(),
        clamp: params.clamp,
        ..Report::default()
    };
    if params.check {
        inspect(samples, params, &mut report)?;
    }
    let clamp = report.clamp;
    let positions = samples.positions();
    let lo = positions
        .iter()
        .fold(DVec3::splat(f64::INFINITY), |a, &p| a.min(p));
    let hi = positions
        .iter()
        .fold(DVec3::splat(f64::NEG_INFINITY), |a, &p| a.max(p));
    let extent = (hi - lo).max_element();
    let norm = Normalization {
        trans: lo,
        scale: if extent > 0.0 { extent } else { 1.0 },
    };
    let centers: Vec<DVec3> = positions
        .iter()
        .map(|&p| (p - norm.trans) / norm.scale)
        .collect();
    let values: Vec<f64> = samples.values().iter().map(|&s| s / norm.scale).collect();
    let cap = clamp.map_or(f64::INFINITY, |c| c / norm.scale);
    let spheres: Vec<Sphere> = centers
        .iter()
        .zip(&values)
        .map(|(&c, &s)| Sphere::new(c, s.abs().min(cap)))
        .collect();
    let n = spheres.len();
    let fparams = rfta_feasible::Params {
        tol: params.tol,
        local_search_iters: params.local_search_iters,
        k_search: rfta_feasible::Params::k_search_for(n),
        tau: params.tau,
        n_max: params.n_max,
        clamp: cap,
        ..rfta_feasible::Params::default()
    };
    let res = params
        .raster_res
        .unwrap_or_else(|| rfta_raster::default_resolution(n));
    report.raster_res = res;
    let backend = if params.gpu {
        rfta_raster::Backend::Gpu
    } else {
        rfta_raster::Backend::Cpu
    };

    // Initial tangency points, one sign set at a time.
    progress(Stage::Initial);
    let t = Instant::now();
    let neg: Vec<u32> = (0..n as u32)
        .filter(|&i| values[i as usize] < 0.0)
        .collect();
    let pos: Vec<u32> = (0..n as u32)
        .filter(|&i| values[i as usize] >= 0.0)
        .collect();
    report.negative = neg.len();
    report.non_negative = pos.len();
    let mut parts = Vec::new();
    for (k, set) in [(1u64, &pos), (2u64, &neg)] {
        if set.is_empty() {
            continue;
        }
        let c: Vec<DVec3> = set.iter().map(|&i| centers[i as usize]).collect();
        let r: Vec<f64> = set.iter().map(|&i| spheres[i as usize].radius).collect();
        let raster = rfta_raster::RasterParams {
            res,
            seed: hash(params.seed, k),
        };
        let empty = rfta_raster::rasterize(&c, &r, &raster, backend)?;
        report.empty_space_points += empty.points.len();
        let batch = draw_batch(set, params.batch, hash(params.seed, 10 + k));
        let tree = SphereTree::with_indices(&spheres, &batch);
        parts.push(counted(set.len(), progress, |done| {
            rfta_feasible::initial_points_counted(
                &spheres,
                &values,
                set,
                &empty.points,
                &tree,
                &fparams,
                done,
            )
        }));
    }
    let mut cloud = merge_by_owner(parts);
    report.feasible_initial = cloud.len();
    report.timings.push(("initial points".into(), t.elapsed()));
    if cloud.len() < 3 {
        return Err(Error::TooFewPoints {
            feasible: cloud.len(),
            spheres: n,
        });
    }

    let spsr = SpsrParams {
        depth: params.spsr_depth,
        screening: params.screening,
        threads: None,
        ..SpsrParams::rfta_reference()
    };
    for round in 1..=params.k_max {
        progress(Stage::FineTune {
            round,
            of: params.k_max,
        });
        report.points_per_round.push(cloud.len());
        let t = Instant::now();
        let tree = SphereTree::batch(
            &spheres,
            params.batch,
            hash(params.seed, 100 + round as u64),
        );
        let mesh = match solve(&cloud, &spsr) {
            Ok(m) => m,
            Err(e) => {
                report.stopped_early = Some(format!("round {round}: {e}"));
                break;
            }
        };
        let next = counted(n, progress, |done| {
            rfta_feasible::fine_tune_counted(
                &spheres, &values, &mesh, &cloud, &tree, &fparams, done,
            )
        });
        report
            .timings
            .push((format!("fine-tuning round {round}"), t.elapsed()));
        if next.len() < 3 {
            report.stopped_early = Some(format!(
                "round {round}: only {} feasible points remained",
                next.len()
            ));
            break;
        }
        cloud = next;
    }
    progress(Stage::Final);
    report.points_per_round.push(cloud.len());
    let t = Instant::now();
    let mut mesh = solve(&cloud, &spsr)?;
    report
        .timings
        .push(("final screened Poisson".into(), t.elapsed()));
    let mut owners = cloud.owners.clone();
    owners.dedup();
    report.spheres_without_point = n - owners.len();
    mesh.map_vertices(|v| v * norm.scale + norm.trans);
    let spacing = sample_spacing(samples);
    if params.min_island > 0.0 {
        let (kept, removed) = remove_islands(&mesh, params.min_island * spacing);
        mesh = kept;
        report.islands_removed = removed;
    }
    report.mesh = check_mesh(&mesh)?;
    // A few spheres covered by their neighbours are normal (the reference has them too); a
    // twentieth of them means clamped, zero or inconsistent values and a less certain surface.
    if report.spheres_without_point * 20 > n {
        report.warnings.push(format!(
            "{} of {n} spheres ended without a tangency point (clamped, zero-valued, or covered by other spheres)",
            report.spheres_without_point
        ));
    }
    if !report.mesh.watertight {
        report.warnings.push(format!(
            "the mesh is not watertight: {} boundary and {} non-manifold edges",
            report.mesh.boundary_edges, report.mesh.nonmanifold_edges
        ));
    }
    if report.mesh.zero_area_faces > 0 {
        report.warnings.push(format!(
            "the mesh has {} faces of zero area ({} with a repeated vertex)",
            report.mesh.zero_area_faces, report.mesh.degenerate_faces
        ));
    }
    let points = TangentPoints {
        points: cloud
            .points
            .iter()
            .map(|&p| p * norm.scale + norm.trans)
            .collect(),
        normals: cloud.normals,
        owners: cloud.owners,
    };
    Ok(Reconstruction {
        mesh,
        points,
        report,
    })
}

/// Runs [`check::inspect`] and applies [`Params::check`]'s policy.
fn inspect(samples: &SdfSamples, params: &Params, report: &mut Report) -> Result<()> {
    let found = check::inspect(samples);
    report.inconsistent_samples = found.inconsistent;
    if params.clamp.is_none()
        && let Some((c, count)) = found.clamp
    {
        report.clamp = Some(c);
        report.warnings.push(format!(
            "the values look clamped at {c}: {count} samples sit on flat plateaus at that magnitude; they are treated as at least {c} from the surface (set a clamp to override, or turn the check off)"
        ));
    }
    if let Some(&i) = found
        .beyond_extent
        .iter()
        .find(|&&i| report.clamp.is_none_or(|c| samples.values()[i].abs() < c))
    {
        let b = samples.bounds();
        return Err(Error::NotADistance(format!(
            "{} exceeds the diagonal {} of the samples' bounding box, which no distance to a surface crossing them can ({} such samples); if it stands for 'far away', set a clamp below it so such samples count as at least that far",
            check::describe(samples, i),
            (b.max - b.min).length(),
            found.beyond_extent.len()
        )));
    }
    if found.inconsistent > 0 {
        let worst = found.worst.map_or(String::new(), |(i, j, r)| {
            format!(
                "; worst: {} and {} are {:.3e} apart, their spheres overlap by a factor {r:.3}",
                check::describe(samples, i),
                check::describe(samples, j),
                (samples.position(i) - samples.position(j)).length()
            )
        });
        let what = format!(
            "{} of {} samples ({:.1}%) overlap the nearest sample of the other sign, so |s| is larger than the distance to the surface there{worst}",
            found.inconsistent,
            found.checked,
            100.0 * found.inconsistent_fraction()
        );
        if found.severe_fraction() > params.max_inconsistent {
            return Err(Error::NotADistance(format!(
                "{what}; {:.1}% overlap by more than a factor {}. Is it an occupancy, density or rescaled field? Turn the check off to reconstruct anyway",
                100.0 * found.severe_fraction(),
                check::SEVERE_RATIO
            )));
        }
        report.warnings.push(what);
    }
    Ok(())
}

/// Refuses non-finite vertices and reports degenerate faces and topology.
fn check_mesh(mesh: &TriMesh) -> Result<MeshCheck> {
    if let Some(i) = mesh.vertices.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFiniteOutput(i));
    }
    let zero_area_faces = (0..mesh.faces.len())
        .filter(|&f| mesh.face_normal_scaled(f).length_squared() == 0.0)
        .count();
    let topo = rfta_mesh::Topology::of(mesh);
    Ok(MeshCheck {
        degenerate_faces: topo.degenerate_faces,
        zero_area_faces,
        watertight: topo.is_watertight(),
        boundary_edges: topo.boundary_edges,
        nonmanifold_edges: topo.nonmanifold_edges,
        components: topo.components,
    })
}

/// The grid spacing (largest axis), or for scattered samples the side of a cube holding one
/// sample on average over their bounding box.
fn sample_spacing(samples: &SdfSamples) -> f64 {
    match samples.as_grid() {
        Some(g) => g.spacing().max_element(),
        None => {
            let b = samples.bounds();
            let e = (b.max - b.min).max(DVec3::splat(1e-300));
            (e.x * e.y * e.z / samples.len().max(1) as f64).cbrt()
        }
    }
}

/// Removes connected components (by shared vertices) whose bounding-box diagonal is below
/// `min_diagonal`, unless that would remove everything; unused vertices are dropped.
fn remove_islands(mesh: &TriMesh, min_diagonal: f64) -> (TriMesh, usize) {
    let n = mesh.vertices.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for f in &mesh.faces {
        let a = root(&mut parent, f[0]);
        for &v in &f[1..] {
            let b = root(&mut parent, v);
            if a != b {
                parent[b as usize] = a;
            }
        }
    }
    let mut lo = vec![DVec3::splat(f64::INFINITY); n];
    let mut hi = vec![DVec3::splat(f64::NEG_INFINITY); n];
    for f in &mesh.faces {
        let r = root(&mut parent, f[0]) as usize;
        for &v in f {
            lo[r] = lo[r].min(mesh.vertices[v as usize]);
            hi[r] = hi[r].max(mesh.vertices[v as usize]);
        }
    }
    let mut roots: Vec<u32> = mesh.faces.iter().map(|f| root(&mut parent, f[0])).collect();
    let keep_root = |r: u32| (hi[r as usize] - lo[r as usize]).length() >= min_diagonal;
    if !roots.iter().any(|&r| keep_root(r)) {
        return (mesh.clone(), 0);
    }
    let mut removed_roots: Vec<u32> = roots.iter().copied().filter(|&r| !keep_root(r)).collect();
    removed_roots.sort_unstable();
    removed_roots.dedup();
    if removed_roots.is_empty() {
        return (mesh.clone(), 0);
    }
    let mut remap = vec![u32::MAX; n];
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for (f, r) in mesh.faces.iter().zip(roots.iter_mut()) {
        if !keep_root(*r) {
            continue;
        }
        let g = f.map(|v| {
            if remap[v as usize] == u32::MAX {
                remap[v as usize] = vertices.len() as u32;
                vertices.push(mesh.vertices[v as usize]);
            }
            remap[v as usize]
        });
        faces.push(g);
    }
    (TriMesh { vertices, faces }, removed_roots.len())
}

/// `b` indices drawn with replacement from `set` (all of it when `b` is 0 or at least its size).
fn draw_batch(set: &[u32], b: usize, seed: u64) -> Vec<u32> {
    if b == 0 || b >= set.len() {
        return set.to_vec();
    }
    let mut rng = rfta_geom::rng::Rng::new(seed);
    (0..b)
        .map(|_| set[rng.below(set.len() as u64) as usize])
        .collect()
}

fn merge_by_owner(parts: Vec<TangentPoints>) -> TangentPoints {
    let mut all: Vec<(u32, DVec3, DVec3)> = parts
        .into_iter()
        .flat_map(|p| {
            p.owners
                .into_iter()
                .zip(p.points)
                .zip(p.normals)
                .map(|((o, x), n)| (o, x, n))
        })
        .collect();
    all.sort_by_key(|e| e.0);
    TangentPoints {
        owners: all.iter().map(|e| e.0).collect(),
        points: all.iter().map(|e| e.1).collect(),
        normals: all.iter().map(|e| e.2).collect(),
    }
}

fn solve(
    cloud: &TangentPoints,
    spsr: &SpsrParams,
) -> std::result::Result<TriMesh, rfta_spsr::Error> {
    let pts = OrientedPoints::new(cloud.points.clone(), cloud.normals.clone(), None)
        .map_err(|e| rfta_spsr::Error::DegenerateInput(format!("tangency points: {e}")))?;
    Ok(rfta_spsr::reconstruct(&pts, spsr)?.mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_stages_report_progress_and_short_ones_stay_quiet() {
        let mut seen = Vec::new();
        let out = counted(12, &mut |s| seen.push(s), |done| {
            for _ in 0..12 {
                std::thread::sleep(Duration::from_millis(100));
                done.fetch_add(1, Ordering::Relaxed);
            }
            7
        });
        assert_eq!(out, 7);
        assert!(!seen.is_empty(), "a 1.2 s stage reports");
        let mut last = 0;
        for s in &seen {
            let Stage::Progress { done, of } = *s else {
                panic!("{s:?}");
            };
            assert!(of == 12 && done >= last && done <= 12, "{seen:?}");
            last = done;
        }
        let mut quiet = Vec::new();
        let start = Instant::now();
        counted(5, &mut |s| quiet.push(s), |done| {
            done.fetch_add(5, Ordering::Relaxed);
        });
        assert!(quiet.is_empty());
        // The monitor is woken when the work ends, not after its half-second nap.
        assert!(start.elapsed() < Duration::from_millis(400));
    }
}
