//! The integer lattice shared by the CPU and GPU paths.
//!
//! A cell has [`SUBCELLS`] lattice steps per axis; a point is `(X + 0.5) / (res * SUBCELLS)` for
//! an integer lattice coordinate `X`. A cell's sample point is at `X = 16 i + m` with a jitter `m`
//! in `0..16` per axis from [`jitter`]. A sphere is its centre rounded to the lattice and the
//! integer threshold `floor(0.95 (r L)^2)` with `L = res * SUBCELLS`; a cell is occupied when the
//! integer squared distance from its sample to some centre is at most that threshold. With
//! `res <= 1024` every quantity fits `u32`.

use rfta_geom::glam::DVec3;

use crate::{Error, MAX_RES, RasterParams};

/// Lattice steps per cell per axis.
pub const SUBCELLS: u32 = 16;

/// The reference's shrink factor on the squared radius.
pub(crate) const SHRINK: f64 = 0.95;

/// A sphere on the lattice, with its candidate cell range (inclusive).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(C)]
pub(crate) struct QSphere {
    /// Centre in lattice coordinates (clamped to [-L, 2L]).
    pub(crate) c: [i32; 3],
    /// Occupancy threshold on the squared lattice distance.
    pub(crate) r2: u32,
    /// First candidate cell per axis.
    pub(crate) lo: [u32; 3],
    /// Last candidate cell per axis (`lo > hi` on some axis: no cells).
    pub(crate) hi: [u32; 3],
}

/// A 32-bit integer hash (the PCG output permutation, O'Neill 2014), the same in WGSL.
pub(crate) fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The 32-bit seed mixed into the jitter hash.
pub(crate) fn seed32(seed: u64) -> u32 {
    let m = rfta_geom::rng::mix64(seed);
    (m ^ (m >> 32)) as u32
}

/// The jitter `(mx, my, mz)` in `0..SUBCELLS` of the cell with linear index `cell`.
pub(crate) fn jitter(seed: u32, cell: u32) -> [u32; 3] {
    let h1 = pcg_hash(cell ^ seed);
    let h2 = pcg_hash(h1);
    let h3 = pcg_hash(h2);
    [h1 >> 28, h2 >> 28, h3 >> 28]
}

/// The linear cell index used for jitter: `(ix * res + iy) * res + iz`.
pub(crate) fn cell_index(res: u32, ix: u32, iy: u32, iz: u32) -> u32 {
    (ix * res + iy) * res + iz
}

/// The jittered sample point of cell `(ix, iy, iz)` in unit-box coordinates: the cell's occupancy
/// is decided there, and it is the point emitted for a kept cell.
pub fn cell_sample(params: &RasterParams, cell: [u32; 3]) -> DVec3 {
    let res = params.res as u32;
    let m = jitter(
        seed32(params.seed),
        cell_index(res, cell[0], cell[1], cell[2]),
    );
    let lattice = DVec3::new(
        (cell[0] * SUBCELLS + m[0]) as f64,
        (cell[1] * SUBCELLS + m[1]) as f64,
        (cell[2] * SUBCELLS + m[2]) as f64,
    );
    (lattice + DVec3::splat(0.5)) / (res * SUBCELLS) as f64
}

/// Integer square root (floor).
pub(crate) fn isqrt(v: u64) -> u64 {
    let mut r = (v as f64).sqrt() as u64;
    while r * r > v {
        r -= 1;
    }
    while (r + 1) * (r + 1) <= v {
        r += 1;
    }
    r
}

pub(crate) fn prepare(
    centers: &[DVec3],
    radii: &[f64],
    params: &RasterParams,
) -> Result<Vec<QSphere>, Error> {
    if params.res == 0 || params.res > MAX_RES {
        return Err(Error::Resolution(params.res));
    }
    if centers.len() != radii.len() {
        return Err(Error::LengthMismatch {
            centers: centers.len(),
            radii: radii.len(),
        });
    }
    let res = params.res as i64;
    let l = (params.res as u32 * SUBCELLS) as f64;
    centers
        .iter()
        .zip(radii)
        .enumerate()
        .map(|(i, (c, &r))| {
            if !(c.is_finite() && r.is_finite() && r >= 0.0) {
                return Err(Error::InvalidSphere(i));
            }
            let q = (*c * l - DVec3::splat(0.5))
                .round()
                .clamp(DVec3::splat(-l), DVec3::splat(2.0 * l));
            let qc = [q.x as i64, q.y as i64, q.z as i64];
            let r2f = (SHRINK * (r * l) * (r * l)).floor();
            let r2 = if r2f >= u32::MAX as f64 {
                u32::MAX as u64
            } else {
                r2f as u64
            };
            let reach = isqrt(r2) as i64 + 1;
            let (mut lo, mut hi) = ([1u32; 3], [0u32; 3]);
            let mut empty = false;
            for a in 0..3 {
                let first = (qc[a] - reach).div_euclid(SUBCELLS as i64);
                let last = (qc[a] + reach).div_euclid(SUBCELLS as i64);
                empty |= last < 0 || first > res - 1;
                lo[a] = first.clamp(0, res - 1) as u32;
                hi[a] = last.clamp(0, res - 1) as u32;
            }
            if empty {
                // A sphere off the grid: an empty range (lo > hi).
                (lo, hi) = ([1; 3], [0; 3]);
            }
            Ok(QSphere {
                c: qc.map(|v| v as i32),
                r2: r2 as u32,
                lo,
                hi,
            })
        })
        .collect()
}

/// The cells inside the spheres' bounding box, widened by one cell (the reference's band region):
/// inclusive `(lo, hi)` per axis.
pub(crate) fn cell_bbox(centers: &[DVec3], radii: &[f64], res: usize) -> ([u32; 3], [u32; 3]) {
    let mut lo = DVec3::INFINITY;
    let mut hi = DVec3::NEG_INFINITY;
    for (c, r) in centers.iter().zip(radii) {
        lo = lo.min(*c - DVec3::splat(*r));
        hi = hi.max(*c + DVec3::splat(*r));
    }
    let n = res as f64;
    let to_cell = |v: f64| v.clamp(0.0, n - 1.0) as u32;
    let a = (lo * n - DVec3::ONE).floor();
    let b = (hi * n + DVec3::ONE).ceil();
    (
        [to_cell(a.x), to_cell(a.y), to_cell(a.z)],
        [to_cell(b.x), to_cell(b.y), to_cell(b.z)],
    )
}

/// Squared lattice distance from a cell's sample point to a sphere's centre.
pub(crate) fn dist2(s: &QSphere, x: [u32; 3]) -> u64 {
    (0..3)
        .map(|a| (x[a] as i64 - s.c[a] as i64).pow(2) as u64)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_is_in_range_and_spread() {
        let mut seen = [[0u32; 16]; 3];
        for cell in 0..16_000 {
            for (a, m) in jitter(seed32(9), cell).iter().enumerate() {
                seen[a][*m as usize] += 1;
            }
        }
        // 1000 expected per level, sd ~ 31: allow 5 sigma.
        assert!(
            seen.iter().flatten().all(|&n| (845..1155).contains(&n)),
            "{seen:?}"
        );
    }

    #[test]
    fn isqrt_is_exact() {
        for v in [
            0u64,
            1,
            2,
            3,
            4,
            15,
            16,
            17,
            (1 << 40) - 1,
            1 << 40,
            u32::MAX as u64,
        ] {
            let r = isqrt(v);
            assert!(r * r <= v && (r + 1) * (r + 1) > v, "{v}");
        }
    }
}
