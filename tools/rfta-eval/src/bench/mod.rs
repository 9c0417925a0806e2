//! `cargo xtask bench`: measurements that compare, each in its own child process so that its
//! peak memory and CPU time are its own.
//!
//! - `bench spsr`: our screened Poisson against PoissonRecon on the same clouds ([`spsr`]).
//! - `bench e2e`: the whole reconstruction against marching cubes and gpytoolbox's
//!   `reach_for_the_arcs` on the same grids ([`e2e`]).

pub(crate) mod e2e;
pub(crate) mod spsr;

use anyhow::{Result, bail};

/// `cargo xtask bench`'s benchmarks.
#[derive(Debug, Clone, clap::Subcommand)]
pub(crate) enum Bench {
    /// Our screened Poisson and PoissonRecon on the same clouds (PoissonRecon needs
    /// `cargo bench-spsr`, i.e. the `poissonrecon` feature).
    Spsr(spsr::Args),
    /// The whole reconstruction against marching cubes and gpytoolbox on the same grids: wall,
    /// CPU, memory, Chamfer and ratios (release build: `cargo bench-e2e`).
    E2e(e2e::Args),
}

/// Runs the benchmark `b` names.
pub(crate) fn run(b: &Bench) -> Result<()> {
    match b {
        Bench::Spsr(a) => spsr::run(a),
        Bench::E2e(a) => e2e::run(a),
    }
}

/// The child processes: `bench-child spsr ...` or `bench-child e2e ...`.
pub(crate) fn child_main(args: &[String]) -> Result<()> {
    match args.first().map(String::as_str) {
        Some("spsr") => spsr::child_main(&args[1..]),
        Some("e2e") => e2e::child_main(&args[1..]),
        _ => bail!("bench-child spsr|e2e ..."),
    }
}
