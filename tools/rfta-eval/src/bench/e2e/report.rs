//! `bench e2e`'s tables: the rows read back from a run's CSV, the report in Markdown, and the
//! scaling from one core to two.

use super::*;

/// The rows and inputs of an `e2e.csv` this command wrote.
#[allow(clippy::type_complexity)]
pub(super) fn read_csv(
    path: &Path,
) -> Result<(
    Vec<(String, usize, String, usize, Result<Run>)>,
    Vec<(String, usize)>,
)> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    let mut rows = Vec::new();
    let mut inputs: Vec<(String, usize)> = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 11 {
            bail!("{}: short row '{line}'", path.display());
        }
        let num = |i: usize| {
            f.get(i)
                .and_then(|x| x.parse::<f64>().ok())
                .unwrap_or(f64::NAN)
        };
        let (shape, n) = (f[0].to_string(), f[1].parse::<usize>()?);
        if !inputs.contains(&(shape.clone(), n)) {
            inputs.push((shape.clone(), n));
        }
        let run = if f[10] == "ok" {
            Ok(Run {
                wall: num(4),
                cpu: num(5),
                rss_mb: num(6),
                chamfer: num(7),
                faces: f[8].parse().unwrap_or(0),
                watertight: f[9] == "true",
                walls: f
                    .get(11)
                    .map(|w| w.split(';').filter_map(|v| v.parse().ok()).collect())
                    .unwrap_or_else(|| vec![num(4)]),
                steals: f
                    .get(12)
                    .map(|w| w.split(';').filter_map(|v| v.parse().ok()).collect())
                    .unwrap_or_default(),
                hash: 0,
                simplified: num(13),
            })
        } else {
            Err(anyhow::anyhow!("{}", f[10]))
        };
        rows.push((shape, n, f[2].to_string(), f[3].parse()?, run));
    }
    Ok((rows, inputs))
}

pub(super) fn name_of(dir: &Path) -> String {
    dir.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The tables: per N and method, means over the shapes that every method finished, and the
/// ratios; then every row.
pub(super) fn report(
    rows: &[(String, usize, String, usize, Result<Run>)],
    inputs: &[(String, usize)],
) -> Result<String> {
    let mut s = String::new();
    writeln!(
        s,
        "| N | shapes | method | threads | wall s | CPU s | peak MB | Chamfer | gpytoolbox CPU / this | this wall / mc wall | this wall / skimage wall |"
    )?;
    writeln!(s, "|{}", "---|".repeat(11))?;
    let mut ns: Vec<usize> = inputs.iter().map(|i| i.1).collect();
    ns.dedup();
    for &n in &ns {
        let find = |shape: &str, m: &str, t: usize| {
            rows.iter().find_map(|(sh, nn, mm, tt, r)| {
                (sh == shape && *nn == n && mm == m && *tt == t)
                    .then_some(r.as_ref().ok())
                    .flatten()
            })
        };
        let shapes: Vec<&str> = inputs
            .iter()
            .filter(|i| i.1 == n)
            .map(|i| i.0.as_str())
            .collect();
        for &(m, t) in &REPORT_ORDER {
            // Shapes this method and marching cubes both finished (gpytoolbox too, when it ran).
            let ok: Vec<&str> = shapes
                .iter()
                .copied()
                .filter(|sh| find(sh, m, t).is_some() && find(sh, "mc", 1).is_some())
                .collect();
            if ok.is_empty() {
                continue;
            }
            let mean = |f: &dyn Fn(&Run) -> f64, m: &str, t: usize| {
                ok.iter()
                    .filter_map(|sh| find(sh, m, t))
                    .map(f)
                    .sum::<f64>()
                    / ok.len() as f64
            };
            let cpu = mean(&|r| r.cpu, m, t);
            let gpy: Vec<f64> = ok
                .iter()
                .filter_map(|sh| find(sh, "gpytoolbox", 1).map(|r| r.cpu))
                .collect();
            let vs_gpy = if gpy.len() == ok.len() && m != "gpytoolbox" && m != "mc" && cpu > 0.0 {
                format!("{:.1}", gpy.iter().sum::<f64>() / ok.len() as f64 / cpu)
            } else {
                "-".into()
            };
            let wall = mean(&|r| r.wall, m, t);
            let vs = |peer: &str| {
                let all = ok.iter().all(|sh| find(sh, peer, 1).is_some());
                let theirs = mean(&|r| r.wall, peer, 1);
                if all && m != peer && theirs > 0.0 {
                    ratio(wall / theirs)
                } else {
                    "-".into()
                }
            };
            let (vs_mc, vs_skimage) = (vs("mc"), vs("skimage"));
            writeln!(
                s,
                "| {n} | {} | {m} | {t} | {:.2} | {:.2} | {:.0} | {:.5} | {vs_gpy} | {vs_mc} | {vs_skimage} |",
                ok.len(),
                wall,
                cpu,
                ok.iter()
                    .filter_map(|sh| find(sh, m, t))
                    .map(|r| r.rss_mb)
                    .fold(0.0, f64::max),
                mean(&|r| r.chamfer, m, t),
            )?;
        }
    }
    writeln!(
        s,
        "\nPeak MB is the largest over the shapes; CPU seconds are user + system of the child during the call (10 ms resolution: marching cubes shows 0). With more than one run (the default preset on 1 and 2 threads, {SCALING_REPEATS} runs each, alternating), a row is the run of median wall time.\n"
    )?;
    for &n in &ns {
        let Some(rfta) = Scaling::of(rows, n, "rfta-default") else {
            continue;
        };
        writeln!(
            s,
            "From 1 to 2 threads at N = {n} ({} shapes, {} runs each per thread count): median wall time per shape {:.2} to {:.2} s, **{:.2}x**; fastest runs {:.2} to {:.2} s, {:.2}x.\n",
            rfta.shapes,
            rfta.runs,
            rfta.median.0,
            rfta.median.1,
            rfta.median.0 / rfta.median.1,
            rfta.fastest.0,
            rfta.fastest.1,
            rfta.fastest.0 / rfta.fastest.1,
        )?;
        let total = 2 * rfta.shapes * rfta.runs;
        match rfta.quiet {
            Some((q, k)) => writeln!(
                s,
                "Over the quiet runs only ({k} of {total}: the hypervisor took at most {:.0}% of the machine's CPU time during the run, by `steal` in /proc/stat): median wall time per shape {:.2} to {:.2} s, **{:.2}x**.\n",
                100.0 * QUIET_STEAL,
                q.0,
                q.1,
                q.0 / q.1,
            )?,
            None => writeln!(
                s,
                "Too few quiet runs for a speed-up over them (some shape has no run on a thread count during which the hypervisor took at most {:.0}% of the CPU time, or this machine has no `steal` counter).\n",
                100.0 * QUIET_STEAL,
            )?,
        }
        if let Some(c) = Scaling::of(rows, n, "ceiling") {
            let (ceiling, ours) = (c.median.0 / c.median.1, rfta.median.0 / rfta.median.1);
            writeln!(
                s,
                "The machine's ceiling in the same loop (a perfectly parallel workload, run between them the same number of times): median {:.2} to {:.2} s, **{ceiling:.2}x**; fastest {:.2}x. The pipeline's speed-up is {:.0}% of the ceiling's (median runs).\n",
                c.median.0,
                c.median.1,
                c.fastest.0 / c.fastest.1,
                100.0 * (ours - 1.0) / (ceiling - 1.0).max(f64::EPSILON),
            )?;
        }
    }
    targets(&mut s, rows, &ns)?;
    simplification_share(&mut s, rows, &ns)?;
    writeln!(
        s,
        "| shape | N | method | threads | wall s | CPU s | peak MB | Chamfer | faces | watertight |"
    )?;
    writeln!(s, "|{}", "---|".repeat(10))?;
    for (shape, n, m, t, r) in rows {
        match r {
            // The ceiling's workload writes no mesh.
            Ok(r) if m == "ceiling" => writeln!(
                s,
                "| {shape} | {n} | {m} | {t} | {:.2} | {:.2} | {:.0} | - | - | - |",
                r.wall, r.cpu, r.rss_mb
            )?,
            Ok(r) => writeln!(
                s,
                "| {shape} | {n} | {m} | {t} | {:.2} | {:.2} | {:.0} | {:.5} | {} | {} |",
                r.wall, r.cpu, r.rss_mb, r.chamfer, r.faces, r.watertight
            )?,
            Err(e) => writeln!(
                s,
                "| {shape} | {n} | {m} | {t} | failed: {} |||||",
                format!("{e:#}").replace(['|', '\n'], " ")
            )?,
        }
    }
    Ok(s)
}

/// A ratio: two decimals below 10 (`0.85`, `3.46`), whole numbers from there (`12`, `850`).
fn ratio(x: f64) -> String {
    if x < 10.0 {
        format!("{x:.2}")
    } else {
        format!("{x:.0}")
    }
}

/// The default preset's finished runs on 2 threads at `n`: what both target tables read.
fn default_runs(rows: &[(String, usize, String, usize, Result<Run>)], n: usize) -> Vec<&Run> {
    rows.iter()
        .filter(|(_, nn, m, t, _)| *nn == n && m == "rfta-default" && *t == 2)
        .filter_map(|(_, _, _, _, r)| r.as_ref().ok())
        .collect()
}

/// The speed issue's targets ([`TARGETS`]) beside the default preset's runs on 2 threads at each N
/// this run has: mean wall time per shape and the largest peak memory, and which of them are met.
fn targets(
    s: &mut String,
    rows: &[(String, usize, String, usize, Result<Run>)],
    ns: &[usize],
) -> Result<()> {
    let mut lines = Vec::new();
    for &(n, wall_target, mb_target) in &TARGETS {
        let runs = default_runs(rows, n);
        if !ns.contains(&n) || runs.is_empty() {
            continue;
        }
        let wall = runs.iter().map(|r| r.wall).sum::<f64>() / runs.len() as f64;
        let mb = runs.iter().map(|r| r.rss_mb).fold(0.0, f64::max);
        let verdict = match (wall <= wall_target, mb_target.is_none_or(|t| mb <= t)) {
            (true, true) => "met",
            (false, true) => "**time not met**",
            (true, false) => "**memory not met**",
            (false, false) => "**neither met**",
        };
        lines.push(format!(
            "| {n} | {} | {wall:.2} | {wall_target} | {mb:.0} | {} | {verdict} |",
            runs.len(),
            mb_target.map_or("-".into(), |t| format!("{t:.0}")),
        ));
    }
    table(
        s,
        "The speed issue's targets for the default preset on 2 threads (mean wall seconds per shape, the largest peak memory):",
        &[
            "N",
            "shapes",
            "wall s",
            "target s",
            "peak MB",
            "target MB",
            "",
        ],
        &lines,
    )
}

/// The simplification issue's time target (issue 59: the step at most [`SIMPLIFY_SHARE`] of the
/// run) beside the default preset's runs on 2 threads at each N this run has: the step's seconds
/// over the runs' wall seconds, summed over the shapes.
fn simplification_share(
    s: &mut String,
    rows: &[(String, usize, String, usize, Result<Run>)],
    ns: &[usize],
) -> Result<()> {
    let mut lines = Vec::new();
    for &n in ns {
        let runs: Vec<&Run> = default_runs(rows, n)
            .into_iter()
            .filter(|r| r.simplified.is_finite())
            .collect();
        if runs.is_empty() {
            continue;
        }
        let step = runs.iter().map(|r| r.simplified).sum::<f64>();
        let wall = runs.iter().map(|r| r.wall).sum::<f64>();
        let share = step / wall;
        lines.push(format!(
            "| {n} | {} | {step:.2} | {wall:.2} | {:.1}% | {} |",
            runs.len(),
            100.0 * share,
            if share <= SIMPLIFY_SHARE {
                "met"
            } else {
                "**not met**"
            },
        ));
    }
    table(
        s,
        &format!(
            "The simplification's share of the default preset's wall time on 2 threads (issue 59's target: at most {:.0}%):",
            100.0 * SIMPLIFY_SHARE
        ),
        &["N", "shapes", "step s", "wall s", "share", ""],
        &lines,
    )
}

/// A markdown table of `rows` (already formatted) under `intro` and `header`; nothing without
/// rows.
fn table(s: &mut String, intro: &str, header: &[&str], rows: &[String]) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    writeln!(s, "{intro}\n")?;
    writeln!(s, "| {} |", header.join(" | "))?;
    writeln!(s, "|{}", "---|".repeat(header.len()))?;
    for r in rows {
        writeln!(s, "{r}")?;
    }
    writeln!(s)?;
    Ok(())
}

/// The 1- and 2-thread runs of one method at one resolution, over the shapes that have both:
/// mean wall time per shape of the median and of the fastest runs, `(1 thread, 2 threads)`.
pub(super) struct Scaling {
    shapes: usize,
    runs: usize,
    median: (f64, f64),
    fastest: (f64, f64),
    /// The median over the quiet runs only (steal up to [`QUIET_STEAL`]), and how many runs
    /// that is; `None` where some shape has no quiet run on a thread count.
    quiet: Option<((f64, f64), usize)>,
}

impl Scaling {
    fn of(
        rows: &[(String, usize, String, usize, Result<Run>)],
        n: usize,
        method: &str,
    ) -> Option<Self> {
        let walls = |t: usize| -> Vec<(&str, &Run)> {
            rows.iter()
                .filter(|(_, nn, m, tt, _)| *nn == n && m == method && *tt == t)
                .filter_map(|(sh, _, _, _, r)| r.as_ref().ok().map(|r| (sh.as_str(), r)))
                .collect()
        };
        let (one, two) = (walls(1), walls(2));
        let runs: Vec<(&Run, &Run)> = one
            .iter()
            .filter_map(|(sh, r1)| {
                two.iter()
                    .find(|(s2, _)| s2 == sh)
                    .map(|(_, r2)| (*r1, *r2))
            })
            .collect();
        let pairs: Vec<(&[f64], &[f64])> = runs
            .iter()
            .map(|(a, b)| (&a.walls[..], &b.walls[..]))
            .collect();
        // Wall times of the quiet runs (sorted, as `walls` is).
        let quiet_walls = |r: &Run| -> Vec<f64> {
            r.walls
                .iter()
                .zip(&r.steals)
                .filter(|(_, s)| **s <= QUIET_STEAL)
                .map(|(w, _)| *w)
                .collect()
        };
        let quiet: Vec<(Vec<f64>, Vec<f64>)> = runs
            .iter()
            .map(|(a, b)| (quiet_walls(a), quiet_walls(b)))
            .collect();
        let quiet = quiet
            .iter()
            .all(|(a, b)| !a.is_empty() && !b.is_empty())
            .then(|| {
                let k = quiet.len() as f64;
                let med = |w: &[f64]| w[(w.len() - 1) / 2];
                (
                    (
                        quiet.iter().map(|q| med(&q.0)).sum::<f64>() / k,
                        quiet.iter().map(|q| med(&q.1)).sum::<f64>() / k,
                    ),
                    quiet.iter().map(|q| q.0.len() + q.1.len()).sum(),
                )
            });
        let k = pairs.len() as f64;
        let mean = |pick: &dyn Fn(&[f64]) -> f64| -> (f64, f64) {
            (
                pairs.iter().map(|p| pick(p.0)).sum::<f64>() / k,
                pairs.iter().map(|p| pick(p.1)).sum::<f64>() / k,
            )
        };
        Some(Self {
            shapes: pairs.len(),
            runs: pairs.first()?.0.len(),
            median: mean(&|w| w[(w.len() - 1) / 2]),
            fastest: mean(&|w| w[0]),
            quiet,
        })
    }
}

/// The ceiling's workload: 64 equal tasks, each 2,000 passes of arithmetic over a private
/// 32 KiB buffer (in a core's own cache), handed out one at a time, so nothing is serial,
/// shared or unbalanced: what 2 threads gain over 1 on it is what this machine gives at that
/// moment (about 0.55 s on one thread of the project's VM). Returns a checksum, so that the work
/// is not optimized away.
pub(super) fn ceiling_work() -> f64 {
    use rayon::prelude::*;
    (0..64u32)
        .into_par_iter()
        .with_max_len(1)
        .map(|task| {
            let mut x: Vec<f64> = (0..4096).map(|i| f64::from(i + task) * 1e-3).collect();
            for pass in 0..2000 {
                let a = 1.0 - 1e-7 * f64::from(pass);
                for v in &mut x {
                    *v = (*v * a + 1e-9).sqrt() * 1.0001;
                }
            }
            x.iter().sum::<f64>()
        })
        .sum()
}

#[cfg(test)]
mod tests;
