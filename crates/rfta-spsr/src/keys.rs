//! Morton keys for octree cells and grid nodes, and a fast hasher for integer keys.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Spread the low 21 bits of `v` so that bit `k` lands on bit `3k`.
fn spread(v: u32) -> u64 {
    let mut x = u64::from(v) & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Inverse of [`spread`].
fn compact(v: u64) -> u32 {
    let mut x = v & 0x1249_2492_4924_9249;
    x = (x | (x >> 2)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x >> 4)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x >> 8)) & 0x001f_0000_ff00_00ff;
    x = (x | (x >> 16)) & 0x001f_0000_0000_ffff;
    x = (x | (x >> 32)) & 0x1f_ffff;
    x as u32
}

/// Morton (Z-order) key of integer coordinates below 2^21: x in bit 0, y in bit 1, z in bit 2.
/// Sorting cells of one depth by key groups the eight children of a parent together, and a
/// parent's key is its child's key shifted right by 3.
pub(crate) fn morton(c: [u32; 3]) -> u64 {
    spread(c[0]) | (spread(c[1]) << 1) | (spread(c[2]) << 2)
}

/// Coordinates of a Morton key.
pub(crate) fn demorton(k: u64) -> [u32; 3] {
    [compact(k), compact(k >> 1), compact(k >> 2)]
}

/// Multiplicative hasher for `u64` keys (keys are Morton codes, so the low bits are already well
/// spread; one multiply and a fold mix the high bits in).
#[derive(Default, Clone, Copy)]
pub(crate) struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b) ^ self.0.rotate_left(8));
        }
    }

    fn write_u64(&mut self, i: u64) {
        let h = i.wrapping_mul(0x9e37_79b9_7f4a_7c15);
        self.0 = h ^ (h >> 29);
    }
}

/// Map from a Morton key to a value (an index by default).
pub(crate) type KeyMap<V = u32> = HashMap<u64, V, BuildHasherDefault<KeyHasher>>;

/// An empty [`KeyMap`] with room for `n` keys.
pub(crate) fn key_map<V>(n: usize) -> KeyMap<V> {
    KeyMap::with_capacity_and_hasher(n, BuildHasherDefault::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_round_trips_and_orders_children_after_parents() {
        for c in [[0, 0, 0], [1, 2, 3], [2_097_151, 5, 1_000_000], [7, 7, 7]] {
            assert_eq!(demorton(morton(c)), c);
        }
        // The 8 children of cell (3, 5, 6) at the next depth have keys parent * 8 + 0..8.
        let parent = morton([3, 5, 6]);
        for c in 0..8u32 {
            let child = [6 + (c & 1), 10 + ((c >> 1) & 1), 12 + ((c >> 2) & 1)];
            assert_eq!(morton(child), parent * 8 + u64::from(c));
        }
    }

    /// `block27` against 27 lookups, on random sparse sets indexed densely (extent 37, not a
    /// multiple of the brick) and by hashing (extent 1500), at every point of the set, at points
    /// next to it and at the edges of the extent.
    #[test]
    fn block27_is_the_27_lookups() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move |n: u32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % u64::from(n)) as u32
        };
        for (extent, count) in [(37u32, 4000usize), (1500, 20_000)] {
            let span = if extent > 100 { 40 } else { extent };
            let base = extent - span;
            let mut coords: Vec<[u32; 3]> = (0..count)
                .map(|_| [0; 3].map(|_| base + next(span)))
                .collect();
            coords.sort_by_key(|&c| morton(c));
            coords.dedup();
            let index = SparseIndex::new(coords.iter().copied(), extent, coords.len());
            assert!(matches!(index.bricks, Bricks::Dense { .. }) == (extent < 100));
            let e = i64::from(extent);
            let mut probes: Vec<[i64; 3]> = coords
                .iter()
                .map(|c| [0, 1, 2].map(|a| i64::from(c[a]) + i64::from(next(3)) - 1))
                .collect();
            probes.extend([
                [0, 0, 0],
                [e - 1, e - 1, e - 1],
                [e, 0, e - 1],
                [-1, e - 8, 7],
            ]);
            for c in probes {
                let mut want = [NONE; 27];
                for (o, w) in want.iter_mut().enumerate() {
                    let q = [0, 1, 2].map(|a| c[a] + [o % 3, o / 3 % 3, o / 9][a] as i64 - 1);
                    *w = index.get(q).unwrap_or(NONE);
                }
                assert_eq!(index.block27(c), want, "around {c:?}");
            }
        }
    }
}

/// Sentinel for an absent entry.
pub(crate) const NONE: u32 = u32::MAX;

/// Index of a sparse set of integer points: 8x8x8 bricks, each a dense array of 512 slots, found
/// through a dense table of all bricks when the extent is small enough (at most
/// [`DENSE_BRICKS`] bricks, 8 MB) and by hashing the brick's key otherwise. A lookup costs one
/// table read (or one hash probe into a table ~100 times smaller than the set) and one array read.
#[derive(Debug, Clone, Default)]
pub(crate) struct SparseIndex {
    bricks: Bricks,
    slots: Vec<u32>,
    extent: i64,
}

/// Where each brick's slots start, by brick.
#[derive(Debug, Clone)]
enum Bricks {
    /// `table[bx + n (by + n bz)]`, `n` bricks per axis (`NONE` where empty).
    Dense { table: Vec<u32>, n: usize },
    /// By Morton key of the brick.
    Hashed(KeyMap<u32>),
}

impl Default for Bricks {
    fn default() -> Self {
        Bricks::Hashed(KeyMap::default())
    }
}

/// The largest brick count indexed by a dense table (2^21 bricks: extents up to 1024).
const DENSE_BRICKS: usize = 1 << 21;

impl Bricks {
    fn new(extent: u32, hint: usize) -> Self {
        let n = (extent as usize).div_ceil(8);
        if n.saturating_mul(n).saturating_mul(n) <= DENSE_BRICKS {
            Bricks::Dense {
                table: vec![NONE; n * n * n],
                n,
            }
        } else {
            Bricks::Hashed(key_map(hint / 64 + 16))
        }
    }

    /// The brick at brick coordinates `b` (each below the extent / 8).
    #[inline]
    fn get(&self, b: [u32; 3]) -> Option<u32> {
        match self {
            Bricks::Dense { table, n } => {
                let id = table[b[0] as usize + n * (b[1] as usize + n * b[2] as usize)];
                (id != NONE).then_some(id)
            }
            Bricks::Hashed(map) => map.get(&morton(b)).copied(),
        }
    }

    /// The brick at `b`, made `next` if it has none yet.
    fn get_or_insert(&mut self, b: [u32; 3], next: u32) -> u32 {
        match self {
            Bricks::Dense { table, n } => {
                let e = &mut table[b[0] as usize + *n * (b[1] as usize + *n * b[2] as usize)];
                if *e == NONE {
                    *e = next;
                }
                *e
            }
            Bricks::Hashed(map) => *map.entry(morton(b)).or_insert(next),
        }
    }
}

impl SparseIndex {
    /// Index points `coords[i] -> i`; coordinates must be below `extent`.
    pub(crate) fn new(coords: impl Iterator<Item = [u32; 3]>, extent: u32, hint: usize) -> Self {
        let mut bricks = Bricks::new(extent, hint);
        let mut slots: Vec<u32> = Vec::new();
        let mut last = ([u32::MAX; 3], 0u32);
        for (i, c) in coords.enumerate() {
            let bc = [c[0] >> 3, c[1] >> 3, c[2] >> 3];
            let b = if bc == last.0 {
                last.1
            } else {
                let next = (slots.len() / 512) as u32;
                let b = bricks.get_or_insert(bc, next);
                if b == next {
                    slots.resize(slots.len() + 512, NONE);
                }
                last = (bc, b);
                b
            };
            slots[b as usize * 512 + slot(c)] = i as u32;
        }
        Self {
            bricks,
            slots,
            extent: i64::from(extent),
        }
    }

    /// Index of a point, if present.
    #[inline]
    pub(crate) fn get(&self, c: [i64; 3]) -> Option<u32> {
        if c.iter().any(|&v| v < 0 || v >= self.extent) {
            return None;
        }
        let c = [c[0] as u32, c[1] as u32, c[2] as u32];
        let b = self.bricks.get([c[0] >> 3, c[1] >> 3, c[2] >> 3])?;
        let s = self.slots[b as usize * 512 + slot(c)];
        (s != NONE).then_some(s)
    }
}

impl SparseIndex {
    /// Indices of the 3x3x3 block around `c` (`NONE` where absent), in the order
    /// `(x + 1) + 3 (y + 1) + 9 (z + 1)`: one brick probe per brick the block overlaps (one for
    /// most points, at most eight) instead of 27.
    pub(crate) fn block27(&self, c: [i64; 3]) -> [u32; 27] {
        let mut out = [NONE; 27];
        let bricks_per_axis = (self.extent + 7) / 8;
        // Per axis: the brick holding `c - 1` with the offsets `k` (of `c + k - 1`) inside it,
        // and the next brick with the rest (empty when the block stays in one brick). A brick
        // outside the index holds nothing; points past the extent inside a brick are `NONE`.
        let mut span = [[(0i64, 0usize, 0usize); 2]; 3];
        for a in 0..3 {
            let lo = (c[a] - 1).div_euclid(8);
            let split = (lo * 8 + 9 - c[a]).min(3) as usize;
            span[a] = [(lo, 0, split), (lo + 1, split, 3)];
        }
        let used = |&&(b, k0, k1): &&(i64, usize, usize)| k0 < k1 && b >= 0 && b < bricks_per_axis;
        for &(bz, z0, z1) in span[2].iter().filter(used) {
            for &(by, y0, y1) in span[1].iter().filter(used) {
                for &(bx, x0, x1) in span[0].iter().filter(used) {
                    let Some(id) = self.bricks.get([bx as u32, by as u32, bz as u32]) else {
                        continue;
                    };
                    let slots = &self.slots[id as usize * 512..id as usize * 512 + 512];
                    let local = |a: usize, k: usize, b: i64| (c[a] + k as i64 - 1 - 8 * b) as usize;
                    for kz in z0..z1 {
                        for ky in y0..y1 {
                            for kx in x0..x1 {
                                let sl = (local(2, kz, bz) << 6)
                                    | (local(1, ky, by) << 3)
                                    | local(0, kx, bx);
                                out[kx + 3 * ky + 9 * kz] = slots[sl];
                            }
                        }
                    }
                }
            }
        }
        out
    }
}

#[inline]
fn slot(c: [u32; 3]) -> usize {
    (((c[2] & 7) << 6) | ((c[1] & 7) << 3) | (c[0] & 7)) as usize
}
