//! The occupancy bit grid, the one-cell narrow band and the emitted points.

use rayon::prelude::*;
use rfta_geom::glam::DVec3;

use crate::RasterParams;
use crate::lattice::cell_sample;

/// One bit per cell. Cell `(ix, iy, iz)` is bit `iz` of column `ix * res + iy`; each column is
/// padded to whole 64-bit words (little-endian, so the same memory read as `u32` words has bit `iz`
/// in word `iz / 32`, which is how the GPU path writes it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BitGrid {
    res: usize,
    words_per_column: usize,
    words: Vec<u64>,
}

impl BitGrid {
    /// An empty grid of `res^3` cells.
    pub fn new(res: usize) -> Self {
        let words_per_column = res.div_ceil(64);
        Self {
            res,
            words_per_column,
            words: vec![0; res * res * words_per_column],
        }
    }

    /// A grid from its 64-bit words (as [`BitGrid::words`] returns them).
    pub(crate) fn from_words(res: usize, words: Vec<u64>) -> Self {
        Self {
            res,
            words_per_column: res.div_ceil(64),
            words,
        }
    }

    /// Cells per axis.
    pub fn res(&self) -> usize {
        self.res
    }

    /// 64-bit words per column.
    pub fn words_per_column(&self) -> usize {
        self.words_per_column
    }

    /// The raw words.
    pub fn words(&self) -> &[u64] {
        &self.words
    }

    /// Whether cell `(ix, iy, iz)` is set.
    pub fn get(&self, ix: usize, iy: usize, iz: usize) -> bool {
        let w = (ix * self.res + iy) * self.words_per_column + iz / 64;
        self.words[w] >> (iz % 64) & 1 == 1
    }

    /// Number of set cells.
    pub fn count_ones(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }

    fn column(&self, ix: usize, iy: usize) -> &[u64] {
        let start = (ix * self.res + iy) * self.words_per_column;
        &self.words[start..start + self.words_per_column]
    }

    /// The jittered sample point of every empty cell that has an occupied cell among its 26
    /// neighbours, within the inclusive cell box `bbox`, in grid order.
    pub(crate) fn narrow_band_points(
        &self,
        bbox: ([u32; 3], [u32; 3]),
        params: &RasterParams,
    ) -> Vec<DVec3> {
        let (lo, hi) = bbox;
        if (0..3).any(|a| lo[a] > hi[a]) || self.res == 0 {
            return Vec::new();
        }
        let res = self.res;
        let wpc = self.words_per_column;
        let z_mask = mask_range(wpc, lo[2] as usize, hi[2] as usize);
        let slabs: Vec<Vec<DVec3>> = (lo[0] as usize..=hi[0] as usize)
            .into_par_iter()
            .map(|ix| {
                let mut out = Vec::new();
                let mut dil = vec![0u64; wpc];
                for iy in lo[1] as usize..=hi[1] as usize {
                    dil.iter_mut().for_each(|w| *w = 0);
                    for nx in ix.saturating_sub(1)..=(ix + 1).min(res - 1) {
                        for ny in iy.saturating_sub(1)..=(iy + 1).min(res - 1) {
                            for (d, s) in dil.iter_mut().zip(self.column(nx, ny)) {
                                *d |= *s;
                            }
                        }
                    }
                    let own = self.column(ix, iy);
                    for w in 0..wpc {
                        let below = if w > 0 { dil[w - 1] >> 63 } else { 0 };
                        let above = if w + 1 < wpc { dil[w + 1] << 63 } else { 0 };
                        let grown = dil[w] | (dil[w] << 1) | below | (dil[w] >> 1) | above;
                        let mut band = grown & !own[w] & z_mask[w];
                        while band != 0 {
                            let iz = w * 64 + band.trailing_zeros() as usize;
                            band &= band - 1;
                            out.push(cell_sample(params, [ix as u32, iy as u32, iz as u32]));
                        }
                    }
                }
                out
            })
            .collect();
        slabs.concat()
    }
}

/// Per-word masks selecting bits `lo..=hi` of a column.
fn mask_range(wpc: usize, lo: usize, hi: usize) -> Vec<u64> {
    (0..wpc).map(|w| word_mask(w, lo, hi)).collect()
}

/// The bits of word `w` (bits `64 w .. 64 w + 63`) that fall in `lo..=hi`.
pub(crate) fn word_mask(w: usize, lo: usize, hi: usize) -> u64 {
    let (a, b) = (w * 64, w * 64 + 63);
    if hi < a || lo > b {
        return 0;
    }
    let from = lo.max(a) - a;
    let to = hi.min(b) - a;
    let upper = if to == 63 {
        u64::MAX
    } else {
        (1u64 << (to + 1)) - 1
    };
    upper & !((1u64 << from) - 1)
}
