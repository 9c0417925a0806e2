//! A grid's tree as OpenVDB writes it (`tree/RootNode.h`, `InternalNode.h`, `LeafNode.h`,
//! `io/Compression.h`), read into tiles and leaves, and made dense over a box.
//!
//! The standard tree is a root of 4096^3-voxel children, internal nodes of 32^3 children of 16^3
//! children of 8^3-voxel leaves. The topology comes first: the root's background, its tiles and
//! children; each internal node's child mask, value mask and the values of its entries that are
//! not children (its tiles), then its children; a leaf's value mask. The leaves' values follow,
//! leaf by leaf in the same order. Values are written "compressed": a byte says which inactive
//! values were dropped (with the active-mask option), the one or two inactive values and a mask
//! choosing between them where needed, then the kept values, raw, zipped or Blosc-compressed,
//! as 16-bit halves for grids saved that way.

use super::blosc;
use super::bytes::Bytes;
use crate::error::{ParseError, ParseResult};

/// `COMPRESS_ZIP`, `COMPRESS_ACTIVE_MASK`, `COMPRESS_BLOSC` (`io/Compression.h`).
pub(super) const ZIP: u32 = 0x1;
pub(super) const ACTIVE_MASK: u32 = 0x2;
pub(super) const BLOSC: u32 = 0x4;

/// How the grid's values are stored.
#[derive(Debug, Clone, Copy)]
pub(super) struct Storage {
    /// The grid's compression flags.
    pub(super) compression: u32,
    /// Values are `f64` (a double grid), else `f32`.
    pub(super) double: bool,
    /// Leaf and tile values were saved as 16-bit halves.
    pub(super) half: bool,
}

/// A cube of voxels of one value: a tile of the root or of an internal node.
#[derive(Debug, Clone, Copy)]
pub(super) struct Tile {
    pub(super) origin: [i32; 3],
    pub(super) size: i32,
    pub(super) value: f64,
    pub(super) active: bool,
}

/// An 8^3 block of voxels, `values[(x << 6) | (y << 3) | z]` for voxel `origin + (x, y, z)`.
pub(super) struct Leaf {
    pub(super) origin: [i32; 3],
    pub(super) active: [u64; 8],
    pub(super) values: Vec<f64>,
}

/// A grid's tree: its background, the tiles that differ from it, and the leaves.
pub(super) struct Tree {
    pub(super) background: f64,
    pub(super) tiles: Vec<Tile>,
    pub(super) leaves: Vec<Leaf>,
}

/// Internal nodes: 2^5 and 2^4 entries per axis over children of 2^7 and 2^3 voxels.
const UPPER: (u32, u32) = (5, 7);
const LOWER: (u32, u32) = (4, 3);

impl Tree {
    /// Reads the topology: the background, the tiles and where the leaves are with their
    /// value masks (their values follow, [`Tree::read_values`]).
    pub(super) fn read_topology(b: &mut Bytes<'_>, s: Storage) -> ParseResult<Self> {
        let _buffer_count = b.i32("the tree")?;
        let background = value(b, s.double, "the background value")?;
        let mut tree = Self {
            background,
            tiles: Vec::new(),
            leaves: Vec::new(),
        };
        let tiles = b.u32("the root's tile count")?;
        let children = b.u32("the root's child count")?;
        for _ in 0..tiles {
            let origin = b.coord("a root tile")?;
            let value = value(b, s.double, "a root tile")?;
            let active = b.u8("a root tile")? != 0;
            tree.keep(Tile {
                origin,
                size: 1 << (UPPER.0 + UPPER.1),
                value,
                active,
            });
        }
        for _ in 0..children {
            let origin = b.coord("a root child")?;
            tree.read_internal(b, s, origin, UPPER)?;
        }
        Ok(tree)
    }

    /// Reads the leaves' values, which follow the topology (512 values a leaf).
    pub(super) fn read_values(&mut self, b: &mut Bytes<'_>, s: Storage) -> ParseResult<()> {
        let background = self.background;
        for leaf in &mut self.leaves {
            leaf.active = mask::<8>(b, "a leaf's value mask")?;
            leaf.values = compressed_values(b, s, 512, &leaf.active, background)?;
        }
        Ok(())
    }

    /// Keeps a tile unless it is inactive background, what every voxel is by default.
    fn keep(&mut self, t: Tile) {
        if t.active || t.value != self.background {
            self.tiles.push(t);
        }
    }

    fn read_internal(
        &mut self,
        b: &mut Bytes<'_>,
        s: Storage,
        origin: [i32; 3],
        (log2dim, child_log2): (u32, u32),
    ) -> ParseResult<()> {
        let (children, values) = if log2dim == UPPER.0 {
            let c = mask::<512>(b, "an internal node's child mask")?.to_vec();
            let v = mask::<512>(b, "an internal node's value mask")?.to_vec();
            (c, v)
        } else {
            let c = mask::<64>(b, "an internal node's child mask")?.to_vec();
            let v = mask::<64>(b, "an internal node's value mask")?.to_vec();
            (c, v)
        };
        let n = 1usize << (3 * log2dim);
        let tile_values = compressed_values(b, s, n, &values, self.background)?;
        let offset = |i: usize| -> [i32; 3] {
            let dim = 1usize << log2dim;
            let xyz = [
                i >> (2 * log2dim),
                (i >> log2dim) & (dim - 1),
                i & (dim - 1),
            ];
            std::array::from_fn(|a| origin[a].saturating_add((xyz[a] as i32) << child_log2))
        };
        for (i, &v) in tile_values.iter().enumerate() {
            if !bit(&children, i) {
                self.keep(Tile {
                    origin: offset(i),
                    size: 1 << child_log2,
                    value: v,
                    active: bit(&values, i),
                });
            }
        }
        for i in (0..n).filter(|&i| bit(&children, i)) {
            if log2dim == UPPER.0 {
                self.read_internal(b, s, offset(i), LOWER)?;
            } else {
                let active = mask::<8>(b, "a leaf's value mask")?;
                self.leaves.push(Leaf {
                    origin: offset(i),
                    active,
                    values: Vec::new(),
                });
            }
        }
        Ok(())
    }
}

impl Tree {
    /// The number of active voxels (in leaves and active tiles).
    pub(super) fn active_count(&self) -> u64 {
        let tiles: u64 = self
            .tiles
            .iter()
            .filter(|t| t.active)
            .map(|t| (t.size as u64).pow(3))
            .sum();
        self.leaf_active_count() + tiles
    }

    /// The number of active voxels in leaves.
    pub(super) fn leaf_active_count(&self) -> u64 {
        self.leaves
            .iter()
            .flat_map(|l| l.active)
            .map(|w| u64::from(w.count_ones()))
            .sum()
    }

    /// The smallest index box holding every active voxel, as its first and last voxel.
    pub(super) fn active_box(&self) -> Option<([i32; 3], [i32; 3])> {
        let mut lo = [i32::MAX; 3];
        let mut hi = [i32::MIN; 3];
        let mut grow = |p: [i32; 3], q: [i32; 3]| {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(q[a]);
            }
        };
        for t in self.tiles.iter().filter(|t| t.active) {
            grow(t.origin, t.origin.map(|o| o.saturating_add(t.size - 1)));
        }
        for l in &self.leaves {
            for i in (0..512).filter(|&i| bit(&l.active, i)) {
                let p = voxel(l.origin, i);
                grow(p, p);
            }
        }
        (lo[0] <= hi[0]).then_some((lo, hi))
    }

    /// Every voxel of the box from `lo` with `dims` voxels per axis, in C order (z fastest):
    /// a leaf's value where a leaf is, a tile's where a tile is, the background elsewhere.
    pub(super) fn dense(&self, lo: [i32; 3], dims: [usize; 3]) -> Vec<f64> {
        let mut out = vec![self.background; dims[0] * dims[1] * dims[2]];
        let hi: [i64; 3] = std::array::from_fn(|a| i64::from(lo[a]) + dims[a] as i64);
        let index = |p: [i64; 3]| {
            let r: [usize; 3] = std::array::from_fn(|a| (p[a] - i64::from(lo[a])) as usize);
            (r[0] * dims[1] + r[1]) * dims[2] + r[2]
        };
        for t in &self.tiles {
            let from: [i64; 3] =
                std::array::from_fn(|a| i64::from(t.origin[a]).max(i64::from(lo[a])));
            let to: [i64; 3] =
                std::array::from_fn(|a| (i64::from(t.origin[a]) + i64::from(t.size)).min(hi[a]));
            if (0..3).any(|a| from[a] >= to[a]) {
                continue;
            }
            for x in from[0]..to[0] {
                for y in from[1]..to[1] {
                    let row = index([x, y, from[2]]);
                    out[row..row + (to[2] - from[2]) as usize].fill(t.value);
                }
            }
        }
        for l in &self.leaves {
            for (i, &v) in l.values.iter().enumerate() {
                let p = voxel(l.origin, i).map(i64::from);
                if (0..3).all(|a| p[a] >= i64::from(lo[a]) && p[a] < hi[a]) {
                    out[index(p)] = v;
                }
            }
        }
        out
    }
}

/// Voxel `i` of the leaf at `origin`.
fn voxel(origin: [i32; 3], i: usize) -> [i32; 3] {
    let xyz = [i >> 6, (i >> 3) & 7, i & 7];
    std::array::from_fn(|a| origin[a].saturating_add(xyz[a] as i32))
}

/// Bit `i` of a node mask.
pub(super) fn bit(words: &[u64], i: usize) -> bool {
    words[i >> 6] >> (i & 63) & 1 == 1
}

fn mask<const W: usize>(b: &mut Bytes<'_>, what: &str) -> ParseResult<[u64; W]> {
    let mut m = [0u64; W];
    for w in &mut m {
        *w = b.u64(what)?;
    }
    Ok(m)
}

/// One value at full precision.
fn value(b: &mut Bytes<'_>, double: bool, what: &str) -> ParseResult<f64> {
    if double {
        b.f64(what)
    } else {
        b.f32(what).map(f64::from)
    }
}

/// Per-node metadata of compressed values (`io::readCompressedValues`).
const NO_MASK_OR_INACTIVE_VALS: u8 = 0;
const NO_MASK_AND_ONE_INACTIVE_VAL: u8 = 2;
const MASK_AND_NO_INACTIVE_VALS: u8 = 3;
const MASK_AND_ONE_INACTIVE_VAL: u8 = 4;
const MASK_AND_TWO_INACTIVE_VALS: u8 = 5;
const NO_MASK_AND_ALL_VALS: u8 = 6;

/// Reads a node's `count` values written with `active` as its value mask.
fn compressed_values(
    b: &mut Bytes<'_>,
    s: Storage,
    count: usize,
    active: &[u64],
    background: f64,
) -> ParseResult<Vec<f64>> {
    let meta = b.u8("a node's value metadata")?;
    if meta > NO_MASK_AND_ALL_VALS {
        return Err(ParseError::new(format!(
            "a node's value metadata is {meta} at offset {} (known: 0 to 6); corrupt file?",
            b.offset() - 1
        )));
    }
    let mut inactive = [
        if meta == NO_MASK_OR_INACTIVE_VALS {
            background
        } else {
            -background
        },
        background,
    ];
    if matches!(
        meta,
        NO_MASK_AND_ONE_INACTIVE_VAL | MASK_AND_ONE_INACTIVE_VAL | MASK_AND_TWO_INACTIVE_VALS
    ) {
        inactive[0] = value(b, s.double, "an inactive value")?;
        if meta == MASK_AND_TWO_INACTIVE_VALS {
            inactive[1] = value(b, s.double, "an inactive value")?;
        }
    }
    let selection = if matches!(
        meta,
        MASK_AND_NO_INACTIVE_VALS | MASK_AND_ONE_INACTIVE_VAL | MASK_AND_TWO_INACTIVE_VALS
    ) {
        let mut m = vec![0u64; count / 64];
        for w in &mut m {
            *w = b.u64("a selection mask")?;
        }
        Some(m)
    } else {
        None
    };
    let kept = if s.compression & ACTIVE_MASK != 0 && meta != NO_MASK_AND_ALL_VALS {
        active.iter().map(|w| w.count_ones() as usize).sum()
    } else {
        count
    };
    let values = data(b, s, kept)?;
    if kept == count {
        return Ok(values);
    }
    let mut next = values.into_iter();
    Ok((0..count)
        .map(|i| {
            if bit(active, i) {
                next.next().unwrap_or(background)
            } else {
                let chosen = selection.as_ref().is_some_and(|m| bit(m, i));
                inactive[usize::from(chosen)]
            }
        })
        .collect())
}

/// Reads `count` values stored with the grid's codec (`io::readData`, `io::HalfReader`).
fn data(b: &mut Bytes<'_>, s: Storage, count: usize) -> ParseResult<Vec<f64>> {
    let size = if s.half {
        2
    } else if s.double {
        8
    } else {
        4
    };
    // OpenVDB writes nothing at all for no values saved as halves (`io::HalfWriter`).
    if s.half && count == 0 {
        return Ok(Vec::new());
    }
    let nbytes = count * size;
    let raw: std::borrow::Cow<'_, [u8]> = if s.compression & (BLOSC | ZIP) != 0 {
        let n = b.i64("a compressed block's size")?;
        if n <= 0 {
            if n.unsigned_abs() != nbytes as u64 {
                return Err(ParseError::new(format!(
                    "an uncompressed block of {} bytes where {nbytes} were expected (offset {})",
                    n.unsigned_abs(),
                    b.offset()
                )));
            }
            b.take(nbytes, "an uncompressed block")?.into()
        } else {
            let packed = b.take(n as usize, "a compressed block")?;
            if s.compression & BLOSC != 0 {
                blosc::decompress(packed, nbytes)?.into()
            } else {
                super::inflate(packed, nbytes, "a zip block")?.into()
            }
        }
    } else {
        b.take(nbytes, "a block of values")?.into()
    };
    Ok(match size {
        2 => raw
            .chunks_exact(2)
            .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f64())
            .collect(),
        4 => raw
            .chunks_exact(4)
            .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])))
            .collect(),
        _ => raw
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(std::array::from_fn(|i| c[i])))
            .collect(),
    })
}
