//! `cargo xtask eval scenario NAME[,NAME]`: the paper's other inputs, measured on the dev shapes.
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
//!   ([`crate::swept`]), scored against the zero set of the same function.
//! - `collision` (Figure 22): random segments (projectiles) of each length tested against the
//!   ground truth and against each method's mesh: false negatives and false positives.
//!
//! Marching cubes runs on the changed grid and on the clean one. Per row: Chamfer against the
//! ground truth, CPU time, the spheres left without a tangency point, what the check measured
//! (the noise, or the clamp it detected) or that it refused the grid. Written in the usual
//! layout: `results.csv`, `report.md`, `chamfer.svg`.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{Grid, SdfSamples, TriMesh};
use rfta_mesh::MeshIndex;

mod collision;
mod kind;
mod report;

use crate::chart::{Line, line_chart};
use crate::shapes::{Shape, Source};
use collision::{Collisions, Segment, projectiles};
pub(crate) use kind::Scenario;
use report::{mean_chamfer, mean_of, write_csv, write_markdown};

/// `cargo xtask eval scenario`'s arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Args {
    /// Scenarios: noise, clamp, scattered, swept, collision, rounds, raster, batch; `params` names
    /// the last three.
    #[arg(value_delimiter = ',', required = true, value_parser = parse_names)]
    names: Vec<Vec<Scenario>>,
    /// The scenarios' levels instead of each one's own (noise 0.005,0.01,0.02,0.05; clamp 4,2,1).
    #[arg(long, value_delimiter = ',', value_parser = non_negative)]
    levels: Option<Vec<f64>>,
    #[command(flatten)]
    source: Source,
    /// Grid resolutions N.
    #[arg(long, value_delimiter = ',', default_value = "10,20,30")]
    res: Vec<usize>,
    #[command(flatten)]
    scoring: crate::table::Scoring,
    /// One small shape at N = 20, two levels, fewer Chamfer samples: the CI smoke run.
    #[arg(long)]
    quick: bool,
    /// The run's folder; each scenario writes into `<out>/<scenario>/` (default:
    /// `<target>/eval/<quick|full>-<pid>`).
    #[arg(long, value_name = "DIR")]
    out: Option<std::path::PathBuf>,
}

fn parse_names(name: &str) -> std::result::Result<Vec<Scenario>, String> {
    if name == "params" {
        return Ok(Scenario::PARAMS.to_vec());
    }
    Scenario::ALL
        .into_iter()
        .find(|s| s.name() == name)
        .map(|s| vec![s])
        .ok_or_else(|| {
            let known: Vec<&str> = Scenario::ALL.iter().map(|s| s.name()).collect();
            format!(
                "unknown scenario '{name}' (known: {}, params)",
                known.join(", ")
            )
        })
}

/// A level: a number at least 0.
pub(crate) fn non_negative(v: &str) -> std::result::Result<f64, String> {
    match v.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("'{v}' is not a number at least 0")),
    }
}

/// Runs each scenario `a` names, into `<out>/<scenario>/`.
pub(crate) fn command(a: &Args) -> Result<()> {
    let (mut shapes, unreadable) = a.source.load()?;
    let (mut res, mut samples) = (a.res.clone(), a.scoring.samples);
    if a.quick {
        crate::shapes::smallest(&mut shapes);
        res = vec![20];
        samples = samples.min(100_000);
    } else {
        for (name, why) in &unreadable {
            eprintln!("warning: skipping {name}: {why}");
        }
    }
    anyhow::ensure!(!shapes.is_empty(), "no shapes found");
    let run_id = format!(
        "{}-{}",
        if a.quick { "quick" } else { "full" },
        std::process::id()
    );
    let out = crate::out_dir(a.out.as_deref(), &run_id)?;
    for &sc in a.names.iter().flatten() {
        let levels = match (&a.levels, a.quick) {
            (Some(l), _) => l.clone(),
            (None, true) => sc.quick_levels(),
            (None, false) => sc.levels(),
        };
        let dir = out.join(sc.name());
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        run(sc, &shapes, &res, &levels, samples, &dir)?;
        println!("wrote {}", dir.display());
    }
    Ok(())
}

/// The noise levels of the paper's Figure 23 (fractions of the values).
pub(crate) const NOISE_LEVELS: [f64; 4] = [0.005, 0.01, 0.02, 0.05];

/// The levels of the scattered scenario: the two distributions.
const UNIFORM: f64 = 0.0;
const NEAR_SURFACE: f64 = 1.0;

/// The clamps of the paper's Figure 24 (grid spacings).
pub(crate) const CLAMP_LEVELS: [f64; 3] = [4.0, 2.0, 1.0];

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

/// Runs `scenario` over `shapes` at resolutions `res` and `levels`, writing into `out`.
fn run(
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
                let sweep = crate::swept::Sweep::new(&shape.gt, &gt_index, level);
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
            let (grid, clean) = crate::shapes::grid_for(shape, &gt_index, n)?;
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
                        k => crate::table::defect(k),
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
    crate::table::no_defects(rows.iter().map(|r| {
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
    let cpu = crate::usage::process_usage().0;
    let result = rfta::reconstruct(samples, params);
    let cpu_seconds = crate::usage::process_usage().0 - cpu;
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
                    k => crate::table::defect(k),
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
