//! Table 2 of the paper on a folder of shapes, with marching cubes measured in the same run,
//! scored against the ground truth, next to the reference results when present (what
//! `cargo xtask eval` runs without a mode). Output: `results.csv`, `report.md`, `chamfer.svg`
//! and `contact_sheet.png` in the run's folder.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta_geom::{Grid, SdfSamples, TriMesh, glam::DVec3};
use rfta_mesh::MeshIndex;

use crate::report::{self, Row};
use crate::shapes::{Shape, Source, grid_for};
use crate::{chart, render};

/// The methods `--methods` takes; the first four run without it. `rfta-genus` is the default
/// preset told the ground truth's genus (`rfta::Params::genus`), as a user who knows it would;
/// `rfta-default-unsimplified` the default's mesh before simplification.
const METHODS: [&str; 6] = [
    "mc",
    "rfta",
    "rfta-default",
    "rfta-paper",
    "rfta-genus",
    "rfta-default-unsimplified",
];

/// `cargo xtask eval [table]`'s arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Args {
    #[command(flatten)]
    pub(crate) source: Source,
    /// Grid resolutions N (N + 1 samples per axis).
    #[arg(long, value_delimiter = ',', default_value = "10,20,30", value_parser = clap::value_parser!(usize))]
    pub(crate) res: Vec<usize>,
    /// Methods: mc, rfta (fast preset), rfta-default, rfta-paper, rfta-genus (the default preset
    /// told the ground truth's genus) and rfta-default-unsimplified (the default's mesh before
    /// simplification); the last two run only when named.
    #[arg(long, value_delimiter = ',', default_value = "mc,rfta,rfta-default,rfta-paper",
          value_parser = clap::builder::PossibleValuesParser::new(METHODS))]
    pub(crate) methods: Vec<String>,
    #[command(flatten)]
    pub(crate) scoring: Scoring,
    #[command(flatten)]
    pub(crate) tuning: Tuning,
    /// One small shape at N = 10 and 20 and fewer Chamfer samples: the CI smoke run.
    #[arg(long)]
    pub(crate) quick: bool,
    /// The run's folder (default: `<target>/eval/<quick|full>-<pid>`).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<std::path::PathBuf>,
}

/// How outputs are scored.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Scoring {
    /// Points sampled on each surface for the Chamfer distance.
    #[arg(long, default_value_t = 1_000_000)]
    pub(crate) samples: usize,
}

/// Overrides of the rfta methods' parameters (`rfta::Params`' serde names), for the tables of
/// docs/speed.md and docs/faithfulness.md.
#[derive(Debug, Clone, Default, clap::Args)]
pub(crate) struct Tuning {
    /// The screened Poisson depth of every rfta method's solves (default: matched to the spacing).
    #[arg(long)]
    depth: Option<u32>,
    /// Spheres within K spacings of the surface own points (0: all, as the reference).
    #[arg(long, value_name = "K")]
    owner_band: Option<f64>,
    /// The rasterization's resolution.
    #[arg(long, alias = "raster-res", value_name = "R")]
    raster_resolution: Option<usize>,
    /// Fine-tuning rounds.
    #[arg(long)]
    rounds: Option<usize>,
    /// The seed of the random batches.
    #[arg(long)]
    seed: Option<u64>,
    /// How the initial points are found: gradient or raster.
    #[arg(long, value_parser = ["gradient", "raster"])]
    initial: Option<String>,
    /// Keep the cavities the samples leave open.
    #[arg(long)]
    keep_cavities: bool,
    /// How far the simplified surface may lie from the unsimplified one, in sample spacings.
    #[arg(long, value_name = "SPACINGS")]
    simplify_tolerance: Option<f64>,
}

impl Tuning {
    /// The overrides as `rfta::Params::with_options` takes them.
    pub(crate) fn options(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        let mut put = |k: &str, v: Option<serde_json::Value>| {
            if let Some(v) = v {
                m.insert(k.to_string(), v);
            }
        };
        put("depth", self.depth.map(Into::into));
        put("owner_band", self.owner_band.map(Into::into));
        put("raster_resolution", self.raster_resolution.map(Into::into));
        put("rounds", self.rounds.map(Into::into));
        put("seed", self.seed.map(Into::into));
        put("initial", self.initial.clone().map(Into::into));
        put("keep_cavities", self.keep_cavities.then_some(true.into()));
        put(
            "simplify_tolerance",
            self.simplify_tolerance.map(Into::into),
        );
        m
    }
}

/// Runs Table 2 as `a` says.
pub(crate) fn run(a: &Args) -> Result<()> {
    let (mut shapes, mut unreadable) = a.source.load()?;
    let (mut res, mut chamfer_samples) = (a.res.clone(), a.scoring.samples);
    if a.quick {
        // One small shape, two resolutions, fewer samples: the CI smoke run.
        unreadable.clear();
        crate::shapes::smallest(&mut shapes);
        res = vec![10, 20];
        chamfer_samples = chamfer_samples.min(100_000);
    }
    if shapes.is_empty() {
        bail!("no shapes found");
    }
    let run_id = format!(
        "{}-{}",
        if a.quick { "quick" } else { "full" },
        std::process::id()
    );
    let out = crate::out_dir(a.out.as_deref(), &run_id)?;
    let tuning = a.tuning.options();
    let jobs = shapes.len() * res.len() * a.methods.len();
    let bar = indicatif::ProgressBar::new(jobs as u64);
    let mut rows = Vec::new();
    // A shape that cannot be read is a row per job, so the report shows it.
    for (name, why) in &unreadable {
        eprintln!("warning: skipping {name}: {why}");
        for &n in &res {
            for method in &a.methods {
                let status = format!("unreadable input: {why}");
                rows.push(Row {
                    shape: name.clone(),
                    n,
                    method: method.clone(),
                    seconds: 0.0,
                    cpu_seconds: 0.0,
                    chamfer: f64::NAN,
                    hausdorff: f64::NAN,
                    e_sdf: f64::NAN,
                    watertight: false,
                    genus: None,
                    gt_genus: None,
                    components: 0,
                    faces: 0,
                    cavities: 0,
                    gt_cavities: 0,
                    consistency: None,
                    status,
                });
            }
        }
    }
    let mut renders = Vec::new();
    for shape in &shapes {
        let gt_summary = rfta_metrics::MeshSummary::of(&shape.gt);
        let gt_index = MeshIndex::new(&shape.gt)
            .with_context(|| format!("{}: empty ground truth", shape.name))?;
        let mut shape_renders = vec![(format!("{} GT", shape.name), shape.gt.clone())];
        for &n in &res {
            let (grid, values) = grid_for(shape, &gt_index, n)?;
            let positions: Vec<DVec3> = (0..grid.len()).map(|i| grid.position(i)).collect();
            let samples = SdfSamples::grid(grid, values.clone())
                .with_context(|| format!("{} n={n}: grid samples", shape.name))?;
            for method in &a.methods {
                bar.set_message(format!("{} n={n} {method}", shape.name));
                let t = Instant::now();
                let cpu = crate::usage::process_usage().0;
                let result = run_method(method, &grid, &values, &tuning, gt_summary.genus);
                let seconds = t.elapsed().as_secs_f64();
                let cpu_seconds = crate::usage::process_usage().0 - cpu;
                let row = match result {
                    Ok(mesh) if mesh.unreferenced_vertices() > 0 => failed_row(
                        shape,
                        n,
                        method,
                        (seconds, cpu_seconds),
                        gt_summary.genus,
                        defect(mesh.unreferenced_vertices()),
                    ),
                    Ok(mesh) if !mesh.is_empty() => {
                        let s = rfta_metrics::MeshSummary::of(&mesh);
                        let index = MeshIndex::new(&mesh)?;
                        let (gt, rec) = ((&shape.gt, &gt_index), (&mesh, &index));
                        let chamfer = rfta_metrics::chamfer_indexed(gt, rec, chamfer_samples, 1);
                        let hausdorff = rfta_metrics::hausdorff_indexed(gt, rec);
                        let e_sdf = rfta_metrics::sdf_energy_indexed(&positions, &values, &index);
                        let consistency = rfta::consistency::measure(&samples, &mesh, None)
                            .with_context(|| format!("{} n={n} {method}", shape.name))?;
                        if method == "mc" || n == *res.last().unwrap_or(&n) {
                            shape_renders.push((format!("{method} n={n}"), mesh.clone()));
                        }
                        Row {
                            shape: shape.name.clone(),
                            n,
                            method: method.clone(),
                            seconds,
                            cpu_seconds,
                            chamfer,
                            hausdorff,
                            e_sdf,
                            watertight: s.watertight,
                            genus: s.genus,
                            gt_genus: gt_summary.genus,
                            components: s.components,
                            faces: mesh.n_faces(),
                            cavities: s.cavities,
                            gt_cavities: gt_summary.cavities,
                            consistency: Some(consistency),
                            status: "ok".into(),
                        }
                    }
                    Ok(_) => failed_row(
                        shape,
                        n,
                        method,
                        (seconds, cpu_seconds),
                        gt_summary.genus,
                        "empty mesh".into(),
                    ),
                    Err(e) => failed_row(
                        shape,
                        n,
                        method,
                        (seconds, cpu_seconds),
                        gt_summary.genus,
                        e,
                    ),
                };
                rows.push(row);
                bar.inc(1);
            }
        }
        renders.push(shape_renders);
    }
    bar.finish_and_clear();
    let reference = report::read_reference(&crate::data_dir().join("reference/gpytoolbox.csv"));
    report::write_csv(&out.join("results.csv"), &rows)?;
    report::write_markdown(
        &out.join("report.md"),
        &rows,
        &reference,
        &res,
        &a.methods,
        chamfer_samples,
    )?;
    chart::write_svg(
        &out.join("chamfer.svg"),
        &rows,
        &reference,
        &res,
        &a.methods,
    )?;
    render::write_contact_sheet(&out.join("contact_sheet.png"), &renders)?;
    println!("wrote {}", out.display());
    no_defects(
        rows.iter()
            .map(|r| (format!("{} n={} {}", r.shape, r.n, r.method), &r.status)),
    )
}

/// The status of an output that is not a valid result whatever its accuracy: `count` vertices
/// that no face (or edge) uses. Every output the evaluation scores is checked for it.
pub(crate) fn defect(count: usize) -> String {
    format!("{DEFECT} {count} unreferenced vertices")
}

/// How [`defect`]'s statuses begin.
const DEFECT: &str = "defect:";

/// Fails the run, after its reports are written, when any output had a [`defect`].
pub(crate) fn no_defects<'a>(rows: impl Iterator<Item = (String, &'a String)>) -> Result<()> {
    let bad: Vec<String> = rows
        .filter(|(_, status)| status.starts_with(DEFECT))
        .map(|(row, status)| format!("{row}: {status}"))
        .collect();
    if !bad.is_empty() {
        bail!("{} output(s) with a defect:\n{}", bad.len(), bad.join("\n"));
    }
    Ok(())
}

fn failed_row(
    shape: &Shape,
    n: usize,
    method: &str,
    (seconds, cpu_seconds): (f64, f64),
    gt_genus: Option<i64>,
    why: String,
) -> Row {
    Row {
        shape: shape.name.clone(),
        n,
        method: method.to_string(),
        seconds,
        cpu_seconds,
        chamfer: f64::NAN,
        hausdorff: f64::NAN,
        e_sdf: f64::NAN,
        watertight: false,
        genus: None,
        gt_genus,
        components: 0,
        faces: 0,
        cavities: 0,
        gt_cavities: 0,
        consistency: None,
        status: why,
    }
}

/// Runs one method; an error is recorded in the row's status, so the run goes on.
fn run_method(
    method: &str,
    grid: &Grid,
    values: &[f64],
    tuning: &serde_json::Map<String, serde_json::Value>,
    gt_genus: Option<i64>,
) -> Result<TriMesh, String> {
    match method {
        "mc" => Ok(rfta_mc::marching_cubes(grid, values, 0.0)),
        "rfta" | "rfta-default" | "rfta-paper" | "rfta-genus" | "rfta-default-unsimplified" => {
            // `rfta-genus` is the default preset told the genus; the others name their preset.
            let base = match method {
                "rfta-genus" => rfta::Params {
                    genus: Some(
                        gt_genus
                            .and_then(|g| usize::try_from(g).ok())
                            .ok_or("rfta-genus needs the ground truth's genus")?,
                    ),
                    ..rfta::Params::default()
                },
                _ => crate::method::rfta_params(method)
                    .ok_or_else(|| format!("unknown method {method}"))?,
            };
            let params = base
                .with_options(tuning.clone())
                .map_err(|e| e.to_string())?;
            let samples =
                rfta_geom::SdfSamples::grid(*grid, values.to_vec()).map_err(|e| e.to_string())?;
            rfta::reconstruct(&samples, &params)
                .map(|r| r.mesh)
                .map_err(|e| e.to_string())
        }
        other => Err(format!("unknown method {other}")),
    }
}
