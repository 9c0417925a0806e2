//! `cargo xtask eval --scenario NAME`: the paper's other inputs, measured on the dev shapes.
//!
//! - `noise` (Figure 23): each grid's values get relative noise `s (1 + p u)`, `u` uniform in
//!   [-1, 1] (seeded per shape, N and level), for each level `p`; rfta's default preset runs on the
//!   noisy grid.
//! - `clamp` (Figure 24): each grid's values are clamped at `k h` (`h` the grid spacing), for each
//!   `k`; rfta's default preset runs with the clamp given (`--clamp`) and without it (detected by
//!   the check).
//! - `params` = `rounds`, `raster`, `batch` (Figures 13, 11, 12): the default preset on the clean
//!   grids of two shapes with one parameter swept.
//! - `scattered`: as many samples as each grid has, uniform in its box or near the surface as
//!   DeepSDF draws them, at exact signed distances; the default preset on them against the grid of
//!   the same count (rfta and marching cubes).
//! - `swept` (Figure 25): the pseudo-SDF of each shape swept along a motion of each length
//!   ([`super::swept`]), scored against the zero set of the same function.
//! - `collision` (Figure 22): random segments (projectiles) of each length tested against the
//!   ground truth and against each method's mesh: false negatives and false positives.
//!
//! Marching cubes runs on the changed grid and on the clean one. Per row: Chamfer against the
//! ground truth, CPU time, the spheres left without a tangency point, what the check measured
//! (the noise, or the clamp it detected) or that it refused the grid. Written in the usual
//! layout: `results.csv`, `report.md`, `chamfer.svg`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{Grid, SdfSamples, TriMesh};
use rfta_mesh::MeshIndex;

use super::Shape;
use super::report::{Line, line_chart};

/// The noise levels of the paper's Figure 23 (fractions of the values).
pub(crate) const NOISE_LEVELS: [f64; 4] = [0.005, 0.01, 0.02, 0.05];

/// The levels of the scattered scenario: the two distributions.
const UNIFORM: f64 = 0.0;
const NEAR_SURFACE: f64 = 1.0;

/// The clamps of the paper's Figure 24 (grid spacings).
pub(crate) const CLAMP_LEVELS: [f64; 3] = [4.0, 2.0, 1.0];

/// A scenario: what it does to a grid and which rfta runs it compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scenario {
    Noise,
    Clamp,
    /// Figure 13: fine-tuning rounds.
    Rounds,
    /// Figure 11: rasterization resolution.
    Raster,
    /// Figure 12: spheres per feasibility batch.
    Batch,
    /// Scattered samples (uniform, or near the surface as DeepSDF draws them) as many as a grid's.
    Scattered,
    /// Figure 25: the pseudo-SDF of a swept volume.
    Swept,
    /// Figure 22: segments against the ground truth and the reconstructions.
    Collision,
}

impl Scenario {
    pub(crate) const ALL: [Scenario; 8] = [
        Scenario::Noise,
        Scenario::Clamp,
        Scenario::Scattered,
        Scenario::Swept,
        Scenario::Collision,
        Scenario::Rounds,
        Scenario::Raster,
        Scenario::Batch,
    ];

    /// `params` names the three parameter sweeps.
    pub(crate) const PARAMS: [Scenario; 3] = [Scenario::Rounds, Scenario::Raster, Scenario::Batch];

    pub(crate) fn name(self) -> &'static str {
        match self {
            Scenario::Noise => "noise",
            Scenario::Clamp => "clamp",
            Scenario::Rounds => "rounds",
            Scenario::Raster => "raster",
            Scenario::Batch => "batch",
            Scenario::Scattered => "scattered",
            Scenario::Swept => "swept",
            Scenario::Collision => "collision",
        }
    }

    /// The parameter sweeps run on two shapes (the paper's Figures 11 to 13 use a few).
    pub(crate) fn shapes(self) -> usize {
        match self {
            Scenario::Rounds | Scenario::Raster | Scenario::Batch => 2,
            _ => usize::MAX,
        }
    }

    /// The default levels (see [`NOISE_LEVELS`], [`CLAMP_LEVELS`]).
    pub(crate) fn levels(self) -> Vec<f64> {
        match self {
            Scenario::Noise => NOISE_LEVELS.to_vec(),
            Scenario::Clamp => CLAMP_LEVELS.to_vec(),
            Scenario::Rounds => vec![0.0, 1.0, 3.0, 5.0, 10.0, 20.0],
            Scenario::Raster => vec![32.0, 64.0, 128.0, 256.0, 512.0],
            // 0: every sphere in one batch.
            Scenario::Batch => vec![300.0, 1000.0, 3000.0, 10000.0, 0.0],
            Scenario::Scattered => vec![UNIFORM, NEAR_SURFACE],
            // Sweep lengths (0: the shape standing still, its exact SDF).
            Scenario::Swept => vec![0.0, 0.3, 0.6],
            // Projectile lengths.
            Scenario::Collision => vec![0.05, 0.2, 0.8],
        }
    }

    /// The levels of the CI's quick run.
    pub(crate) fn quick_levels(self) -> Vec<f64> {
        match self {
            Scenario::Noise => vec![0.01, 0.02],
            Scenario::Clamp => vec![2.0],
            Scenario::Rounds => vec![1.0, 3.0],
            Scenario::Raster => vec![64.0, 128.0],
            Scenario::Batch => vec![1000.0, 0.0],
            Scenario::Scattered => vec![NEAR_SURFACE],
            Scenario::Swept => vec![0.3],
            Scenario::Collision => vec![0.2],
        }
    }

    /// The level a clean grid has (added to every run as the baseline), if the scenario has one.
    fn clean_level(self) -> Option<f64> {
        match self {
            Scenario::Noise => Some(0.0),
            Scenario::Clamp => None,
            // The default setting.
            Scenario::Rounds => Some(10.0),
            Scenario::Raster
            | Scenario::Batch
            | Scenario::Scattered
            | Scenario::Swept
            | Scenario::Collision => None,
        }
    }

    fn level_label(self, level: f64) -> String {
        match self {
            Scenario::Noise => format!("{}%", 100.0 * level),
            Scenario::Clamp => format!("{level} h"),
            Scenario::Batch if level == 0.0 => "all".into(),
            Scenario::Scattered if level == UNIFORM => "uniform".into(),
            Scenario::Scattered => "near-surface".into(),
            _ => format!("{level}"),
        }
    }

    /// Where level `level`, the `i`-th, goes on a chart's x axis: at its value, or in order for
    /// the batch sizes (whose last, "all", is 0).
    fn chart_x(self, i: usize, level: f64) -> f64 {
        match self {
            Scenario::Batch | Scenario::Scattered => i as f64,
            _ => level,
        }
    }

    fn axis_label(self) -> &'static str {
        match self {
            Scenario::Noise => "noise (% of the value)",
            Scenario::Clamp => "clamp (grid spacings)",
            Scenario::Rounds => "fine-tuning rounds",
            Scenario::Raster => "rasterization cells per axis",
            Scenario::Batch => "spheres per batch (last: all)",
            Scenario::Scattered => "sample distribution",
            Scenario::Swept => "sweep length (and radians turned)",
            Scenario::Collision => "projectile length",
        }
    }

    fn title(self) -> &'static str {
        match self {
            Scenario::Noise => "noise (the paper's Figure 23)",
            Scenario::Clamp => "clamp (the paper's Figure 24)",
            Scenario::Rounds => "fine-tuning rounds (the paper's Figure 13)",
            Scenario::Raster => "rasterization resolution (the paper's Figure 11)",
            Scenario::Batch => "batch size (the paper's Figure 12)",
            Scenario::Scattered => "scattered samples",
            Scenario::Swept => "swept volumes (the paper's Figure 25)",
            Scenario::Collision => "collision queries (the paper's Figure 22)",
        }
    }

    fn explanation(self) -> &'static str {
        match self {
            Scenario::Noise => {
                "Relative noise `s (1 + p u)`, `u` uniform in [-1, 1], seeded; `rfta-default` is the default preset on the noisy grid; \"measured\" is the noise the check found (a fraction of the values)."
            }
            Scenario::Clamp => {
                "Values clamped at `k h` (`h` the grid spacing): `sign(s) min(|s|, k h)`; `rfta-given` is the default preset told the clamp, `rfta-detected` the default preset left to detect it; \"measured\" is the clamp the check detected, in spacings (0: none)."
            }
            Scenario::Rounds => {
                "The default preset with `Params::rounds` (the paper's k_max) set to each level on the clean grid; the default is 10."
            }
            Scenario::Raster => {
                "The default preset with `Params::raster_resolution` set to each level on the clean grid; the default is the paper's `64 ceil(n^(1/3) / 16)` (128 at N = 20 and 30)."
            }
            Scenario::Scattered => {
                "As many samples as the grid of each N has, at exact signed distances from the ground truth: uniform in the grid's box, or near the surface as DeepSDF draws them (scaled to the box side L: 5% uniform, the rest on the surface plus Gaussian offsets of 0.008 L for one half and 0.025 L for the other); `rfta-default` is the default preset on them (scattered samples: every sphere owns points), `rfta-grid` the default preset on the grid of the same count; marching cubes cannot run on scattered samples, so both mc columns are the grid's."
            }
            Scenario::Swept => {
                "Each shape, scaled by 0.6 about its box's centre, moves by the level along x while turning the level in radians about z, sampled at copies no point of which moves more than 0.02 between two; the grid holds the least of the copies' exact signed distances (a pseudo-SDF: exact outside, a lower bound of the depth inside). The ground truth is the zero set of the same function, marching cubes on a 257^3 grid evaluated exactly near the surface; level 0 is the scaled shape standing still (an exact SDF). Both mc columns are marching cubes on the same grid."
            }
            Scenario::Collision => {
                "20,000 segments of the level's length per shape (seeded; midpoints uniform in the ground truth's box grown by 0.1, directions uniform), each tested against the ground truth and against each method's mesh (`MeshIndex::segment_hits`): a false negative is a segment that hits the ground truth and misses the mesh (a projectile that passes through), a false positive one that misses the ground truth and hits the mesh; given as shares of the segments that hit, and that miss, the ground truth. The same segments at every N."
            }
            Scenario::Batch => {
                "The default preset with `Params::batch_size` (the paper's b) set to each level on the clean grid (all: every sphere in every feasibility test); the default is 10^4, which holds all of a 21^3 or 31^3 grid."
            }
        }
    }

    /// The rfta runs: label and whether the clamp is given.
    fn runs(self) -> &'static [(&'static str, bool)] {
        match self {
            Scenario::Clamp => &[("rfta-given", true), ("rfta-detected", false)],
            Scenario::Scattered => &[("rfta-default", false), ("rfta-grid", false)],
            _ => &[("rfta-default", false)],
        }
    }

    /// The grid's values at `level` (`h` the spacing; `rng` seeded for this grid and level).
    fn apply(self, clean: &[f64], level: f64, h: f64, rng: &mut rfta_geom::rng::Rng) -> Vec<f64> {
        match self {
            Scenario::Noise => clean
                .iter()
                .map(|&s| s * (1.0 + level * (2.0 * rng.next_f64() - 1.0)))
                .collect(),
            Scenario::Clamp => clean
                .iter()
                .map(|&s| s.signum() * s.abs().min(level * h))
                .collect(),
            Scenario::Rounds
            | Scenario::Raster
            | Scenario::Batch
            | Scenario::Scattered
            | Scenario::Swept
            | Scenario::Collision => clean.to_vec(),
        }
    }

    /// The default preset on one thread (the clean row it is compared with runs the same), set
    /// for `level`: the clamp when `given` (`level` spacings of `h`), or the swept parameter.
    fn params(self, level: f64, h: f64, given: bool) -> rfta::Params {
        let base = rfta::Params {
            threads: Some(1),
            clamp: given.then_some(level * h),
            ..rfta::Params::default()
        };
        match self {
            Scenario::Rounds => rfta::Params {
                rounds: level as usize,
                ..base
            },
            Scenario::Raster => rfta::Params {
                raster_resolution: Some(level as usize),
                ..base
            },
            Scenario::Batch => rfta::Params {
                batch_size: level as usize,
                ..base
            },
            Scenario::Noise
            | Scenario::Clamp
            | Scenario::Scattered
            | Scenario::Swept
            | Scenario::Collision => base,
        }
    }
}

/// One run of a scenario.
#[derive(Clone)]
struct ScenarioRow {
    shape: String,
    n: usize,
    level: f64,
    /// An rfta run's label, `mc` (on the changed grid) or `mc-clean`.
    method: String,
    cpu_seconds: f64,
    chamfer: f64,
    /// Spheres that may own points and those of them left without one (rfta only).
    owners: usize,
    without_point: usize,
    /// What the check measured (see [`Scenario::explanation`]).
    measured: f64,
    /// The collision scenario's counts.
    collision: Option<Collisions>,
    status: String,
}

/// Segments against a ground truth and a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Collisions {
    segments: usize,
    /// Segments that hit the ground truth.
    gt_hits: usize,
    /// Segments that hit the ground truth and miss the mesh.
    false_negatives: usize,
    /// Segments that miss the ground truth and hit the mesh.
    false_positives: usize,
}

impl Collisions {
    /// `segments` (with whether each hits the ground truth) against `mesh`.
    fn count(segments: &[Segment], gt_hit: &[bool], mesh: &TriMesh) -> Result<Self> {
        let hits: Vec<bool> = if mesh.is_empty() {
            vec![false; segments.len()]
        } else {
            let index = MeshIndex::new(mesh)?;
            segments
                .par_iter()
                .map(|&(a, b)| index.segment_hits(a, b))
                .collect()
        };
        let both = |g: bool, m: bool| {
            gt_hit
                .iter()
                .zip(&hits)
                .filter(|&(&x, &y)| x == g && y == m)
                .count()
        };
        Ok(Collisions {
            segments: segments.len(),
            gt_hits: gt_hit.iter().filter(|&&h| h).count(),
            false_negatives: both(true, false),
            false_positives: both(false, true),
        })
    }

    fn false_negative_rate(&self) -> f64 {
        self.false_negatives as f64 / self.gt_hits.max(1) as f64
    }

    fn false_positive_rate(&self) -> f64 {
        self.false_positives as f64 / (self.segments - self.gt_hits).max(1) as f64
    }

    /// Share of all segments the mesh answers wrongly.
    fn misclassified(&self) -> f64 {
        (self.false_negatives + self.false_positives) as f64 / self.segments.max(1) as f64
    }
}

/// A segment, from one end to the other.
type Segment = (DVec3, DVec3);

/// Segments per shape and length in the collision scenario.
const COLLISION_SEGMENTS: usize = 20_000;

/// `COLLISION_SEGMENTS` segments of length `length` with midpoints uniform in `bounds` grown by
/// 0.1 and directions uniform on the sphere.
fn projectiles(bounds: rfta_geom::Aabb, length: f64, seed: u64) -> Vec<Segment> {
    let b = bounds.padded(0.1);
    let mut rng = rfta_geom::rng::Rng::new(seed);
    (0..COLLISION_SEGMENTS)
        .map(|_| {
            let mid = b.min
                + (b.max - b.min) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            // Uniform direction: z uniform in [-1, 1], azimuth uniform.
            let z = 2.0 * rng.next_f64() - 1.0;
            let phi = std::f64::consts::TAU * rng.next_f64();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let half = 0.5 * length * DVec3::new(r * phi.cos(), r * phi.sin(), z);
            (mid - half, mid + half)
        })
        .collect()
}

/// Runs `scenario` over `shapes` at resolutions `res` and `levels`, writing into `out`.
pub(crate) fn run(
    scenario: Scenario,
    shapes: &[Shape],
    res: &[usize],
    levels: &[f64],
    samples: usize,
    out: &Path,
) -> Result<()> {
    let mut levels: Vec<f64> = levels.to_vec();
    if let Some(clean) = scenario.clean_level() {
        if !levels.contains(&clean) {
            levels.push(clean);
        }
        levels.sort_by(f64::total_cmp);
    }
    let shapes = &shapes[..shapes.len().min(scenario.shapes())];
    let bar = indicatif::ProgressBar::new((shapes.len() * res.len() * levels.len()) as u64);
    let mut rows = Vec::new();
    for (k, shape) in shapes.iter().enumerate() {
        let gt_index = MeshIndex::new(&shape.gt)
            .with_context(|| format!("{}: empty ground truth", shape.name))?;
        // What each level is scored against: the shape, or (swept) the zero set of the level's
        // pseudo-SDF, with the sweep that makes the level's grids.
        let mut sweeps = Vec::new();
        let mut swept_gts = Vec::new();
        if scenario == Scenario::Swept {
            for &level in &levels {
                bar.set_message(format!("{} swept {level}: ground truth", shape.name));
                let sweep = super::swept::Sweep::new(&shape.gt, &gt_index, level);
                let gt = sweep.ground_truth()?;
                let index = MeshIndex::new(&gt)?;
                sweeps.push(sweep);
                swept_gts.push((gt, index));
            }
        }
        let gt_of = |l: usize| match swept_gts.get(l) {
            Some((gt, index)) => (gt, index),
            None => (&shape.gt, &gt_index),
        };
        // The collision scenario's segments: the same at every N.
        let segments: Vec<(Vec<Segment>, Vec<bool>)> = if scenario == Scenario::Collision {
            levels
                .iter()
                .enumerate()
                .map(|(l, &length)| {
                    let seed = 0x636f_6c6c ^ ((k as u64) << 32) ^ l as u64;
                    let segs = projectiles(gt_index.bounds(), length, seed);
                    let hits = segs
                        .par_iter()
                        .map(|&(a, b)| gt_index.segment_hits(a, b))
                        .collect();
                    (segs, hits)
                })
                .collect()
        } else {
            Vec::new()
        };
        for &n in res {
            let (grid, clean) = super::grid_for(shape, &gt_index, n)?;
            let h = grid.spacing().max_element();
            // Marching cubes on the clean grid, scored against the shape (the swept scenario has
            // no clean grid: its levels are different shapes).
            let clean_mc = match scenario {
                Scenario::Swept => None,
                _ => Some(score(
                    (&shape.gt, &gt_index),
                    &rfta_mc::marching_cubes(&grid, &clean, 0.0),
                    samples,
                )?),
            };
            // A run that is the same at every level (the scattered scenario's on the grid, the
            // collision scenario's): done once per shape and N.
            let mut once: Option<(ScenarioRow, TriMesh)> = None;
            for (l, &level) in levels.iter().enumerate() {
                bar.set_message(format!(
                    "{} n={n} {} {}",
                    shape.name,
                    scenario.name(),
                    scenario.level_label(level)
                ));
                let mut rng = rfta_geom::rng::Rng::new(
                    0x006e_6f69_7365 ^ ((k as u64) << 32) ^ ((n as u64) << 16) ^ l as u64,
                );
                let values = match sweeps.get(l) {
                    Some(sweep) => sweep.grid_values(&grid),
                    None => scenario.apply(&clean, level, h, &mut rng),
                };
                let (gt, gt_idx) = gt_of(l);
                let chamfer = |mesh: &TriMesh| score((gt, gt_idx), mesh, samples);
                let collisions = |mesh: &TriMesh| -> Result<Option<Collisions>> {
                    match segments.get(l) {
                        Some((segs, hits)) => Ok(Some(Collisions::count(segs, hits, mesh)?)),
                        None => Ok(None),
                    }
                };
                let row = |method: &str, cpu_seconds, chamfer| ScenarioRow {
                    shape: shape.name.clone(),
                    n,
                    level,
                    method: method.to_string(),
                    cpu_seconds,
                    chamfer,
                    owners: 0,
                    without_point: 0,
                    measured: 0.0,
                    collision: None,
                    status: "ok".into(),
                };
                if let Some(c) = clean_mc {
                    rows.push(row("mc-clean", 0.0, c));
                }
                let t = Instant::now();
                let mc = rfta_mc::marching_cubes(&grid, &values, 0.0);
                let cpu = t.elapsed().as_secs_f64();
                rows.push(ScenarioRow {
                    collision: collisions(&mc)?,
                    status: match mc.unreferenced_vertices() {
                        0 => "ok".into(),
                        k => super::defect(k),
                    },
                    ..row("mc", cpu, chamfer(&mc)?)
                });
                for &(label, given) in scenario.runs() {
                    let params = scenario.params(level, h, given);
                    let base = row(label, 0.0, f64::NAN);
                    let reuse = matches!(
                        (scenario, label),
                        (Scenario::Scattered, "rfta-grid") | (Scenario::Collision, _)
                    );
                    let (mut run, mesh) = match (&once, scenario, label) {
                        (Some((done, mesh)), ..) if reuse => (
                            ScenarioRow {
                                level,
                                ..done.clone()
                            },
                            mesh.clone(),
                        ),
                        (_, Scenario::Scattered, "rfta-default") => {
                            let seed = rng.next_u64();
                            let samples = scattered(&shape.gt, &gt_index, &grid, level, seed)?;
                            run_rfta(scenario, &samples, &params, h, base, &chamfer)?
                        }
                        _ => {
                            let samples = SdfSamples::grid(grid, values.clone())?;
                            run_rfta(scenario, &samples, &params, h, base, &chamfer)?
                        }
                    };
                    if reuse && once.is_none() {
                        once = Some((run.clone(), mesh.clone()));
                    }
                    run.collision = collisions(&mesh)?;
                    if let Some(sweep) = sweeps.get(l) {
                        run.measured = sweep.copies() as f64;
                    }
                    rows.push(run);
                }
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    write_csv(scenario, &out.join("results.csv"), &rows)?;
    write_markdown(
        scenario,
        &out.join("report.md"),
        &rows,
        &levels,
        res,
        samples,
    )?;
    let mut methods: Vec<&str> = scenario.runs().iter().map(|r| r.0).collect();
    methods.push("mc");
    if scenario != Scenario::Swept {
        methods.push("mc-clean");
    }
    // The collision scenario charts the share of segments answered wrongly, the others Chamfer.
    let measure = |rows: &[ScenarioRow], m: &str, p: f64| match scenario {
        Scenario::Collision => mean_of(rows, m, p, None, |r| {
            r.collision.map(|c| 100.0 * c.misclassified())
        }),
        _ => mean_chamfer(rows, m, p, None),
    };
    let series: Vec<Line> = methods
        .iter()
        .filter(|m| !(scenario == Scenario::Collision && **m == "mc-clean"))
        .map(|m| {
            let pts = levels
                .iter()
                .enumerate()
                .filter_map(|(i, &p)| measure(&rows, m, p).map(|v| (scenario.chart_x(i, p), v)))
                .collect();
            (m.to_string(), *m == "mc-clean", pts)
        })
        .collect();
    let ticks: Vec<(f64, String)> = levels
        .iter()
        .enumerate()
        .map(|(i, &p)| (scenario.chart_x(i, p), scenario.level_label(p)))
        .collect();
    let title = match scenario {
        Scenario::Collision => {
            "Segments answered wrongly, % (false negatives + false positives; log scale)".into()
        }
        _ => format!("Mean Chamfer vs {} (log scale)", scenario.name()),
    };
    line_chart(
        &out.join("chamfer.svg"),
        &title,
        scenario.axis_label(),
        &ticks,
        &series,
        1,
    )?;
    super::no_defects(rows.iter().map(|r| {
        let level = scenario.level_label(r.level);
        (
            format!("{} n={} {level} {}", r.shape, r.n, r.method),
            &r.status,
        )
    }))
}

/// Chamfer distance between `gt` and `mesh` (NaN for an empty mesh).
fn score(gt: (&TriMesh, &MeshIndex), mesh: &TriMesh, samples: usize) -> Result<f64> {
    if mesh.is_empty() {
        return Ok(f64::NAN);
    }
    let index = MeshIndex::new(mesh)?;
    Ok(rfta_metrics::chamfer_indexed(
        gt,
        (mesh, &index),
        samples,
        1,
    ))
}

/// `grid.len()` scattered samples of `gt` at exact signed distances: uniform in the grid's box
/// (`level` [`UNIFORM`]) or near the surface, as DeepSDF draws them ([`NEAR_SURFACE`]).
fn scattered(
    gt: &TriMesh,
    index: &MeshIndex,
    grid: &Grid,
    level: f64,
    seed: u64,
) -> Result<SdfSamples> {
    let n = grid.len();
    let b = grid.bounds();
    let side = (b.max - b.min).max_element();
    let mut rng = rfta_geom::rng::Rng::new(seed);
    let uniform = |rng: &mut rfta_geom::rng::Rng| {
        b.min + (b.max - b.min) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64())
    };
    let positions: Vec<DVec3> = if level == UNIFORM {
        (0..n).map(|_| uniform(&mut rng)).collect()
    } else {
        let n_uniform = n / 20;
        let on = rfta_mesh::sample_surface(gt, n - n_uniform, seed ^ 0x5eed);
        let gauss = |rng: &mut rfta_geom::rng::Rng| {
            // Box-Muller.
            let (u, v) = (rng.next_f64().max(f64::MIN_POSITIVE), rng.next_f64());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        };
        let mut p: Vec<DVec3> = on
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let sigma = if i % 2 == 0 { 0.008 } else { 0.025 } * side;
                s.point + sigma * DVec3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng))
            })
            .collect();
        p.extend((0..n_uniform).map(|_| uniform(&mut rng)));
        p
    };
    let values = index.signed_distances(&positions);
    Ok(SdfSamples::scattered(positions, values)?)
}

/// rfta with `params` on `samples`; `row` holds the row's identity. Also returns the mesh
/// (empty when the run failed).
fn run_rfta(
    scenario: Scenario,
    samples: &SdfSamples,
    params: &rfta::Params,
    h: f64,
    row: ScenarioRow,
    chamfer: &dyn Fn(&TriMesh) -> Result<f64>,
) -> Result<(ScenarioRow, TriMesh)> {
    let values = samples.values();
    let cpu = crate::bench::process_usage().0;
    let result = rfta::reconstruct(samples, params);
    let cpu_seconds = crate::bench::process_usage().0 - cpu;
    Ok(match result {
        Ok(out) => {
            let r = &out.report;
            // Clamped spheres own no point by design: neither owners nor missing ones.
            let clamped = r
                .input
                .clamp
                .map_or(0, |c| values.iter().filter(|v| v.abs() >= c).count());
            let row = ScenarioRow {
                cpu_seconds,
                chamfer: chamfer(&out.mesh)?,
                owners: (r.input.samples - r.final_solve.far_spheres).saturating_sub(clamped),
                without_point: r.final_solve.spheres_without_point.saturating_sub(clamped),
                measured: match scenario {
                    Scenario::Noise => r.input.radius_scale.map_or(0.0, |s| s.powf(-0.5) - 1.0),
                    Scenario::Clamp => r.input.clamp.map_or(0.0, |c| c / h),
                    _ => 0.0,
                },
                status: match out.mesh.unreferenced_vertices() {
                    0 => row.status,
                    k => super::defect(k),
                },
                ..row
            };
            (row, out.mesh)
        }
        Err(e) => (
            ScenarioRow {
                cpu_seconds,
                status: match e {
                    rfta::Error::NotADistance(_) => format!("refused: {e}"),
                    _ => format!("failed: {e}"),
                },
                ..row
            },
            TriMesh::default(),
        ),
    })
}

fn mean_chamfer(rows: &[ScenarioRow], method: &str, level: f64, n: Option<usize>) -> Option<f64> {
    mean_of(rows, method, level, n, |r| Some(r.chamfer))
}

/// The mean of `value` over the rows of `method` at `level` (and `n`, if given) where it is a
/// finite number.
fn mean_of(
    rows: &[ScenarioRow],
    method: &str,
    level: f64,
    n: Option<usize>,
    value: impl Fn(&ScenarioRow) -> Option<f64>,
) -> Option<f64> {
    let v: Vec<f64> = rows
        .iter()
        .filter(|r| r.method == method && r.level == level && n.is_none_or(|n| r.n == n))
        .filter_map(value)
        .filter(|c| c.is_finite())
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn write_csv(scenario: Scenario, path: &Path, rows: &[ScenarioRow]) -> Result<()> {
    let mut s = String::from(
        "scenario,shape,n,level,method,cpu_seconds,chamfer,owners,without_point,measured,segments,gt_hits,false_negatives,false_positives,status\n",
    );
    for r in rows {
        writeln!(
            s,
            "{},{},{},{},{},{:.4},{:.6},{},{},{:.5},{},\"{}\"",
            scenario.name(),
            r.shape,
            r.n,
            r.level,
            r.method,
            r.cpu_seconds,
            r.chamfer,
            r.owners,
            r.without_point,
            r.measured,
            r.collision.map_or(",,,".into(), |c| format!(
                "{},{},{},{}",
                c.segments, c.gt_hits, c.false_negatives, c.false_positives
            )),
            r.status.replace('"', "'")
        )?;
    }
    rfta_io::write_atomic(path, |w| w.write_all(s.as_bytes()))?;
    Ok(())
}

fn write_markdown(
    scenario: Scenario,
    path: &Path,
    rows: &[ScenarioRow],
    levels: &[f64],
    res: &[usize],
    samples: usize,
) -> Result<()> {
    let mut s = format!("# Scenario: {}\n\n", scenario.title());
    if scenario == Scenario::Collision {
        writeln!(
            s,
            "{} Runs on one thread; Chamfer with {samples} samples per side; rates are means over the shapes.\n",
            scenario.explanation()
        )?;
    } else {
        writeln!(
            s,
            "{} Runs on one thread; Chamfer with {samples} samples per side. \"kept\" is the share of the spheres that may own a point (near the surface, not clamped) that ended with one, for the worst shape; \"CPU / clean\" is the largest ratio of a run's CPU time to the clean grid's (noise) or the default setting's (rounds).\n",
            scenario.explanation()
        )?;
    }
    let fmt = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.5}"));
    for &n in res {
        writeln!(s, "## N = {n}\n")?;
        if scenario == Scenario::Collision {
            collision_table(&mut s, rows, levels, n)?;
            continue;
        }
        for &(method, _) in scenario.runs() {
            writeln!(s, "`{method}`:\n")?;
            s.push_str("| level | Chamfer | mc (changed grid) | mc (clean grid) | kept, worst shape | CPU / clean, worst shape | measured, mean | refused |\n|---|---|---|---|---|---|---|---|\n");
            for &level in levels {
                let ours: Vec<&ScenarioRow> = rows
                    .iter()
                    .filter(|r| r.n == n && r.level == level && r.method == method)
                    .collect();
                let ok: Vec<&&ScenarioRow> = ours.iter().filter(|r| r.status == "ok").collect();
                let kept = ok
                    .iter()
                    .map(|r| 1.0 - r.without_point as f64 / r.owners.max(1) as f64)
                    .fold(f64::INFINITY, f64::min);
                let slowdown = scenario.clean_level().and_then(|clean| {
                    ok.iter()
                        .filter_map(|r| {
                            rows.iter()
                                .find(|c| {
                                    c.shape == r.shape
                                        && c.n == n
                                        && c.level == clean
                                        && c.method == method
                                })
                                .map(|c| r.cpu_seconds / c.cpu_seconds.max(1e-9))
                        })
                        .reduce(f64::max)
                });
                let measured = ok.iter().map(|r| r.measured).sum::<f64>() / ok.len().max(1) as f64;
                let refused = ours
                    .iter()
                    .filter(|r| r.status.starts_with("refused"))
                    .count();
                writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} | {refused} of {} |",
                    scenario.level_label(level),
                    fmt(mean_chamfer(rows, method, level, Some(n))),
                    fmt(mean_chamfer(rows, "mc", level, Some(n))),
                    fmt(mean_chamfer(rows, "mc-clean", level, Some(n))),
                    if kept.is_finite() {
                        format!("{:.1}%", 100.0 * kept)
                    } else {
                        "-".into()
                    },
                    slowdown.map_or("-".into(), |v| format!("{v:.2}")),
                    match scenario {
                        Scenario::Noise => format!("{:.2}%", 100.0 * measured),
                        Scenario::Clamp => format!("{measured:.2} h"),
                        Scenario::Swept => format!("copies: {measured:.0}"),
                        _ => "-".into(),
                    },
                    ours.len()
                )?;
            }
            s.push('\n');
        }
    }
    // One row per run: what every scenario has, then the collision counts or the sphere figures.
    let tail = match scenario {
        Scenario::Collision => "hit the ground truth | false negatives | false positives |",
        _ => "without a point | measured | status |",
    };
    writeln!(
        s,
        "## Every run\n\n| shape | N | level | method | CPU s | Chamfer | {tail}\n|---|---|---|---|---|---|---|---|---|"
    )?;
    for r in rows.iter().filter(|r| r.method != "mc-clean") {
        let tail = match (scenario, r.collision) {
            (Scenario::Collision, Some(c)) => format!(
                "{} of {} | {} | {} |",
                c.gt_hits, c.segments, c.false_negatives, c.false_positives
            ),
            (Scenario::Collision, None) => format!("- | - | {} |", r.status),
            _ => format!(
                "{} of {} | {:.4} | {} |",
                r.without_point, r.owners, r.measured, r.status
            ),
        };
        writeln!(
            s,
            "| {} | {} | {} | {} | {:.2} | {:.5} | {tail}",
            r.shape,
            r.n,
            scenario.level_label(r.level),
            r.method,
            r.cpu_seconds,
            r.chamfer,
        )?;
    }
    rfta_io::write_atomic(path, |w| w.write_all(s.as_bytes()))?;
    Ok(())
}

/// The collision scenario's table at `n`: per length and method, the mean rates over the shapes.
fn collision_table(s: &mut String, rows: &[ScenarioRow], levels: &[f64], n: usize) -> Result<()> {
    s.push_str("| length | method | Chamfer | false negatives (of the hits) | false positives (of the misses) | wrong (of all) |\n|---|---|---|---|---|---|\n");
    for &level in levels {
        for method in ["rfta-default", "mc"] {
            let pct = |f: fn(&Collisions) -> f64| {
                mean_of(rows, method, level, Some(n), |r| {
                    r.collision.as_ref().map(|c| 100.0 * f(c))
                })
                .map_or("-".into(), |v| format!("{v:.2}%"))
            };
            writeln!(
                s,
                "| {} | {method} | {} | {} | {} | {} |",
                Scenario::Collision.level_label(level),
                mean_chamfer(rows, method, level, Some(n))
                    .map_or("-".into(), |v| format!("{v:.5}")),
                pct(Collisions::false_negative_rate),
                pct(Collisions::false_positive_rate),
                pct(Collisions::misclassified),
            )?;
        }
    }
    s.push('\n');
    Ok(())
}
