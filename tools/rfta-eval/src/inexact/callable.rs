//! The networks as functions to ask: rfta's adaptive mode against MISE (when a venv with it is
//! given), at MISE's evaluations (30,000 without MISE), scored against the network's zero set.

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
        "\n## The networks as functions to ask\n\n{} rfta's adaptive mode (default parameters) at {}. Seconds: outside the function (the network's own time excluded).\n\n| field | method | evaluations | Chamfer | pieces | genus (reference) | seconds |\n|---|---|---|---|---|---|---|",
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
    let mean = |m: &str| {
        let v: Vec<f64> = rows
            .iter()
            .filter(|r| r.method == m)
            .map(|r| r.chamfer)
            .collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    if let (Some(rfta), Some(mise)) = (mean("rfta"), mean("mise")) {
        let _ = writeln!(
            s,
            "\nMean Chamfer: rfta {rfta:.5}, MISE {mise:.5} ({:.2}x).",
            rfta / mise
        );
    }
    s
}

/// The goals on the callable rows: rfta's Chamfer at most MISE's and no more pieces.
pub(super) fn missed(rows: &[CallableRow]) -> Vec<String> {
    let mut missed = Vec::new();
    for r in rows.iter().filter(|r| r.method == "rfta") {
        let Some(m) = rows
            .iter()
            .find(|o| o.field == r.field && o.method == "mise")
        else {
            continue;
        };
        if r.chamfer > m.chamfer {
            missed.push(format!(
                "{} as a callable: Chamfer {:.5} above MISE's {:.5}",
                r.field, r.chamfer, m.chamfer
            ));
        }
        if r.summary.components > m.summary.components {
            missed.push(format!(
                "{} as a callable: {} pieces, MISE {}",
                r.field, r.summary.components, m.summary.components
            ));
        }
    }
    missed
}
