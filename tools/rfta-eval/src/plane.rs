//! `cargo xtask eval plane`: the 2D pipeline and marching squares on a folder of 2D inputs
//! (`NAME/gt2d.obj`, `NAME/sdf2d_n{N}.npy` on `linspace(-1, 1, N + 1)^2`), scored as the shared
//! reference `gpytoolbox2d.csv` is (Chamfer over 10^5 length-uniform samples each way, Hausdorff
//! over vertices, loops), with the reference's means beside ours.
//!
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use rfta_geom::glam::DVec2;
use rfta_geom::plane::Polylines;
use rfta_metrics::plane::{chamfer_2d, hausdorff_2d};

/// Samples per polyline set for the Chamfer distance (the reference's).
const SAMPLES: usize = 100_000;

/// One reference row: the shape, its Chamfer, CPU seconds and loop count.
struct RefRow {
    shape: String,
    chamfer: f64,
    cpu: f64,
    loops: usize,
    right: bool,
}

/// The reference's rows by (method, n).
type Reference = BTreeMap<(String, usize), Vec<RefRow>>;

/// The methods compared.
#[derive(Clone, Copy)]
enum Method {
    /// Marching squares.
    Ms,
    /// Reach for the Arcs, default parameters.
    Rfta,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Ms => "ms",
            Method::Rfta => "rfta",
        }
    }
}

struct Row2 {
    shape: String,
    n: usize,
    method: &'static str,
    cpu_seconds: f64,
    chamfer: f64,
    hausdorff: f64,
    loops: usize,
    gt_loops: usize,
    status: String,
}

/// `cargo xtask eval plane`'s arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Args {
    /// 2D inputs (`NAME/gt2d.obj`, `NAME/sdf2d_n{N}.npy`; default: the shared data's `inputs2d`).
    #[arg(long, value_name = "DIR")]
    inputs: Option<std::path::PathBuf>,
    /// Grid resolutions N.
    #[arg(long, value_delimiter = ',', default_value = "16,32,64")]
    res: Vec<usize>,
    /// The run's folder (default: `<target>/eval/2d-<pid>`).
    #[arg(long, value_name = "DIR")]
    out: Option<std::path::PathBuf>,
}

/// Runs the 2D evaluation as `a` says.
pub(crate) fn command(a: &Args) -> Result<()> {
    let data = crate::data_dir();
    let inputs = a.inputs.clone().unwrap_or(data.join("inputs2d"));
    let out = crate::out_dir(a.out.as_deref(), &format!("2d-{}", std::process::id()))?;
    run(
        &inputs,
        &a.res,
        &data.join("reference/gpytoolbox2d.csv"),
        &out,
    )
}

fn run(inputs: &Path, res: &[usize], reference: &Path, out: &Path) -> Result<()> {
    let mut names: Vec<String> = std::fs::read_dir(inputs)
        .with_context(|| format!("cannot read {}", inputs.display()))?
        .filter_map(|e| e.ok())
        .filter(|e| e.path().join("gt2d.obj").exists())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    anyhow::ensure!(
        !names.is_empty(),
        "no NAME/gt2d.obj under {}",
        inputs.display()
    );
    let mut rows = Vec::new();
    for name in &names {
        let gt = rfta_io::read_polylines(&inputs.join(name).join("gt2d.obj"))?;
        for &n in res {
            let path = inputs.join(name).join(format!("sdf2d_n{n}.npy"));
            let samples =
                rfta_io::read_sdf_2d(&path, Some((DVec2::splat(-1.0), DVec2::splat(1.0))))?;
            let grid = *samples.as_grid().context("a 2D input is a grid")?;
            for m in [Method::Ms, Method::Rfta] {
                let method = m.name();
                let cpu = crate::usage::process_usage().0;
                let result: Result<Polylines> = match m {
                    Method::Ms => Ok(rfta_mc::marching_squares(&grid, samples.values(), 0.0)),
                    Method::Rfta => rfta::plane::reconstruct(&samples, &rfta::Params::default())
                        .map(|r| r.curve)
                        .map_err(Into::into),
                };
                let cpu_seconds = crate::usage::process_usage().0 - cpu;
                // A curve with a defect is no result, whatever its accuracy.
                let result =
                    result.map_err(|e| format!("error: {e}")).and_then(|curve| {
                        match curve.unreferenced_vertices() {
                            0 => Ok(curve),
                            k => Err(crate::table::defect(k)),
                        }
                    });
                let row = match result {
                    Ok(curve) => Row2 {
                        shape: name.clone(),
                        n,
                        method,
                        cpu_seconds,
                        chamfer: chamfer_2d(&curve, &gt, SAMPLES),
                        hausdorff: hausdorff_2d(&curve, &gt),
                        loops: curve.loops(),
                        gt_loops: gt.loops(),
                        status: "ok".into(),
                    },
                    Err(status) => Row2 {
                        shape: name.clone(),
                        n,
                        method,
                        cpu_seconds,
                        chamfer: f64::NAN,
                        hausdorff: f64::NAN,
                        loops: 0,
                        gt_loops: gt.loops(),
                        status,
                    },
                };
                println!(
                    "{:<12} n={:<3} {:<5} chamfer {:.5} loops {}/{} cpu {:.3}s {}",
                    row.shape,
                    row.n,
                    row.method,
                    row.chamfer,
                    row.loops,
                    row.gt_loops,
                    row.cpu_seconds,
                    row.status
                );
                rows.push(row);
            }
        }
    }
    let mut csv =
        String::from("mesh,n,method,cpu_seconds,chamfer,hausdorff,loops,gt_loops,status\n");
    for r in &rows {
        let _ = writeln!(
            csv,
            "{},{},{},{:.4},{:.6},{:.6},{},{},{}",
            r.shape,
            r.n,
            r.method,
            r.cpu_seconds,
            r.chamfer,
            r.hausdorff,
            r.loops,
            r.gt_loops,
            r.status.replace(',', ";")
        );
    }
    std::fs::write(out.join("results.csv"), csv)?;
    let report = report(&rows, &reference_rows(reference, &names));
    std::fs::write(out.join("report.md"), &report)?;
    println!("{report}\nwrote {}", out.display());
    crate::table::no_defects(
        rows.iter()
            .map(|r| (format!("{} n={} {}", r.shape, r.n, r.method), &r.status)),
    )
}

/// The reference's rows for the shapes evaluated: (method, n) -> (chamfer, cpu, loops right).
fn reference_rows(path: &Path, names: &[String]) -> Reference {
    let mut out = Reference::new();
    let Ok(text) = std::fs::read_to_string(path) else {
        return out;
    };
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 10 || !names.iter().any(|n| n == f[0]) {
            continue;
        }
        let (Ok(n), Ok(cpu), Ok(chamfer), Ok(loops)) =
            (f[1].parse(), f[4].parse(), f[5].parse(), f[8].parse())
        else {
            continue;
        };
        out.entry((f[2].to_string(), n)).or_default().push(RefRow {
            shape: f[0].to_string(),
            chamfer,
            cpu,
            loops,
            right: f[8] == f[9],
        });
    }
    out
}

fn report(rows: &[Row2], reference: &Reference) -> String {
    let mut ns: Vec<usize> = rows.iter().map(|r| r.n).collect();
    ns.sort_unstable();
    ns.dedup();
    let mut s = String::from(
        "| samples | method | mean Chamfer | loops right | median CPU s | failed |\n|---|---|---|---|---|---|\n",
    );
    for &n in &ns {
        for method in ["ms", "rfta"] {
            let of: Vec<&Row2> = rows
                .iter()
                .filter(|r| r.n == n && r.method == method)
                .collect();
            let ok: Vec<&&Row2> = of.iter().filter(|r| r.status == "ok").collect();
            let mean = ok.iter().map(|r| r.chamfer).sum::<f64>() / ok.len().max(1) as f64;
            let right = ok.iter().filter(|r| r.loops == r.gt_loops).count();
            let mut cpu: Vec<f64> = of.iter().map(|r| r.cpu_seconds).collect();
            cpu.sort_by(f64::total_cmp);
            let median = cpu.get(cpu.len() / 2).copied().unwrap_or(f64::NAN);
            let _ = writeln!(
                s,
                "| {}^2 | {method} (rfta) | {mean:.5} | {right}/{} | {median:.3} | {} |",
                n + 1,
                of.len(),
                of.len() - ok.len()
            );
            if let Some(r) = reference.get(&(method.to_string(), n)) {
                let mean = r.iter().map(|x| x.chamfer).sum::<f64>() / r.len() as f64;
                let right = r.iter().filter(|x| x.right).count();
                let mut cpu: Vec<f64> = r.iter().map(|x| x.cpu).collect();
                cpu.sort_by(f64::total_cmp);
                let _ = writeln!(
                    s,
                    "| {}^2 | {method} (gpytoolbox) | {mean:.5} | {right}/{} | {:.3} | |",
                    n + 1,
                    r.len(),
                    cpu[cpu.len() / 2]
                );
            }
        }
    }
    s.push_str(
        "\nPer shape: Chamfer (loops; the ground truth's in the header), ours and gpytoolbox's.\n\n\
         | shape | samples | gt loops | ms | ms (gpytoolbox) | rfta | rfta (gpytoolbox) |\n\
         |---|---|---|---|---|---|---|\n",
    );
    let cell = |r: Option<&Row2>| {
        r.map_or("-".to_string(), |r| {
            format!("{:.5} ({})", r.chamfer, r.loops)
        })
    };
    let theirs = |method: &str, n: usize, shape: &str| {
        reference
            .get(&(method.to_string(), n))
            .and_then(|v| v.iter().find(|x| x.shape == shape))
            .map_or("-".to_string(), |x| {
                format!("{:.5} ({})", x.chamfer, x.loops)
            })
    };
    let mut shapes: Vec<&str> = rows.iter().map(|r| r.shape.as_str()).collect();
    shapes.dedup();
    for shape in shapes {
        for &n in &ns {
            let find = |m: &str| {
                rows.iter()
                    .find(|r| r.shape == shape && r.n == n && r.method == m)
            };
            let gt = find("rfta").map_or(0, |r| r.gt_loops);
            let _ = writeln!(
                s,
                "| {shape} | {}^2 | {gt} | {} | {} | {} | {} |",
                n + 1,
                cell(find("ms")),
                theirs("ms", n, shape),
                cell(find("rfta")),
                theirs("rfta", n, shape)
            );
        }
    }
    s
}
