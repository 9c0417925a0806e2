//! `cargo xtask bench`: measurements that compare, each in its own child process so that its
//! peak memory and CPU time are its own.
//!
//! - `bench spsr`: our screened Poisson against PoissonRecon on the same clouds ([`spsr`]).
//! - `bench e2e`: the whole reconstruction against marching cubes and gpytoolbox's
//!   `reach_for_the_arcs` on the same grids ([`e2e`]).

pub(crate) mod e2e;
pub(crate) mod spsr;

use std::path::Path;

use anyhow::{Result, bail};

const USAGE: &str =
    "usage: cargo xtask bench spsr [--quick] [--points N] [--depths 8,10] [--out DIR]
       cargo xtask bench e2e [--quick] [--python PATH] [--res 20,30] [--large 64,128] [--out DIR]
       cargo xtask bench e2e --from-csv FILE";

/// Entry: `bench spsr ...` or `bench e2e ...`.
pub(crate) fn run(root: &Path, args: &[String]) -> Result<()> {
    match args.first().map(String::as_str) {
        Some("spsr") => spsr::run(root, &args[1..]),
        Some("e2e") => e2e::run(root, &args[1..]),
        _ => bail!("{USAGE}"),
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

/// CPU time the hypervisor gave to other guests since boot, summed over this machine's cores
/// (`steal` of /proc/stat, in its 100 Hz ticks); NaN where there is no such file (not Linux).
pub(crate) fn steal_seconds() -> f64 {
    std::fs::read_to_string("/proc/stat")
        .ok()
        .and_then(|s| {
            let cpu = s.lines().next()?.split_whitespace().collect::<Vec<_>>();
            (cpu.first() == Some(&"cpu"))
                .then(|| cpu.get(8)?.parse::<f64>().ok())
                .flatten()
        })
        .map_or(f64::NAN, |ticks| ticks / 100.0)
}

/// CPU seconds (user + system, all threads) and peak resident memory (MB) of this process so far,
/// from `/proc` (Linux; NaN elsewhere). CPU time has a 10 ms resolution.
pub(crate) fn process_usage() -> (f64, f64) {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are the 12th and 13th.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        f.get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    let cpu = (ticks(11) + ticks(12)) / 100.0;
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let rss = status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0);
    (cpu, rss)
}
