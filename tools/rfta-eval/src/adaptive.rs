//! `cargo xtask eval adaptive [--budgets B,..]`: reconstruction from an SDF that can be
//! asked (`rfta::adaptive`), each dev shape's ground truth as the oracle (its exact signed
//! distance), under budgets of evaluations (default 5k, 10k, 30k, 100k).
//!
//! Beside each budget: marching cubes and rfta's default preset on the grid over `[-1, 1]^3`
//! with about as many points (`N + 1` points per axis, `N = round(cbrt(B)) - 1`), and marching
//! cubes on the 129^3 grid (2.1 million evaluations). Per row: Chamfer against the ground truth,
//! genus and components, cavities, thin loops, samples on the wrong side and spheres entered
//! (against the samples the method had), rfta's own seconds and the oracle's. Output:
//! `results.csv`, `report.md` and `chamfer.svg` (mean Chamfer against evaluations).

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::{Context, Result};
use rfta_geom::glam::DVec3;
use rfta_geom::{Aabb, SdfSamples, TriMesh};
use rfta_mesh::MeshIndex;
use rfta_metrics::MeshSummary;

use crate::chart::{Line, line_chart};
use crate::mise::Mise;
use crate::shapes::{Shape, Source};

/// `cargo xtask eval adaptive`'s arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Args {
    /// Budgets of evaluations.
    #[arg(
        long,
        alias = "levels",
        value_delimiter = ',',
        default_value = "5000,10000,30000,100000"
    )]
    budgets: Vec<usize>,
    #[command(flatten)]
    source: Source,
    #[command(flatten)]
    scoring: crate::table::Scoring,
    #[command(flatten)]
    tuning: crate::table::Tuning,
    /// MISE's venv (built by `bash ../shared/peer-tests/mise/build.sh VENV`; default
    /// `$RFTA_MISE_VENV`): MISE to 128^3 on each shape, and rfta at its evaluations and at a
    /// third of them.
    #[arg(long, value_name = "VENV")]
    mise: Option<std::path::PathBuf>,
    /// The run's folder (default: `<target>/eval/adaptive-<pid>`).
    #[arg(long, value_name = "DIR")]
    out: Option<std::path::PathBuf>,
}

/// Runs the adaptive evaluation as `a` says.
pub(crate) fn command(a: &Args) -> Result<()> {
    let (shapes, _) = a.source.load()?;
    let out = crate::out_dir(
        a.out.as_deref(),
        &format!("adaptive-{}", std::process::id()),
    )?;
    let mise = Mise::find(a.mise.as_deref())?;
    if mise.is_none() {
        println!("SKIPPED MISE: no venv (--mise VENV or RFTA_MISE_VENV)");
    }
    run(
        &shapes,
        &a.budgets,
        a.scoring.samples,
        &a.tuning.options(),
        mise.as_ref(),
        &out,
    )?;
    println!("wrote {}", out.display());
    Ok(())
}

/// The grid marching cubes is measured on for comparison: 129^3 points.
const FINE_GRID: usize = 128;

/// One (shape, budget, method) result.
struct Row {
    shape: String,
    budget: usize,
    method: &'static str,
    evaluations: usize,
    chamfer: f64,
    summary: Option<MeshSummary>,
    gt_genus: Option<i64>,
    consistency: Option<rfta::Consistency>,
    rfta_seconds: f64,
    oracle_seconds: f64,
    passes: usize,
    status: String,
}

impl Row {
    fn right_topology(&self) -> bool {
        self.summary
            .as_ref()
            .is_some_and(|s| s.components == 1 && s.genus == self.gt_genus)
    }
}

/// The grid cells per axis whose points number about `budget`.
fn grid_cells(budget: usize) -> usize {
    ((budget as f64).cbrt().round() as usize)
        .saturating_sub(1)
        .max(2)
}

fn run(
    shapes: &[Shape],
    budgets: &[usize],
    samples: usize,
    tuning: &serde_json::Map<String, serde_json::Value>,
    mise: Option<&Mise>,
    out: &Path,
) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let params = rfta::Params::default()
        .with_options(tuning.clone())
        .context("eval options")?;
    let mut rows = Vec::new();
    for shape in shapes {
        let gt = MeshIndex::new(&shape.gt).with_context(|| format!("{}: empty", shape.name))?;
        let gt_genus = MeshSummary::of(&shape.gt).genus;
        let score = |mesh: &TriMesh| -> Result<(f64, MeshSummary)> {
            let index = MeshIndex::new(mesh)?;
            let chamfer =
                rfta_metrics::chamfer_indexed((&shape.gt, &gt), (mesh, &index), samples, 1);
            Ok((chamfer, MeshSummary::of(mesh)))
        };
        let base = |budget, method, evaluations| Row {
            shape: shape.name.clone(),
            budget,
            method,
            evaluations,
            chamfer: f64::NAN,
            summary: None,
            gt_genus,
            consistency: None,
            rfta_seconds: 0.0,
            oracle_seconds: 0.0,
            passes: 0,
            status: "ok".into(),
        };
        // Marching cubes on the fine grid, once per shape.
        let (grid, values) = crate::shapes::grid_for(shape, &gt, FINE_GRID)?;
        let t = Instant::now();
        let mesh = rfta_mc::marching_cubes(&grid, &values, 0.0);
        let mut row = base(0, "mc-129", grid.len());
        row.rfta_seconds = t.elapsed().as_secs_f64();
        (row.chamfer, _) = score(&mesh)?;
        row.summary = Some(MeshSummary::of(&mesh));
        rows.push(row);
        // rfta asking the shape's exact distance, at most `budget` times.
        let adaptive = |mut row: Row, budget: usize| -> Result<Row> {
            let mut oracle = |p: &[DVec3]| -> Result<Vec<f64>, rfta::adaptive::OracleError> {
                Ok(gt.signed_distances(p))
            };
            let result = rfta::adaptive::reconstruct_adaptive(
                &mut oracle,
                Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
                rfta::adaptive::Budget::evaluations(budget),
                &params,
                &mut |_| {},
                &mut |_| {},
                &AtomicBool::new(false),
            );
            match result {
                Ok(a) => {
                    let mesh = &a.reconstruction.mesh;
                    let (chamfer, summary) = score(mesh)?;
                    row.evaluations = a.report.evaluations;
                    row.chamfer = chamfer;
                    row.summary = Some(summary);
                    row.consistency = Some(a.reconstruction.report.consistency.clone());
                    row.rfta_seconds = a.report.rfta_seconds;
                    row.oracle_seconds = a.report.oracle_seconds;
                    row.passes = a.report.passes.len();
                }
                Err(e) => row.status = e.to_string(),
            }
            println!(
                "{} {budget} {}: Chamfer {:.6}, genus {:?} in {} component(s), {:.2} s",
                shape.name,
                row.method,
                row.chamfer,
                row.summary.as_ref().and_then(|s| s.genus),
                row.summary.as_ref().map_or(0, |s| s.components),
                row.rfta_seconds
            );
            Ok(row)
        };
        if let Some(mise) = mise {
            rows.extend(beside_mise(mise, shape, out, &score, &base, &adaptive)?);
        }
        for &budget in budgets {
            // The adaptive run.
            let row = adaptive(base(budget, "rfta-adaptive", 0), budget)?;
            rows.push(row);
            // The grid with about as many points.
            let n = grid_cells(budget);
            let (grid, values) = crate::shapes::grid_for(shape, &gt, n)?;
            let t = Instant::now();
            let mesh = rfta_mc::marching_cubes(&grid, &values, 0.0);
            let mut row = base(budget, "mc-grid", grid.len());
            row.rfta_seconds = t.elapsed().as_secs_f64();
            (row.chamfer, _) = score(&mesh)?;
            row.summary = Some(MeshSummary::of(&mesh));
            rows.push(row);
            let grid_samples = SdfSamples::grid(grid, values)?;
            let t = Instant::now();
            let mut row = base(budget, "rfta-grid", grid.len());
            match rfta::reconstruct(&grid_samples, &params) {
                Ok(r) => {
                    row.rfta_seconds = t.elapsed().as_secs_f64();
                    let (chamfer, summary) = score(&r.mesh)?;
                    row.chamfer = chamfer;
                    row.summary = Some(summary);
                    row.consistency = Some(r.report.consistency);
                }
                Err(e) => row.status = e.to_string(),
            }
            rows.push(row);
        }
    }
    write_csv(&out.join("results.csv"), &rows)?;
    write_markdown(&out.join("report.md"), &rows, budgets)?;
    chart(&out.join("chamfer.svg"), &rows, budgets)?;
    crate::table::no_defects(
        rows.iter()
            .map(|r| (format!("{} {} {}", r.shape, r.budget, r.method), &r.status)),
    )
}

/// MISE on `shape` (its mesh written beside the outputs for the runner), then rfta at MISE's
/// evaluations and at a third of them: the rows `mise`, `rfta-at-mise`, `rfta-at-mise/3`.
fn beside_mise(
    mise: &Mise,
    shape: &Shape,
    out: &Path,
    score: &dyn Fn(&TriMesh) -> Result<(f64, MeshSummary)>,
    base: &dyn Fn(usize, &'static str, usize) -> Row,
    adaptive: &dyn Fn(Row, usize) -> Result<Row>,
) -> Result<Vec<Row>> {
    let gt_path = out.join(format!("{}-gt.obj", shape.name));
    rfta_io::write_mesh(&gt_path, &shape.gt)?;
    let run = mise.run(&gt_path, &out.join(format!("{}-mise.obj", shape.name)))?;
    let e = run.evaluations;
    let mut row = base(e, "mise", e);
    (row.chamfer, _) = score(&run.mesh)?;
    row.summary = Some(MeshSummary::of(&run.mesh));
    row.rfta_seconds = run.seconds;
    row.oracle_seconds = run.oracle_seconds;
    println!(
        "{} MISE: {e} evaluations, Chamfer {:.6}, {:.2} s",
        shape.name, row.chamfer, run.seconds
    );
    Ok(vec![
        row,
        adaptive(base(e, "rfta-at-mise", 0), e)?,
        adaptive(base(e / 3, "rfta-at-mise/3", 0), e / 3)?,
    ])
}

fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut s = String::from(
        "shape,budget,method,evaluations,chamfer,genus,gt_genus,components,cavities,thin_loops,sign_errors,entered,rfta_seconds,oracle_seconds,passes,status\n",
    );
    for r in rows {
        let genus = r.summary.as_ref().and_then(|s| s.genus);
        let c = r.consistency.as_ref();
        writeln!(
            s,
            "{},{},{},{},{:.6},{},{},{},{},{},{},{},{:.3},{:.3},{},\"{}\"",
            r.shape,
            r.budget,
            r.method,
            r.evaluations,
            r.chamfer,
            genus.map_or(String::new(), |g| g.to_string()),
            r.gt_genus.map_or(String::new(), |g| g.to_string()),
            r.summary.as_ref().map_or(0, |s| s.components),
            r.summary.as_ref().map_or(0, |s| s.cavities),
            c.map_or(String::new(), |c| c.thin_loops.len().to_string()),
            c.map_or(String::new(), |c| c.sign_errors.to_string()),
            c.map_or(String::new(), |c| c.entered.to_string()),
            r.rfta_seconds,
            r.oracle_seconds,
            r.passes,
            r.status.replace('"', "'")
        )?;
    }
    std::fs::write(path, s).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// The mean of a method's Chamfer at a budget, with how many rows had the right genus in one
/// component, over the rows that ran.
fn mean(rows: &[Row], budget: usize, method: &str) -> Option<(f64, usize, usize, f64)> {
    let mine: Vec<&Row> = rows
        .iter()
        .filter(|r| r.budget == budget && r.method == method && r.chamfer.is_finite())
        .collect();
    if mine.is_empty() {
        return None;
    }
    let n = mine.len() as f64;
    Some((
        mine.iter().map(|r| r.chamfer).sum::<f64>() / n,
        mine.iter().filter(|r| r.right_topology()).count(),
        mine.len(),
        mine.iter().map(|r| r.rfta_seconds).sum::<f64>() / n,
    ))
}

fn write_markdown(path: &Path, rows: &[Row], budgets: &[usize]) -> Result<()> {
    let mut s = String::from("# Adaptive sampling: rfta asking the SDF, against grids\n\n");
    s.push_str(
        "Each dev shape's ground truth is the oracle (its exact signed distance). `rfta-adaptive`: \
         `rfta::adaptive::reconstruct_adaptive` over [-1, 1]^3 with the budget; `rfta-grid` and \
         `mc-grid`: rfta's default preset and marching cubes on the grid with about as many \
         points; `mc-129`: marching cubes on the 129^3 grid. Seconds are rfta's own (the \
         oracle's apart).\n\n",
    );
    if let Some((chamfer, right, of, secs)) = mean(rows, 0, "mc-129") {
        writeln!(
            s,
            "Marching cubes on 129^3 (2,146,689 evaluations): mean Chamfer {chamfer:.6}, right genus in one component {right} of {of}, {secs:.3} s.\n"
        )?;
    }
    s.push_str("| budget | method | evaluations | mean Chamfer | right genus, 1 component | mean s |\n|---|---|---|---|---|---|\n");
    for &b in budgets {
        for method in ["rfta-adaptive", "rfta-grid", "mc-grid"] {
            if let Some((chamfer, right, of, secs)) = mean(rows, b, method) {
                let evals = rows
                    .iter()
                    .find(|r| r.budget == b && r.method == method)
                    .map_or(0, |r| r.evaluations);
                let evals = if method == "rfta-adaptive" {
                    format!("<= {b}")
                } else {
                    evals.to_string()
                };
                writeln!(
                    s,
                    "| {b} | {method} | {evals} | {chamfer:.6} | {right} of {of} | {secs:.2} |"
                )?;
            }
        }
    }
    s.push_str(&beside_mise_table(rows));
    s.push_str("\n## Per shape\n\nChamfer, genus/components (ground truth's genus in the shape column), thin loops, wrong side, entered, rfta s (+ oracle s).\n\n| shape | budget | method | Chamfer | genus/comps | thin | wrong | entered | s |\n|---|---|---|---|---|---|---|---|---|\n");
    for r in rows {
        let summary = r.summary.as_ref();
        let c = r.consistency.as_ref();
        writeln!(
            s,
            "| {} ({}) | {} | {} | {} | {}/{} | {} | {} | {} | {:.2}{} |",
            r.shape,
            r.gt_genus.map_or("?".into(), |g| g.to_string()),
            if r.budget == 0 {
                "-".into()
            } else {
                r.budget.to_string()
            },
            r.method,
            if r.chamfer.is_finite() {
                format!("{:.6}", r.chamfer)
            } else {
                r.status.clone()
            },
            summary
                .and_then(|s| s.genus)
                .map_or("-".into(), |g| g.to_string()),
            summary.map_or(0, |s| s.components),
            c.map_or("-".into(), |c| c.thin_loops.len().to_string()),
            c.map_or("-".into(), |c| c.sign_errors.to_string()),
            c.map_or("-".into(), |c| c.entered.to_string()),
            r.rfta_seconds,
            if r.oracle_seconds > 0.0 {
                format!(" (+{:.2})", r.oracle_seconds)
            } else {
                String::new()
            },
        )?;
    }
    std::fs::write(path, s).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// The section beside MISE, when it ran: per shape MISE's evaluations, Chamfer, topology and
/// own time, rfta's at as many evaluations and at a third of them, then the means.
fn beside_mise_table(rows: &[Row]) -> String {
    let of =
        |shape: &str, method: &str| rows.iter().find(|r| r.shape == shape && r.method == method);
    let cell = |r: Option<&Row>| {
        r.map_or("- | - | -".to_string(), |r| {
            let topology = r.summary.as_ref().map_or("-".to_string(), |s| {
                format!(
                    "{}/{}",
                    s.genus.map_or("-".into(), |g| g.to_string()),
                    s.components
                )
            });
            format!("{:.6} | {topology} | {:.2}", r.chamfer, r.rfta_seconds)
        })
    };
    let mise: Vec<&Row> = rows.iter().filter(|r| r.method == "mise").collect();
    if mise.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "\n## Beside MISE\n\nMISE (Occupancy Networks' multiresolution isosurface extraction, \
         `../shared/peer-tests/mise`, r0 16, depth 3: 128^3) on each shape's exact distance, \
         and rfta's adaptive mode at MISE's evaluations and at a third of them. Chamfer, \
         genus/components, seconds outside the oracle.\n\n\
         | shape | MISE evaluations | MISE Chamfer | genus/comps | s | rfta at as many | genus/comps | s | rfta at a third | genus/comps | s |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for m in &mise {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            m.shape,
            m.evaluations,
            cell(Some(m)),
            cell(of(&m.shape, "rfta-at-mise")),
            cell(of(&m.shape, "rfta-at-mise/3")),
        ));
    }
    let mean = |method: &str| {
        let c: Vec<f64> = rows
            .iter()
            .filter(|r| r.method == method && r.chamfer.is_finite())
            .map(|r| r.chamfer)
            .collect();
        c.iter().sum::<f64>() / c.len().max(1) as f64
    };
    s.push_str(&format!(
        "\nMean Chamfer: MISE {:.6}, rfta at as many evaluations {:.6}, at a third {:.6}.\n",
        mean("mise"),
        mean("rfta-at-mise"),
        mean("rfta-at-mise/3")
    ));
    s.push_str(&time_table(rows));
    s
}

/// Mean seconds to the mesh per method, its own time plus its evaluations at an oracle cost of
/// 1 us, 100 us and 10 ms each (a fast analytic SDF, a small network on a CPU, a large one),
/// beside its mean Chamfer: what a user with a callable field weighs.
fn time_table(rows: &[Row]) -> String {
    let methods = ["mise", "rfta-at-mise", "rfta-at-mise/3", "mc-129"];
    let mut s = String::from(
        "\nSeconds to the mesh, rfta's or MISE's own time plus the evaluations at each oracle \
         cost (means over the shapes):\n\n\
         | method | mean evaluations | mean Chamfer | own s | 1 us each | 100 us each | 10 ms each |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for method in methods {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| r.method == method && r.chamfer.is_finite())
            .collect();
        if mine.is_empty() {
            continue;
        }
        let n = mine.len() as f64;
        let evals = mine.iter().map(|r| r.evaluations as f64).sum::<f64>() / n;
        let chamfer = mine.iter().map(|r| r.chamfer).sum::<f64>() / n;
        let own = mine.iter().map(|r| r.rfta_seconds).sum::<f64>() / n;
        let at = |cost: f64| own + evals * cost;
        s.push_str(&format!(
            "| {method} | {evals:.0} | {chamfer:.6} | {own:.2} | {:.2} | {:.2} | {:.1} |\n",
            at(1e-6),
            at(1e-4),
            at(1e-2)
        ));
    }
    s
}

/// Mean Chamfer against evaluations (log10 on the x axis).
fn chart(path: &Path, rows: &[Row], budgets: &[usize]) -> Result<()> {
    let series: Vec<Line> = ["rfta-adaptive", "rfta-grid", "mc-grid"]
        .iter()
        .map(|&method| {
            let points = budgets
                .iter()
                .filter_map(|&b| mean(rows, b, method).map(|m| ((b as f64).log10(), m.0)))
                .collect();
            (method.to_string(), method == "mc-grid", points)
        })
        .chain(mean(rows, 0, "mc-129").map(|m| {
            let xs = budgets.iter().map(|&b| (b as f64).log10());
            (
                "mc-129 (2.1M evaluations)".to_string(),
                true,
                xs.map(|x| (x, m.0)).collect(),
            )
        }))
        .collect();
    let ticks: Vec<(f64, String)> = budgets
        .iter()
        .map(|&b| ((b as f64).log10(), b.to_string()))
        .collect();
    line_chart(
        path,
        "Mean Chamfer vs evaluations of the SDF (log scale)",
        "evaluations",
        &ticks,
        &series,
        1,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &'static str, evaluations: usize, chamfer: f64, seconds: f64) -> Row {
        Row {
            shape: "s".into(),
            budget: evaluations,
            method,
            evaluations,
            chamfer,
            summary: None,
            gt_genus: None,
            consistency: None,
            rfta_seconds: seconds,
            oracle_seconds: 0.0,
            passes: 0,
            status: "ok".into(),
        }
    }

    /// The time to a mesh is the method's own time plus its evaluations at each oracle cost,
    /// averaged over the shapes: 2,000 evaluations and 0.2 s of its own at 10 ms an evaluation
    /// is 20.2 s.
    #[test]
    fn the_time_to_a_mesh_adds_the_oracles_cost() {
        let rows = [
            row("mise", 1000, 0.001, 0.1),
            row("mise", 3000, 0.003, 0.3),
            row("rfta-at-mise", 2000, f64::NAN, 9.0),
        ];
        let table = time_table(&rows);
        assert!(
            table.contains("| mise | 2000 | 0.002000 | 0.20 | 0.20 | 0.40 | 20.2 |"),
            "{table}"
        );
        // A method without a finished row has no line.
        assert!(!table.contains("| rfta-at-mise |"), "{table}");
    }
}
