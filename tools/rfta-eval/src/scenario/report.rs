//! A scenario's `results.csv` and `report.md`.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use super::*;

pub(super) fn mean_chamfer(
    rows: &[ScenarioRow],
    method: &str,
    level: f64,
    n: Option<usize>,
) -> Option<f64> {
    mean_of(rows, method, level, n, |r| Some(r.chamfer))
}

/// The mean of `value` over the rows of `method` at `level` (and `n`, if given) where it is a
/// finite number.
pub(super) fn mean_of(
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

pub(super) fn write_csv(scenario: Scenario, path: &Path, rows: &[ScenarioRow]) -> Result<()> {
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

pub(super) fn write_markdown(
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
