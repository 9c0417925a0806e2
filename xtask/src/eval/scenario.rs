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
//!
//! Marching cubes runs on the changed grid and on the clean one. Per row: Chamfer against the
//! ground truth, CPU time, the spheres left without a tangency point, what the check measured
//! (the noise, or the clamp it detected) or that it refused the grid. Written in the usual
//! layout: `results.csv`, `report.md`, `chamfer.svg`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
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
}

impl Scenario {
    pub(crate) const ALL: [Scenario; 6] = [
        Scenario::Noise,
        Scenario::Clamp,
        Scenario::Scattered,
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
        }
    }

    /// The parameter sweeps run on two shapes (the paper's Figures 11 to 13 use a few).
    pub(crate) fn shapes(self) -> usize {
        match self {
            Scenario::Noise | Scenario::Clamp | Scenario::Scattered => usize::MAX,
            _ => 2,
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
        }
    }

    /// The level a clean grid has (added to every run as the baseline), if the scenario has one.
    fn clean_level(self) -> Option<f64> {
        match self {
            Scenario::Noise => Some(0.0),
            Scenario::Clamp => None,
            // The default setting.
            Scenario::Rounds => Some(10.0),
            Scenario::Raster | Scenario::Batch | Scenario::Scattered => None,
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
            Scenario::Rounds | Scenario::Raster | Scenario::Batch | Scenario::Scattered => {
                clean.to_vec()
            }
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
            Scenario::Noise | Scenario::Clamp | Scenario::Scattered => base,
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
    status: String,
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
        let chamfer = |mesh: &TriMesh| -> Result<f64> {
            if mesh.is_empty() {
                return Ok(f64::NAN);
            }
            let index = MeshIndex::new(mesh)?;
            Ok(rfta_metrics::chamfer_indexed(
                (&shape.gt, &gt_index),
                (mesh, &index),
                samples,
                1,
            ))
        };
        for &n in res {
            let (grid, clean) = super::grid_for(shape, &gt_index, n)?;
            let h = grid.spacing().max_element();
            let clean_mc = chamfer(&rfta_mc::marching_cubes(&grid, &clean, 0.0))?;
            // The scattered scenario's run on the grid itself is the same at every level.
            let mut on_grid: Option<ScenarioRow> = None;
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
                let values = scenario.apply(&clean, level, h, &mut rng);
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
                    status: "ok".into(),
                };
                rows.push(row("mc-clean", 0.0, clean_mc));
                let t = Instant::now();
                let mc = rfta_mc::marching_cubes(&grid, &values, 0.0);
                rows.push(row("mc", t.elapsed().as_secs_f64(), chamfer(&mc)?));
                for &(label, given) in scenario.runs() {
                    let params = scenario.params(level, h, given);
                    let base = row(label, 0.0, f64::NAN);
                    let run = match (scenario, label) {
                        (Scenario::Scattered, "rfta-grid") => match &on_grid {
                            Some(done) => ScenarioRow {
                                level,
                                ..done.clone()
                            },
                            None => {
                                let samples = SdfSamples::grid(grid, values.clone())?;
                                run_rfta(scenario, &samples, &params, h, base, &chamfer)?
                            }
                        },
                        (Scenario::Scattered, _) => {
                            let seed = rng.next_u64();
                            let samples = scattered(&shape.gt, &gt_index, &grid, level, seed)?;
                            run_rfta(scenario, &samples, &params, h, base, &chamfer)?
                        }
                        _ => {
                            let samples = SdfSamples::grid(grid, values.clone())?;
                            run_rfta(scenario, &samples, &params, h, base, &chamfer)?
                        }
                    };
                    if scenario == Scenario::Scattered && label == "rfta-grid" {
                        on_grid.get_or_insert_with(|| run.clone());
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
    methods.extend(["mc", "mc-clean"]);
    let series: Vec<Line> = methods
        .iter()
        .map(|m| {
            let pts = levels
                .iter()
                .enumerate()
                .filter_map(|(i, &p)| {
                    mean_chamfer(&rows, m, p, None).map(|v| (scenario.chart_x(i, p), v))
                })
                .collect();
            (m.to_string(), *m == "mc-clean", pts)
        })
        .collect();
    let ticks: Vec<(f64, String)> = levels
        .iter()
        .enumerate()
        .map(|(i, &p)| (scenario.chart_x(i, p), scenario.level_label(p)))
        .collect();
    line_chart(
        &out.join("chamfer.svg"),
        &format!("Mean Chamfer vs {} (log scale)", scenario.name()),
        scenario.axis_label(),
        &ticks,
        &series,
        1,
    )
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

/// rfta with `params` on `samples`; `row` holds the row's identity.
fn run_rfta(
    scenario: Scenario,
    samples: &SdfSamples,
    params: &rfta::Params,
    h: f64,
    row: ScenarioRow,
    chamfer: &dyn Fn(&TriMesh) -> Result<f64>,
) -> Result<ScenarioRow> {
    let values = samples.values();
    let cpu = crate::bench::process_usage().0;
    let result = rfta::reconstruct(samples, params);
    let cpu_seconds = crate::bench::process_usage().0 - cpu;
    Ok(match result {
        Ok(out) => {
            let r = &out.report;
            // Clamped spheres own no point by design: neither owners nor missing ones.
            let clamped = r
                .clamp
                .map_or(0, |c| values.iter().filter(|v| v.abs() >= c).count());
            ScenarioRow {
                cpu_seconds,
                chamfer: chamfer(&out.mesh)?,
                owners: (r.samples - r.far_spheres).saturating_sub(clamped),
                without_point: r.spheres_without_point.saturating_sub(clamped),
                measured: match scenario {
                    Scenario::Noise => r.radius_scale.map_or(0.0, |s| s.powf(-0.5) - 1.0),
                    Scenario::Clamp => r.clamp.map_or(0.0, |c| c / h),
                    _ => 0.0,
                },
                ..row
            }
        }
        Err(e) => ScenarioRow {
            cpu_seconds,
            status: match e {
                rfta::Error::NotADistance(_) => format!("refused: {e}"),
                _ => format!("failed: {e}"),
            },
            ..row
        },
    })
}

fn mean_chamfer(rows: &[ScenarioRow], method: &str, level: f64, n: Option<usize>) -> Option<f64> {
    let v: Vec<f64> = rows
        .iter()
        .filter(|r| r.method == method && r.level == level && n.is_none_or(|n| r.n == n))
        .map(|r| r.chamfer)
        .filter(|c| c.is_finite())
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn write_csv(scenario: Scenario, path: &Path, rows: &[ScenarioRow]) -> Result<()> {
    let mut s = String::from(
        "scenario,shape,n,level,method,cpu_seconds,chamfer,owners,without_point,measured,status\n",
    );
    for r in rows {
        writeln!(
            s,
            "{},{},{},{},{},{:.4},{:.6},{},{},{:.5},\"{}\"",
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
    writeln!(
        s,
        "{} Runs on one thread; Chamfer with {samples} samples per side. \"kept\" is the share of the spheres that may own a point (near the surface, not clamped) that ended with one, for the worst shape; \"CPU / clean\" is the largest ratio of a run's CPU time to the clean grid's (noise) or the default setting's (rounds).\n",
        scenario.explanation()
    )?;
    let fmt = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.5}"));
    for &n in res {
        writeln!(s, "## N = {n}\n")?;
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
                        _ => "-".into(),
                    },
                    ours.len()
                )?;
            }
            s.push('\n');
        }
    }
    s.push_str("## Every run\n\n| shape | N | level | method | CPU s | Chamfer | without a point | measured | status |\n|---|---|---|---|---|---|---|---|---|\n");
    for r in rows.iter().filter(|r| r.method != "mc-clean") {
        writeln!(
            s,
            "| {} | {} | {} | {} | {:.2} | {:.5} | {} of {} | {:.4} | {} |",
            r.shape,
            r.n,
            scenario.level_label(r.level),
            r.method,
            r.cpu_seconds,
            r.chamfer,
            r.without_point,
            r.owners,
            r.measured,
            r.status
        )?;
    }
    rfta_io::write_atomic(path, |w| w.write_all(s.as_bytes()))?;
    Ok(())
}
