//! `cargo xtask eval`: the paper's Table 2 on a folder of shapes, with marching cubes measured in
//! the same run, scored against the ground truth, next to the reference results when present.
//!
//! ```text
//! cargo xtask eval [--inputs DIR | --meshes DIR] [--res 10,20,30] [--methods mc,rfta,rfta-default,rfta-paper,rfta-genus]
//!                  [--samples N] [--depth D] [--owner-band K] [--raster-resolution R] [--rounds R] [--seed S]
//!                  [--initial gradient|raster] [--keep-cavities] [--quick]
//!                  [--out DIR]
//! cargo xtask eval --scenario noise,clamp,scattered,swept,collision,params [--levels L,..] [--inputs DIR] [--quick]
//! ```
//!
//! `--scenario` runs the paper's Figures 23 (noise), 24 (clamp), 25 (`swept`), 22 (`collision`)
//! and 11 to 13 (`params`: raster, batch, rounds), and scattered samples (`scattered`), instead of
//! Table 2, each into `<out>/<scenario>/` ([`scenario`]).
//!
//! `--depth D` runs every rfta method's screened Poisson solves at octree depth `D` instead of the
//! depth matched to the sample spacing, and `--owner-band K` gives points to the spheres within
//! `K` sample spacings of the surface (0: to all, as the reference): the tables of docs/speed.md.
//!
//! `--inputs DIR` takes prepared inputs (`NAME/gt.obj`, `NAME/sdf_n{N}.npy`) as they are; a
//! missing grid is sampled from `gt.obj`. `--meshes DIR` takes raw meshes, normalises each (box
//! centred, longest side 1, a rotation seeded by the shape's name) and samples its SDF on
//! `linspace(-1, 1, N + 1)^3` with `rfta sample`'s code. Output: `target/eval/<run>/results.csv`,
//! `report.md`, `chamfer.svg` and `contact_sheet.png`.

mod adaptive;
mod plane;
mod render;
mod report;
mod scenario;
mod swept;
mod vdb;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta_geom::{Grid, Layout, SdfSamples, TriMesh, glam::DMat3, glam::DVec3, rng};
use rfta_mesh::MeshIndex;

/// One shape of the evaluation.
pub(crate) struct Shape {
    pub(crate) name: String,
    pub(crate) gt: TriMesh,
    /// Where prepared grids live (`--inputs`), if any.
    dir: Option<PathBuf>,
}

/// One (shape, resolution, method) result.
#[derive(Debug, Clone)]
pub(crate) struct Row {
    pub(crate) shape: String,
    pub(crate) n: usize,
    pub(crate) method: String,
    pub(crate) seconds: f64,
    /// CPU seconds of this process (all threads) while the method ran.
    pub(crate) cpu_seconds: f64,
    pub(crate) chamfer: f64,
    pub(crate) hausdorff: f64,
    pub(crate) e_sdf: f64,
    pub(crate) watertight: bool,
    pub(crate) genus: Option<i64>,
    pub(crate) gt_genus: Option<i64>,
    pub(crate) components: usize,
    /// Components facing inward (`rfta_mesh::cavities`), and the ground truth's.
    pub(crate) cavities: usize,
    pub(crate) gt_cavities: usize,
    /// Agreement with every input sample (`rfta::consistency`); `None` when the method failed.
    pub(crate) consistency: Option<rfta::Consistency>,
    pub(crate) status: String,
}

/// Overrides of the rfta methods' parameters by `rfta::Params`' serde names (`--depth D`,
/// `--owner-band K`, `--raster-resolution R`, `--keep-cavities`), for the tables of docs/speed.md
/// and docs/faithfulness.md.
type Tuning = serde_json::Map<String, serde_json::Value>;

struct Args {
    inputs: Option<PathBuf>,
    meshes: Option<PathBuf>,
    res: Vec<usize>,
    methods: Vec<String>,
    samples: usize,
    tuning: Tuning,
    quick: bool,
    out: Option<PathBuf>,
    /// `--scenario NAME[,NAME]`: scenarios instead of Table 2 ([`scenario`]).
    scenarios: Vec<scenario::Scenario>,
    /// `--levels L[,L]`: the scenarios' levels instead of each one's own.
    levels: Option<Vec<f64>>,
    /// `--2d`: the 2D pipeline on 2D inputs ([`plane`]).
    plane: bool,
    /// `--res` was given.
    res_given: bool,
    /// `--vdb`: rfta against OpenVDB's volumeToMesh on level sets ([`vdb`]).
    vdb: bool,
    /// `--scenario adaptive`: reconstruction from the ground truth's SDF under budgets
    /// (`--levels`), against grids of as many points ([`adaptive`]).
    adaptive: bool,
}

/// The methods `--methods` takes; all but the last run without it. `rfta-genus` is the default
/// preset told the ground truth's genus (`rfta::Params::genus`), as a user who knows it would.
const METHODS: [&str; 5] = ["mc", "rfta", "rfta-default", "rfta-paper", "rfta-genus"];

fn parse(args: &[String]) -> Result<Args> {
    let mut a = Args {
        inputs: None,
        meshes: None,
        res: vec![10, 20, 30],
        methods: METHODS[..4].iter().map(|m| m.to_string()).collect(),
        samples: 1_000_000,
        tuning: Tuning::default(),
        quick: false,
        out: None,
        scenarios: Vec::new(),
        levels: None,
        plane: false,
        res_given: false,
        vdb: false,
        adaptive: false,
    };
    let mut it = args.iter();
    while let Some(flag) = it.next() {
        let mut value = || it.next().with_context(|| format!("{flag} needs a value"));
        match flag.as_str() {
            "--inputs" => a.inputs = Some(PathBuf::from(value()?)),
            "--meshes" => a.meshes = Some(PathBuf::from(value()?)),
            "--2d" => a.plane = true,
            "--vdb" => a.vdb = true,
            "--res" => {
                a.res_given = true;
                a.res = value()?
                    .split(',')
                    .map(|t| t.trim().parse::<usize>())
                    .collect::<Result<_, _>>()
                    .context("--res takes numbers like 10,20,30")?;
            }
            "--methods" => {
                a.methods = value()?.split(',').map(|t| t.trim().to_string()).collect();
                if let Some(bad) = a.methods.iter().find(|m| !METHODS.contains(&m.as_str())) {
                    bail!("unknown method '{bad}' (known: {})", METHODS.join(", "));
                }
            }
            "--samples" => a.samples = value()?.parse().context("--samples takes a number")?,
            "--depth"
            | "--owner-band"
            | "--raster-resolution"
            | "--raster-res"
            | "--rounds"
            | "--seed" => {
                let name = match flag.as_str() {
                    "--raster-res" => "raster_resolution".to_string(),
                    flag => flag.trim_start_matches('-').replace('-', "_"),
                };
                let number: f64 = value()?
                    .parse()
                    .with_context(|| format!("{flag} takes a number"))?;
                let value = if number.fract() == 0.0 && number >= 0.0 {
                    serde_json::Value::from(number as u64)
                } else {
                    serde_json::Value::from(number)
                };
                a.tuning.insert(name, value);
            }
            "--keep-cavities" => {
                a.tuning.insert("keep_cavities".into(), true.into());
            }
            "--initial" => {
                a.tuning.insert("initial".into(), value()?.clone().into());
            }
            "--quick" => a.quick = true,
            "--scenario" => {
                for name in value()?.split(',').map(str::trim) {
                    if name == "params" {
                        a.scenarios.extend(scenario::Scenario::PARAMS);
                        continue;
                    }
                    if name == "adaptive" {
                        a.adaptive = true;
                        continue;
                    }
                    let Some(sc) = scenario::Scenario::ALL
                        .into_iter()
                        .find(|s| s.name() == name)
                    else {
                        let known: Vec<&str> =
                            scenario::Scenario::ALL.iter().map(|s| s.name()).collect();
                        bail!(
                            "unknown scenario '{name}' (known: {}, params, adaptive)",
                            known.join(", ")
                        );
                    };
                    a.scenarios.push(sc);
                }
            }
            "--levels" => {
                let levels: Vec<f64> = value()?
                    .split(',')
                    .map(|t| t.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .context("--levels takes numbers like 0.005,0.01 (noise) or 4,2,1 (clamp)")?;
                if levels.iter().any(|p| !p.is_finite() || *p < 0.0) {
                    bail!("--levels must be non-negative numbers");
                }
                a.levels = Some(levels);
            }
            "--out" => a.out = Some(PathBuf::from(value()?)),
            other => bail!("unknown eval option '{other}'"),
        }
    }
    if a.inputs.is_some() && a.meshes.is_some() {
        bail!("give --inputs or --meshes, not both");
    }
    if a.res.contains(&0) {
        bail!("--res values must be positive");
    }
    Ok(a)
}

pub(crate) fn run(root: &Path, args: &[String]) -> Result<()> {
    let mut a = parse(args)?;
    let data = std::env::var_os("RFTA_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or(root.join("../shared/data"));
    if a.plane {
        let inputs = a.inputs.clone().unwrap_or(data.join("inputs2d"));
        let res = if a.res_given {
            a.res.clone()
        } else {
            vec![16, 32, 64]
        };
        let out = a.out.clone().unwrap_or_else(|| {
            root.join("target/eval")
                .join(format!("2d-{}", std::process::id()))
        });
        std::fs::create_dir_all(&out)
            .with_context(|| format!("cannot create {}", out.display()))?;
        return plane::run(
            &inputs,
            &res,
            &data.join("reference/gpytoolbox2d.csv"),
            &out,
        );
    }
    if a.inputs.is_none() && a.meshes.is_none() {
        a.inputs = Some(data.join("inputs"));
    }
    let (mut shapes, mut unreadable) = match (&a.inputs, &a.meshes) {
        (Some(dir), _) => load_inputs(dir)?,
        (_, Some(dir)) => load_meshes(dir)?,
        _ => unreachable!("one of them is set above"),
    };
    if a.adaptive {
        let budgets: Vec<usize> = a
            .levels
            .clone()
            .unwrap_or(adaptive::BUDGETS.to_vec())
            .iter()
            .map(|&b| b as usize)
            .collect();
        let out = a.out.clone().unwrap_or_else(|| {
            root.join("target/eval")
                .join(format!("adaptive-{}", std::process::id()))
        });
        adaptive::run(&shapes, &budgets, a.samples, &a.tuning, &out)?;
        println!("wrote {}", out.display());
        return Ok(());
    }
    if a.vdb {
        let res = if a.res_given {
            a.res.clone()
        } else {
            vec![50, 100]
        };
        let out = a.out.clone().unwrap_or_else(|| {
            root.join("target/eval")
                .join(format!("vdb-{}", std::process::id()))
        });
        return vdb::run(&shapes, &res, a.samples, &out);
    }
    if a.quick {
        // One small shape, two resolutions, fewer samples: the CI smoke run (a scenario: one
        // resolution, two levels).
        unreadable.clear();
        shapes.sort_by_key(|s| s.gt.n_faces());
        shapes.truncate(1);
        a.res = vec![10, 20];
        a.samples = a.samples.min(100_000);
        if !a.scenarios.is_empty() {
            a.res = vec![20];
        }
    }
    if shapes.is_empty() {
        bail!("no shapes found");
    }
    let run_id = format!(
        "{}-{}",
        if a.quick { "quick" } else { "full" },
        std::process::id()
    );
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| root.join("target/eval").join(&run_id));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    if !a.scenarios.is_empty() {
        for (name, why) in &unreadable {
            eprintln!("warning: skipping {name}: {why}");
        }
        for &sc in &a.scenarios {
            let levels = match (&a.levels, a.quick) {
                (Some(l), _) => l.clone(),
                (None, true) => sc.quick_levels(),
                (None, false) => sc.levels(),
            };
            let dir = out.join(sc.name());
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            scenario::run(sc, &shapes, &a.res, &levels, a.samples, &dir)?;
            println!("wrote {}", dir.display());
        }
        return Ok(());
    }

    let jobs = shapes.len() * a.res.len() * a.methods.len();
    let bar = indicatif::ProgressBar::new(jobs as u64);
    let mut rows = Vec::new();
    // A shape that cannot be read is a row per job, so the report shows it.
    for (name, why) in &unreadable {
        eprintln!("warning: skipping {name}: {why}");
        for &n in &a.res {
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
        for &n in &a.res {
            let (grid, values) = grid_for(shape, &gt_index, n)?;
            let positions: Vec<DVec3> = (0..grid.len()).map(|i| grid.position(i)).collect();
            let samples = SdfSamples::grid(grid, values.clone())
                .with_context(|| format!("{} n={n}: grid samples", shape.name))?;
            for method in &a.methods {
                bar.set_message(format!("{} n={n} {method}", shape.name));
                let t = Instant::now();
                let cpu = crate::bench::process_usage().0;
                let result = run_method(method, &grid, &values, &a.tuning, gt_summary.genus);
                let seconds = t.elapsed().as_secs_f64();
                let cpu_seconds = crate::bench::process_usage().0 - cpu;
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
                        let chamfer = rfta_metrics::chamfer_indexed(gt, rec, a.samples, 1);
                        let hausdorff = rfta_metrics::hausdorff_indexed(gt, rec);
                        let e_sdf = rfta_metrics::sdf_energy_indexed(&positions, &values, &index);
                        let consistency = rfta::consistency::measure(&samples, &mesh, None)
                            .with_context(|| format!("{} n={n} {method}", shape.name))?;
                        if method == "mc" || n == *a.res.last().unwrap_or(&n) {
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
    let reference = report::read_reference(&data.join("reference/gpytoolbox.csv"));
    report::write_csv(&out.join("results.csv"), &rows)?;
    report::write_markdown(
        &out.join("report.md"),
        &rows,
        &reference,
        &a.res,
        &a.methods,
        a.samples,
    )?;
    report::write_svg(
        &out.join("chamfer.svg"),
        &rows,
        &reference,
        &a.res,
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
    tuning: &Tuning,
    gt_genus: Option<i64>,
) -> Result<TriMesh, String> {
    match method {
        "mc" => Ok(rfta_mc::marching_cubes(grid, values, 0.0)),
        "rfta" | "rfta-default" | "rfta-paper" | "rfta-genus" => {
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

/// The grid of a shape at resolution `n`: the prepared `sdf_n{n}.npy` if present, else sampled.
pub(crate) fn grid_for(shape: &Shape, gt: &MeshIndex, n: usize) -> Result<(Grid, Vec<f64>)> {
    if let Some(dir) = &shape.dir {
        let path = dir.join(format!("sdf_n{n}.npy"));
        if path.is_file() {
            let raw = rfta_io::read_sdf(&path, None)?;
            if let Layout::Grid(g) = raw.layout {
                return Ok((g, raw.values));
            }
        }
    }
    let grid = Grid::cube(n, -1.0, 1.0)?;
    let values = gt.signed_distances(
        &(0..grid.len())
            .map(|i| grid.position(i))
            .collect::<Vec<_>>(),
    );
    Ok((grid, values))
}

/// Shapes that load, and `(name, reason)` for those that do not.
type Loaded = (Vec<Shape>, Vec<(String, String)>);

pub(crate) fn load_inputs(dir: &Path) -> Result<Loaded> {
    let mut shapes = Vec::new();
    let mut unreadable = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("gt.obj").is_file())
        .collect();
    entries.sort();
    for p in entries {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        match rfta_io::read_mesh(&p.join("gt.obj")) {
            Ok(gt) => shapes.push(Shape {
                name,
                gt,
                dir: Some(p),
            }),
            Err(e) => unreadable.push((name, e.to_string())),
        }
    }
    Ok((shapes, unreadable))
}

fn load_meshes(dir: &Path) -> Result<Loaded> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| rfta_io::MeshFormat::from_path(p).is_ok())
        .collect();
    files.sort();
    let mut shapes = Vec::new();
    let mut unreadable = Vec::new();
    for p in files {
        let name = p
            .file_stem()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        match rfta_io::read_mesh(&p) {
            Ok(mut gt) if !gt.is_empty() => {
                normalize(&mut gt, &name);
                shapes.push(Shape {
                    name,
                    gt,
                    dir: None,
                });
            }
            Ok(_) => unreadable.push((name, "the mesh has no triangles".into())),
            Err(e) => unreadable.push((name, e.to_string())),
        }
    }
    Ok((shapes, unreadable))
}

/// The paper's preparation: bounding box centred at the origin, longest side 1, then a rotation
/// about a random axis by a random angle, seeded by the shape's name (Sellán et al. 2024, §5).
fn normalize(mesh: &mut TriMesh, name: &str) {
    let b = mesh.bounds();
    let (center, scale) = (b.center(), b.longest_side().max(f64::MIN_POSITIVE));
    let seed = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, c| {
        (h ^ c as u64).wrapping_mul(0x100_0000_01b3)
    });
    let mut r = rng::Rng::new(seed);
    let axis = DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()).normalize_or(DVec3::Z);
    let rot = DMat3::from_axis_angle(axis, r.next_f64() * std::f64::consts::TAU);
    mesh.map_vertices(|v| rot * ((v - center) / scale));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalize_centres_scales_and_rotates_by_name() {
        let mut a = rfta_geom::shapes::cuboid(DVec3::new(2.0, 1.0, 0.5));
        a.map_vertices(|v| v + DVec3::new(5.0, -3.0, 1.0));
        let mut b = a.clone();
        normalize(&mut a, "box");
        normalize(&mut b, "box");
        assert_eq!(a, b, "the rotation is seeded by the name");
        // Rotation keeps the centre at the origin and the longest edge (4 units, scaled to 1) at 1.
        let c = a.vertices.iter().copied().sum::<DVec3>() / a.n_vertices() as f64;
        assert!(c.length() < 1e-12);
        let longest = (0..a.n_vertices()).flat_map(|i| (0..a.n_vertices()).map(move |j| (i, j)));
        let diag = longest
            .map(|(i, j)| a.vertices[i].distance(a.vertices[j]))
            .fold(0.0, f64::max);
        // The box's diagonal sqrt(16 + 4 + 1) / 4.
        assert!((diag - 21f64.sqrt() / 4.0).abs() < 1e-12, "{diag}");
        let mut other = b.clone();
        normalize(&mut other, "another name");
        assert_ne!(other, b);
    }
}
