//! `cargo xtask eval --scenario noise`: the paper's Figure 23, noisy SDF values.
//!
//! Each grid's values get relative noise `s (1 + p u)`, `u` uniform in [-1, 1] (seeded per shape,
//! N and level), for each level `p`; rfta's default preset and marching cubes run on the noisy
//! grid, marching cubes also on the clean one. Per row: Chamfer against the ground truth, CPU
//! time, the spheres left without a tangency point, the noise the check measured (or that it
//! refused the grid). Written beside the usual layout: `results.csv`, `report.md`, `chamfer.svg`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use rfta_geom::{Grid, SdfSamples, TriMesh};
use rfta_mesh::MeshIndex;

use super::Shape;
use super::report::{Line, line_chart};

/// The noise levels of the paper's Figure 23.
pub(crate) const NOISE_LEVELS: [f64; 4] = [0.005, 0.01, 0.02, 0.05];

/// One run of the noise scenario.
struct NoiseRow {
    shape: String,
    n: usize,
    noise: f64,
    /// `rfta-default`, `mc` (on the noisy grid) or `mc-clean`.
    method: &'static str,
    cpu_seconds: f64,
    chamfer: f64,
    /// Spheres near the surface (owners) and those of them left without a point (rfta only).
    owners: usize,
    without_point: usize,
    /// The noise the check measured, as a fraction of the values (rfta only; 0: none).
    measured: f64,
    status: String,
}

/// Runs the scenario over `shapes` at resolutions `res` and noise `levels` (0 is added: the clean
/// grid), writing into `out`.
pub(crate) fn noise(
    shapes: &[Shape],
    res: &[usize],
    levels: &[f64],
    samples: usize,
    out: &Path,
) -> Result<()> {
    let mut levels: Vec<f64> = levels.to_vec();
    if !levels.contains(&0.0) {
        levels.insert(0, 0.0);
    }
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
            let clean_mc = chamfer(&rfta_mc::marching_cubes(&grid, &clean, 0.0))?;
            for (l, &p) in levels.iter().enumerate() {
                bar.set_message(format!("{} n={n} noise {p}", shape.name));
                let mut rng = rfta_geom::rng::Rng::new(
                    0x006e_6f69_7365 ^ ((k as u64) << 32) ^ ((n as u64) << 16) ^ l as u64,
                );
                let values: Vec<f64> = clean
                    .iter()
                    .map(|&s| s * (1.0 + p * (2.0 * rng.next_f64() - 1.0)))
                    .collect();
                let row = |method, cpu_seconds, chamfer| NoiseRow {
                    shape: shape.name.clone(),
                    n,
                    noise: p,
                    method,
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
                let mc_cpu = t.elapsed().as_secs_f64();
                rows.push(row("mc", mc_cpu, chamfer(&mc)?));
                rows.push(run_rfta(&grid, values, &row, &chamfer)?);
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    write_csv(&out.join("results.csv"), &rows)?;
    write_markdown(&out.join("report.md"), &rows, &levels, res, samples)?;
    let series: Vec<Line> = ["rfta-default", "mc", "mc-clean"]
        .iter()
        .map(|m| {
            let pts = levels
                .iter()
                .filter_map(|&p| mean_chamfer(&rows, m, p, None).map(|v| (100.0 * p, v)))
                .collect();
            (m.to_string(), *m == "mc-clean", pts)
        })
        .collect();
    let ticks: Vec<(f64, String)> = levels
        .iter()
        .map(|&p| (100.0 * p, format!("{}%", 100.0 * p)))
        .collect();
    line_chart(
        &out.join("chamfer.svg"),
        "Mean Chamfer vs relative noise (log scale)",
        "noise (% of the value)",
        &ticks,
        &series,
        1,
    )
}

/// rfta's default preset on the noisy values (one thread, as the clean row it is compared with).
fn run_rfta(
    grid: &Grid,
    values: Vec<f64>,
    row: &dyn Fn(&'static str, f64, f64) -> NoiseRow,
    chamfer: &dyn Fn(&TriMesh) -> Result<f64>,
) -> Result<NoiseRow> {
    let params = rfta::Params {
        threads: Some(1),
        ..rfta::Params::default()
    };
    let samples = SdfSamples::grid(*grid, values)?;
    let cpu = crate::bench::process_usage().0;
    let result = rfta::reconstruct(&samples, &params);
    let cpu_seconds = crate::bench::process_usage().0 - cpu;
    Ok(match result {
        Ok(out) => {
            let r = &out.report;
            NoiseRow {
                owners: r.samples - r.far_spheres,
                without_point: r.spheres_without_point,
                measured: r.radius_scale.map_or(0.0, |s| s.powf(-0.5) - 1.0),
                ..row("rfta-default", cpu_seconds, chamfer(&out.mesh)?)
            }
        }
        Err(e) => NoiseRow {
            status: match e {
                rfta::Error::NotADistance(_) => format!("refused: {e}"),
                _ => format!("failed: {e}"),
            },
            ..row("rfta-default", cpu_seconds, f64::NAN)
        },
    })
}

fn mean_chamfer(rows: &[NoiseRow], method: &str, noise: f64, n: Option<usize>) -> Option<f64> {
    let v: Vec<f64> = rows
        .iter()
        .filter(|r| r.method == method && r.noise == noise && n.is_none_or(|n| r.n == n))
        .map(|r| r.chamfer)
        .filter(|c| c.is_finite())
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn write_csv(path: &Path, rows: &[NoiseRow]) -> Result<()> {
    let mut s = String::from(
        "scenario,shape,n,noise,method,cpu_seconds,chamfer,owners,without_point,measured_noise,status\n",
    );
    for r in rows {
        writeln!(
            s,
            "noise,{},{},{},{},{:.4},{:.6},{},{},{:.5},\"{}\"",
            r.shape,
            r.n,
            r.noise,
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
    path: &Path,
    rows: &[NoiseRow],
    levels: &[f64],
    res: &[usize],
    samples: usize,
) -> Result<()> {
    let mut s = String::from("# Scenario: noise (the paper's Figure 23)\n\n");
    writeln!(
        s,
        "Relative noise `s (1 + p u)`, `u` uniform in [-1, 1], seeded; rfta's default preset on one thread; Chamfer with {samples} samples per side. \"kept\" is the share of the spheres near the surface that ended with a tangency point; CPU is rfta's time against the clean grid's.\n"
    )?;
    for &n in res {
        writeln!(s, "## N = {n}\n")?;
        s.push_str("| noise | rfta-default | mc (noisy) | mc (clean) | kept, worst shape | CPU / clean, worst shape | measured noise, mean | refused |\n|---|---|---|---|---|---|---|---|\n");
        for &p in levels {
            let fmt = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.5}"));
            let ours: Vec<&NoiseRow> = rows
                .iter()
                .filter(|r| r.n == n && r.noise == p && r.method == "rfta-default")
                .collect();
            let kept = ours
                .iter()
                .filter(|r| r.status == "ok")
                .map(|r| 1.0 - r.without_point as f64 / r.owners.max(1) as f64)
                .fold(f64::INFINITY, f64::min);
            let slowdown = ours
                .iter()
                .filter(|r| r.status == "ok")
                .filter_map(|r| {
                    rows.iter()
                        .find(|c| {
                            c.shape == r.shape
                                && c.n == n
                                && c.noise == 0.0
                                && c.method == "rfta-default"
                        })
                        .map(|c| r.cpu_seconds / c.cpu_seconds.max(1e-9))
                })
                .fold(0.0, f64::max);
            let measured = ours.iter().map(|r| r.measured).sum::<f64>() / ours.len().max(1) as f64;
            let refused = ours
                .iter()
                .filter(|r| r.status.starts_with("refused"))
                .count();
            writeln!(
                s,
                "| {}% | {} | {} | {} | {:.1}% | {slowdown:.2} | {:.2}% | {refused} of {} |",
                100.0 * p,
                fmt(mean_chamfer(rows, "rfta-default", p, Some(n))),
                fmt(mean_chamfer(rows, "mc", p, Some(n))),
                fmt(mean_chamfer(rows, "mc-clean", p, Some(n))),
                if kept.is_finite() { 100.0 * kept } else { 0.0 },
                100.0 * measured,
                ours.len()
            )?;
        }
        s.push('\n');
    }
    s.push_str("## Every run\n\n| shape | N | noise | method | CPU s | Chamfer | without a point | measured noise | status |\n|---|---|---|---|---|---|---|---|---|\n");
    for r in rows.iter().filter(|r| r.method != "mc-clean") {
        writeln!(
            s,
            "| {} | {} | {}% | {} | {:.2} | {:.5} | {} of {} | {:.2}% | {} |",
            r.shape,
            r.n,
            100.0 * r.noise,
            r.method,
            r.cpu_seconds,
            r.chamfer,
            r.without_point,
            r.owners,
            100.0 * r.measured,
            r.status
        )?;
    }
    rfta_io::write_atomic(path, |w| w.write_all(s.as_bytes()))?;
    Ok(())
}
