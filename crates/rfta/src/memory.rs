//! The memory a reconstruction needs, estimated before any work so that inputs too large for the
//! machine are refused with a clear error instead of running out of memory.

use crate::{Error, Params, Result};

/// An upper estimate of the peak resident memory, in bytes, of reconstructing from `n` samples
/// (the samples included): a fixed 128 MiB (thread stacks, the binary, the coarse solves), 72 B per
/// sample (the input's value, the unit box's sphere and value, the check's empty radius and group
/// per sample), 32 KiB per `n^(2/3)` (what follows the surface, whose area grows as `n^(2/3)` on a
/// grid: tangency points, the octree, the meshes and their indices), plus 200 B per sample for
/// each tangency point allowed beyond 3 per sphere.
///
/// Checked against the peaks of `rfta reconstruct` on the bunny's SDF (docs/hardening.md, "Memory":
/// 90, 233, 604, 2,638 and 10,927 MiB at 33^3, 65^3, 129^3, 257^3 and 513^3 samples; the estimate
/// is 1.2 to 1.8 times these).
pub fn estimate_peak_memory(n: usize, params: &Params) -> u64 {
    const BASE: u64 = 128 << 20;
    const PER_SAMPLE: u64 = 72;
    const PER_SURFACE_CELL: f64 = 32.0 * 1024.0;
    const PER_EXTRA_POINT: u64 = 200;
    let extra_points = params.max_points_per_sphere.saturating_sub(3) as u64;
    let surface = (PER_SURFACE_CELL * rfta_geom::math::cbrt(n as f64).powi(2)) as u64;
    BASE.saturating_add(surface).saturating_add(
        (n as u64).saturating_mul(PER_SAMPLE.saturating_add(extra_points * PER_EXTRA_POINT)),
    )
}

/// Whether `n` samples fit in [`Params::memory_limit`] by [`estimate_peak_memory`]: callers
/// that know `n` before loading the samples (from a file header) can refuse early.
///
/// # Errors
/// [`Error::TooLarge`] with the estimate and the limit.
pub fn check_memory(n: usize, params: &Params) -> Result<()> {
    match params.memory_limit {
        Some(limit) if estimate_peak_memory(n, params) > limit => Err(Error::TooLarge {
            samples: n,
            needed: estimate_peak_memory(n, params),
            limit,
        }),
        _ => Ok(()),
    }
}

/// Memory this process can still use: `MemAvailable` of /proc/meminfo, lowered to the cgroup's
/// remaining allowance and to the address space `ulimit -v` leaves (an allocation past it
/// aborts the process) where they are set. `None` where none can be read.
pub fn available_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
    let avail = meminfo.as_deref().and_then(|m| {
        m.lines()
            .find(|l| l.starts_with("MemAvailable:"))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kb| kb.parse::<u64>().ok())
            .map(|kb| kb * 1024)
    });
    let read = |p: &str| {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|t| t.trim().parse::<u64>().ok())
    };
    let cgroup = match (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        (Some(max), Some(cur)) => Some(max.saturating_sub(cur)),
        _ => None,
    };
    // RLIMIT_AS, soft ("Max address space  LIMIT  HARD  bytes"), less what is mapped now.
    let address_space = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("Max address space"))
                .and_then(|l| l.split_whitespace().nth(3))
                .and_then(|v| v.parse::<u64>().ok())
        })
        .map(|limit| {
            let mapped = std::fs::read_to_string("/proc/self/status")
                .ok()
                .and_then(|t| {
                    t.lines()
                        .find(|l| l.starts_with("VmSize:"))
                        .and_then(|l| l.split_whitespace().nth(1))
                        .and_then(|kb| kb.parse::<u64>().ok())
                })
                .unwrap_or(0)
                * 1024;
            limit.saturating_sub(mapped)
        });
    [avail, cgroup, address_space].into_iter().flatten().min()
}

/// Bytes as "1.5 GiB".
pub fn format_bytes(bytes: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = bytes as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{bytes} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}
