//! Occupancy on the CPU: exact, hierarchical, parallel over spheres.
//!
//! Deep inside the union of spheres every cell is occupied many times over; only cells near the
//! union's boundary need testing. So the grid is cut into blocks of [`BLOCK`]^3 cells and:
//!
//! 1. every sphere marks the blocks it holds entirely (every lattice point of every cell inside,
//!    checked with exact integer arithmetic; a block run per column of blocks);
//! 2. every sphere rasterizes its cells in the blocks it touches that no sphere covers: per column
//!    of cells, the run of cells entirely inside is set word by word and the remaining candidates
//!    are tested at their jittered sample;
//! 3. every covered block is filled.
//!
//! A covered block's cells are all occupied (its covering sphere holds every sample), and every
//! other cell is tested against every sphere that can reach it, so the result equals testing every
//! candidate cell against every sphere, which is what the GPU path does.

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use crate::RasterParams;
use crate::band::{BitGrid, word_mask};
use crate::lattice::{QSphere, SUBCELLS, cell_index, dist2, isqrt, jitter, seed32};

/// Cells per block side.
const BLOCK: u32 = 8;

/// Bits per axis and columns of a grid of `n` cells (or blocks) per axis.
struct Bits {
    n: usize,
    words_per_column: usize,
    words: Vec<AtomicU64>,
}

impl Bits {
    fn new(n: usize) -> Self {
        let wpc = n.div_ceil(64);
        Self {
            n,
            words_per_column: wpc,
            words: (0..n * n * wpc).map(|_| AtomicU64::new(0)).collect(),
        }
    }

    fn column(&self, x: u32, y: u32) -> &[AtomicU64] {
        let base = (x as usize * self.n + y as usize) * self.words_per_column;
        &self.words[base..base + self.words_per_column]
    }

    /// Sets bits `lo..=hi` of column `(x, y)`.
    fn set_run(&self, x: u32, y: u32, lo: u32, hi: u32) {
        let col = self.column(x, y);
        for (w, word) in col
            .iter()
            .enumerate()
            .take(hi as usize / 64 + 1)
            .skip(lo as usize / 64)
        {
            word.fetch_or(word_mask(w, lo as usize, hi as usize), Ordering::Relaxed);
        }
    }
}

pub(crate) fn occupancy(spheres: &[QSphere], params: &RasterParams) -> BitGrid {
    let res = params.res as u32;
    let seed = seed32(params.seed);
    let n_blocks = res.div_ceil(BLOCK);
    let covered = Bits::new(n_blocks as usize);
    spheres
        .par_iter()
        .for_each(|s| cover_blocks(s, res, &covered));
    let fine = Bits::new(res as usize);
    spheres
        .par_iter()
        .for_each(|s| rasterize_uncovered(s, res, seed, &covered, &fine));
    (0..n_blocks).into_par_iter().for_each(|bx| {
        for by in 0..n_blocks {
            for (w, word) in covered.column(bx, by).iter().enumerate() {
                let mut bits = word.load(Ordering::Relaxed);
                while bits != 0 {
                    let bz = (w * 64) as u32 + bits.trailing_zeros();
                    bits &= bits - 1;
                    let (z0, z1) = block_cells(bz, res);
                    for ix in block_cells(bx, res).0..=block_cells(bx, res).1 {
                        for iy in block_cells(by, res).0..=block_cells(by, res).1 {
                            fine.set_run(ix, iy, z0, z1);
                        }
                    }
                }
            }
        }
    });
    BitGrid::from_words(
        res as usize,
        fine.words.into_iter().map(AtomicU64::into_inner).collect(),
    )
}

/// First and last cell of block `b`.
fn block_cells(b: u32, res: u32) -> (u32, u32) {
    (b * BLOCK, ((b + 1) * BLOCK).min(res) - 1)
}

/// Nearest and farthest squared lattice distance along one axis from the lattice points of cells
/// `first..=last` (lattice `16 first .. 16 last + 15`) to the centre coordinate `c`.
fn axis_range(first: u32, last: u32, c: i32) -> (u64, u64) {
    let a = (first * SUBCELLS) as i64 - c as i64;
    let b = ((last + 1) * SUBCELLS) as i64 - 1 - c as i64;
    let far = a.abs().max(b.abs()) as u64;
    let near = if a <= 0 && b >= 0 {
        0
    } else {
        a.abs().min(b.abs()) as u64
    };
    (near * near, far * far)
}

fn empty(s: &QSphere) -> bool {
    (0..3).any(|a| s.lo[a] > s.hi[a])
}

/// Step 1: marks the blocks whose every lattice point is inside `s`.
fn cover_blocks(s: &QSphere, res: u32, covered: &Bits) {
    if empty(s) {
        return;
    }
    let r2 = s.r2 as u64;
    let span = (BLOCK * SUBCELLS) as i64;
    let last_block = (res - 1) / BLOCK;
    for bx in s.lo[0] / BLOCK..=s.hi[0] / BLOCK {
        let (x0, x1) = block_cells(bx, res);
        let (_, fx) = axis_range(x0, x1, s.c[0]);
        for by in s.lo[1] / BLOCK..=s.hi[1] / BLOCK {
            let (y0, y1) = block_cells(by, res);
            let (_, fy) = axis_range(y0, y1, s.c[1]);
            if fx + fy > r2 {
                continue;
            }
            // Full-size blocks entirely inside in z; a smaller last block may be missed, which
            // only costs time (step 2 then tests its cells).
            let h = isqrt(r2 - fx - fy) as i64;
            let c = s.c[2] as i64;
            let lo = (c - h + span - 1).div_euclid(span).max(0);
            let hi = (c + h - (span - 1)).div_euclid(span).min(last_block as i64);
            if lo <= hi {
                covered.set_run(bx, by, lo as u32, hi as u32);
            }
        }
    }
}

/// Step 2: the cells of `s` in blocks that no sphere covers.
fn rasterize_uncovered(s: &QSphere, res: u32, seed: u32, covered: &Bits, fine: &Bits) {
    if empty(s) {
        return;
    }
    let r2 = s.r2 as u64;
    let (bz_lo, bz_hi) = (s.lo[2] / BLOCK, s.hi[2] / BLOCK);
    for bx in s.lo[0] / BLOCK..=s.hi[0] / BLOCK {
        let (x0, x1) = block_cells(bx, res);
        let (x0, x1) = (x0.max(s.lo[0]), x1.min(s.hi[0]));
        let (nx, _) = axis_range(x0, x1, s.c[0]);
        if nx > r2 {
            continue;
        }
        for by in s.lo[1] / BLOCK..=s.hi[1] / BLOCK {
            let (y0, y1) = block_cells(by, res);
            let (y0, y1) = (y0.max(s.lo[1]), y1.min(s.hi[1]));
            let (ny, _) = axis_range(y0, y1, s.c[1]);
            if nx + ny > r2 {
                continue;
            }
            for (w, word) in covered.column(bx, by).iter().enumerate() {
                let mut open =
                    !word.load(Ordering::Relaxed) & word_mask(w, bz_lo as usize, bz_hi as usize);
                while open != 0 {
                    let bz = (w * 64) as u32 + open.trailing_zeros();
                    open &= open - 1;
                    let (z0, z1) = block_cells(bz, res);
                    let (z0, z1) = (z0.max(s.lo[2]), z1.min(s.hi[2]));
                    if nx + ny + axis_range(z0, z1, s.c[2]).0 > r2 {
                        continue;
                    }
                    for ix in x0..=x1 {
                        for iy in y0..=y1 {
                            rasterize_column(s, res, seed, fine, [ix, iy], z0, z1);
                        }
                    }
                }
            }
        }
    }
}

/// Cells `z0..=z1` of column `(ix, iy)`: the run entirely inside is set at once, the others are
/// tested at their jittered sample.
fn rasterize_column(
    s: &QSphere,
    res: u32,
    seed: u32,
    fine: &Bits,
    [ix, iy]: [u32; 2],
    z0: u32,
    z1: u32,
) {
    let r2 = s.r2 as u64;
    let (nx, fx) = axis_range(ix, ix, s.c[0]);
    let (ny, fy) = axis_range(iy, iy, s.c[1]);
    if nx + ny > r2 {
        return;
    }
    let (mut full_lo, mut full_hi) = (1i64, 0i64);
    if fx + fy <= r2 {
        let h = isqrt(r2 - fx - fy) as i64;
        let (c, sub) = (s.c[2] as i64, SUBCELLS as i64);
        full_lo = (c - h + sub - 1).div_euclid(sub).max(z0 as i64);
        full_hi = (c + h - (sub - 1)).div_euclid(sub).min(z1 as i64);
        if full_lo <= full_hi {
            fine.set_run(ix, iy, full_lo as u32, full_hi as u32);
        }
    }
    // Only cells whose nearest lattice point can be inside are candidates.
    let reach = isqrt(r2 - nx - ny) as i64;
    let c = s.c[2] as i64;
    let sub = SUBCELLS as i64;
    let z0 = ((c - reach).div_euclid(sub)).max(z0 as i64);
    let z1 = ((c + reach).div_euclid(sub)).min(z1 as i64);
    if z0 > z1 {
        return;
    }
    let (z0, z1) = (z0 as u32, z1 as u32);
    let col = fine.column(ix, iy);
    for iz in z0..=z1 {
        if (iz as i64) >= full_lo && (iz as i64) <= full_hi {
            continue;
        }
        let bit = 1u64 << (iz % 64);
        let word = &col[iz as usize / 64];
        if word.load(Ordering::Relaxed) & bit != 0 {
            continue;
        }
        let m = jitter(seed, cell_index(res, ix, iy, iz));
        let x = [
            ix * SUBCELLS + m[0],
            iy * SUBCELLS + m[1],
            iz * SUBCELLS + m[2],
        ];
        if dist2(s, x) <= r2 {
            word.fetch_or(bit, Ordering::Relaxed);
        }
    }
}
