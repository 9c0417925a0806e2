//! `cargo xtask eval vdb`: rfta against OpenVDB's own mesher on OpenVDB level sets.
//!
//! Each dev shape becomes two narrow-band level sets (half width 3 voxels) at voxel sizes `2 / N`
//! for each `--res N` (the spacing of an `N + 1`-point grid over `[-1, 1]`), both made and written
//! as `.vdb` files by OpenVDB: `mesh`, OpenVDB's own mesh-to-volume conversion of the ground
//! truth, and `exact`, the exact signed distance on the voxels clamped to the band. OpenVDB
//! meshes each with `volumeToMesh` (isovalue 0, adaptivity 0), and rfta reconstructs the same
//! file as `rfta reconstruct` reads it (the dense band, the background as the clamp, the
//! default preset). Both meshes are scored against the
//! ground truth with the evaluation's Chamfer distance. OpenVDB's side runs in the system Python
//! of Debian's `python3-openvdb` (`openvdb.py`, written into the output folder); its times are
//! OpenVDB's own calls, rfta's the whole reconstruction (wall and CPU seconds of this process).
//!
//! Output: `<out>/results.csv` and `<out>/report.md`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta_geom::TriMesh;
use rfta_mesh::MeshIndex;
use rfta_metrics::MeshSummary;

use crate::shapes::{Shape, Source};

const SCRIPT: &str = include_str!("openvdb.py");
/// The two level sets of each shape and voxel size (see the module docs).
const SOURCES: [&str; 2] = ["mesh", "exact"];

/// One (shape, voxel size) comparison.
struct VdbRow {
    shape: String,
    n: usize,
    /// "mesh" (OpenVDB's mesh to volume) or "exact" (the exact SDF in the band).
    source: String,
    active: u64,
    dense: usize,
    to_volume: f64,
    vtm_seconds: f64,
    vtm_chamfer: f64,
    vtm: MeshSummary,
    rfta_seconds: f64,
    rfta_cpu: f64,
    rfta_chamfer: f64,
    rfta: MeshSummary,
    gt_genus: Option<i64>,
}

/// The Python that has `pyopenvdb`: `RFTA_OPENVDB_PYTHON`, else the system's.
fn python() -> Result<PathBuf> {
    let p =
        std::env::var_os("RFTA_OPENVDB_PYTHON").map_or("/usr/bin/python3".into(), PathBuf::from);
    let ok = std::process::Command::new(&p)
        .args(["-c", "import pyopenvdb"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        bail!(
            "eval vdb needs OpenVDB's Python module: {} cannot import pyopenvdb (Debian: apt-get \
             install python3-openvdb; or set RFTA_OPENVDB_PYTHON)",
            p.display()
        );
    }
    Ok(p)
}

/// `cargo xtask eval vdb`'s arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Args {
    #[command(flatten)]
    source: Source,
    /// Voxel sizes 2/N.
    #[arg(long, value_delimiter = ',', default_value = "50,100")]
    res: Vec<usize>,
    #[command(flatten)]
    scoring: crate::table::Scoring,
    /// The run's folder (default: `<target>/eval/vdb-<pid>`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// Runs the OpenVDB comparison as `a` says.
pub(crate) fn command(a: &Args) -> Result<()> {
    let (shapes, _) = a.source.load()?;
    let out = crate::out_dir(a.out.as_deref(), &format!("vdb-{}", std::process::id()))?;
    run(&shapes, &a.res, a.scoring.samples, &out)
}

fn run(shapes: &[Shape], res: &[usize], samples: usize, out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let python = python()?;
    let script = out.join("openvdb.py");
    std::fs::write(&script, SCRIPT)?;
    let mut jobs = Vec::new();
    for shape in shapes {
        let gt = out.join(format!("{}-gt.obj", shape.name));
        rfta_io::write_mesh(&gt, &shape.gt)?;
        let index = MeshIndex::new(&shape.gt)?;
        for &n in res {
            let voxel = 2.0 / n as f64;
            // The exact SDF on the voxels of the shape's box and 4 more (the band is 3).
            let b = shape.gt.bounds();
            let lo = (b.min / voxel).floor() - 4.0;
            let hi = (b.max / voxel).ceil() + 4.0;
            let dims = ((hi - lo).to_array()).map(|d| d as usize + 1);
            let grid =
                rfta_geom::Grid::new(dims, lo * voxel, rfta_geom::glam::DVec3::splat(voxel))?;
            let sdf = out.join(format!("{}-n{n}-sdf.npy", shape.name));
            let values = index.signed_distances(
                &(0..grid.len())
                    .map(|i| grid.position(i))
                    .collect::<Vec<_>>(),
            );
            let mut bytes = Vec::new();
            rfta_io::write_npy_f64(&mut bytes, &dims, &values)?;
            std::fs::write(&sdf, bytes)?;
            jobs.push(serde_json::json!({
                "name": shape.name,
                "gt": gt,
                "voxel": voxel,
                "sdf": sdf,
                "lo": lo.to_array().map(|v| v as i64),
                "out": out.join(format!("{}-n{n}", shape.name)),
            }));
        }
    }
    let jobs_file = out.join("jobs.json");
    std::fs::write(&jobs_file, serde_json::to_string_pretty(&jobs)?)?;
    println!(
        "==> OpenVDB: {} level sets and their volumeToMesh meshes",
        2 * jobs.len()
    );
    let o = std::process::Command::new(&python)
        .arg(&script)
        .arg(&jobs_file)
        .output()
        .context("running OpenVDB's Python")?;
    if !o.status.success() {
        bail!(
            "{} failed:\n{}",
            script.display(),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(serde_json::from_str)
        .collect::<Result<_, _>>()
        .context("OpenVDB's Python printed something other than JSON lines")?;
    let mut rows = Vec::new();
    for shape in shapes {
        let index = MeshIndex::new(&shape.gt)?;
        let gt_genus = MeshSummary::of(&shape.gt).genus;
        for &n in res {
            for source in SOURCES {
                let line = lines
                    .iter()
                    .find(|l| {
                        l["name"] == shape.name.as_str()
                            && l["source"] == source
                            && l["voxel"].as_f64() == Some(2.0 / n as f64)
                    })
                    .with_context(|| {
                        format!(
                            "OpenVDB gave no {source} level set of {} at N = {n}",
                            shape.name
                        )
                    })?;
                let row = compare(shape, &index, n, source, line, out, samples, gt_genus)?;
                println!(
                    "{:>12} N={n:<3} {source:<5} rfta {:.5} ({:.2} s)  volumeToMesh {:.5} ({:.3} s)",
                    row.shape, row.rfta_chamfer, row.rfta_seconds, row.vtm_chamfer, row.vtm_seconds
                );
                rows.push(row);
            }
        }
    }
    write_csv(&out.join("results.csv"), &rows)?;
    let md = markdown(&rows, res);
    std::fs::write(out.join("report.md"), &md)?;
    println!("{md}");
    println!("wrote {}", out.display());
    Ok(())
}

#[allow(
    clippy::too_many_arguments,
    reason = "one row's identity and where its files are"
)]
fn compare(
    shape: &Shape,
    index: &MeshIndex,
    n: usize,
    source: &str,
    line: &serde_json::Value,
    out: &Path,
    samples: usize,
    gt_genus: Option<i64>,
) -> Result<VdbRow> {
    let stem = format!("{}-n{n}-{source}", shape.name);
    let vdb = out.join(format!("{stem}.vdb"));
    let raw = rfta_io::read_vdb(&vdb, None, None)?;
    let params = rfta::Params {
        clamp: raw.clamp,
        ..rfta::Params::default()
    };
    let samples_in = raw.validate(&vdb)?;
    let cpu = crate::usage::process_usage().0;
    let t = Instant::now();
    let result = rfta::reconstruct(&samples_in, &params)
        .with_context(|| format!("rfta on {}", vdb.display()))?;
    let rfta_seconds = t.elapsed().as_secs_f64();
    let rfta_cpu = crate::usage::process_usage().0 - cpu;
    rfta_io::write_mesh(&out.join(format!("{stem}-rfta.obj")), &result.mesh)?;
    let vtm = rfta_io::read_mesh(&out.join(format!("{stem}-volumetomesh.obj")))?;
    let score = |mesh: &TriMesh| -> Result<f64> {
        if mesh.is_empty() {
            return Ok(f64::NAN);
        }
        let mi = MeshIndex::new(mesh)?;
        Ok(rfta_metrics::chamfer_indexed(
            (&shape.gt, index),
            (mesh, &mi),
            samples,
            1,
        ))
    };
    Ok(VdbRow {
        shape: shape.name.clone(),
        n,
        source: source.to_string(),
        active: line["active"].as_u64().unwrap_or(0),
        dense: samples_in.len(),
        to_volume: line["to_volume"].as_f64().unwrap_or(f64::NAN),
        vtm_seconds: line["to_mesh"].as_f64().unwrap_or(f64::NAN),
        vtm_chamfer: score(&vtm)?,
        vtm: MeshSummary::of(&vtm),
        rfta_seconds,
        rfta_cpu,
        rfta_chamfer: score(&result.mesh)?,
        rfta: MeshSummary::of(&result.mesh),
        gt_genus,
    })
}

fn genus(g: Option<i64>) -> String {
    g.map_or("-".into(), |g| g.to_string())
}

fn write_csv(path: &Path, rows: &[VdbRow]) -> Result<()> {
    let mut s = String::from(
        "shape,n,level_set,voxel,active_voxels,dense_samples,openvdb_to_volume_s,volumetomesh_s,\
         volumetomesh_chamfer,volumetomesh_components,volumetomesh_genus,rfta_s,rfta_cpu_s,\
         rfta_chamfer,rfta_components,rfta_genus,gt_genus\n",
    );
    for r in rows {
        writeln!(
            s,
            "{},{},{},{},{},{},{:.4},{:.4},{:.6},{},{},{:.3},{:.3},{:.6},{},{},{}",
            r.shape,
            r.n,
            r.source,
            2.0 / r.n as f64,
            r.active,
            r.dense,
            r.to_volume,
            r.vtm_seconds,
            r.vtm_chamfer,
            r.vtm.components,
            genus(r.vtm.genus),
            r.rfta_seconds,
            r.rfta_cpu,
            r.rfta_chamfer,
            r.rfta.components,
            genus(r.rfta.genus),
            genus(r.gt_genus)
        )?;
    }
    std::fs::write(path, s).with_context(|| format!("cannot write {}", path.display()))
}

fn markdown(rows: &[VdbRow], res: &[usize]) -> String {
    let mut s = String::from(
        "# rfta against OpenVDB's volumeToMesh on OpenVDB level sets\n\n\
         Each shape as a narrow-band level set made and written by OpenVDB (half width 3 voxels, \
         voxel size 2/N): `mesh`, OpenVDB's mesh-to-volume conversion of the ground truth; \
         `exact`, the exact signed distance on the voxels clamped to the band. Each meshed by \
         OpenVDB's `volumeToMesh` (adaptivity 0) and by rfta from the same `.vdb` (default \
         preset, the background as the clamp). Chamfer distance to the ground truth \
         (lower is better); times in seconds (volumeToMesh: the call alone; rfta: the whole \
         reconstruction, wall clock on this machine). Genus shown as `components/genus`.\n\n",
    );
    for (source, &n) in SOURCES.iter().flat_map(|s| res.iter().map(move |n| (s, n))) {
        let _ = writeln!(
            s,
            "## {source}, N = {n} (voxel size {:.4})\n",
            2.0 / n as f64
        );
        s.push_str(
            "| shape | active voxels | volumeToMesh Chamfer | rfta Chamfer | ratio | volumeToMesh s | rfta s | volumeToMesh c/g | rfta c/g | truth g |\n\
             |---|---|---|---|---|---|---|---|---|---|\n",
        );
        let at: Vec<&VdbRow> = rows
            .iter()
            .filter(|r| r.n == n && r.source == *source)
            .collect();
        for r in &at {
            let _ = writeln!(
                s,
                "| {} | {} | {:.5} | {:.5} | {:.2} | {:.3} | {:.2} | {}/{} | {}/{} | {} |",
                r.shape,
                r.active,
                r.vtm_chamfer,
                r.rfta_chamfer,
                r.vtm_chamfer / r.rfta_chamfer,
                r.vtm_seconds,
                r.rfta_seconds,
                r.vtm.components,
                genus(r.vtm.genus),
                r.rfta.components,
                genus(r.rfta.genus),
                genus(r.gt_genus)
            );
        }
        let mean = |f: &dyn Fn(&VdbRow) -> f64| {
            at.iter().map(|r| f(r)).sum::<f64>() / at.len().max(1) as f64
        };
        let _ = writeln!(
            s,
            "| **mean** | | **{:.5}** | **{:.5}** | **{:.2}** | {:.3} | {:.2} | | | |\n",
            mean(&|r| r.vtm_chamfer),
            mean(&|r| r.rfta_chamfer),
            mean(&|r| r.vtm_chamfer) / mean(&|r| r.rfta_chamfer),
            mean(&|r| r.vtm_seconds),
            mean(&|r| r.rfta_seconds)
        );
    }
    s
}
