//! Project automation, run as `cargo xtask <command>`:
//!
//! - `ci`: everything CI checks, in order: fmt, clippy, tests, docs, the Python package's tests,
//!   the Slurm job array, shaders, tidy, a quick eval and quick scenarios.
//! - `shaders`: parse and validate every `shaders/*.wgsl` with naga.
//! - `slurm`: docs/batch.md's job-array script on a real one-node Slurm cluster (see [`slurm`]).
//! - `tidy`: repository rules (see [`tidy`]).
//! - `eval`: the paper's Table 2 on a folder of shapes (see [`eval`]).
//! - `bench spsr | e2e`: our screened Poisson against PoissonRecon, and the whole reconstruction
//!   against marching cubes and gpytoolbox, same inputs, same run (see [`mod@bench`]).

#![expect(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "a command-line tool reports on its terminal"
)]

mod bench;
mod eval;
mod method;
mod shaders;
mod slurm;
mod tidy;
mod web;

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

const HELP: &str = "\
cargo xtask <command>

commands:
  ci        fmt --check, clippy -D warnings, tests, docs -D warnings, python (pip install crates/rfta-py into a
            fresh venv, gpytoolbox's own tests against the drop-in, pytest, the adaptive example), slurm, shaders, tidy, eval --quick (mc, rfta), eval --2d --res 16,32, eval --scenario noise,clamp,scattered,swept,collision,params --quick
  shaders   validate every shaders/*.wgsl with naga
  web       [--out DIR] [--check]: the browser demo (rfta-web as WebAssembly, wasm32-wasip1) as one
            page, <out>/index.html (default target/web); --check opens it in headless Chromium:
            the genus-2 shape at 21^3 under 5 s with the native mesh (one thread), a screenshot
  slurm     [--out DIR] docs/batch.md's Slurm job-array script, unchanged, on a one-node cluster started
            here (slurm-wlm, munge; root): dev grids and a corrupt row, then a cancelled task resumed
  tidy      repository rules: crate docs and lints, dependency graph, one glam, no unwrap in libraries
  eval      [--inputs DIR | --meshes DIR] [--res 10,20,30] [--methods mc,rfta,rfta-default,rfta-paper]
            [rfta-genus: the default preset told the ground truth's genus; not run unless named]
            [--2d: the 2D pipeline and marching squares on inputs2d, --res 16,32,64]
            [--vdb: each shape as an OpenVDB level set (voxel 2/N, --res 50,100), rfta against
            OpenVDB's volumeToMesh on it (needs Debian's python3-openvdb)]
            [--samples N] [--depth D] [--owner-band K] [--rounds R] [--seed S] [--initial gradient|raster]
            [--keep-cavities] [--quick] [--out DIR]: Table 2 with marching
            cubes measured in the same run, written to target/eval/<run>/ (results.csv, report.md,
            chamfer.svg, contact_sheet.png and .html); --depth and --owner-band override the rfta methods'
            Poisson depth and owner band (0: every sphere owns points)
            --scenario noise,clamp,scattered,swept,collision,params [--levels L,..]: the paper's
            Figures 23 (relative noise, levels 0.005,0.01,0.02,0.05), 24 (clamps at 4,2,1 spacings,
            given and detected), 25 (swept volumes' pseudo-SDFs, sweep lengths 0,0.3,0.6), 22
            (collision: segments of length 0.05,0.2,0.8, false negatives and positives), 11-13
            (params = raster,batch,rounds swept on two shapes), and scattered samples (uniform and
            near-surface, as many as the grid's), rfta against marching cubes on the changed and the
            clean grid, into <out>/<scenario>/
  bench     spsr [--quick] [--points N] [--depths 8,10] [--out DIR]: our sPSR and PoissonRecon
            side by side (PoissonRecon needs `cargo bench-spsr`, i.e. --features poissonrecon)
  bench     e2e [--quick] [--python PATH] [--res 20,30] [--large 64,128] [--shape bunny] [--out DIR]:
            rfta (default, fast), marching cubes and gpytoolbox on the same grids, wall/CPU/memory/
            Chamfer and ratios (release build: `cargo bench-e2e`); --from-csv FILE prints the tables again
";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = workspace_root();
    match args.first().map(String::as_str) {
        Some("ci") => ci(&root),
        Some("shaders") => shaders::run(&root),
        Some("tidy") => tidy::run(&root),
        Some("eval") => eval::run(&root, &args[1..]),
        Some("web") => web::run(&root, &args[1..]),
        Some("bench") => bench::run(&root, &args[1..]),
        Some("bench-child") => bench::child_main(&args[1..]),
        Some("slurm") => slurm::run(&root, &args[1..]),
        Some("help" | "--help" | "-h") | None => {
            print!("{HELP}");
            Ok(())
        }
        Some(other) => bail!("unknown command '{other}'\n\n{HELP}"),
    }
}

/// Builds the Python package from `crates/rfta-py` into a fresh virtual environment (pip and
/// maturin from PyPI), runs gpytoolbox's own tests against the drop-in, then the package's tests,
/// the CLI comparison against the debug `rfta` the test step built.
fn python(root: &Path, cargo: &str) -> Result<()> {
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from);
    let venv = target.join("py-venv");
    let _ = std::fs::remove_dir_all(&venv);
    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
    let run = |program: &Path, args: &[&str], env: &[(&str, &Path)]| -> Result<()> {
        let status = Command::new(program)
            .args(args)
            .envs(env.iter().map(|(k, v)| (*k, v.as_os_str())))
            .current_dir(root)
            .status()
            .with_context(|| format!("cannot run {}", program.display()))?;
        if !status.success() {
            bail!("{} {} failed ({status})", program.display(), args.join(" "));
        }
        Ok(())
    };
    run(
        Path::new(&python),
        &["-m", "venv", &venv.display().to_string()],
        &[],
    )?;
    let bin = venv.join("bin");
    run(
        &bin.join("pip"),
        &["install", "-q", "crates/rfta-py[test]"],
        &[],
    )?;
    // The binary the pytest CLI comparison runs: the one `cargo test` built.
    let status = Command::new(cargo)
        .args(["build", "-q", "-p", "rfta-cli"])
        .current_dir(root)
        .status()?;
    if !status.success() {
        bail!("cargo build -p rfta-cli failed ({status})");
    }
    // gpytoolbox's own tests of `reach_for_the_arcs`, unchanged, against the drop-in: a peer's
    // code, run from the shared folder beside the repository, never copied into it. Its runner
    // adds gpytoolbox to the venv, so the side-by-side test below runs too.
    let peer = rfta_testkit::data_dir()
        .and_then(|data| {
            data.parent()
                .map(|s| s.join("peer-tests/gpytoolbox/run.sh"))
        })
        .filter(|p| p.is_file());
    match peer {
        Some(script) => {
            println!("==> gpytoolbox's test_reach_for_the_arcs.py against rfta.reach_for_the_arcs");
            run(
                Path::new("bash"),
                &[&script.display().to_string(), &venv.display().to_string()],
                &[],
            )?;
        }
        None if std::env::var_os("CI").is_some() => {
            bail!("../shared/peer-tests/gpytoolbox/run.sh not found; required under CI")
        }
        None => println!("SKIPPED gpytoolbox's own tests: ../shared/peer-tests not found"),
    }
    let rfta_bin = target.join("debug").join("rfta");
    run(
        &bin.join("pytest"),
        &["-q", "crates/rfta-py/tests"],
        &[("RFTA_BIN", &rfta_bin)],
    )?;
    // The documented example of a callable SDF (adaptive sampling), as a user runs it.
    println!("==> crates/rfta-py/examples/adaptive_sdf.py");
    let mesh = target.join("adaptive_sdf.obj");
    run(
        &bin.join("python"),
        &[
            "crates/rfta-py/examples/adaptive_sdf.py",
            &mesh.display().to_string(),
        ],
        &[],
    )
}

/// The repository root (the parent of this crate's directory).
pub(crate) fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

fn ci(root: &Path) -> Result<()> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    type Step = (
        &'static str,
        &'static [&'static str],
        &'static [(&'static str, &'static str)],
    );
    let steps: [Step; 4] = [
        ("fmt", &["fmt", "--all", "--check"], &[]),
        (
            "clippy",
            &[
                "clippy",
                "--workspace",
                "--all-targets",
                "--",
                "-D",
                "warnings",
            ],
            &[],
        ),
        ("test", &["test", "--workspace"], &[]),
        (
            "doc",
            &["doc", "--workspace", "--no-deps"],
            &[("RUSTDOCFLAGS", "-D warnings")],
        ),
    ];
    for (name, args, env) in steps {
        println!("==> {name}: cargo {}", args.join(" "));
        let status = Command::new(&cargo)
            .args(args)
            .envs(env.iter().copied())
            .current_dir(root)
            .status()
            .with_context(|| format!("cannot run cargo for step '{name}'"))?;
        if !status.success() {
            bail!("step '{name}' failed ({status})");
        }
    }
    println!(
        "==> python: the rfta package built into a fresh venv, gpytoolbox's tests, then pytest"
    );
    python(root, &cargo)?;
    println!("==> slurm: docs/batch.md's job array on a one-node Slurm cluster started here");
    slurm::run(root, &[])?;
    println!("==> web --check: the browser demo in headless Chromium");
    web::run(root, &["--check".to_string()])?;
    println!("==> shaders");
    shaders::run(root)?;
    println!("==> tidy");
    tidy::run(root)?;
    println!("==> eval --quick");
    eval::run(
        root,
        &[
            "--quick".to_string(),
            // The Table 2 setting (20 rounds, 30 points per sphere) is for full runs.
            "--methods".to_string(),
            "mc,rfta".to_string(),
            "--out".to_string(),
            root.join("target/eval/ci-quick").display().to_string(),
        ],
    )?;
    println!("==> eval --2d --res 16,32");
    eval::run(
        root,
        &[
            "--2d".to_string(),
            "--res".to_string(),
            "16,32".to_string(),
            "--out".to_string(),
            root.join("target/eval/ci-2d").display().to_string(),
        ],
    )?;
    println!("==> eval --scenario noise,clamp,scattered,swept,collision,params --quick");
    eval::run(
        root,
        &[
            "--scenario".to_string(),
            "noise,clamp,scattered,swept,collision,params".to_string(),
            "--quick".to_string(),
            "--out".to_string(),
            root.join("target/eval/ci-scenarios").display().to_string(),
        ],
    )?;
    println!("==> ci passed");
    Ok(())
}
