//! Occupancy on the CPU: spheres in parallel, columns of cells, bits set atomically.

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use crate::RasterParams;
use crate::band::BitGrid;
use crate::band::word_mask;
use crate::lattice::{QSphere, SUBCELLS, cell_index, dist2, isqrt, jitter, seed32};

/// Sets the bit of every cell whose sample point is inside some sphere.
///
/// Per column of candidate cells, the cells whose every lattice point is inside (so whatever their
/// jitter) form a run found with exact integer arithmetic and are set word by word; the remaining
/// candidates are tested at their jittered sample. The result equals testing every candidate cell.
pub(crate) fn occupancy(spheres: &[QSphere], params: &RasterParams) -> BitGrid {
    let res = params.res;
    let wpc = res.div_ceil(64);
    let words: Vec<AtomicU64> = (0..res * res * wpc).map(|_| AtomicU64::new(0)).collect();
    let seed = seed32(params.seed);
    spheres.par_iter().for_each(|s| rasterize_sphere(s, res, wpc, seed, &words));
    BitGrid::from_words(res, words.into_iter().map(AtomicU64::into_inner).collect())
}

/// Largest and smallest squared lattice distance along one axis from a cell's lattice points
/// (`16 i .. 16 i + 15`) to the centre coordinate `c`.
fn axis_range(i: u32, c: i32) -> (u64, u64) {
    let a = (i * SUBCELLS) as i64 - c as i64;
    let b = a + SUBCELLS as i64 - 1;
    let far = a.abs().max(b.abs()) as u64;
    let near = if a <= 0 && b >= 0 { 0 } else { a.abs().min(b.abs()) as u64 };
    (near * near, far * far)
}

fn rasterize_sphere(s: &QSphere, res: usize, wpc: usize, seed: u32, words: &[AtomicU64]) {
    if (0..3).any(|a| s.lo[a] > s.hi[a]) {
        return;
    }
    let r2 = s.r2 as u64;
    for ix in s.lo[0]..=s.hi[0] {
        let (nx, fx) = axis_range(ix, s.c[0]);
        if nx > r2 {
            continue;
        }
        for iy in s.lo[1]..=s.hi[1] {
            let (ny, fy) = axis_range(iy, s.c[1]);
            if nx + ny > r2 {
                continue;
            }
            let base = (ix as usize * res + iy as usize) * wpc;
            let col = &words[base..base + wpc];
            // Cells whose farthest lattice point is inside: a contiguous run in z.
            let (mut full_lo, mut full_hi) = (1i64, 0i64);
            if fx + fy <= r2 {
                let h = isqrt(r2 - fx - fy) as i64;
                let c = s.c[2] as i64;
                let sub = SUBCELLS as i64;
                full_lo = (c - h + sub - 1).div_euclid(sub).max(s.lo[2] as i64);
                full_hi = (c + h - (sub - 1)).div_euclid(sub).min(s.hi[2] as i64);
                if full_lo <= full_hi {
                    set_run(col, full_lo as usize, full_hi as usize);
                }
            }
            for iz in s.lo[2]..=s.hi[2] {
                if (iz as i64) >= full_lo && (iz as i64) <= full_hi {
                    continue;
                }
                let m = jitter(seed, cell_index(res as u32, ix, iy, iz));
                let x = [ix * SUBCELLS + m[0], iy * SUBCELLS + m[1], iz * SUBCELLS + m[2]];
                if dist2(s, x) <= r2 {
                    col[iz as usize / 64].fetch_or(1 << (iz % 64), Ordering::Relaxed);
                }
            }
        }
    }
}

/// Sets bits `lo..=hi` of a column.
fn set_run(col: &[AtomicU64], lo: usize, hi: usize) {
    for (w, word) in col.iter().enumerate().take(hi / 64 + 1).skip(lo / 64) {
        word.fetch_or(word_mask(w, lo, hi), Ordering::Relaxed);
    }
}
