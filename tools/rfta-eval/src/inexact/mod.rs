//! `cargo xtask eval inexact`: fields that are not distances (issue 56), rfta against marching
//! cubes on the same grids, each mesh scored against the field's own zero set.
//!
//! The fields ([`fields`]): each dev shape's network (`tools/rfta-eval/inexact/NAME.npy`,
//! trained once by `train.py` beside it, DeepSDF-style: clamped L1, its values flat away from
//! the surface and a few to tens of percent off near it), and CSG trees of exact distances
//! (min, max, a smooth minimum: bounds where they switch). Each is sampled on
//! `linspace(-1, 1, N + 1)^3` for each `--res N`; marching cubes and rfta (default parameters:
//! it reads the values as it judges them, [`rfta::FieldReport`]) mesh the grid; for CSG the
//! readings it did not choose of the level set and bounds are run too (`rfta-level-set`,
//! `rfta-bound`). The reference is the field's
//! zero set by marching cubes at `--reference-res` cells per axis, evaluated where the zero set
//! passes. Chamfer as the evaluation's (`rfta_metrics::chamfer`). Each field is also asked as
//! a function ([`callable`]; the CSG trees not with `--quick`): rfta's adaptive mode against
//! MISE (`--mise VENV` or `$RFTA_MISE_VENV`) at MISE's evaluations on the networks, against
//! marching cubes on a grid of as many points on the CSG trees.
//!
//! Output: `<out>/results.csv`, `<out>/report.md`, `<out>/inexact-chamfer.svg`, each field's
//! reference mesh (`<out>/FIELD-reference.ply`) and its meshes as a function
//! (`<out>/FIELD-mise.obj`, `<out>/FIELD-rfta.obj`). The run fails when a goal is missed
//! ([`goals`]): on any field, a reading above marching cubes' Chamfer, with a sample on the
//! wrong side or in more pieces; as a function, rfta above its baseline's Chamfer or in more
//! pieces.

mod callable;
mod fields;
mod mlp;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use rfta_geom::{SdfSamples, TriMesh};
use rfta_metrics::MeshSummary;

use fields::{Field, Kind};

/// `cargo xtask eval inexact`'s arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Args {
    /// Grid resolutions N (N + 1 samples per axis).
    #[arg(long, value_delimiter = ',', default_value = "32,64")]
    res: Vec<usize>,
    /// Cells per axis of the references' marching cubes (a power-of-two multiple of 32 or
    /// more).
    #[arg(long, default_value_t = 256)]
    reference_res: usize,
    /// Only these fields (`network-NAME`, `csg-...`), comma-separated.
    #[arg(long, value_delimiter = ',')]
    fields: Vec<String>,
    /// Where the networks are (default: `tools/rfta-eval/inexact`).
    #[arg(long, value_name = "DIR")]
    networks: Option<PathBuf>,
    /// CI's form: two networks and two CSG fields at N = 32, references at 128, 100,000
    /// points per surface.
    #[arg(long)]
    quick: bool,
    /// A venv where MISE imports (`bash ../shared/peer-tests/mise/build.sh VENV`; default
    /// `$RFTA_MISE_VENV`): MISE beside rfta on each network as a function to ask.
    #[arg(long, value_name = "VENV")]
    mise: Option<PathBuf>,
    #[command(flatten)]
    scoring: crate::table::Scoring,
    /// The run's folder (default: `<target>/eval/inexact`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// One mesh of one field at one resolution.
struct Row {
    field: String,
    kind: Kind,
    n: usize,
    method: &'static str,
    seconds: f64,
    chamfer: f64,
    mc_chamfer: f64,
    summary: MeshSummary,
    reference: MeshSummary,
    /// rfta's reading: the field report's reach and whether it read a level set.
    reading: Option<rfta::FieldReport>,
    sign_errors: Option<usize>,
}

pub(crate) fn command(a: &Args) -> Result<()> {
    let out = crate::out_dir(a.out.as_deref(), "inexact")?;
    let dir = a
        .networks
        .clone()
        .unwrap_or_else(|| crate::workspace_root().join("tools/rfta-eval/inexact"));
    let (res, reference_res, samples, only) = if a.quick {
        let only = [
            "network-bunny",
            "network-spot",
            "csg-box-ball-torus",
            "csg-drilled",
        ];
        (vec![32], 128, 100_000, only.map(String::from).to_vec())
    } else {
        (
            a.res.clone(),
            a.reference_res,
            a.scoring.samples,
            a.fields.clone(),
        )
    };
    let wanted: Vec<String> = only
        .iter()
        .filter_map(|f| f.strip_prefix("network-").map(String::from))
        .collect();
    let mut all = if only.is_empty() || !wanted.is_empty() {
        fields::networks(&dir, &wanted)?
    } else {
        Vec::new()
    };
    all.extend(fields::csg(&only));
    anyhow::ensure!(
        !all.is_empty(),
        "no field to evaluate (networks in {})",
        dir.display()
    );
    let mise = crate::mise::Mise::find(a.mise.as_deref())?;
    let mut rows = Vec::new();
    let mut callable_rows = Vec::new();
    for field in &all {
        let t = Instant::now();
        let reference = field.reference(reference_res)?;
        rfta_io::write_mesh(
            &out.join(format!("{}-reference.ply", field.name)),
            &reference,
        )?;
        eprintln!(
            "{}: reference at {reference_res}^3, {} faces, {:.1} s",
            field.name,
            reference.n_faces(),
            t.elapsed().as_secs_f64()
        );
        for &n in &res {
            rows.extend(compare(field, n, &reference, samples)?);
        }
        // CSG trees as functions in full runs (minutes each; `--quick` holds the grids).
        if field.kind == Kind::Network || !a.quick {
            callable_rows.extend(callable::compare(
                field,
                &reference,
                samples,
                mise.as_ref(),
                &out,
            )?);
        }
    }
    write_csv(&out.join("results.csv"), &rows)?;
    let md = markdown(&rows, &res, reference_res, samples)
        + &callable::markdown(&callable_rows, mise.is_some());
    std::fs::write(out.join("report.md"), &md)?;
    chart(&out.join("inexact-chamfer.svg"), &rows, &res)?;
    println!("{md}");
    println!("wrote {}", out.display());
    goals(&rows, callable::missed(&callable_rows))
}

/// The goals the run holds rfta to (the module docs), each miss named, after those `missed` on
/// the networks as functions.
fn goals(rows: &[Row], mut missed: Vec<String>) -> Result<()> {
    for r in rows.iter().filter(|r| r.method != "mc") {
        let mc = rows
            .iter()
            .find(|o| o.field == r.field && o.n == r.n && o.method == "mc");
        let what = format!("{} at {}: {}", r.field, r.n, r.method);
        if r.chamfer > r.mc_chamfer {
            missed.push(format!(
                "{what}: Chamfer {:.5} above marching cubes' {:.5}",
                r.chamfer, r.mc_chamfer
            ));
        }
        if r.sign_errors.unwrap_or(0) > 0 {
            missed.push(format!(
                "{what}: {} samples on the wrong side",
                r.sign_errors.unwrap_or(0)
            ));
        }
        if let Some(mc) = mc.filter(|mc| r.summary.components > mc.summary.components) {
            missed.push(format!(
                "{what}: {} pieces, marching cubes {}",
                r.summary.components, mc.summary.components
            ));
        }
    }
    anyhow::ensure!(
        missed.is_empty(),
        "goals missed:\n  {}",
        missed.join("\n  ")
    );
    Ok(())
}

/// Marching cubes and rfta on `field` at `n`, scored against `reference`.
fn compare(field: &Field, n: usize, reference: &TriMesh, samples: usize) -> Result<Vec<Row>> {
    let (grid, values) = field.grid(n)?;
    let score = |m: &TriMesh| rfta_metrics::chamfer(m, reference, samples, 7);
    let t = Instant::now();
    let mc = rfta_mc::marching_cubes(&grid, &values, 0.0);
    let mc_seconds = t.elapsed().as_secs_f64();
    let mc_chamfer = score(&mc)?;
    let reference = MeshSummary::of(reference);
    let mut rows = vec![Row {
        field: field.name.clone(),
        kind: field.kind,
        n,
        method: "mc",
        seconds: mc_seconds,
        chamfer: mc_chamfer,
        mc_chamfer,
        summary: MeshSummary::of(&mc),
        reference,
        reading: None,
        sign_errors: None,
    }];
    let samples_in = SdfSamples::grid(grid, values)?;
    // The default, then, on CSG, the reading it did not choose.
    let mut readings = vec![("rfta", rfta::Field::Auto)];
    let mut k = 0;
    while let Some(&(method, reading)) = readings.get(k) {
        k += 1;
        let params = rfta::Params {
            field: reading,
            ..rfta::Params::default()
        };
        let t = Instant::now();
        let r = rfta::reconstruct(&samples_in, &params)
            .with_context(|| format!("{} at {n}: {method}", field.name))?;
        let seconds = t.elapsed().as_secs_f64();
        let chamfer = score(&r.mesh)?;
        eprintln!(
            "{} n={n}: {method} Chamfer {chamfer:.5} ({:.2}x marching cubes' {mc_chamfer:.5}), {seconds:.1} s",
            field.name,
            chamfer / mc_chamfer
        );
        rows.push(Row {
            field: field.name.clone(),
            kind: field.kind,
            n,
            method,
            seconds,
            chamfer,
            mc_chamfer,
            summary: MeshSummary::of(&r.mesh),
            reference,
            reading: Some(r.report.field.clone()),
            sign_errors: Some(r.report.consistency.sign_errors),
        });
        if reading == rfta::Field::Auto && field.kind == Kind::Csg {
            let others = [
                (
                    "rfta-level-set",
                    rfta::Field::LevelSet,
                    rfta::Reading::LevelSet,
                ),
                ("rfta-bound", rfta::Field::Bound, rfta::Reading::Bounds),
            ];
            readings.extend(
                (others.into_iter())
                    .filter(|o| o.2 != r.report.field.read_as)
                    .map(|(method, field, _)| (method, field)),
            );
        }
    }
    Ok(rows)
}

fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut s = String::from(
        "field,kind,n,method,seconds,chamfer,mc_chamfer,faces,components,genus,ref_components,ref_genus,reach,read_as,sign_errors\n",
    );
    for r in rows {
        let g = |v: Option<i64>| v.map(|g| g.to_string()).unwrap_or_default();
        writeln!(
            s,
            "{},{},{},{},{:.4},{:.6},{:.6},{},{},{},{},{},{},{},{}",
            r.field,
            r.kind.name(),
            r.n,
            r.method,
            r.seconds,
            r.chamfer,
            r.mc_chamfer,
            r.summary.n_faces,
            r.summary.components,
            g(r.summary.genus),
            r.reference.components,
            g(r.reference.genus),
            (r.reading.as_ref().and_then(|f| f.reach)).map_or(String::new(), |x| format!("{x:.3}")),
            r.reading
                .as_ref()
                .map_or(String::new(), |f| f.read_as.to_string()),
            r.sign_errors.map_or(String::new(), |e| e.to_string()),
        )?;
    }
    rfta_io::write_atomic(path, |w| w.write_all(s.as_bytes()))?;
    Ok(())
}

/// Mean Chamfer against N, one line per kind of field and method.
fn chart(path: &Path, rows: &[Row], res: &[usize]) -> Result<()> {
    let mut series: Vec<crate::chart::Line> = Vec::new();
    for kind in [Kind::Network, Kind::Csg] {
        let mut methods: Vec<&str> = Vec::new();
        for r in rows.iter().filter(|r| r.kind == kind) {
            if !methods.contains(&r.method) {
                methods.push(r.method);
            }
        }
        for m in methods {
            let points = res
                .iter()
                .filter_map(|&n| {
                    let these: Vec<f64> = (rows.iter())
                        .filter(|r| r.kind == kind && r.n == n && r.method == m)
                        .map(|r| r.chamfer)
                        .collect();
                    let mean = these.iter().sum::<f64>() / these.len() as f64;
                    (!these.is_empty()).then_some((n as f64, mean))
                })
                .collect();
            series.push((format!("{} {m}", kind.name()), m != "mc", points));
        }
    }
    let ticks: Vec<(f64, String)> = res.iter().map(|&n| (n as f64, n.to_string())).collect();
    crate::chart::line_chart(
        path,
        "Mean Chamfer to the field's zero set vs N (log scale)",
        "N (grid cells per axis)",
        &ticks,
        &series,
        1,
    )
}

/// Whether a row has the reference's genus in one piece.
fn right(r: &Row) -> bool {
    r.summary.components == 1 && r.summary.genus == r.reference.genus
}

fn markdown(rows: &[Row], res: &[usize], reference_res: usize, samples: usize) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Fields that are not distances\n\nGenerated by `cargo xtask eval inexact` (`tools/rfta-eval/src/inexact/`). Each field sampled on `linspace(-1, 1, N + 1)^3`; Chamfer (sum of the two RMS one-sided distances, {samples} points per surface) against the field's own zero set (marching cubes at {reference_res}^3 where it passes). `rfta` is the default: it reads the values as distances, as a level set or as bounds as it judges them (`reach`: how far, as a median fraction, values far from the zero set reach towards it, below 0.5 a level set; `covered`: the fraction of the spheres near it that others cover, above 0.5% bounds). Right = the reference's genus in one piece.\n"
    );
    let _ = writeln!(
        s,
        "## Summary\n\n| fields | N | method | mean Chamfer | against mc | right genus, one piece | more pieces than mc | sign errors |\n|---|---|---|---|---|---|---|---|"
    );
    for kind in [Kind::Network, Kind::Csg] {
        for &n in res {
            let mut methods: Vec<&str> = Vec::new();
            for r in rows.iter().filter(|r| r.kind == kind && r.n == n) {
                if !methods.contains(&r.method) {
                    methods.push(r.method);
                }
            }
            for m in methods {
                let these: Vec<&Row> = rows
                    .iter()
                    .filter(|r| r.kind == kind && r.n == n && r.method == m)
                    .collect();
                let k = these.len() as f64;
                let mean = these.iter().map(|r| r.chamfer).sum::<f64>() / k;
                let mc = these.iter().map(|r| r.mc_chamfer).sum::<f64>() / k;
                let more = rows
                    .iter()
                    .filter(|r| r.kind == kind && r.n == n && r.method == m)
                    .filter(|r| {
                        rows.iter().any(|o| {
                            o.field == r.field
                                && o.n == n
                                && o.method == "mc"
                                && r.summary.components > o.summary.components
                        })
                    })
                    .count();
                let errors: usize = these.iter().filter_map(|r| r.sign_errors).sum();
                let _ = writeln!(
                    s,
                    "| {} ({}) | {n} | {m} | {mean:.5} | {:.2}x | {} | {more} | {} |",
                    kind.name(),
                    these.len(),
                    mean / mc,
                    these.iter().filter(|r| right(r)).count(),
                    if m == "mc" {
                        "-".into()
                    } else {
                        errors.to_string()
                    },
                );
            }
        }
    }
    let _ = writeln!(
        s,
        "\n## Per field\n\n| field | N | method | Chamfer | against mc | faces | pieces | genus (reference) | seconds | reach | covered | read as |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in rows {
        let g = |v: Option<i64>| v.map_or("?".into(), |g| g.to_string());
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.5} | {:.2}x | {} | {} | {} ({}) | {:.2} | {} | {} | {} |",
            r.field,
            r.n,
            r.method,
            r.chamfer,
            r.chamfer / r.mc_chamfer,
            r.summary.n_faces,
            r.summary.components,
            g(r.summary.genus),
            g(r.reference.genus),
            r.seconds,
            (r.reading.as_ref().and_then(|f| f.reach)).map_or("-".into(), |x| format!("{x:.2}")),
            (r.reading.as_ref().and_then(|f| f.covered))
                .map_or("-".into(), |x| format!("{:.1}%", 100.0 * x)),
            r.reading
                .as_ref()
                .map_or("-".into(), |f| f.read_as.to_string()),
        );
    }
    s
}
