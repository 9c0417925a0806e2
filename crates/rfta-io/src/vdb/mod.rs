//! OpenVDB level sets (`.vdb`), read as the dense clamped grid they stand for.
//!
//! A level set in OpenVDB is a sparse narrow band: the voxels within a few voxels of the surface
//! are active and hold signed distances; everything else is inactive and holds the background
//! value (the band's half width) outside or its negative inside. That is a clamped SDF, which
//! rfta reconstructs as it is (the paper's Figure 24), so a level set reads as the grid of every
//! voxel of the box around its active voxels and one voxel more on every side, inactive ones at
//! plus or minus the background, with the background as the clamp.
//!
//! The reader is rfta's own, for the files OpenVDB 3 and later write (file format 222 and up):
//! float and double grids of the standard tree (`Tree_float_5_4_3`, `Tree_double_5_4_3`), saved
//! at full or half precision, uncompressed, zipped or Blosc/LZ4-compressed, with or without
//! active-mask compression; transforms that scale and translate the voxel axes. Anything else
//! (another value type or tree, a rotating or frustum transform, an instanced grid, a file
//! written as a stream without grid offsets) is an error naming what is not supported.

mod blosc;
mod bytes;
mod transform;
mod tree;

use bytes::Bytes;
use rfta_geom::glam::DVec3;
use tree::{Storage, Tree};

use crate::error::{ParseError, ParseResult};

/// `OPENVDB_MAGIC`, the file's first eight bytes.
const MAGIC: i64 = 0x5644_4220;
/// `OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION`: the oldest format this reader follows.
const OLDEST: u32 = 222;
/// Voxels taken beyond the active ones on every side: a layer of inactive voxels (at the
/// background outside the band) closes the band. Without it the outermost samples are active,
/// nothing says what lies beyond them, and the reconstruction of a box closed only by its band
/// grew a second, open sheet far outside the grid (measured on `tests/data/vdb/box.vdb`: two
/// components with 40 boundary edges at no margin, one watertight box at 1, 2, 3, 4 and 6).
const MARGIN: i32 = 1;
/// The most voxels a level set may make dense (16 GiB of `f64`).
const MAX_DENSE: u64 = 1 << 31;
/// The most voxels the dense box may hold per active voxel of the leaves, beyond a floor of
/// [`SMALL_BOX`]. A narrow band of half width w around a surface of r voxels across fills
/// about 1 / (0.1 r) of its box for w = 3 (0.11 r voxels of box per voxel of band): 64 allows a
/// sphere up to 600 voxels in radius, more than [`MAX_DENSE`] holds. A file whose few active
/// voxels sit at far corners (or a corrupt one) would otherwise ask for gigabytes from kilobytes.
const BOX_PER_ACTIVE: u64 = 64;
const SMALL_BOX: u64 = 1 << 24;

/// A level set read from a `.vdb` file, made dense over the box of its active voxels grown by
/// [`MARGIN`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LevelSet {
    /// Voxels per axis of the box.
    pub(crate) dims: [usize; 3],
    /// World position of the box's first voxel.
    pub(crate) origin: DVec3,
    /// The voxel size per axis.
    pub(crate) spacing: DVec3,
    /// Every voxel of the box, C order (z fastest).
    pub(crate) values: Vec<f64>,
    /// The background value: what inactive voxels hold, the clamp.
    pub(crate) background: f64,
    /// What was read, for `rfta info` and reports.
    pub(crate) description: String,
}

/// One grid's entry in the file's table of grids.
struct Descriptor {
    name: String,
    tree: String,
    half: bool,
    parent: String,
    position: u64,
}

impl Descriptor {
    /// The name without the suffix OpenVDB adds to tell grids of the same name apart.
    fn short_name(&self) -> &str {
        self.name.split('\u{1e}').next().unwrap_or("")
    }
}

/// A grid's header: its compression, metadata and the class its metadata names.
struct GridHead {
    compression: u32,
    class: String,
}

/// The grid chosen, its storage and transform, and its tree's topology (no values yet).
struct Chosen<'d> {
    descriptor: &'d Descriptor,
    storage: Storage,
    xform: transform::AxisAligned,
    tree: Tree,
    /// The dense box: its first voxel and voxels per axis.
    lo: [i32; 3],
    dims: [usize; 3],
}

/// Reads the file up to the topology of the level set named `grid` (or the first), and checks
/// what making it dense would take before anything of that size is allocated: the box comes
/// from the leaves and tiles themselves, not from metadata a file may omit or get wrong
/// (hostile test E2), and the values from the leaves counted.
fn topology<'d>(
    b: &mut Bytes<'_>,
    descriptors: &'d [Descriptor],
    grid: Option<&str>,
) -> ParseResult<Chosen<'d>> {
    let (d, head) = choose(b, descriptors, grid)?;
    let xform = transform::read(b)?;
    let storage = Storage {
        compression: head.compression,
        double: d.tree == "Tree_double_5_4_3",
        half: d.half,
    };
    let tree = Tree::read_topology(b, storage)?;
    let bg = tree.background;
    // A level set's background is the half width of its band, what inactive voxels outside
    // hold: positive and finite. Anything else does not say where inside and outside are.
    if !(bg.is_finite() && bg > 0.0) {
        return Err(ParseError::new(format!(
            "the grid {:?} has background value {bg}: a level set's background is the positive \
             half width of its narrow band (what its inactive voxels outside hold), so this grid \
             is not a signed distance level set",
            d.short_name()
        )));
    }
    let (lo, hi) = tree.active_box().ok_or_else(|| {
        ParseError::new(format!(
            "the level set {:?} has no active voxels",
            d.short_name()
        ))
    })?;
    let lo = lo.map(|v| v.saturating_sub(MARGIN));
    let hi = hi.map(|v| v.saturating_add(MARGIN));
    let dims: [usize; 3] =
        std::array::from_fn(|a| (i64::from(hi[a]) - i64::from(lo[a]) + 1) as usize);
    let total = dims
        .iter()
        .try_fold(1u64, |acc, &n| acc.checked_mul(n as u64));
    let band = tree.leaf_active_count();
    let most = MAX_DENSE.min(
        band.saturating_mul(BOX_PER_ACTIVE)
            .saturating_add(SMALL_BOX),
    );
    if total.is_none_or(|t| t > most) {
        return Err(ParseError::new(format!(
            "the active voxels of {:?} ({band} in leaves) span a box of {} x {} x {} voxels, more \
             than rfta makes dense for them ({most}: at most {MAX_DENSE}, and {BOX_PER_ACTIVE} \
             per active voxel beyond {SMALL_BOX}); crop the level set to one object",
            d.short_name(),
            dims[0],
            dims[1],
            dims[2]
        )));
    }
    // What the values take: 512 per leaf as read, then the dense box; both in f64.
    let limit = crate::read_limit();
    let leaf_bytes = (tree.leaves.len() as u64).saturating_mul(512 * 8);
    let dense_bytes = total.unwrap_or(u64::MAX).saturating_mul(8);
    if leaf_bytes.saturating_add(dense_bytes) > limit {
        return Err(ParseError::new(format!(
            "the level set {:?} makes a dense box of {} x {} x {} voxels ({} bytes, with {} bytes \
             of leaf values as read), more than the {limit} bytes this process may take for one \
             input (a quarter of the memory it can use); crop the level set or free memory",
            d.short_name(),
            dims[0],
            dims[1],
            dims[2],
            dense_bytes,
            leaf_bytes
        )));
    }
    Ok(Chosen {
        descriptor: d,
        storage,
        xform,
        tree,
        lo,
        dims,
    })
}

/// Reads the level set named `grid`, or the first level set in the file.
pub(crate) fn parse(bytes: &[u8], grid: Option<&str>) -> ParseResult<LevelSet> {
    let mut b = Bytes::new(bytes);
    let descriptors = read_header(&mut b)?;
    let Chosen {
        descriptor: d,
        storage,
        xform,
        mut tree,
        lo,
        dims,
    } = topology(&mut b, &descriptors, grid)?;
    tree.read_values(&mut b, storage)?;
    let head_compression = storage.compression;
    let codec = match (
        head_compression & (tree::BLOSC | tree::ZIP),
        head_compression & tree::ACTIVE_MASK,
    ) {
        (0, 0) => "uncompressed",
        (0, _) => "active-mask compressed",
        (c, m) if c & tree::BLOSC != 0 => {
            if m == 0 {
                "blosc"
            } else {
                "blosc + active mask"
            }
        }
        (_, m) => {
            if m == 0 {
                "zip"
            } else {
                "zip + active mask"
            }
        }
    };
    let description = format!(
        "OpenVDB level set {:?} ({}{}, {codec}), {} active voxels in a {} x {} x {} box, voxel \
         size {}, background {}",
        d.short_name(),
        if storage.double { "double" } else { "float" },
        if d.half { " saved as half" } else { "" },
        tree.active_count(),
        dims[0],
        dims[1],
        dims[2],
        xform.scale,
        tree.background
    );
    Ok(LevelSet {
        dims,
        origin: xform.world(lo),
        spacing: xform.scale,
        values: tree.dense(lo, dims),
        background: tree.background,
        description,
    })
}

/// The number of voxels [`parse`] would make dense for the level set named `grid` (or the
/// first), from its tree's topology (without its values), after the same checks.
pub(crate) fn peek_len(bytes: &[u8], grid: Option<&str>) -> ParseResult<u64> {
    let mut b = Bytes::new(bytes);
    let descriptors = read_header(&mut b)?;
    let chosen = topology(&mut b, &descriptors, grid)?;
    Ok(chosen.dims.iter().map(|&n| n as u64).product())
}

/// Reads the file header and the table of grids.
fn read_header(b: &mut Bytes<'_>) -> ParseResult<Vec<Descriptor>> {
    if b.i64("the header")? != MAGIC {
        return Err(ParseError::new(
            "not an OpenVDB file (no \"VDB\" magic number)",
        ));
    }
    let version = b.u32("the header")?;
    if version < OLDEST {
        return Err(ParseError::new(format!(
            "VDB file format {version} predates {OLDEST} (OpenVDB 3), which rfta does not read; \
             save the grid again with a newer OpenVDB"
        )));
    }
    let _library = (b.u32("the header")?, b.u32("the header")?);
    let offsets = b.u8("the header")? != 0;
    b.take(36, "the file's UUID")?;
    skip_metadata(b)?;
    if !offsets {
        return Err(ParseError::new(
            "the file was written as a stream, without grid offsets, which rfta does not read; \
             write it with openvdb.write or vdb_print's tools as a file",
        ));
    }
    let count = b.i32("the grid count")?;
    // Each entry takes at least three string lengths and three positions: a count the rest
    // of the file cannot hold is corrupt (and would be trusted for nothing).
    const ENTRY: u64 = 3 * 4 + 3 * 8;
    let room = b.remaining() as u64 / ENTRY;
    if u64::try_from(count).is_ok_and(|c| c > room) {
        return Err(ParseError::new(format!(
            "the file says it holds {count} grids, more than its {} bytes can describe",
            b.len()
        )));
    }
    let mut out = Vec::new();
    for _ in 0..count.max(0) {
        let name = b.string("a grid's name")?;
        let kind = b.string("a grid's type")?;
        let parent = b.string("a grid's instance parent")?;
        let position = b.i64("a grid's position")?;
        let _blocks = b.i64("a grid's position")?;
        // Each grid's entry is written just before the grid: the next entry follows its end.
        let end = b.i64("a grid's position")?;
        // Entries follow one another: an entry that ends where it began, or earlier, would
        // make the table loop (hostile test E1: 119 bytes grew to 5 GB).
        if u64::try_from(end).is_ok_and(|e| e <= b.offset() as u64) {
            return Err(ParseError::new(format!(
                "grid {:?}'s entry says the next one starts at byte {end}, not after it (byte {}): \
                 the table of grids is corrupt",
                name,
                b.offset()
            )));
        }
        b.seek(
            u64::try_from(end).unwrap_or(u64::MAX),
            "the next grid's entry",
        )?;
        let (tree, half) = match kind.strip_suffix("_HalfFloat") {
            Some(t) => (t.to_string(), true),
            None => (kind, false),
        };
        out.push(Descriptor {
            name,
            tree,
            half,
            parent,
            position: u64::try_from(position).unwrap_or(u64::MAX),
        });
    }
    Ok(out)
}

/// The grid named `want`, or else the first level set; leaves `b` at its transform.
fn choose<'d>(
    b: &mut Bytes<'_>,
    descriptors: &'d [Descriptor],
    want: Option<&str>,
) -> ParseResult<(&'d Descriptor, GridHead)> {
    let mut seen = Vec::new();
    for d in descriptors {
        if want.is_some_and(|w| w != d.short_name() && w != d.name) {
            continue;
        }
        b.seek(d.position, "a grid")?;
        let head = read_grid_head(b)?;
        let readable = matches!(d.tree.as_str(), "Tree_float_5_4_3" | "Tree_double_5_4_3");
        let level_set = head.class == "level set" || (want.is_some() && head.class != "fog volume");
        if readable && level_set && d.parent.is_empty() {
            return Ok((d, head));
        }
        if want.is_some() {
            let why = if !readable {
                format!("its type is {}, not a float or double scalar grid", d.tree)
            } else if !d.parent.is_empty() {
                format!(
                    "it is an instance of {:?}, which rfta does not read",
                    d.parent
                )
            } else {
                format!("it is a {}, not a level set", head.class)
            };
            return Err(ParseError::new(format!("grid {:?}: {why}", d.short_name())));
        }
        seen.push(format!("{:?} ({}, {})", d.short_name(), d.tree, head.class));
    }
    Err(ParseError::new(match want {
        Some(w) => format!(
            "no grid named {w:?}; the file holds {}",
            list(descriptors.iter().map(|d| format!("{:?}", d.short_name())))
        ),
        None => format!(
            "no level set (a float or double grid of class \"level set\"); the file holds {}",
            list(seen.into_iter())
        ),
    }))
}

fn list(items: impl Iterator<Item = String>) -> String {
    let v: Vec<String> = items.collect();
    if v.is_empty() {
        "no grids".into()
    } else {
        v.join(", ")
    }
}

fn read_grid_head(b: &mut Bytes<'_>) -> ParseResult<GridHead> {
    let compression = b.u32("a grid's compression")?;
    let mut head = GridHead {
        compression,
        class: "unknown".into(),
    };
    let count = b.u32("a grid's metadata")?;
    for _ in 0..count {
        let name = b.string("a metadata name")?;
        let kind = b.string("a metadata type")?;
        let size = b.u32("a metadata value")? as usize;
        let value = b.take(size, "a metadata value")?;
        if (name.as_str(), kind.as_str()) == ("class", "string") {
            head.class = String::from_utf8_lossy(value).into_owned();
        }
    }
    Ok(head)
}

/// A zlib stream (a zipped block, or a Blosc stream of the zlib codec) that must hold exactly
/// `nbytes`; `what` names it in the error.
fn inflate(packed: &[u8], nbytes: usize, what: &str) -> ParseResult<Vec<u8>> {
    let v = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(packed, nbytes)
        .map_err(|e| ParseError::new(format!("invalid {what}: {:?}", e.status)))?;
    if v.len() == nbytes {
        Ok(v)
    } else {
        Err(ParseError::new(format!(
            "{what} holds {} bytes where {nbytes} were expected",
            v.len()
        )))
    }
}

/// Skips the file's metadata (a count, then name, type, size and value of each entry).
fn skip_metadata(b: &mut Bytes<'_>) -> ParseResult<()> {
    let count = b.u32("the file's metadata")?;
    for _ in 0..count {
        b.string("a metadata name")?;
        b.string("a metadata type")?;
        let size = b.u32("a metadata value")? as usize;
        b.take(size, "a metadata value")?;
    }
    Ok(())
}
