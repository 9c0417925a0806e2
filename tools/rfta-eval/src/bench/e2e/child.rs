//! `bench e2e`'s child processes: each method on one grid in a process of its own (rfta and
//! marching cubes as `bench-child e2e`, gpytoolbox and scikit-image in Python), its time, CPU
//! and peak memory.

use super::*;

/// The Python the peers run in, and which of them it can import.
pub(super) struct Python {
    pub(super) path: PathBuf,
    /// gpytoolbox's `reach_for_the_arcs`.
    pub(super) gpytoolbox: bool,
    /// scikit-image's `marching_cubes`.
    pub(super) skimage: bool,
}

/// `--python`, else `python3`, with the peers it imports (numpy at least; `--python` must have
/// one of them).
pub(super) fn find_python(given: Option<&str>, out: &Path) -> Result<Option<Python>> {
    let candidate = given.unwrap_or("python3");
    let imports = |module: &str| {
        Command::new(candidate)
            .args(["-c", &format!("import numpy, {module}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let python = Python {
        path: PathBuf::from(candidate),
        gpytoolbox: imports("gpytoolbox"),
        skimage: imports("skimage.measure"),
    };
    if !python.gpytoolbox && !python.skimage {
        if given.is_some() {
            bail!("{candidate} imports neither gpytoolbox nor scikit-image (with numpy)");
        }
        return Ok(None);
    }
    std::fs::write(out.join("peers_child.py"), PYTHON_CHILD)?;
    Ok(Some(python))
}

/// The peers on a grid, in a process of their own: `peers_child.py METHOD SDF OUT LO.. HI..` runs
/// scikit-image's marching cubes at level 0 at the grid's spacing and origin (`skimage`) or
/// gpytoolbox's `reach_for_the_arcs` with its defaults (`gpytoolbox`), writes the mesh as OBJ
/// and prints one JSON line: the time of the call alone, as for every method, and the process's
/// peak memory.
pub(super) const PYTHON_CHILD: &str = r#"import json, resource, sys, time
import numpy as np
method, sdf, out = sys.argv[1], sys.argv[2], sys.argv[3]
lo = [float(v) for v in sys.argv[4:7]]
hi = [float(v) for v in sys.argv[7:10]]
S = np.load(sdf)
if method == "skimage":
    from skimage import measure
    spacing = tuple((hi[a] - lo[a]) / (S.shape[a] - 1) for a in range(3))
    t, c = time.perf_counter(), time.process_time()
    V, F, _, _ = measure.marching_cubes(S, level=0.0, spacing=spacing)
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    V = V + np.array(lo)
else:
    import gpytoolbox as gpy
    axes = [np.linspace(lo[a], hi[a], S.shape[a]) for a in range(3)]
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    U = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    t, c = time.perf_counter(), time.process_time()
    V, F = gpy.reach_for_the_arcs(U, S.ravel())
    wall, cpu = time.perf_counter() - t, time.process_time() - c
with open(out, "w") as f:
    f.writelines("v %.17g %.17g %.17g\n" % tuple(v) for v in V)
    f.writelines("f %d %d %d\n" % tuple(t + 1) for t in F)
# VmHWM: this process's own peak (getrusage's ru_maxrss carries the parent's over exec).
try:
    with open("/proc/self/status") as f:
        rss = next(float(l.split()[1]) for l in f if l.startswith("VmHWM:")) / 1024.0
except (OSError, StopIteration):
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(json.dumps({"wall": wall, "cpu": cpu, "rss_mb": rss}))
"#;

/// Runs one method in a child process; `(wall, cpu, peak MB, steal share, seconds simplifying)`
/// (the last NaN but for rfta).
pub(super) fn child(
    exe: &Path,
    python: Option<&Python>,
    method: &str,
    threads: usize,
    input: &Input,
    mesh: &Path,
) -> Result<(f64, f64, f64, f64, f64)> {
    let peer = matches!(method, "gpytoolbox" | "skimage");
    let mut cmd = if peer {
        let python = python.context("no Python with the peers")?;
        let raw = rfta_io::read_sdf(&input.path, None)?;
        let Layout::Grid(g) = raw.layout else {
            bail!("{} is not a grid", input.path.display());
        };
        let b = g.bounds();
        let mut c = Command::new(&python.path);
        let script = mesh
            .parent()
            .unwrap_or(Path::new("."))
            .join("peers_child.py");
        c.arg(script)
            .arg(method)
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
    if peer {
        // Scored as PLY like the others.
        let m = rfta_io::read_mesh(&mesh.with_extension("obj"))?;
        rfta_io::write_mesh(mesh, &m)?;
    }
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = stdout.lines().last().unwrap_or_default();
    let v: serde_json::Value = serde_json::from_str(line.trim()).context("child output")?;
    let get = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    Ok((
        get("wall"),
        get("cpu"),
        get("rss_mb"),
        get("steal"),
        get("simplified"),
    ))
}

/// The share of the machine's CPU time (all cores over `wall` seconds) that the hypervisor
/// gave to other guests since `steal0` ([`crate::usage::steal_seconds`]).
pub(super) fn steal_share(steal0: f64, wall: f64) -> f64 {
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
    // The mesh, and for rfta the seconds its simplification step took (issue 59's share).
    let (mesh, simplified): (TriMesh, Option<f64>) = match method.as_str() {
        "mc" => {
            let grid = samples.as_grid().context("marching cubes needs a grid")?;
            (rfta_mc::marching_cubes(grid, samples.values(), 0.0), None)
        }
        m if m.starts_with("rfta") => {
            let base =
                crate::method::rfta_params(m).with_context(|| format!("unknown method {m}"))?;
            let params = rfta::Params {
                threads: Some(threads),
                ..base
            };
            let r = rfta::reconstruct(&samples, &params)?;
            let simplified = (r.report.timings.iter())
                .filter(|(step, _)| *step == rfta::Step::Simplify)
                .map(|(_, d)| d.as_secs_f64())
                .sum();
            (r.mesh, Some(simplified))
        }
        other => bail!("unknown method {other}"),
    };
    let wall = t.elapsed().as_secs_f64();
    let (cpu, rss_mb) = crate::usage::process_usage();
    let steal = steal_share(steal0, wall);
    rfta_io::write_mesh(Path::new(mesh_out), &mesh)?;
    let simplified = simplified.map_or(String::new(), |x| format!(", \"simplified\": {x}"));
    println!(
        "{{\"wall\": {wall}, \"cpu\": {}, \"rss_mb\": {rss_mb}, \"steal\": {steal}{simplified}}}",
        cpu - cpu0
    );
    Ok(())
}
