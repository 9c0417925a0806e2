//! The memory a reconstruction needs, estimated before any work so that inputs too large for the
//! machine are refused with a clear error instead of running out of memory.

use crate::{Error, Params, Result};

/// An upper estimate of the peak resident memory, in bytes, of reconstructing from `n` samples
/// (the samples included): a fixed 256 MiB (the depth-10 screened Poisson octree, thread stacks,
/// the binary) plus 1 KiB per sample (positions, spheres, sphere tree, k-d trees, tangency points
/// and their octree cells, the empty-space samples of a raster that grows with `n^(1/3)`), plus
/// 200 B per sample for each tangency point allowed beyond 3 per sphere.
///
/// Checked against `/usr/bin/time -v` peaks of `rfta reconstruct` on the bunny's SDF at 33^3, 65^3
/// and 129^3 samples (185, 444 and 1409 MiB; the estimate is 1.6, 1.2 and 1.7 times these; see
/// docs/hardening.md).
pub fn estimate_peak_memory(n: usize, params: &Params) -> u64 {
    const BASE: u64 = 256 << 20;
    const PER_SAMPLE: u64 = 1024;
    const PER_EXTRA_POINT: u64 = 200;
    let extra_points = params.max_points_per_sphere.saturating_sub(3) as u64;
    BASE.saturating_add(
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
