//! Occupancy on the CPU: exact, hierarchical, parallel over spheres.
//!
//! Deep inside the union of spheres every cell is occupied many times over; only cells near the
//! union's boundary need testing. So the grid is cut into blocks of [`BLOCK`]^3 cells, and blocks
//! into superblocks of [`SUPER`]^3 blocks, and:
//!
//! 1. every sphere marks the superblocks it holds entirely (every lattice point of every cell
//!    inside, checked with exact integer arithmetic; a run per column of superblocks);
//! 2. every sphere marks the blocks it holds entirely, in the superblocks it reaches that no
//!    sphere holds;
//! 3. every sphere rasterizes its cells in the blocks it reaches that no sphere holds, visiting
//!    only superblocks with such a block: the cells of a block are one cache line ([`Cells`]), the
//!    cells some sphere has set already are skipped a row of the block at a time, the others are
//!    set when entirely inside or tested at their jittered sample, and a block that becomes full
//!    is marked held so that the spheres after it skip it;
//! 4. every held block and superblock is filled.
//!
//! A held block's cells are all occupied (its covering sphere holds every sample), and every
//! other cell is tested against every sphere that can reach it, so the result equals testing every
//! candidate cell against every sphere, which is what the GPU path does. The superblocks make a
//! large sphere's work follow the part of its boundary near the union's boundary rather than its
//! bounding box: on a 129^3 grid (2.1 million spheres, most of them large) rasterized at 576^3,
//! visiting every block column of every sphere's box was most of the time.

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use crate::RasterParams;
use crate::band::{BitGrid, word_mask};
use crate::lattice::{QSphere, SUBCELLS, cell_index, dist2, isqrt, jitter, seed32};

/// Cells per block side.
const BLOCK: u32 = 8;

/// Blocks per superblock side.
const SUPER: u32 = 8;

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

    fn get(&self, x: u32, y: u32, z: u32) -> bool {
        self.column(x, y)[z as usize / 64].load(Ordering::Relaxed) >> (z % 64) & 1 == 1
    }

    /// Bits `lo..=hi` of column `(x, y)`, word by word: `(word index, bits)`.
    fn run(&self, x: u32, y: u32, lo: u32, hi: u32) -> impl Iterator<Item = (usize, u64)> + '_ {
        self.column(x, y)
            .iter()
            .enumerate()
            .take(hi as usize / 64 + 1)
            .skip(lo as usize / 64)
            .map(move |(w, word)| {
                let mask = word_mask(w, lo as usize, hi as usize);
                (w, word.load(Ordering::Relaxed) & mask)
            })
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
            // Runs are often set already by overlapping spheres: a load is cheaper than a
            // read-modify-write on a cache line the other threads share.
            let mask = word_mask(w, lo as usize, hi as usize);
            if word.load(Ordering::Relaxed) & mask != mask {
                word.fetch_or(mask, Ordering::Relaxed);
            }
        }
    }
}

/// One level of the hierarchy: units of `size` cells per side over a grid of `res` cells.
#[derive(Clone, Copy)]
struct Level {
    size: u32,
    res: u32,
}

impl Level {
    /// Units per axis.
    fn n(self) -> u32 {
        self.res.div_ceil(self.size)
    }

    /// The superblocks over these units: [`SUPER`] of them per side.
    fn supers(self) -> Level {
        Level {
            size: self.size * SUPER,
            ..self
        }
    }

    /// Lattice steps per unit (a power of two).
    fn span(self) -> i64 {
        (self.size * SUBCELLS) as i64
    }

    /// `log2` of [`Level::span`].
    fn shift(self) -> u32 {
        (self.size * SUBCELLS).trailing_zeros()
    }

    /// First and last cell of unit `b`.
    fn cells(self, b: u32) -> (u32, u32) {
        (b * self.size, ((b + 1) * self.size).min(self.res) - 1)
    }

    /// The units holding the sphere's candidate cells on axis `a` (inclusive).
    fn range(self, s: &QSphere, a: usize) -> std::ops::RangeInclusive<u32> {
        s.lo[a] / self.size..=s.hi[a] / self.size
    }

    /// The units of column `(bx, by)` entirely inside `s` (every lattice point of every cell);
    /// `None` if there are none. A smaller last unit may be missed, which only costs time.
    fn inside_run(self, s: &QSphere, bx: u32, by: u32) -> Option<(u32, u32)> {
        let r2 = s.r2 as u64;
        let (x0, x1) = self.cells(bx);
        let (y0, y1) = self.cells(by);
        let (_, fx) = axis_range(x0, x1, s.c[0]);
        let (_, fy) = axis_range(y0, y1, s.c[1]);
        if fx + fy > r2 {
            return None;
        }
        let h = isqrt(r2 - fx - fy) as i64;
        let (c, span, shift) = (s.c[2] as i64, self.span(), self.shift());
        // Floor division by the power of two `span` is an arithmetic shift.
        let lo = ((c - h + span - 1) >> shift).max(0);
        let hi = ((c + h - (span - 1)) >> shift).min(self.n() as i64 - 1);
        (lo <= hi).then_some((lo as u32, hi as u32))
    }

    /// The units of column `(bx, by)` that hold a lattice point inside `s`, within the sphere's
    /// candidate cells and the units `lo..=hi`; `None` if there are none.
    fn reach_run(self, s: &QSphere, bx: u32, by: u32, lo: u32, hi: u32) -> Option<(u32, u32)> {
        let r2 = s.r2 as u64;
        let (x0, x1) = self.cells(bx);
        let (y0, y1) = self.cells(by);
        let (nx, _) = axis_range(x0.max(s.lo[0]), x1.min(s.hi[0]), s.c[0]);
        let (ny, _) = axis_range(y0.max(s.lo[1]), y1.min(s.hi[1]), s.c[1]);
        if nx + ny > r2 {
            return None;
        }
        let reach = isqrt(r2 - nx - ny) as i64;
        let (c, shift) = (s.c[2] as i64, self.shift());
        let first = ((c - reach) >> shift).max(lo as i64);
        let last = ((c + reach) >> shift).min(hi as i64);
        (first <= last).then_some((first as u32, last as u32))
    }
}

pub(crate) fn occupancy(spheres: &[QSphere], params: &RasterParams) -> BitGrid {
    let res = params.res as u32;
    let seed = seed32(params.seed);
    let blocks = Level { size: BLOCK, res };
    let supers = blocks.supers();
    let held_super = Bits::new(supers.n() as usize);
    spheres
        .par_iter()
        .for_each(|s| hold_units(s, supers, &held_super));
    let held = Bits::new(blocks.n() as usize);
    spheres
        .par_iter()
        .for_each(|s| hold_blocks(s, blocks, &held_super, &held));
    let open = open_supers(&held_super, &held);
    let fine = Cells::new(blocks.n() as usize);
    spheres
        .par_iter()
        .for_each(|s| rasterize_open(s, blocks, seed, &open, &held, &fine));
    fill(&held_super, supers, &fine);
    fill(&held, blocks, &fine);
    fine.into_grid(res as usize)
}

/// The cells, block by block: block `(bx, by, bz)` is [`BLOCK`] words (word `ix % 8`, bit
/// `8 (iy % 8) + iz % 8`), one cache line, so a sphere reads and writes a block it reaches at
/// once. Bits of cells beyond the grid's last cell may be set (filled blocks); they are dropped
/// by [`Cells::into_grid`].
struct Cells {
    nb: usize,
    words: Vec<AtomicU64>,
}

/// Every bit of a block.
const FULL: u64 = u64::MAX;

impl Cells {
    fn new(nb: usize) -> Self {
        Self {
            nb,
            words: (0..nb * nb * nb * BLOCK as usize)
                .map(|_| AtomicU64::new(0))
                .collect(),
        }
    }

    fn block(&self, [bx, by, bz]: [u32; 3]) -> &[AtomicU64] {
        let b = (bx as usize * self.nb + by as usize) * self.nb + bz as usize;
        &self.words[b * BLOCK as usize..(b + 1) * BLOCK as usize]
    }

    /// Sets every cell of a block.
    fn fill_block(&self, b: [u32; 3]) {
        for word in self.block(b) {
            if word.load(Ordering::Relaxed) != FULL {
                word.store(FULL, Ordering::Relaxed);
            }
        }
    }

    /// The cells of a `res^3` grid in column order.
    fn into_grid(self, res: usize) -> BitGrid {
        let nb = self.nb;
        let words: Vec<u64> = self.words.into_iter().map(AtomicU64::into_inner).collect();
        let wpc = res.div_ceil(64);
        let mut out = vec![0u64; res * res * wpc];
        out.par_chunks_mut(res * wpc)
            .enumerate()
            .for_each(|(ix, slab)| {
                let (bx, lx) = (ix / BLOCK as usize, ix % BLOCK as usize);
                for (iy, column) in slab.chunks_mut(wpc).enumerate() {
                    let (by, ly) = (iy / BLOCK as usize, iy % BLOCK as usize);
                    for bz in 0..nb {
                        let word = words[((bx * nb + by) * nb + bz) * BLOCK as usize + lx];
                        let byte = (word >> (8 * ly)) & 0xff;
                        let z = bz * BLOCK as usize;
                        column[z / 64] |= byte << (z % 64);
                    }
                    // Cells beyond the grid.
                    if !res.is_multiple_of(64) {
                        column[wpc - 1] &= (1u64 << (res % 64)) - 1;
                    }
                }
            });
        BitGrid::from_words(res, out)
    }
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

/// Step 1: marks the units of `level` whose every lattice point is inside `s`.
fn hold_units(s: &QSphere, level: Level, held: &Bits) {
    if empty(s) {
        return;
    }
    for bx in level.range(s, 0) {
        for by in level.range(s, 1) {
            if let Some((lo, hi)) = level.inside_run(s, bx, by) {
                held.set_run(bx, by, lo, hi);
            }
        }
    }
}

/// Step 2: marks the blocks whose every lattice point is inside `s`, in the superblocks `s`
/// reaches that no sphere holds.
fn hold_blocks(s: &QSphere, blocks: Level, held_super: &Bits, held: &Bits) {
    if empty(s) {
        return;
    }
    let supers = blocks.supers();
    let (sz_lo, sz_hi) = supers.range(s, 2).into_inner();
    for sx in supers.range(s, 0) {
        for sy in supers.range(s, 1) {
            let Some((lo, hi)) = supers.reach_run(s, sx, sy, sz_lo, sz_hi) else {
                continue;
            };
            let all_held = held_super
                .run(sx, sy, lo, hi)
                .all(|(w, bits)| bits == word_mask(w, lo as usize, hi as usize));
            if all_held {
                continue;
            }
            let (z_lo, z_hi) = (lo * SUPER, ((hi + 1) * SUPER).min(blocks.n()) - 1);
            for bx in sub_units(sx, blocks, &s.lo, &s.hi, 0) {
                for by in sub_units(sy, blocks, &s.lo, &s.hi, 1) {
                    if let Some((a, b)) = blocks.inside_run(s, bx, by) {
                        let (a, b) = (a.max(z_lo), b.min(z_hi));
                        if a <= b {
                            held.set_run(bx, by, a, b);
                        }
                    }
                }
            }
        }
    }
}

/// The blocks of superblock `sb` on axis `a` that hold candidate cells `lo[a]..=hi[a]`.
fn sub_units(
    sb: u32,
    blocks: Level,
    lo: &[u32; 3],
    hi: &[u32; 3],
    a: usize,
) -> std::ops::RangeInclusive<u32> {
    let first = (sb * SUPER).max(lo[a] / blocks.size);
    let last = ((sb + 1) * SUPER - 1).min(hi[a] / blocks.size);
    first..=last
}

/// The superblocks that no sphere holds and that have a block no sphere holds.
fn open_supers(held_super: &Bits, held: &Bits) -> Bits {
    let n = held_super.n as u32;
    let n_blocks = held.n as u32;
    let open = Bits::new(n as usize);
    (0..n).into_par_iter().for_each(|sx| {
        for sy in 0..n {
            for sz in 0..n {
                if held_super.get(sx, sy, sz) {
                    continue;
                }
                let z_lo = sz * SUPER;
                let z_hi = ((sz + 1) * SUPER).min(n_blocks) - 1;
                let some_open = (sx * SUPER..((sx + 1) * SUPER).min(n_blocks)).any(|bx| {
                    (sy * SUPER..((sy + 1) * SUPER).min(n_blocks)).any(|by| {
                        held.run(bx, by, z_lo, z_hi)
                            .any(|(w, bits)| bits != word_mask(w, z_lo as usize, z_hi as usize))
                    })
                });
                if some_open {
                    open.set_run(sx, sy, sz, sz);
                }
            }
        }
    });
    open
}

/// Step 3: the cells of `s` in the blocks no sphere holds, visiting open superblocks only.
fn rasterize_open(s: &QSphere, blocks: Level, seed: u32, open: &Bits, held: &Bits, fine: &Cells) {
    if empty(s) {
        return;
    }
    let supers = blocks.supers();
    let (sz_lo, sz_hi) = supers.range(s, 2).into_inner();
    let (bz_lo, bz_hi) = blocks.range(s, 2).into_inner();
    for sx in supers.range(s, 0) {
        for sy in supers.range(s, 1) {
            let Some((lo, hi)) = supers.reach_run(s, sx, sy, sz_lo, sz_hi) else {
                continue;
            };
            for (w, mut bits) in open.run(sx, sy, lo, hi) {
                while bits != 0 {
                    let sz = (w * 64) as u32 + bits.trailing_zeros();
                    bits &= bits - 1;
                    let z_lo = (sz * SUPER).max(bz_lo);
                    let z_hi = (((sz + 1) * SUPER).min(blocks.n()) - 1).min(bz_hi);
                    for bx in sub_units(sx, blocks, &s.lo, &s.hi, 0) {
                        for by in sub_units(sy, blocks, &s.lo, &s.hi, 1) {
                            if held
                                .run(bx, by, z_lo, z_hi)
                                .all(|(w, bits)| bits == word_mask(w, z_lo as usize, z_hi as usize))
                            {
                                continue;
                            }
                            let Some((a, b)) = blocks.reach_run(s, bx, by, z_lo, z_hi) else {
                                continue;
                            };
                            rasterize_blocks(s, blocks, seed, held, fine, [bx, by], a, b);
                        }
                    }
                }
            }
        }
    }
}

/// The cells of `s` in blocks `a..=b` of block column `(bx, by)` that no sphere holds; a block
/// this fills is marked held, so that no other sphere visits it.
#[expect(clippy::too_many_arguments, reason = "one block column of one sphere")]
fn rasterize_blocks(
    s: &QSphere,
    blocks: Level,
    seed: u32,
    held: &Bits,
    fine: &Cells,
    [bx, by]: [u32; 2],
    a: u32,
    b: u32,
) {
    for (w, bits) in held.run(bx, by, a, b) {
        let mut free = !bits & word_mask(w, a as usize, b as usize);
        while free != 0 {
            let bz = (w * 64) as u32 + free.trailing_zeros();
            free &= free - 1;
            if rasterize_block(s, blocks, seed, fine, [bx, by, bz]) {
                held.set_run(bx, by, bz, bz);
            }
        }
    }
}

/// Step 4: fills every cell of every held unit of `level` (blocks or superblocks).
fn fill(held: &Bits, level: Level, fine: &Cells) {
    let n = level.n();
    let per = level.size / BLOCK;
    let n_blocks = fine.nb as u32;
    (0..n).into_par_iter().for_each(|ux| {
        for uy in 0..n {
            for (w, word) in held.column(ux, uy).iter().enumerate() {
                let mut bits = word.load(Ordering::Relaxed);
                while bits != 0 {
                    let uz = (w * 64) as u32 + bits.trailing_zeros();
                    bits &= bits - 1;
                    let blocks = |u: u32| u * per..((u + 1) * per).min(n_blocks);
                    for bx in blocks(ux) {
                        for by in blocks(uy) {
                            for bz in blocks(uz) {
                                fine.fill_block([bx, by, bz]);
                            }
                        }
                    }
                }
            }
        }
    });
}

/// The cells of block `b` that `s` reaches and no other sphere has set yet: a cell entirely
/// inside is set at once, the others are tested at their jittered sample. Returns whether the
/// block is now full.
fn rasterize_block(s: &QSphere, blocks: Level, seed: u32, fine: &Cells, b: [u32; 3]) -> bool {
    let r2 = s.r2 as u64;
    let range = |a: usize| {
        let (c0, c1) = blocks.cells(b[a]);
        (c0.max(s.lo[a]), c1.min(s.hi[a]))
    };
    let ((x0, x1), (y0, y1), (z0, z1)) = (range(0), range(1), range(2));
    if x0 > x1 || y0 > y1 || z0 > z1 {
        return false;
    }
    // The block's bits of rows y0..=y1, cells z0..=z1 of each.
    let z_bits = (0xffu64 >> (7 - z1 % BLOCK)) & (0xff << (z0 % BLOCK));
    let plane = (y0..=y1).fold(0, |m, iy| m | z_bits << (BLOCK * (iy % BLOCK)));
    let words = fine.block(b);
    for ix in x0..=x1 {
        let word = &words[(ix % BLOCK) as usize];
        // Near the union's boundary most cells are set already by other spheres.
        let mut need = !word.load(Ordering::Relaxed) & plane;
        let (nx, fx) = axis_range(ix, ix, s.c[0]);
        if need == 0 || nx > r2 {
            continue;
        }
        let mut add = 0;
        while need != 0 {
            let bit = need.trailing_zeros();
            need &= need - 1;
            let iy = b[1] * BLOCK + bit / BLOCK;
            let iz = b[2] * BLOCK + bit % BLOCK;
            let (ny, fy) = axis_range(iy, iy, s.c[1]);
            let (nz, fz) = axis_range(iz, iz, s.c[2]);
            if nx + ny + nz > r2 {
                continue;
            }
            // Every lattice point of the cell inside, or its jittered sample.
            let inside = fx + fy + fz <= r2 || {
                let m = jitter(seed, cell_index(blocks.res, ix, iy, iz));
                let x = [
                    ix * SUBCELLS + m[0],
                    iy * SUBCELLS + m[1],
                    iz * SUBCELLS + m[2],
                ];
                dist2(s, x) <= r2
            };
            if inside {
                add |= 1u64 << bit;
            }
        }
        if add != 0 {
            word.fetch_or(add, Ordering::Relaxed);
        }
    }
    words.iter().all(|w| w.load(Ordering::Relaxed) == FULL)
}
