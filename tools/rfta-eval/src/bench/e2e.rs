//! `cargo xtask bench e2e`: where the reconstruction stands, end to end, in one run.
//!
//! ```text
//! cargo bench-e2e [--quick] [--python PATH] [--res 20,30] [--large 64,128] [--shape bunny]
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
//! - `rfta-fast` (`--preset fast`, gpytoolbox's 3 rounds) on 2 threads;
//! - `mc`, marching cubes;
//! - `gpytoolbox`, `reach_for_the_arcs` with its defaults, when a Python with gpytoolbox is found
//!   (`--python PATH`, else `python3`); on the `--res` grids only (the reference did not finish
//!   N = 50 within 20 minutes).
//!
//! Each run is a child process of its own: wall and CPU seconds of the reconstruction call, peak
//! resident memory of the child. The parent scores every mesh against `gt.obj` (the paper's
//! Chamfer, 2 x 10^5 samples per side) and writes `e2e.md` and `e2e.csv` to `--out`
//! (`target/bench`), with the ratios of gpytoolbox's CPU time to ours and ours to marching cubes'.

use std::fmt::Write as _;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta_geom::{Grid, Layout, TriMesh};
use rfta_mesh::MeshIndex;

/// The rows of the summary table, in order: method and threads.
const REPORT_ORDER: [(&str, usize); 5] = [
    ("rfta-default", 2),
    ("rfta-fast", 2),
    ("mc", 1),
    ("rfta-default", 1),
    ("gpytoolbox", 1),
];

/// One input grid.
struct Input {
    shape: String,
    n: usize,
    path: PathBuf,
    gt: PathBuf,
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
    #[arg(long, value_delimiter = ',', default_value = "20,30")]
    res: Vec<usize>,
    /// Large grids of one shape.
    #[arg(long, value_delimiter = ',', default_value = "64,128")]
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
        let report = report(&rows, &inputs)?;
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
            });
        }
    }
    let python = find_python(a.python.as_deref(), &out)?;
    match &python {
        Some(p) => println!("gpytoolbox: {}", p.display()),
        None => println!("gpytoolbox: no Python with gpytoolbox found (--python PATH); skipped"),
    }
    let exe = std::env::current_exe()?;
    let mut csv = String::from(
        "shape,n,method,threads,wall_s,cpu_s,peak_mb,chamfer,faces,watertight,status,walls_s,steals\n",
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
        these.extend([("rfta-fast", 2), ("mc", 1)]);
        if python.is_some() && a.res.contains(&input.n) {
            these.push(("gpytoolbox", 1));
        }
        // Per method and thread count, every run (the repeats in order).
        let mut done: Vec<(&str, usize, Vec<Result<Run>>)> = Vec::new();
        for &(method, threads) in &these {
            let mesh_path = out.join(format!(
                "{}_n{}_{method}_t{threads}.ply",
                input.shape, input.n
            ));
            let r = child(&exe, python.as_deref(), method, threads, input, &mesh_path).and_then(
                |(wall, cpu, rss_mb, steal)| {
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
                    "{},{},{method},{threads},{:.6},{:.3},{:.0},{:.6},{},{},ok,{},{}",
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
                        .join(";")
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
    let report = report(&rows, &inputs)?;
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

/// The rows and inputs of an `e2e.csv` this command wrote.
#[allow(clippy::type_complexity)]
fn read_csv(
    path: &Path,
) -> Result<(
    Vec<(String, usize, String, usize, Result<Run>)>,
    Vec<(String, usize)>,
)> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    let mut rows = Vec::new();
    let mut inputs: Vec<(String, usize)> = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 11 {
            bail!("{}: short row '{line}'", path.display());
        }
        let num = |i: usize| f[i].parse::<f64>().unwrap_or(f64::NAN);
        let (shape, n) = (f[0].to_string(), f[1].parse::<usize>()?);
        if !inputs.contains(&(shape.clone(), n)) {
            inputs.push((shape.clone(), n));
        }
        let run = if f[10] == "ok" {
            Ok(Run {
                wall: num(4),
                cpu: num(5),
                rss_mb: num(6),
                chamfer: num(7),
                faces: f[8].parse().unwrap_or(0),
                watertight: f[9] == "true",
                walls: f
                    .get(11)
                    .map(|w| w.split(';').filter_map(|v| v.parse().ok()).collect())
                    .unwrap_or_else(|| vec![num(4)]),
                steals: f
                    .get(12)
                    .map(|w| w.split(';').filter_map(|v| v.parse().ok()).collect())
                    .unwrap_or_default(),
                hash: 0,
            })
        } else {
            Err(anyhow::anyhow!("{}", f[10]))
        };
        rows.push((shape, n, f[2].to_string(), f[3].parse()?, run));
    }
    Ok((rows, inputs))
}

fn name_of(dir: &Path) -> String {
    dir.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The tables: per N and method, means over the shapes that every method finished, and the
/// ratios; then every row.
fn report(
    rows: &[(String, usize, String, usize, Result<Run>)],
    inputs: &[(String, usize)],
) -> Result<String> {
    let mut s = String::new();
    writeln!(
        s,
        "| N | shapes | method | threads | wall s | CPU s | peak MB | Chamfer | gpytoolbox CPU / this | this wall / mc wall |"
    )?;
    writeln!(s, "|{}", "---|".repeat(10))?;
    let mut ns: Vec<usize> = inputs.iter().map(|i| i.1).collect();
    ns.dedup();
    for &n in &ns {
        let find = |shape: &str, m: &str, t: usize| {
            rows.iter().find_map(|(sh, nn, mm, tt, r)| {
                (sh == shape && *nn == n && mm == m && *tt == t)
                    .then_some(r.as_ref().ok())
                    .flatten()
            })
        };
        let shapes: Vec<&str> = inputs
            .iter()
            .filter(|i| i.1 == n)
            .map(|i| i.0.as_str())
            .collect();
        for &(m, t) in &REPORT_ORDER {
            // Shapes this method and marching cubes both finished (gpytoolbox too, when it ran).
            let ok: Vec<&str> = shapes
                .iter()
                .copied()
                .filter(|sh| find(sh, m, t).is_some() && find(sh, "mc", 1).is_some())
                .collect();
            if ok.is_empty() {
                continue;
            }
            let mean = |f: &dyn Fn(&Run) -> f64, m: &str, t: usize| {
                ok.iter()
                    .filter_map(|sh| find(sh, m, t))
                    .map(f)
                    .sum::<f64>()
                    / ok.len() as f64
            };
            let cpu = mean(&|r| r.cpu, m, t);
            let gpy: Vec<f64> = ok
                .iter()
                .filter_map(|sh| find(sh, "gpytoolbox", 1).map(|r| r.cpu))
                .collect();
            let vs_gpy = if gpy.len() == ok.len() && m != "gpytoolbox" && m != "mc" && cpu > 0.0 {
                format!("{:.1}", gpy.iter().sum::<f64>() / ok.len() as f64 / cpu)
            } else {
                "-".into()
            };
            let mc = mean(&|r| r.wall, "mc", 1);
            let vs_mc = if m != "mc" && mc > 0.0 {
                format!("{:.0}", mean(&|r| r.wall, m, t) / mc)
            } else {
                "-".into()
            };
            writeln!(
                s,
                "| {n} | {} | {m} | {t} | {:.2} | {:.2} | {:.0} | {:.5} | {vs_gpy} | {vs_mc} |",
                ok.len(),
                mean(&|r| r.wall, m, t),
                cpu,
                ok.iter()
                    .filter_map(|sh| find(sh, m, t))
                    .map(|r| r.rss_mb)
                    .fold(0.0, f64::max),
                mean(&|r| r.chamfer, m, t),
            )?;
        }
    }
    writeln!(
        s,
        "\nPeak MB is the largest over the shapes; CPU seconds are user + system of the child during the call (10 ms resolution: marching cubes shows 0). With more than one run (the default preset on 1 and 2 threads, {SCALING_REPEATS} runs each, alternating), a row is the run of median wall time.\n"
    )?;
    for &n in &ns {
        let Some(rfta) = Scaling::of(rows, n, "rfta-default") else {
            continue;
        };
        writeln!(
            s,
            "From 1 to 2 threads at N = {n} ({} shapes, {} runs each per thread count): median wall time per shape {:.2} to {:.2} s, **{:.2}x**; fastest runs {:.2} to {:.2} s, {:.2}x.\n",
            rfta.shapes,
            rfta.runs,
            rfta.median.0,
            rfta.median.1,
            rfta.median.0 / rfta.median.1,
            rfta.fastest.0,
            rfta.fastest.1,
            rfta.fastest.0 / rfta.fastest.1,
        )?;
        let total = 2 * rfta.shapes * rfta.runs;
        match rfta.quiet {
            Some((q, k)) => writeln!(
                s,
                "Over the quiet runs only ({k} of {total}: the hypervisor took at most {:.0}% of the machine's CPU time during the run, by `steal` in /proc/stat): median wall time per shape {:.2} to {:.2} s, **{:.2}x**.\n",
                100.0 * QUIET_STEAL,
                q.0,
                q.1,
                q.0 / q.1,
            )?,
            None => writeln!(
                s,
                "Too few quiet runs for a speed-up over them (some shape has no run on a thread count during which the hypervisor took at most {:.0}% of the CPU time, or this machine has no `steal` counter).\n",
                100.0 * QUIET_STEAL,
            )?,
        }
        if let Some(c) = Scaling::of(rows, n, "ceiling") {
            let (ceiling, ours) = (c.median.0 / c.median.1, rfta.median.0 / rfta.median.1);
            writeln!(
                s,
                "The machine's ceiling in the same loop (a perfectly parallel workload, run between them the same number of times): median {:.2} to {:.2} s, **{ceiling:.2}x**; fastest {:.2}x. The pipeline's speed-up is {:.0}% of the ceiling's (median runs).\n",
                c.median.0,
                c.median.1,
                c.fastest.0 / c.fastest.1,
                100.0 * (ours - 1.0) / (ceiling - 1.0).max(f64::EPSILON),
            )?;
        }
    }
    writeln!(
        s,
        "| shape | N | method | threads | wall s | CPU s | peak MB | Chamfer | faces | watertight |"
    )?;
    writeln!(s, "|{}", "---|".repeat(10))?;
    for (shape, n, m, t, r) in rows {
        match r {
            // The ceiling's workload writes no mesh.
            Ok(r) if m == "ceiling" => writeln!(
                s,
                "| {shape} | {n} | {m} | {t} | {:.2} | {:.2} | {:.0} | - | - | - |",
                r.wall, r.cpu, r.rss_mb
            )?,
            Ok(r) => writeln!(
                s,
                "| {shape} | {n} | {m} | {t} | {:.2} | {:.2} | {:.0} | {:.5} | {} | {} |",
                r.wall, r.cpu, r.rss_mb, r.chamfer, r.faces, r.watertight
            )?,
            Err(e) => writeln!(
                s,
                "| {shape} | {n} | {m} | {t} | failed: {} |||||",
                format!("{e:#}").replace(['|', '\n'], " ")
            )?,
        }
    }
    Ok(s)
}

/// The 1- and 2-thread runs of one method at one resolution, over the shapes that have both:
/// mean wall time per shape of the median and of the fastest runs, `(1 thread, 2 threads)`.
struct Scaling {
    shapes: usize,
    runs: usize,
    median: (f64, f64),
    fastest: (f64, f64),
    /// The median over the quiet runs only (steal up to [`QUIET_STEAL`]), and how many runs
    /// that is; `None` where some shape has no quiet run on a thread count.
    quiet: Option<((f64, f64), usize)>,
}

impl Scaling {
    fn of(
        rows: &[(String, usize, String, usize, Result<Run>)],
        n: usize,
        method: &str,
    ) -> Option<Self> {
        let walls = |t: usize| -> Vec<(&str, &Run)> {
            rows.iter()
                .filter(|(_, nn, m, tt, _)| *nn == n && m == method && *tt == t)
                .filter_map(|(sh, _, _, _, r)| r.as_ref().ok().map(|r| (sh.as_str(), r)))
                .collect()
        };
        let (one, two) = (walls(1), walls(2));
        let runs: Vec<(&Run, &Run)> = one
            .iter()
            .filter_map(|(sh, r1)| {
                two.iter()
                    .find(|(s2, _)| s2 == sh)
                    .map(|(_, r2)| (*r1, *r2))
            })
            .collect();
        let pairs: Vec<(&[f64], &[f64])> = runs
            .iter()
            .map(|(a, b)| (&a.walls[..], &b.walls[..]))
            .collect();
        // Wall times of the quiet runs (sorted, as `walls` is).
        let quiet_walls = |r: &Run| -> Vec<f64> {
            r.walls
                .iter()
                .zip(&r.steals)
                .filter(|(_, s)| **s <= QUIET_STEAL)
                .map(|(w, _)| *w)
                .collect()
        };
        let quiet: Vec<(Vec<f64>, Vec<f64>)> = runs
            .iter()
            .map(|(a, b)| (quiet_walls(a), quiet_walls(b)))
            .collect();
        let quiet = quiet
            .iter()
            .all(|(a, b)| !a.is_empty() && !b.is_empty())
            .then(|| {
                let k = quiet.len() as f64;
                let med = |w: &[f64]| w[(w.len() - 1) / 2];
                (
                    (
                        quiet.iter().map(|q| med(&q.0)).sum::<f64>() / k,
                        quiet.iter().map(|q| med(&q.1)).sum::<f64>() / k,
                    ),
                    quiet.iter().map(|q| q.0.len() + q.1.len()).sum(),
                )
            });
        let k = pairs.len() as f64;
        let mean = |pick: &dyn Fn(&[f64]) -> f64| -> (f64, f64) {
            (
                pairs.iter().map(|p| pick(p.0)).sum::<f64>() / k,
                pairs.iter().map(|p| pick(p.1)).sum::<f64>() / k,
            )
        };
        Some(Self {
            shapes: pairs.len(),
            runs: pairs.first()?.0.len(),
            median: mean(&|w| w[(w.len() - 1) / 2]),
            fastest: mean(&|w| w[0]),
            quiet,
        })
    }
}

/// The ceiling's workload: 64 equal tasks, each 2,000 passes of arithmetic over a private
/// 32 KiB buffer (in a core's own cache), handed out one at a time, so nothing is serial,
/// shared or unbalanced: what 2 threads gain over 1 on it is what this machine gives at that
/// moment (about 0.55 s on one thread of the project's VM). Returns a checksum, so that the work
/// is not optimized away.
fn ceiling_work() -> f64 {
    use rayon::prelude::*;
    (0..64u32)
        .into_par_iter()
        .with_max_len(1)
        .map(|task| {
            let mut x: Vec<f64> = (0..4096).map(|i| f64::from(i + task) * 1e-3).collect();
            for pass in 0..2000 {
                let a = 1.0 - 1e-7 * f64::from(pass);
                for v in &mut x {
                    *v = (*v * a + 1e-9).sqrt() * 1.0001;
                }
            }
            x.iter().sum::<f64>()
        })
        .sum()
}

/// A Python that imports gpytoolbox: `--python`, else `python3` if it has it.
fn find_python(given: Option<&str>, out: &Path) -> Result<Option<PathBuf>> {
    let candidate = given.unwrap_or("python3");
    let ok = Command::new(candidate)
        .args(["-c", "import gpytoolbox, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        if given.is_some() {
            bail!("{candidate} cannot import gpytoolbox and numpy");
        }
        return Ok(None);
    }
    std::fs::write(out.join("gpytoolbox_child.py"), PYTHON_CHILD)?;
    Ok(Some(PathBuf::from(candidate)))
}

/// gpytoolbox's `reach_for_the_arcs` with its defaults on a grid; one JSON line out.
const PYTHON_CHILD: &str = r#"import json, resource, sys, time
import numpy as np
import gpytoolbox as gpy
sdf, out = sys.argv[1], sys.argv[2]
lo = [float(v) for v in sys.argv[3:6]]
hi = [float(v) for v in sys.argv[6:9]]
S = np.load(sdf)
axes = [np.linspace(lo[a], hi[a], S.shape[a]) for a in range(3)]
X, Y, Z = np.meshgrid(*axes, indexing="ij")
U = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
t, c = time.perf_counter(), time.process_time()
V, F = gpy.reach_for_the_arcs(U, S.ravel())
wall, cpu = time.perf_counter() - t, time.process_time() - c
gpy.write_mesh(out, V, F)
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(json.dumps({"wall": wall, "cpu": cpu, "rss_mb": rss}))
"#;

/// Runs one method in a child process; `(wall, cpu, peak MB)`.
fn child(
    exe: &Path,
    python: Option<&Path>,
    method: &str,
    threads: usize,
    input: &Input,
    mesh: &Path,
) -> Result<(f64, f64, f64, f64)> {
    let mut cmd = if method == "gpytoolbox" {
        let python = python.context("no Python with gpytoolbox")?;
        let raw = rfta_io::read_sdf(&input.path, None)?;
        let Layout::Grid(g) = raw.layout else {
            bail!("{} is not a grid", input.path.display());
        };
        let b = g.bounds();
        let mut c = Command::new(python);
        let script = mesh
            .parent()
            .unwrap_or(Path::new("."))
            .join("gpytoolbox_child.py");
        c.arg(script)
            .arg(&input.path)
            .arg(mesh.with_extension("obj"));
        for v in b.min.to_array().into_iter().chain(b.max.to_array()) {
            c.arg(v.to_string());
        }
        c
    } else {
        let mut c = Command::new(exe);
        c.args(["bench-child", "e2e", method])
            .arg(&input.path)
            .arg(mesh)
            .arg(threads.to_string());
        c
    };
    cmd.env("RAYON_NUM_THREADS", threads.to_string())
        .env("OMP_NUM_THREADS", threads.to_string());
    let o = cmd.output().context("start the benchmark child")?;
    if !o.status.success() {
        bail!("{}", String::from_utf8_lossy(&o.stderr).trim());
    }
    if method == "gpytoolbox" {
        // Scored as PLY like the others.
        let m = rfta_io::read_mesh(&mesh.with_extension("obj"))?;
        rfta_io::write_mesh(mesh, &m)?;
    }
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = stdout.lines().last().unwrap_or_default();
    let v: serde_json::Value = serde_json::from_str(line.trim()).context("child output")?;
    let get = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    Ok((get("wall"), get("cpu"), get("rss_mb"), get("steal")))
}

/// The share of the machine's CPU time (all cores over `wall` seconds) that the hypervisor
/// gave to other guests since `steal0` ([`crate::usage::steal_seconds`]).
fn steal_share(steal0: f64, wall: f64) -> f64 {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    (crate::usage::steal_seconds() - steal0) / (wall * cores)
}

/// The child: `bench-child e2e METHOD SDF MESH THREADS`; prints one JSON line.
pub(crate) fn child_main(args: &[String]) -> Result<()> {
    let [method, sdf, mesh_out, threads] = args else {
        bail!("bench-child e2e METHOD SDF MESH THREADS");
    };
    let threads: usize = threads.parse()?;
    if method == "ceiling" {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let (cpu0, steal0) = (
            crate::usage::process_usage().0,
            crate::usage::steal_seconds(),
        );
        let t = Instant::now();
        let check = pool.install(ceiling_work);
        let wall = t.elapsed().as_secs_f64();
        let (cpu, rss_mb) = crate::usage::process_usage();
        let steal = steal_share(steal0, wall);
        println!(
            "{{\"wall\": {wall}, \"cpu\": {}, \"rss_mb\": {rss_mb}, \"steal\": {steal}, \"check\": {check}}}",
            cpu - cpu0
        );
        return Ok(());
    }
    let path = Path::new(sdf);
    let samples = rfta_io::read_sdf(path, None)?.validate(path)?;
    let (cpu0, steal0) = (
        crate::usage::process_usage().0,
        crate::usage::steal_seconds(),
    );
    let t = Instant::now();
    let mesh: TriMesh = match method.as_str() {
        "mc" => {
            let grid = samples.as_grid().context("marching cubes needs a grid")?;
            rfta_mc::marching_cubes(grid, samples.values(), 0.0)
        }
        m if m.starts_with("rfta") => {
            let base =
                crate::method::rfta_params(m).with_context(|| format!("unknown method {m}"))?;
            let params = rfta::Params {
                threads: Some(threads),
                ..base
            };
            rfta::reconstruct(&samples, &params)?.mesh
        }
        other => bail!("unknown method {other}"),
    };
    let wall = t.elapsed().as_secs_f64();
    let (cpu, rss_mb) = crate::usage::process_usage();
    let steal = steal_share(steal0, wall);
    rfta_io::write_mesh(Path::new(mesh_out), &mesh)?;
    println!(
        "{{\"wall\": {wall}, \"cpu\": {}, \"rss_mb\": {rss_mb}, \"steal\": {steal}}}",
        cpu - cpu0
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(walls: &[f64], steals: &[f64]) -> Result<Run> {
        Ok(Run {
            wall: walls[(walls.len() - 1) / 2],
            cpu: 0.0,
            rss_mb: 0.0,
            chamfer: f64::NAN,
            faces: 0,
            watertight: true,
            walls: walls.to_vec(),
            steals: steals.to_vec(),
            hash: 0,
        })
    }

    #[test]
    fn the_speed_up_pairs_shapes_and_takes_medians_and_fastest_runs() {
        let row = |shape: &str, method: &str, threads, walls: &[f64]| {
            (
                shape.to_string(),
                20,
                method.to_string(),
                threads,
                run(walls, &[0.0; 3]),
            )
        };
        let rows = vec![
            row("a", "rfta", 1, &[1.0, 2.0, 3.0]),
            row("a", "rfta", 2, &[0.5, 1.0, 2.0]),
            row("b", "rfta", 1, &[3.0, 4.0, 9.0]),
            row("b", "rfta", 2, &[2.0, 2.0, 2.0]),
            // No 2-thread run: left out of the pairs.
            row("c", "rfta", 1, &[10.0, 10.0, 10.0]),
            row("a", "ceiling", 1, &[0.6, 0.6, 0.6]),
            row("a", "ceiling", 2, &[0.3, 0.3, 0.4]),
        ];
        let s = Scaling::of(&rows, 20, "rfta").expect("two shapes have both");
        assert_eq!((s.shapes, s.runs), (2, 3));
        // Medians (2 + 4) / 2 and (1 + 2) / 2; fastest (1 + 3) / 2 and (0.5 + 2) / 2.
        assert_eq!(s.median, (3.0, 1.5));
        assert_eq!(s.fastest, (2.0, 1.25));
        let c = Scaling::of(&rows, 20, "ceiling").expect("one shape");
        assert_eq!(c.median, (0.6, 0.3));
        assert!(Scaling::of(&rows, 30, "rfta").is_none());
        assert!(Scaling::of(&rows, 20, "mc").is_none());
        // Every run quiet: the quiet medians are the medians.
        assert_eq!(s.quiet, Some(((3.0, 1.5), 12)));
    }

    #[test]
    fn the_quiet_speed_up_leaves_out_runs_the_hypervisor_slowed() {
        let rows = vec![
            (
                "a".into(),
                20,
                "rfta".into(),
                1,
                run(&[1.0, 2.0, 3.0], &[0.0, 0.5, 0.01]),
            ),
            (
                "a".into(),
                20,
                "rfta".into(),
                2,
                run(&[0.5, 1.0, 2.0], &[0.3, 0.0, 0.0]),
            ),
        ];
        let s = Scaling::of(&rows, 20, "rfta").expect("one shape");
        // Quiet: 1.0 and 3.0 on one thread (median 1.0), 1.0 and 2.0 on two (median 1.0).
        assert_eq!(s.quiet, Some(((1.0, 1.0), 4)));
        assert_eq!(s.median, (2.0, 1.0));
        let rows = vec![
            ("a".into(), 20, "rfta".into(), 1, run(&[1.0], &[0.5])),
            ("a".into(), 20, "rfta".into(), 2, run(&[0.5], &[0.0])),
        ];
        let s = Scaling::of(&rows, 20, "rfta").expect("one shape");
        assert_eq!(s.quiet, None);
    }
}
