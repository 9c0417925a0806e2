//! File formats for rfta: triangle meshes and signed-distance samples, with atomic writes.
//!
//! | what | read | write |
//! |---|---|---|
//! | meshes | OBJ, OFF, PLY (ascii, binary), STL (ascii, binary), GLB | OBJ, PLY (binary), STL (binary), GLB |
//! | SDF grids | NumPy `.npy` (float32/float64, C or Fortran order), OpenEXR volume, OpenVDB level set | `.npy` (float64), OpenEXR |
//! | scattered SDF samples | PLY (`x y z` + `sdf`/`value`/`scalar`), CSV/XYZ text (`x y z s`) | |
//! | oriented points | PLY (`x y z nx ny nz`), text (`x y z nx ny nz`) | PLY |
//! | tables (batch manifests, status files) | CSV with a header ([`table`]) | CSV lines |
//!
//! The format is chosen from the file extension. Every reader takes untrusted bytes: a truncated
//! or malformed file gives an [`Error`] that names the file and what is wrong (and the line, for
//! text formats), never a panic. Every writer writes a temporary file beside the target and renames
//! it into place, so a crash never leaves a half-written output ([`write_atomic`]).
//!
//! # Grid convention
//! A grid file of shape `(nx, ny, nz)` holds `S[i, j, k]` at `origin + (i, j, k) * spacing` in C
//! order (z fastest), exactly as [`rfta_geom::Grid`]. The bounds come, in order of precedence,
//! from the caller ([`GridBounds`]), from a JSON sidecar beside the file (`NAME.json` for `NAME.npy`,
//! see [`Sidecar`]), from the file itself (EXR attributes), or default to `[-1, 1]^3`: a grid of
//! `n + 1` points per axis then matches `numpy.linspace(-1, 1, n + 1)`.
//!
//! # Example
//! ```
//! use rfta_geom::{glam::DVec3, shapes};
//! let dir = std::env::temp_dir().join(format!("rfta-io-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let path = dir.join("box.ply");
//! let mesh = shapes::cuboid(DVec3::splat(0.5));
//! rfta_io::write_mesh(&path, &mesh)?;
//! let back = rfta_io::read_mesh(&path)?;
//! assert_eq!(back, mesh);
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod atomic;
mod error;
mod exr_volume;
mod glb;
mod npy;
mod obj;
mod off;
mod plane;
mod ply;
mod sdf;
mod stl;
pub mod table;
mod text;
mod vdb;

pub use atomic::{OutputTarget, check_writable, output_target, remove_temp_files, write_atomic};
pub use error::{Error, Result};
pub use npy::{NpyArray, parse_npy, write_npy_f64};
pub use plane::{Svg, is_sdf_2d, read_polylines, read_sdf_2d, write_polylines, write_svg};
pub use sdf::{
    GridBounds, RawSdf, SdfFormat, Sidecar, decode_oriented_points, decode_sdf, peek_sdf_len,
    read_oriented_points, read_sdf, read_vdb, sidecar_path, write_oriented_points_ply,
    write_sdf_grid,
};

use std::path::Path;

use rfta_geom::TriMesh;

/// Mesh formats by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (read and write).
    Obj,
    /// Object File Format (read).
    Off,
    /// Stanford PLY, ascii or binary (read; written as binary little endian).
    Ply,
    /// STL, ascii or binary (read; written as binary).
    Stl,
    /// Binary glTF 2.0 (read: every triangle primitive of the default scene; write).
    Glb,
}

impl MeshFormat {
    /// The format of `path` from its extension (case-insensitive).
    ///
    /// # Errors
    /// [`Error::UnknownFormat`] for a missing or unsupported extension.
    pub fn from_path(path: &Path) -> Result<Self> {
        let ext = extension(path);
        match ext.as_deref() {
            Some("obj") => Ok(Self::Obj),
            Some("off") => Ok(Self::Off),
            Some("ply") => Ok(Self::Ply),
            Some("stl") => Ok(Self::Stl),
            Some("glb") => Ok(Self::Glb),
            _ => Err(Error::UnknownFormat {
                path: path.to_path_buf(),
                expected: "a mesh: .obj, .off, .ply, .stl, .glb",
            }),
        }
    }
}

/// Reads a triangle mesh (OBJ, OFF, PLY, STL, GLB); polygons are split into triangle fans.
///
/// # Errors
/// [`Error::Io`] if the file cannot be read, [`Error::Parse`] if it is malformed,
/// [`Error::UnknownFormat`] for an unsupported extension.
pub fn read_mesh(path: &Path) -> Result<TriMesh> {
    let format = MeshFormat::from_path(path)?;
    let bytes = read_bytes(path)?;
    decode_mesh(&bytes, format, path)
}

/// Decodes a triangle mesh held in memory; `path` only names the data in error messages.
///
/// This is [`read_mesh`] without the file system: for data from an archive or a network, and for
/// the fuzz targets. Every byte string gives a mesh or an error, never a panic.
///
/// # Errors
/// [`Error::Parse`] if the bytes are malformed, [`Error::Geom`] if the mesh is not valid (e.g. a
/// face index out of range, a non-finite vertex).
pub fn decode_mesh(bytes: &[u8], format: MeshFormat, path: &Path) -> Result<TriMesh> {
    let parsed = match format {
        MeshFormat::Obj => obj::parse(bytes),
        MeshFormat::Off => off::parse(bytes),
        MeshFormat::Ply => ply::parse_mesh(bytes),
        MeshFormat::Stl => stl::parse(bytes),
        MeshFormat::Glb => glb::parse(bytes),
    };
    let mesh = parsed.map_err(|e| e.at(path))?;
    mesh.validate().map_err(|source| Error::Geom {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(mesh)
}

/// Writes a triangle mesh atomically in the format of the extension (OBJ, PLY, STL, GLB).
///
/// # Errors
/// [`Error::UnknownFormat`] for an unsupported extension (OFF is read-only), [`Error::Geom`] for
/// a mesh with a non-finite vertex or an out-of-range index (nothing is written: no output file
/// ever holds NaN), [`Error::Io`] if the file cannot be written.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<()> {
    let format = MeshFormat::from_path(path)?;
    mesh.validate().map_err(|source| Error::Geom {
        path: path.to_path_buf(),
        source,
    })?;
    match format {
        MeshFormat::Obj => write_atomic(path, |w| obj::write(w, mesh)),
        MeshFormat::Ply => write_atomic(path, |w| ply::write_mesh(w, mesh)),
        MeshFormat::Stl => write_atomic(path, |w| stl::write(w, mesh)),
        MeshFormat::Glb => {
            let bytes = glb::to_bytes(mesh).map_err(|e| e.at(path))?;
            write_atomic(path, |w| w.write_all(&bytes))
        }
        MeshFormat::Off => Err(Error::UnknownFormat {
            path: path.to_path_buf(),
            expected: "a writable mesh: .obj, .ply, .stl, .glb",
        }),
    }
}

/// The file's extension in lower case, if it has one.
pub fn extension_of(path: &Path) -> Option<String> {
    extension(path)
}

pub(crate) fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// The most bytes [`read_bytes`] reads from one file ([`set_read_limit`]; no limit by default).
static READ_LIMIT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(u64::MAX);

/// Bounds what every reader of this crate reads from one file: a larger file, or a device or
/// pipe that goes on past it (a link to `/dev/zero`), is an error instead of memory exhausted.
/// A program sets it once, from the memory it may use.
pub fn set_read_limit(bytes: u64) {
    READ_LIMIT.store(bytes, std::sync::atomic::Ordering::Relaxed);
}

/// The limit [`set_read_limit`] set: also the most bytes one input may take once decoded (an
/// OpenVDB level set made dense).
pub(crate) fn read_limit() -> u64 {
    READ_LIMIT.load(std::sync::atomic::Ordering::Relaxed)
}

pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
    let limit = READ_LIMIT.load(std::sync::atomic::Ordering::Relaxed);
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let too_large = |what: String| Error::Parse {
        path: path.to_path_buf(),
        line: None,
        detail: format!(
            "{what}, more than the {limit} bytes this process may read (its limit, set from the memory it can use)"
        ),
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if meta.is_file() && meta.len() > limit {
        return Err(too_large(format!("the file is {} bytes", meta.len())));
    }
    // A regular file's size is known: one allocation of it (growing by doubling would copy a
    // large grid several times and hold up to twice it at once).
    let mut bytes = Vec::with_capacity(if meta.is_file() {
        usize::try_from(meta.len()).unwrap_or(0)
    } else {
        0
    });
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(too_large("it goes on".into()));
    }
    Ok(bytes)
}
