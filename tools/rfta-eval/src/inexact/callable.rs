//! The fields as functions to ask: rfta's adaptive mode against MISE on the networks (when a
//! venv with it is given), at MISE's evaluations (30,000 without MISE), and against marching
//! cubes on a grid of about as many points on the CSG trees (MISE's runner asks networks only),
//! scored against the field's zero set.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result};
use rfta::adaptive::{Budget, OracleError, reconstruct_adaptive};
use rfta_geom::glam::DVec3;
use rfta_geom::{Aabb, TriMesh};
use rfta_metrics::MeshSummary;

use super::fields::Field;
use crate::mise::Mise;

/// The budget when MISE does not say one.
const BUDGET: usize = 30_000;

/// One network meshed from its values asked where needed.
pub(super) struct CallableRow {
    field: String,
    method: &'static str,
    evaluations: usize,
    /// Seconds outside the oracle.
    seconds: f64,
    chamfer: f64,
    summary: MeshSummary,
    reference: MeshSummary,
}

/// MISE (when `mise` is given) and rfta's adaptive mode on the network `field`, scored against
/// `reference`; MISE's mesh is written into `out`.
pub(super) fn compare(
    field: &Field,
    reference: &TriMesh,
    samples: usize,
    mise: Option<&Mise>,
    out: &Path,
) -> Result<Vec<CallableRow>> {
    let score = |m: &TriMesh| rfta_metrics::chamfer(m, reference, samples, 7);
    let reference = MeshSummary::of(reference);
    let mut rows = Vec::new();
    let mut budget = BUDGET;
    if field.path.is_none() {
        // Marching cubes on the grid of about as many points (31^3 for 30,000).
        let n = (BUDGET as f64).cbrt().floor() as usize - 1;
        let (grid, values) = field.grid(n)?;
        let mesh = rfta_mc::marching_cubes(&grid, &values, 0.0);
        rows.push(CallableRow {
            field: field.name.clone(),
            method: "mc",
            evaluations: grid.len(),
            seconds: 0.0,
            chamfer: score(&mesh)?,
            summary: MeshSummary::of(&mesh),
            reference,
        });
    }
    if let (Some(mise), Some(path)) = (mise, &field.path) {
        let run = mise.run_network(path, &out.join(format!("{}-mise.obj", field.name)))?;
        budget = run.evaluations;
        rows.push(CallableRow {
            field: field.name.clone(),
            method: "mise",
            evaluations: run.evaluations,
            seconds: run.seconds,
            chamfer: score(&run.mesh)?,
            summary: MeshSummary::of(&run.mesh),
            reference,
        });
    }
    let mut oracle = |p: &[DVec3]| -> Result<Vec<f64>, OracleError> { Ok(field.values(p)) };
    let r = reconstruct_adaptive(
        &mut oracle,
        Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
        Budget::evaluations(budget),
        &rfta::Params::default(),
        &mut |_| {},
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .with_context(|| format!("{}: rfta's adaptive mode", field.name))?;
    let mesh = &r.reconstruction.mesh;
    rfta_io::write_mesh(&out.join(format!("{}-rfta.obj", field.name)), mesh)?;
    rows.push(CallableRow {
        field: field.name.clone(),
        method: "rfta",
        evaluations: r.report.evaluations,
        seconds: r.report.rfta_seconds,
        chamfer: score(mesh)?,
        summary: MeshSummary::of(mesh),
        reference,
    });
    for row in &rows {
        eprintln!(
            "{} as a callable: {} {} evaluations, Chamfer {:.5}, {:.2} s",
            row.field, row.method, row.evaluations, row.chamfer, row.seconds
        );
    }
    Ok(rows)
}

/// The callable rows' section of the report.
pub(super) fn markdown(rows: &[CallableRow], mise: bool) -> String {
    let mut s = String::new();
    if rows.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "\n## The fields as functions to ask\n\n{} rfta's adaptive mode (default parameters) at {}; the CSG trees beside marching cubes on the grid of about as many points (31^3), rfta at 30,000 evaluations. Seconds: outside the function (the network's own time excluded).\n\n| field | method | evaluations | Chamfer | pieces | genus (reference) | seconds |\n|---|---|---|---|---|---|---|",
        if mise {
            "MISE to 128^3 (Occupancy Networks' code, `tools/rfta-eval/inexact/mise_network.py`) and"
        } else {
            "MISE skipped (no `--mise VENV`);"
        },
        if mise {
            "MISE's evaluations"
        } else {
            "30,000 evaluations"
        },
    );
    let g = |v: Option<i64>| v.map_or("?".into(), |g| g.to_string());
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.5} | {} | {} ({}) | {:.2} |",
            r.field,
            r.method,
            r.evaluations,
            r.chamfer,
            r.summary.components,
            g(r.summary.genus),
            g(r.reference.genus),
            r.seconds
        );
    }
    // Means over the fields that have the baseline's row.
    let mean = |m: &str, baseline: &str| {
        let v: Vec<f64> = rows
            .iter()
            .filter(|r| r.method == m && baseline_of(rows, r).is_some_and(|b| b.method == baseline))
            .map(|r| r.chamfer)
            .collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    if let (Some(rfta), Some(mise)) = (mean("rfta", "mise"), mean("mise", "mise")) {
        let _ = writeln!(
            s,
            "\nMean Chamfer: rfta {rfta:.5}, MISE {mise:.5} ({:.2}x).",
            rfta / mise
        );
    }
    if let (Some(rfta), Some(mc)) = (mean("rfta", "mc"), mean("mc", "mc")) {
        let _ = writeln!(
            s,
            "\nMean Chamfer of the CSG trees: rfta {rfta:.5}, marching cubes {mc:.5} ({:.2}x).",
            rfta / mc
        );
    }
    s
}

/// The row `r` is held to: the same field's MISE row, or its marching cubes row without one.
fn baseline_of<'a>(rows: &'a [CallableRow], r: &CallableRow) -> Option<&'a CallableRow> {
    let of = |m: &str| rows.iter().find(|o| o.field == r.field && o.method == m);
    of("mise").or_else(|| of("mc"))
}

/// The goals on the callable rows: rfta's Chamfer at most its baseline's (MISE's, or marching
/// cubes' on as many points) and no more pieces.
pub(super) fn missed(rows: &[CallableRow]) -> Vec<String> {
    let mut missed = Vec::new();
    for r in rows.iter().filter(|r| r.method == "rfta") {
        let Some(m) = baseline_of(rows, r) else {
            continue;
        };
        if r.chamfer > m.chamfer {
            missed.push(format!(
                "{} as a callable: Chamfer {:.5} above {}'s {:.5}",
                r.field, r.chamfer, m.method, m.chamfer
            ));
        }
        if r.summary.components > m.summary.components {
            missed.push(format!(
                "{} as a callable: {} pieces, {} {}",
                r.field, r.summary.components, m.method, m.summary.components
            ));
        }
    }
    missed
}
