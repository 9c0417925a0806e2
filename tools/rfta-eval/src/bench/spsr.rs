//! `cargo xtask bench spsr`: our screened Poisson and PoissonRecon on the same clouds, in the
//! same run, each reconstruction in its own child process (so peak memory is its own).
//!
//! Clouds: 100k area-uniform points with exact normals on the torus R = 0.6, r = 0.25 and on the
//! bunny (`../shared/data/inputs/bunny/gt.obj`, face normals). Settings: degree 1, screening 10,
//! Neumann, box 1.1, depth 8 and 10, one thread and two. PoissonRecon comes from the
//! `poissonrecon` crate (Kazhdan's C++ v18.73, which that crate runs serially), compiled in only
//! with `--features poissonrecon`; `cargo bench-spsr` is the alias that does it. One thread is
//! enforced with `taskset -c 0` for both solvers when available.
//!
//! Accuracy: the torus is scored against its exact distance (mean and max over output vertices);
//! the bunny by the mean vertex distance to `gt.obj` and the paper's Chamfer (2 x 10^5 samples).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta_geom::{OrientedPoints, TriMesh, glam::DVec3};
use rfta_mesh::MeshIndex;

struct Cloud {
    name: &'static str,
    path: PathBuf,
    /// Ground truth: exact distance, or a mesh.
    truth: Truth,
}

enum Truth {
    Torus,
    Mesh(TriMesh),
}

struct RunResult {
    wall: f64,
    cpu: f64,
    rss_mb: f64,
    mean: f64,
    max: f64,
    chamfer: Option<f64>,
    faces: usize,
    watertight: bool,
}

/// `cargo xtask bench spsr`'s arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Args {
    /// 10,000 points, depth 8 only.
    #[arg(long)]
    quick: bool,
    /// Points per cloud.
    #[arg(long, default_value_t = 100_000)]
    points: usize,
    /// Octree depths.
    #[arg(long, value_delimiter = ',', default_value = "8,10")]
    depths: Vec<u32>,
    /// Where the clouds, meshes and report go (default: `<target>/bench`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// Runs the benchmark as `a` says.
pub(crate) fn run(a: &Args) -> Result<()> {
    let (points, depths) = if a.quick {
        (10_000, vec![8])
    } else {
        (a.points, a.depths.clone())
    };
    let out = a.out.clone().unwrap_or(crate::target_dir().join("bench"));
    std::fs::create_dir_all(&out)?;
    let clouds = make_clouds(&out, points)?;
    let exe = std::env::current_exe()?;
    let pinned = Command::new("taskset").arg("--version").output().is_ok();
    let mut table = String::new();
    writeln!(
        table,
        "| cloud | depth | threads | ours wall s | PR wall s | wall ratio | ours CPU s | PR CPU s | CPU ratio | ours MB | PR MB | ours mean / max | PR mean / max | ours Chamfer | PR Chamfer | ours F | PR F |"
    )?;
    writeln!(table, "|{}", "---|".repeat(17))?;
    for cloud in &clouds {
        for &depth in &depths {
            for threads in [1usize, 2] {
                let ours = child(&exe, "ours", cloud, &out, depth, threads, pinned)?;
                let pr = child(&exe, "poissonrecon", cloud, &out, depth, threads, pinned);
                let pr = match pr {
                    Ok(r) => Some(r),
                    Err(e) => {
                        eprintln!("poissonrecon: {e:#}");
                        None
                    }
                };
                let f = |v: Option<f64>, p: usize| v.map_or("n/a".into(), |v| format!("{v:.p$}"));
                let ratio =
                    |a: f64, b: Option<f64>| b.map_or("n/a".into(), |b| format!("{:.2}", a / b));
                writeln!(
                    table,
                    "| {} {}k | {depth} | {threads} | {:.2} | {} | {} | {:.2} | {} | {} | {:.0} | {} | {:.2e} / {:.2e} | {} | {} | {} | {}{} | {} |",
                    cloud.name,
                    points / 1000,
                    ours.wall,
                    f(pr.as_ref().map(|r| r.wall), 2),
                    ratio(ours.wall, pr.as_ref().map(|r| r.wall)),
                    ours.cpu,
                    f(pr.as_ref().map(|r| r.cpu), 2),
                    ratio(ours.cpu, pr.as_ref().map(|r| r.cpu)),
                    ours.rss_mb,
                    f(pr.as_ref().map(|r| r.rss_mb), 0),
                    ours.mean,
                    ours.max,
                    pr.as_ref()
                        .map_or("n/a".into(), |r| format!("{:.2e} / {:.2e}", r.mean, r.max)),
                    ours.chamfer.map_or("-".into(), |c| format!("{c:.3e}")),
                    pr.as_ref()
                        .and_then(|r| r.chamfer)
                        .map_or("-".into(), |c| format!("{c:.3e}")),
                    ours.faces,
                    if ours.watertight { "" } else { " (open)" },
                    pr.as_ref().map_or("n/a".into(), |r| format!(
                        "{}{}",
                        r.faces,
                        if r.watertight { "" } else { " (open)" }
                    )),
                )?;
                println!("{}", table.lines().last().unwrap_or_default());
            }
        }
    }
    let report = format!(
        "# sPSR benchmark\n\nDegree 1, screening 10, Neumann, box 1.1; PoissonRecon is Kazhdan's v18.73 through the `poissonrecon` crate (serial). One thread: `taskset -c 0` {}. Times are wall seconds of the reconstruction call and CPU seconds (user + system) of the child process; MB is the child's peak resident set.\n\n{table}",
        if pinned {
            "(used)"
        } else {
            "(not available: one thread is the rayon pool size only)"
        }
    );
    let path = out.join("spsr.md");
    std::fs::write(&path, report)?;
    println!("wrote {}", path.display());
    Ok(())
}

fn make_clouds(out: &Path, n: usize) -> Result<Vec<Cloud>> {
    let mut clouds = Vec::new();
    let (p, nn) = rfta_testkit_torus(n);
    let path = out.join(format!("torus_{n}.ply"));
    rfta_io::write_oriented_points_ply(&path, &OrientedPoints::new(p, nn, None)?)?;
    clouds.push(Cloud {
        name: "torus",
        path,
        truth: Truth::Torus,
    });
    let gt = crate::data_dir().join("inputs/bunny/gt.obj");
    if gt.exists() {
        let mesh = rfta_io::read_mesh(&gt)?;
        let samples = rfta_mesh::sample_surface(&mesh, n, 7);
        let p: Vec<DVec3> = samples.iter().map(|s| s.point).collect();
        let nn: Vec<DVec3> = samples
            .iter()
            .map(|s| mesh.face_normal_scaled(s.face as usize).normalize())
            .collect();
        let path = out.join(format!("bunny_{n}.ply"));
        rfta_io::write_oriented_points_ply(&path, &OrientedPoints::new(p, nn, None)?)?;
        clouds.push(Cloud {
            name: "bunny",
            path,
            truth: Truth::Mesh(mesh),
        });
    } else {
        eprintln!("{} is missing: benchmarking the torus only", gt.display());
    }
    Ok(clouds)
}

/// Area-uniform torus samples (R = 0.6, r = 0.25), the same generator as the crate's tests.
fn rfta_testkit_torus(n: usize) -> (Vec<DVec3>, Vec<DVec3>) {
    rfta_testkit::Analytic::Torus {
        major: 0.6,
        minor: 0.25,
    }
    .oriented_samples(n, 1)
}

fn child(
    exe: &Path,
    solver: &str,
    cloud: &Cloud,
    out: &Path,
    depth: u32,
    threads: usize,
    pinned: bool,
) -> Result<RunResult> {
    let mesh_path = out.join(format!("{}_{solver}_d{depth}_t{threads}.ply", cloud.name));
    let mut cmd = if threads == 1 && pinned {
        let mut c = Command::new("taskset");
        c.args(["-c", "0"]).arg(exe);
        c
    } else {
        Command::new(exe)
    };
    cmd.args(["bench-child", "spsr", solver])
        .arg(&cloud.path)
        .arg(&mesh_path)
        .arg(depth.to_string())
        .arg(threads.to_string())
        .env("RAYON_NUM_THREADS", threads.to_string());
    let o = cmd.output().context("start the benchmark child")?;
    if !o.status.success() {
        bail!("{}", String::from_utf8_lossy(&o.stderr).trim());
    }
    let line = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value = serde_json::from_str(line.trim()).context("child output")?;
    let get = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let mesh = rfta_io::read_mesh(&mesh_path)?;
    let topo = rfta_mesh::Topology::of(&mesh);
    let (mean, max, chamfer) = match &cloud.truth {
        Truth::Torus => {
            let t = rfta_testkit::Analytic::Torus {
                major: 0.6,
                minor: 0.25,
            };
            let d: Vec<f64> = mesh.vertices.iter().map(|&p| t.sdf(p).abs()).collect();
            (
                d.iter().sum::<f64>() / d.len() as f64,
                d.iter().copied().fold(0.0, f64::max),
                None,
            )
        }
        Truth::Mesh(gt) => {
            let index = MeshIndex::new(gt)?;
            let d = index.unsigned_distances(&mesh.vertices);
            let ch = rfta_metrics::chamfer(gt, &mesh, 200_000, 1)?;
            (
                d.iter().sum::<f64>() / d.len() as f64,
                d.iter().copied().fold(0.0, f64::max),
                Some(ch),
            )
        }
    };
    Ok(RunResult {
        wall: get("wall"),
        cpu: get("cpu"),
        rss_mb: get("rss_mb"),
        mean,
        max,
        chamfer,
        faces: mesh.n_faces(),
        watertight: topo.is_watertight(),
    })
}

/// The child: `bench-child spsr SOLVER CLOUD MESH DEPTH THREADS`; prints one JSON line.
pub(crate) fn child_main(args: &[String]) -> Result<()> {
    let [solver, cloud, mesh_out, depth, threads] = args else {
        bail!("bench-child spsr SOLVER CLOUD MESH DEPTH THREADS");
    };
    let depth: u32 = depth.parse()?;
    let threads: usize = threads.parse()?;
    let points = rfta_io::read_oriented_points(Path::new(cloud))?;
    let t = Instant::now();
    let mesh = match solver.as_str() {
        "ours" => {
            let params = rfta_spsr::SpsrParams {
                depth,
                screening: 10.0,
                ..rfta_spsr::SpsrParams::default()
            };
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()?
                .install(|| rfta_spsr::reconstruct(&points, &params))?
                .mesh
        }
        "poissonrecon" => poissonrecon_mesh(&points, depth)?,
        other => bail!("unknown solver {other}"),
    };
    let wall = t.elapsed().as_secs_f64();
    let (cpu, rss_mb) = crate::usage::process_usage();
    rfta_io::write_mesh(Path::new(mesh_out), &mesh)?;
    println!("{{\"wall\": {wall}, \"cpu\": {cpu}, \"rss_mb\": {rss_mb}}}");
    Ok(())
}

#[cfg(feature = "poissonrecon")]
fn poissonrecon_mesh(points: &OrientedPoints, depth: u32) -> Result<TriMesh> {
    use nalgebra::{Point3, Vector3};
    use poissonrecon::{PoissonParamsBuilder, SolutionParametersBuilder};
    let p: Vec<Point3<f64>> = points
        .positions()
        .iter()
        .map(|v| Point3::new(v.x, v.y, v.z))
        .collect();
    let n: Vec<Vector3<f64>> = points
        .normals()
        .iter()
        .map(|v| Vector3::new(v.x, v.y, v.z))
        .collect();
    let solution = SolutionParametersBuilder::default()
        .depth(depth)
        .point_weight(10.0)
        .scale(1.1)
        .build();
    let params = PoissonParamsBuilder::default()
        .solution_params(solution)
        .build();
    let m = poissonrecon::reconstruct_surface(&p, &n, &params)
        .map_err(|e| anyhow::anyhow!("PoissonRecon: {e}"))?;
    let vertices = m
        .vertices
        .iter()
        .map(|v| DVec3::new(v.x, v.y, v.z))
        .collect();
    let faces = m
        .triangles
        .iter()
        .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
        .collect();
    Ok(TriMesh::new(vertices, faces)?)
}

#[cfg(not(feature = "poissonrecon"))]
fn poissonrecon_mesh(_: &OrientedPoints, _: u32) -> Result<TriMesh> {
    bail!("xtask was built without PoissonRecon: run `cargo bench-spsr` (--features poissonrecon)")
}
