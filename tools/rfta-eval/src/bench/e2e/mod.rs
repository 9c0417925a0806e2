//! `cargo xtask bench e2e`: where the reconstruction stands, end to end, in one run.
//!
//! ```text
//! cargo bench-e2e [--quick] [--python PATH] [--res 20,50] [--large 128,256] [--shape bunny]
//!                 [--out DIR]
//! cargo bench-e2e --from-csv target/bench/e2e.csv     # the tables again, from a run's rows
//! ```
//!
//! On the dev shapes' prepared grids (`../shared/data/inputs/NAME/sdf_n{N}.npy`, N from `--res`)
//! and on one shape's grids at the `--large` resolutions (sampled here with `rfta sample`'s code:
//! the exact signed distance to `gt.obj` on `linspace(-1, 1, N + 1)^3`), it runs:
//!
//! - `rfta` (the default preset) on 2 threads, and at the first `--res` on 1 and 2 threads in
//!   turn, 5 runs each, for the thread speed-up (this VM's speed drifts by a quarter over
//!   seconds; the row is the run of median wall time, the speed-up line gives medians and
//!   fastest runs, and every repeat must write the same mesh);
//! - at the first `--res`, between those runs, a perfectly parallel workload of fixed size on 1
//!   and 2 threads ([`ceiling_work`]): the speed-up this machine gives at that moment to work
//!   with no serial part, the ceiling the pipeline's speed-up is read against (2.0x on the
//!   project's idle VM; anything else running on the machine, or a host that gives its two
//!   cores less than two cores' time, shows there first);
//! - `rfta-fast` (`--preset fast`, gpytoolbox's 3 rounds) on 2 threads, on the `--res` grids;
//! - `mc`, the project's marching cubes (`rfta mc`);
//! - `skimage`, scikit-image's `marching_cubes`, when the Python (`--python PATH`, else
//!   `python3`) imports it;
//! - `gpytoolbox`, `reach_for_the_arcs` with its defaults, when that Python imports gpytoolbox;
//!   on the `--res` grids up to N = 30 only (the reference did not finish N = 50 within 20
//!   minutes).
//!
//! Each run is a child process of its own: wall and CPU seconds of the reconstruction call, peak
//! resident memory of the child. The parent scores every mesh against `gt.obj` (the paper's
//! Chamfer, 2 x 10^5 samples per side) and writes `e2e.md` and `e2e.csv` to `--out`
//! (`target/bench`), with the ratios of gpytoolbox's CPU time to ours and of our wall time to
//! each marching cubes', the speed issue's targets (`TARGETS`) beside what was measured, and the
//! simplification step's share of the default preset's wall time (issue 59, `SIMPLIFY_SHARE`:
//! the report's timing of the step, summed over the shapes).

mod child;
mod report;

pub(crate) use child::child_main;
use child::{child, find_python};
use report::{ceiling_work, name_of, read_csv};

use std::fmt::Write as _;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta_geom::{Grid, Layout, TriMesh};
use rfta_mesh::MeshIndex;

/// The rows of the summary table, in order: method and threads.
const REPORT_ORDER: [(&str, usize); 6] = [
    ("rfta-default", 2),
    ("rfta-fast", 2),
    ("mc", 1),
    ("skimage", 1),
    ("rfta-default", 1),
    ("gpytoolbox", 1),
];

/// The largest N gpytoolbox runs at (the reference did not finish N = 50 within 20 minutes).
const GPYTOOLBOX_MAX_N: usize = 30;

/// The speed issue's targets for the default preset on 2 threads: N, the mean wall seconds per
/// shape, and the peak resident memory in MB where one is set.
const TARGETS: [(usize, f64, Option<f64>); 4] = [
    (20, 0.3, None),
    (50, 1.0, None),
    (128, 3.0, Some(500.0)),
    (256, 20.0, Some(2000.0)),
];

/// The simplification issue's target: the step's share of the default preset's wall time.
const SIMPLIFY_SHARE: f64 = 0.10;

/// One input grid.
struct Input {
    shape: String,
    n: usize,
    path: PathBuf,
    gt: PathBuf,
    /// One of the `--large` grids (not a dev-set grid).
    large: bool,
}

/// At the first resolution, runs of the default preset per thread count, alternating.
const SCALING_REPEATS: usize = 5;

/// Most CPU time taken by the hypervisor (as a share of the machine's) for a run to count as
/// quiet: on a virtual machine whose host is busy, single runs lost up to a third of their time.
const QUIET_STEAL: f64 = 0.02;

/// One measured run.
struct Run {
    wall: f64,
    cpu: f64,
    rss_mb: f64,
    chamfer: f64,
    faces: usize,
    watertight: bool,
    /// Wall times of every repeat, fastest first (this run's among them).
    walls: Vec<f64>,
    /// Per repeat (in `walls`' order), the share of the machine's CPU time the hypervisor gave
    /// to other guests while it ran ([`crate::usage::steal_seconds`] over wall time and cores; NaN
    /// where unknown).
    steals: Vec<f64>,
    /// Hash of the mesh file the run wrote.
    hash: u64,
    /// Seconds of the run in rfta's simplification step (NaN for the other methods).
    simplified: f64,
}

/// `cargo xtask bench e2e`'s arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Args {
    /// Print the tables again from a run's rows, without running.
    #[arg(long, value_name = "FILE")]
    from_csv: Option<PathBuf>,
    /// Two shapes at N = 20, no large grids.
    #[arg(long)]
    quick: bool,
    /// The Python with gpytoolbox (default: found or installed into the output's venv).
    #[arg(long, value_name = "PATH")]
    python: Option<String>,
    /// Dev-set resolutions N.
    #[arg(long, value_delimiter = ',', default_value = "20,50")]
    res: Vec<usize>,
    /// Large grids of one shape.
    #[arg(long, value_delimiter = ',', default_value = "128,256")]
    large: Vec<usize>,
    /// The shape of the large grids.
    #[arg(long, default_value = "bunny")]
    shape: String,
    /// Where the rows and the report go (default: `<target>/bench`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// Runs the benchmark as `a` says.
pub(crate) fn run(a: &Args) -> Result<()> {
    let mut a = a.clone();
    if a.quick {
        a.res = vec![20];
        a.large.clear();
    }
    let out = a.out.clone().unwrap_or(crate::target_dir().join("bench"));
    if let Some(csv) = &a.from_csv {
        let (rows, inputs) = read_csv(csv)?;
        let report = report::report(&rows, &inputs)?;
        println!("{report}");
        return Ok(());
    }
    let inputs_dir = crate::data_dir().join("inputs");
    std::fs::create_dir_all(&out)?;
    let mut inputs = Vec::new();
    let mut shapes: Vec<PathBuf> = std::fs::read_dir(&inputs_dir)
        .with_context(|| format!("cannot read {}", inputs_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("gt.obj").is_file())
        .collect();
    shapes.sort();
    if a.quick {
        shapes.truncate(2);
    }
    for &n in &a.res {
        for dir in &shapes {
            let path = dir.join(format!("sdf_n{n}.npy"));
            if path.is_file() {
                inputs.push(Input {
                    shape: name_of(dir),
                    n,
                    path,
                    gt: dir.join("gt.obj"),
                    large: false,
                });
            }
        }
    }
    let large_gt = inputs_dir.join(&a.shape).join("gt.obj");
    if !a.large.is_empty() {
        let gt = rfta_io::read_mesh(&large_gt)?;
        let index = MeshIndex::new(&gt)?;
        for &n in &a.large {
            let path = out.join(format!("{}_n{n}.npy", a.shape));
            if !path.is_file() {
                println!("sampling {} at {}^3", a.shape, n + 1);
                let grid = Grid::cube(n, -1.0, 1.0)?;
                let values = index.signed_distances(
                    &(0..grid.len())
                        .map(|i| grid.position(i))
                        .collect::<Vec<_>>(),
                );
                rfta_io::write_sdf_grid(&path, &grid, &values)?;
            }
            inputs.push(Input {
                shape: a.shape.clone(),
                n,
                path,
                gt: large_gt.clone(),
                large: true,
            });
        }
    }
    let python = find_python(a.python.as_deref(), &out)?;
    match &python {
        Some(p) => println!(
            "{}: gpytoolbox {}, scikit-image {}",
            p.path.display(),
            if p.gpytoolbox { "yes" } else { "no (skipped)" },
            if p.skimage { "yes" } else { "no (skipped)" },
        ),
        None => println!(
            "no Python with gpytoolbox or scikit-image found (--python PATH): both skipped"
        ),
    }
    let exe = std::env::current_exe()?;
    let mut csv = String::from(
        "shape,n,method,threads,wall_s,cpu_s,peak_mb,chamfer,faces,watertight,status,walls_s,steals,simplified_s\n",
    );
    let mut rows: Vec<(String, usize, String, usize, Result<Run>)> = Vec::new();
    for input in &inputs {
        let gt = rfta_io::read_mesh(&input.gt)?;
        let gt_index = MeshIndex::new(&gt)?;
        // At the first resolution the default preset runs on 1 and 2 threads in turn,
        // `SCALING_REPEATS` times each: this VM's speed drifts by a quarter over seconds.
        let scaling = Some(&input.n) == a.res.first();
        let mut these: Vec<(&str, usize)> = Vec::new();
        if scaling {
            for _ in 0..SCALING_REPEATS {
                these.extend([
                    ("rfta-default", 2),
                    ("rfta-default", 1),
                    ("ceiling", 2),
                    ("ceiling", 1),
                ]);
            }
        } else {
            these.push(("rfta-default", 2));
        }
        let dev = !input.large;
        if dev {
            these.push(("rfta-fast", 2));
        }
        these.push(("mc", 1));
        if python.as_ref().is_some_and(|p| p.skimage) {
            these.push(("skimage", 1));
        }
        if python.as_ref().is_some_and(|p| p.gpytoolbox) && dev && input.n <= GPYTOOLBOX_MAX_N {
            these.push(("gpytoolbox", 1));
        }
        // Per method and thread count, every run (the repeats in order).
        let mut done: Vec<(&str, usize, Vec<Result<Run>>)> = Vec::new();
        for &(method, threads) in &these {
            let mesh_path = out.join(format!(
                "{}_n{}_{method}_t{threads}.ply",
                input.shape, input.n
            ));
            let r = child(&exe, python.as_ref(), method, threads, input, &mesh_path).and_then(
                |(wall, cpu, rss_mb, steal, simplified)| {
                    if method == "ceiling" {
                        return Ok(Run {
                            wall,
                            cpu,
                            rss_mb,
                            chamfer: f64::NAN,
                            faces: 0,
                            watertight: true,
                            walls: vec![wall],
                            steals: vec![steal],
                            hash: 0,
                            simplified,
                        });
                    }
                    let bytes = std::fs::read(&mesh_path)?;
                    let hash = {
                        let mut h = std::hash::DefaultHasher::new();
                        bytes.hash(&mut h);
                        h.finish()
                    };
                    // A repeat, or the other thread count, writes the same file: scored once.
                    let same = done
                        .iter()
                        .filter(|(m, _, _)| *m == method)
                        .flat_map(|(_, _, runs)| runs.iter().filter_map(|r| r.as_ref().ok()))
                        .next();
                    let (chamfer, faces, watertight) = match same {
                        Some(prev) if prev.hash != hash => bail!(
                            "{method} on {threads} thread(s) wrote another mesh than before: not deterministic"
                        ),
                        Some(prev) => (prev.chamfer, prev.faces, prev.watertight),
                        None => {
                            let mesh = rfta_io::read_mesh(&mesh_path)?;
                            let index = MeshIndex::new(&mesh)?;
                            let chamfer = rfta_metrics::chamfer_indexed(
                                (&gt, &gt_index),
                                (&mesh, &index),
                                200_000,
                                1,
                            );
                            let watertight = rfta_mesh::Topology::of(&mesh).is_watertight();
                            (chamfer, mesh.n_faces(), watertight)
                        }
                    };
                    Ok(Run {
                        wall,
                        cpu,
                        rss_mb,
                        chamfer,
                        faces,
                        watertight,
                        walls: vec![wall],
                        steals: vec![steal],
                        hash,
                        simplified,
                    })
                },
            );
            match &r {
                Ok(r) => println!(
                    "{} n={} {method} t{threads}: {:.2} s wall, {:.2} CPU-s, {:.0} MB, Chamfer {:.5}",
                    input.shape, input.n, r.wall, r.cpu, r.rss_mb, r.chamfer
                ),
                Err(e) => println!(
                    "{} n={} {method} t{threads}: failed: {e:#}",
                    input.shape, input.n
                ),
            }
            match done
                .iter_mut()
                .find(|(m, t, _)| *m == method && *t == threads)
            {
                Some((_, _, runs)) => runs.push(r),
                None => done.push((method, threads, vec![r])),
            }
        }
        let done = done
            .into_iter()
            .map(|(method, threads, runs)| (method, threads, median_run(runs)));
        for (method, threads, r) in done {
            match &r {
                Ok(r) => writeln!(
                    csv,
                    "{},{},{method},{threads},{:.6},{:.3},{:.0},{:.6},{},{},ok,{},{},{:.6}",
                    input.shape,
                    input.n,
                    r.wall,
                    r.cpu,
                    r.rss_mb,
                    r.chamfer,
                    r.faces,
                    r.watertight,
                    r.walls
                        .iter()
                        .map(|w| format!("{w:.6}"))
                        .collect::<Vec<_>>()
                        .join(";"),
                    r.steals
                        .iter()
                        .map(|w| format!("{w:.4}"))
                        .collect::<Vec<_>>()
                        .join(";"),
                    r.simplified
                )?,
                Err(e) => writeln!(
                    csv,
                    "{},{},{method},{threads},,,,,,,{}",
                    input.shape,
                    input.n,
                    format!("{e:#}").replace([',', '\n'], ";")
                )?,
            }
            rows.push((input.shape.clone(), input.n, method.to_string(), threads, r));
        }
    }
    let inputs: Vec<(String, usize)> = inputs.iter().map(|i| (i.shape.clone(), i.n)).collect();
    let report = report::report(&rows, &inputs)?;
    std::fs::write(out.join("e2e.csv"), csv)?;
    std::fs::write(out.join("e2e.md"), &report)?;
    println!("\n{report}\nwrote {}", out.join("e2e.md").display());
    Ok(())
}

/// One row from the runs of a method and thread count: the run of median wall time, with every
/// run's wall time; the first failure if any failed.
fn median_run(runs: Vec<Result<Run>>) -> Result<Run> {
    let mut ok = runs.into_iter().collect::<Result<Vec<Run>>>()?;
    ok.sort_by(|a, b| a.wall.total_cmp(&b.wall));
    let walls: Vec<f64> = ok.iter().map(|r| r.wall).collect();
    let steals: Vec<f64> = ok.iter().flat_map(|r| r.steals.first().copied()).collect();
    let mut median = ok.swap_remove((ok.len() - 1) / 2);
    median.walls = walls;
    median.steals = steals;
    Ok(median)
}
