//! `rfta-eval`: rfta's evaluation and benchmarks, run as `cargo xtask eval` and
//! `cargo xtask bench` (or `cargo run -p rfta-eval -- ...`). One module per mode, each with its
//! own arguments:
//!
//! - no mode (or `table`): the paper's Table 2 on a folder of shapes, marching cubes measured in
//!   the same run ([`table`]);
//! - `scenario NAME[,NAME]`: the paper's other inputs, noise, clamps, scattered samples, swept
//!   volumes, collisions and parameter sweeps ([`scenario`]);
//! - `plane`: the 2D pipeline against marching squares ([`plane`]);
//! - `vdb`: rfta against OpenVDB's `volumeToMesh` on OpenVDB level sets ([`vdb`]);
//! - `adaptive`: reconstruction from an SDF that can be asked, under budgets ([`adaptive`]);
//! - `inexact`: fields that are not distances, trained networks and CSG ([`inexact`]);
//! - `bench spsr | e2e`: our screened Poisson against PoissonRecon, and the whole reconstruction
//!   against marching cubes and gpytoolbox ([`mod@bench`]).
//!
//! Every output goes under `<target>/eval/<run>/` or `<target>/bench/` unless `--out` says
//! otherwise, `<target>` being `$CARGO_TARGET_DIR` when set, else the repository's `target/`.
//! The shared data is `$RFTA_DATA_DIR`, else `../shared/data` beside the repository.

#![expect(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "a command-line tool reports on its terminal"
)]

mod adaptive;
mod bench;
mod chart;
mod inexact;
mod method;
mod mise;
mod plane;
mod render;
mod report;
mod scenario;
mod shapes;
mod swept;
mod table;
mod usage;
mod vdb;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

/// rfta's evaluation (Table 2 without a mode) and benchmarks.
#[derive(Debug, Parser)]
#[command(
    name = "rfta-eval",
    bin_name = "cargo xtask eval",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    mode: Option<Mode>,
    #[command(flatten)]
    table: table::Args,
}

#[derive(Debug, Subcommand)]
enum Mode {
    /// The paper's Table 2 with marching cubes in the same run (the default).
    Table(table::Args),
    /// The paper's Figures 22 to 25 and 11 to 13, and scattered samples.
    Scenario(scenario::Args),
    /// The 2D pipeline and marching squares on 2D inputs.
    Plane(plane::Args),
    /// Each shape as an OpenVDB level set: rfta against OpenVDB's volumeToMesh (needs Debian's
    /// python3-openvdb).
    Vdb(vdb::Args),
    /// Reconstruction from each shape's exact SDF under budgets, against grids of as many points.
    Adaptive(adaptive::Args),
    /// Fields that are not distances (trained networks, CSG): rfta against marching cubes,
    /// scored against each field's zero set.
    Inexact(inexact::Args),
    /// Benchmarks, each run in a child process of its own.
    #[command(subcommand)]
    Bench(bench::Bench),
    /// A benchmark's child process.
    #[command(hide = true)]
    BenchChild {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match &cli.mode {
        None => table::run(&cli.table),
        Some(Mode::Table(a)) => table::run(a),
        Some(Mode::Scenario(a)) => scenario::command(a),
        Some(Mode::Plane(a)) => plane::command(a),
        Some(Mode::Vdb(a)) => vdb::command(a),
        Some(Mode::Adaptive(a)) => adaptive::command(a),
        Some(Mode::Inexact(a)) => inexact::command(a),
        Some(Mode::Bench(b)) => bench::run(b),
        Some(Mode::BenchChild { args }) => bench::child_main(args),
    }
}

/// The repository root.
pub(crate) fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// Where every generated output goes: `$CARGO_TARGET_DIR`, else the repository's `target/`.
pub(crate) fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| workspace_root().join("target"), PathBuf::from)
}

/// The shared data: `$RFTA_DATA_DIR`, else `../shared/data` beside the repository.
pub(crate) fn data_dir() -> PathBuf {
    std::env::var_os("RFTA_DATA_DIR")
        .map_or_else(|| workspace_root().join("../shared/data"), PathBuf::from)
}

/// A run's folder, created: `out` when given, else `<target>/eval/<run>`.
pub(crate) fn out_dir(out: Option<&Path>, run: &str) -> Result<PathBuf> {
    let dir = out.map_or_else(|| target_dir().join("eval").join(run), Path::to_path_buf);
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    Ok(dir)
}
