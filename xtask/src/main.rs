//! Project automation, run as `cargo xtask <command>`:
//!
//! - `ci`: everything CI checks, in order, with a summary of each step's time at the end: fmt,
//!   clippy, tests, docs, the Python package's tests, the Slurm job array, the browser demo,
//!   shaders, tidy, a quick eval, the inexact fields' quick eval, the 2D eval and quick scenarios.
//! - `shaders`: parse and validate every `shaders/*.wgsl` with naga.
//! - `slurm`: docs/batch.md's job-array script on a real one-node Slurm cluster (see [`slurm`]).
//! - `tidy`: repository rules (see [`tidy`]).
//! - `web`: the browser demo as one page (see [`web`]).
//! - `eval`, `bench`: the evaluation and the benchmarks, the tool crate `tools/rfta-eval`'s
//!   (`cargo xtask eval --help`).

#![expect(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "a command-line tool reports on its terminal"
)]

mod shaders;
mod slurm;
mod tidy;
mod web;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};

const HELP: &str = "\
cargo xtask <command>

commands:
  ci        everything CI checks, as .ci/run runs it: fmt --check, clippy -D warnings, tests,
            docs -D warnings, python (the package in a fresh venv, gpytoolbox's own tests against
            the drop-in, pytest, the adaptive example), slurm, web --check, shaders, tidy, a quick
            eval, the inexact fields' quick eval, the 2D eval, quick scenarios; then each step's time, skipped steps named
  shaders   validate every shaders/*.wgsl with naga
  web       [--out DIR] [--check]: the browser demo as one page, <out>/index.html (default
            <target>/web); --check opens it in headless Chromium
  slurm     [--out DIR] docs/batch.md's Slurm job-array script on a one-node cluster started here
  tidy      repository rules: crate docs and lints, dependency graph, one glam, no unwrap in
            libraries, file and function lengths, public constants
  eval      the evaluation (tools/rfta-eval): cargo xtask eval --help
  bench     the benchmarks (tools/rfta-eval): cargo xtask bench --help

<target> is $CARGO_TARGET_DIR when set, else target/.
";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = workspace_root();
    match args.first().map(String::as_str) {
        Some("ci") => ci(&root),
        Some("shaders") => shaders::run(&root),
        Some("tidy") => tidy::run(&root),
        // The tool says what failed; its exit status is this command's.
        Some("eval") => forward(rfta_eval(&root, &args[1..])),
        Some("bench") => forward(rfta_eval(&root, &args)),
        Some("web") => web::run(&root, &args[1..]),
        Some("slurm") => slurm::run(&root, &args[1..]),
        Some("help" | "--help" | "-h") | None => {
            print!("{HELP}");
            Ok(())
        }
        Some(other) => bail!("unknown command '{other}'\n\n{HELP}"),
    }
}

/// Exits with the tool's own status when it failed (it said why).
fn forward(result: Result<()>) -> Result<()> {
    if result.is_err() {
        std::process::exit(1);
    }
    result
}

/// The tool crate `rfta-eval` with `args`, built as this run of cargo builds.
fn rfta_eval(root: &Path, args: &[String]) -> Result<()> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args(["run", "-q", "-p", "rfta-eval", "--"])
        .args(args)
        .current_dir(root)
        .status()
        .context("cannot run cargo run -p rfta-eval")?;
    if !status.success() {
        bail!("rfta-eval {} failed ({status})", args.join(" "));
    }
    Ok(())
}

/// Where every generated output goes: `$CARGO_TARGET_DIR`, else the repository's `target/`.
pub(crate) fn target_dir(root: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from)
}

/// Builds the Python package from `crates/rfta-py` into a fresh virtual environment (pip and
/// maturin from PyPI), runs gpytoolbox's own tests against the drop-in, then the package's tests,
/// the CLI comparison against the debug `rfta` the test step built.
fn python(root: &Path, cargo: &str) -> Result<()> {
    let target = target_dir(root);
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
    println!(
        "pip install crates/rfta-py[test]: maturin builds the Rust extension in release mode (a few minutes on 2 cores; quiet until done)"
    );
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
        None => skipped("gpytoolbox's own tests: ../shared/peer-tests not found".into()),
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
    )?;
    // A neural SDF (the numpy twin: CI installs no torch) meshed by rfta, marching cubes and,
    // where installed, MISE, each scored against the dev bunny.
    match rfta_testkit::data_dir() {
        Some(data) => {
            println!("==> crates/rfta-py/examples/neural_sdf.py --numpy");
            let bunny = data.join("inputs/bunny/gt.obj");
            run(
                &bin.join("python"),
                &[
                    "crates/rfta-py/examples/neural_sdf.py",
                    "--numpy",
                    "--mesh",
                    &bunny.display().to_string(),
                ],
                &[],
            )
        }
        None => {
            skipped("crates/rfta-py/examples/neural_sdf.py: ../shared/data not found".into());
            Ok(())
        }
    }
}

/// The repository root (the parent of this crate's directory).
pub(crate) fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// Steps skipped in this run, each with why ([`skipped`]).
static SKIPPED: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());

/// Says, loudly, that `what` was skipped, and keeps it for `ci`'s summary.
pub(crate) fn skipped(what: String) {
    println!("SKIPPED {what}");
    if let Ok(mut s) = SKIPPED.lock() {
        s.push(what);
    }
}

fn ci(root: &Path) -> Result<()> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let cargo_step = |args: &[&str], env: &[(&str, &str)]| -> Result<()> {
        let status = Command::new(&cargo)
            .args(args)
            .envs(env.iter().copied())
            .current_dir(root)
            .status()
            .context("cannot run cargo")?;
        if !status.success() {
            bail!("cargo {} failed ({status})", args.join(" "));
        }
        Ok(())
    };
    let eval_dir = |name: &str| {
        target_dir(root)
            .join("eval")
            .join(name)
            .display()
            .to_string()
    };
    let eval = |args: &[&str]| -> Result<()> {
        let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        rfta_eval(root, &args)
    };
    type Step<'a> = (&'static str, Box<dyn Fn() -> Result<()> + 'a>);
    let steps: Vec<Step<'_>> = vec![
        (
            "fmt",
            Box::new(|| cargo_step(&["fmt", "--all", "--check"], &[])),
        ),
        (
            "clippy",
            Box::new(|| {
                cargo_step(
                    &[
                        "clippy",
                        "--workspace",
                        "--all-targets",
                        "--",
                        "-D",
                        "warnings",
                    ],
                    &[],
                )
            }),
        ),
        (
            "test",
            Box::new(|| cargo_step(&["test", "--workspace"], &[])),
        ),
        (
            "doc",
            Box::new(|| {
                cargo_step(
                    &["doc", "--workspace", "--no-deps"],
                    &[("RUSTDOCFLAGS", "-D warnings")],
                )
            }),
        ),
        ("python", Box::new(|| python(root, &cargo))),
        ("slurm", Box::new(|| slurm::run(root, &[]))),
        (
            "web --check",
            Box::new(|| web::run(root, &["--check".to_string()])),
        ),
        ("shaders", Box::new(|| shaders::run(root))),
        ("tidy", Box::new(|| tidy::run(root))),
        (
            "eval --quick (mc, rfta)",
            // The Table 2 setting (20 rounds, 30 points per sphere) is for full runs.
            Box::new(|| {
                eval(&[
                    "--quick",
                    "--methods",
                    "mc,rfta",
                    "--out",
                    &eval_dir("ci-quick"),
                ])
            }),
        ),
        (
            "eval inexact --quick",
            Box::new(|| eval(&["inexact", "--quick", "--out", &eval_dir("ci-inexact")])),
        ),
        (
            "eval plane --res 16,32",
            Box::new(|| eval(&["plane", "--res", "16,32", "--out", &eval_dir("ci-2d")])),
        ),
        (
            "eval scenario noise,clamp,scattered,swept,collision,params --quick",
            Box::new(|| {
                eval(&[
                    "scenario",
                    "noise,clamp,scattered,swept,collision,params",
                    "--quick",
                    "--out",
                    &eval_dir("ci-scenarios"),
                ])
            }),
        ),
    ];
    let mut times = Vec::new();
    for (name, step) in &steps {
        println!("==> {name}");
        let t = Instant::now();
        let result = step();
        times.push((*name, t.elapsed().as_secs_f64(), result.is_ok()));
        if let Err(e) = result {
            summary(&times);
            return Err(e.context(format!("step '{name}' failed")));
        }
    }
    summary(&times);
    println!("==> ci passed");
    Ok(())
}

/// Each step's time and outcome, then the steps skipped, loudly.
fn summary(times: &[(&str, f64, bool)]) {
    println!("\n==> summary");
    for (name, seconds, ok) in times {
        let outcome = if *ok { "ok" } else { "FAILED" };
        println!("  {outcome:6} {seconds:7.1} s  {name}");
    }
    let total: f64 = times.iter().map(|t| t.1).sum();
    println!("  total  {total:7.1} s");
    let skipped = SKIPPED.lock().map(|s| s.clone()).unwrap_or_default();
    for what in &skipped {
        println!("  SKIPPED {what}");
    }
    if skipped.is_empty() {
        println!("  nothing skipped");
    }
}
