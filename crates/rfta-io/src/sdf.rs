//! Reading and writing SDF samples and oriented points.

use std::path::{Path, PathBuf};

use rfta_geom::{Grid, Layout, OrientedPoints, SdfSamples, glam::DVec3};

use crate::error::{ParseError, ParseResult};
use crate::text::{as_text, content_lines};
use crate::{Error, Result, exr_volume, extension, npy, ply, read_bytes, vdb, write_atomic};

/// The corner sample positions of a grid: sample `(0, 0, 0)` at `min`, the last at `max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridBounds {
    /// Position of the first sample.
    pub min: DVec3,
    /// Position of the last sample.
    pub max: DVec3,
}

impl Default for GridBounds {
    /// `[-1, 1]^3`, the paper's sampling box.
    fn default() -> Self {
        Self {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        }
    }
}

/// The JSON sidecar beside a grid file (`NAME.json` for `NAME.npy`): either the corner
/// positions `{"min": [x, y, z], "max": [x, y, z]}` or `{"origin": [x, y, z], "spacing": [x, y, z]}`.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sidecar {
    /// Position of the first sample.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<[f64; 3]>,
    /// Position of the last sample.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<[f64; 3]>,
    /// Position of the first sample (with `spacing`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// Distance between samples per axis (with `origin`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<[f64; 3]>,
}

/// Where the sidecar of a grid file is: the same name with extension `.json`.
pub fn sidecar_path(path: &Path) -> PathBuf {
    path.with_extension("json")
}

/// SDF samples as read, before validation: [`RawSdf::validate`] turns them into
/// [`SdfSamples`]; `rfta info` describes them even when they are not valid.
#[derive(Debug, Clone, PartialEq)]
pub struct RawSdf {
    /// Where the samples are.
    pub layout: Layout,
    /// The values (may contain NaN, or have no sign change).
    pub values: Vec<f64>,
    /// How the file was read, e.g. "npy float32, C order, shape (21, 21, 21)".
    pub description: String,
    /// Where the grid's bounds came from: "command line", "sidecar", "file", "default", or
    /// "samples" for scattered input.
    pub bounds_source: &'static str,
    /// The magnitude the file says its values are clamped at (an OpenVDB level set's
    /// background), for `Params::clamp` when the caller gives none.
    pub clamp: Option<f64>,
}

impl RawSdf {
    /// Validates the samples.
    ///
    /// # Errors
    /// [`Error::Geom`] naming `path` and the first problem (see [`SdfSamples`]).
    pub fn validate(self, path: &Path) -> Result<SdfSamples> {
        let geom = |source| Error::Geom {
            path: path.to_path_buf(),
            source,
        };
        match self.layout {
            Layout::Grid(g) => SdfSamples::grid(g, self.values).map_err(geom),
            Layout::Scattered(p) => SdfSamples::scattered(p, self.values).map_err(geom),
        }
    }
}

/// Reads SDF samples, by extension: `.npy` (a 3-D grid, or an `(n, 4)` array of `x y z s` rows),
/// `.exr` (a grid, see the crate docs), `.vdb` (the first OpenVDB level set, see [`read_vdb`]), `.ply` (scattered: vertex `x y z` and a scalar `sdf`,
/// `value` or `scalar`), `.csv`, `.xyz`, `.txt` (scattered rows `x y z s`, separated by commas or
/// whitespace, `#` comments, an optional header line).
///
/// Grid bounds: `bounds` if given, else the sidecar, else the file's own (EXR), else `[-1, 1]^3`.
///
/// # Errors
/// [`Error::Io`], [`Error::Parse`] naming the file and the problem, [`Error::UnknownFormat`].
pub fn read_sdf(path: &Path, bounds: Option<GridBounds>) -> Result<RawSdf> {
    let format = SdfFormat::from_path(path)?;
    let bytes = read_bytes(path)?;
    decode_sdf(&bytes, format, path, bounds)
}

/// The number of samples in an SDF file, read from its header without loading the data, for
/// the grid formats (`.npy`, `.exr`; `.vdb` from the topology of the level set `grid`, or the
/// first, without its values); `None` for others. Lets a caller refuse an input too large for
/// the machine before reading it.
///
/// # Errors
/// [`Error::Io`] if the file cannot be read, [`Error::Parse`] for a malformed header.
pub fn peek_sdf_len(path: &Path, grid: Option<&str>) -> Result<Option<usize>> {
    use std::io::Read;
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    match SdfFormat::from_path(path)? {
        SdfFormat::Npy => {
            let mut head = Vec::new();
            std::fs::File::open(path)
                .map_err(io)?
                .take(1 << 20)
                .read_to_end(&mut head)
                .map_err(io)?;
            let header = npy::parse_header(&head).map_err(|e| e.at(path))?;
            Ok(Some(match header.shape.as_slice() {
                &[n, 4] => n,
                _ => header.len,
            }))
        }
        SdfFormat::Exr => {
            let file = std::io::BufReader::new(std::fs::File::open(path).map_err(io)?);
            let meta =
                exr::meta::MetaData::read_from_buffered(file, false).map_err(|e| Error::Parse {
                    path: path.to_path_buf(),
                    line: None,
                    detail: format!("invalid OpenEXR header: {e}"),
                })?;
            Ok(meta.headers.first().map(|h| h.layer_size.area()))
        }
        SdfFormat::Vdb => {
            let bytes = read_bytes(path)?;
            let n = vdb::peek_len(&bytes, grid).map_err(|e| e.at(path))?;
            Ok(Some(usize::try_from(n).unwrap_or(usize::MAX)))
        }
        SdfFormat::Ply | SdfFormat::Text => Ok(None),
    }
}

/// Formats of SDF sample files, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdfFormat {
    /// NumPy `.npy`: a 3-D grid or `(n, 4)` rows `x y z s`.
    Npy,
    /// OpenEXR volume `.exr`.
    Exr,
    /// OpenVDB level set `.vdb` (see [`read_vdb`]).
    Vdb,
    /// PLY point cloud with a per-vertex scalar.
    Ply,
    /// Text rows `x y z s` (`.csv`, `.xyz`, `.txt`).
    Text,
}

impl SdfFormat {
    /// The format of `path` from its extension (case-insensitive).
    ///
    /// # Errors
    /// [`Error::UnknownFormat`] for a missing or unsupported extension.
    pub fn from_path(path: &Path) -> Result<Self> {
        match extension(path).as_deref() {
            Some("npy") => Ok(Self::Npy),
            Some("exr") => Ok(Self::Exr),
            Some("vdb") => Ok(Self::Vdb),
            Some("ply") => Ok(Self::Ply),
            Some("csv" | "xyz" | "txt") => Ok(Self::Text),
            _ => Err(Error::UnknownFormat {
                path: path.to_path_buf(),
                expected: "SDF samples: .npy, .exr, .vdb, .ply, .csv, .xyz, .txt",
            }),
        }
    }
}

/// Decodes SDF samples held in memory, as [`read_sdf`]; `path` names the data in error messages
/// and locates the sidecar of a grid (none is read if it does not exist).
///
/// Every byte string gives samples or an error, never a panic (the fuzz targets check this).
///
/// # Errors
/// As [`read_sdf`].
pub fn decode_sdf(
    bytes: &[u8],
    format: SdfFormat,
    path: &Path,
    bounds: Option<GridBounds>,
) -> Result<RawSdf> {
    let at = |e: ParseError| e.at(path);
    match format {
        SdfFormat::Npy => {
            let arr = npy::parse(bytes).map_err(at)?;
            match arr.shape.as_slice() {
                &[nx, ny, nz] => {
                    let dims = [nx, ny, nz];
                    let (grid, source) = resolve_grid(path, dims, bounds, None)?;
                    Ok(RawSdf {
                        layout: Layout::Grid(grid),
                        values: arr.data,
                        description: format!("npy grid, shape ({nx}, {ny}, {nz})"),
                        bounds_source: source,
                        clamp: None,
                    })
                }
                &[n, 4] => {
                    let (positions, values) = (0..n)
                        .map(|r| (DVec3::new(arr.data[4 * r], arr.data[4 * r + 1], arr.data[4 * r + 2]), arr.data[4 * r + 3]))
                        .unzip();
                    Ok(RawSdf {
                        layout: Layout::Scattered(positions),
                        values,
                        description: format!("npy scattered samples, shape ({n}, 4) as rows x y z s"),
                        bounds_source: "samples",
                        clamp: None,
                    })
                }
                other => Err(ParseError::new(format!(
                    "expected a 3-D grid of shape (nx, ny, nz) or rows of shape (n, 4), found shape {other:?}"
                ))
                .at(path)),
            }
        }
        SdfFormat::Exr => {
            let vol = exr_volume::parse(bytes).map_err(at)?;
            let (grid, source) = resolve_grid(path, vol.dims, bounds, vol.origin_spacing)?;
            let [nx, ny, nz] = vol.dims;
            Ok(RawSdf {
                layout: Layout::Grid(grid),
                values: vol.values,
                description: format!("OpenEXR volume, shape ({nx}, {ny}, {nz}), float32"),
                bounds_source: source,
                clamp: None,
            })
        }
        SdfFormat::Vdb => decode_vdb(bytes, None, path, bounds),
        SdfFormat::Ply => {
            let p = ply::parse(bytes).map_err(at)?;
            let positions = p.positions().map_err(at)?;
            let values = p.vertex_scalar(&["sdf", "value", "scalar"]).map_err(at)?;
            Ok(RawSdf {
                description: format!("PLY scattered samples, {} points", positions.len()),
                layout: Layout::Scattered(positions),
                values,
                bounds_source: "samples",
                clamp: None,
            })
        }
        SdfFormat::Text => {
            let (positions, values) = parse_rows(bytes).map_err(at)?;
            Ok(RawSdf {
                description: format!("text scattered samples, {} rows", positions.len()),
                layout: Layout::Scattered(positions),
                values,
                bounds_source: "samples",
                clamp: None,
            })
        }
    }
}

/// Reads the level set named `grid` from an OpenVDB file (`read_sdf` takes the first level
/// set): every voxel of the box around its active voxels, inactive ones at plus or minus the
/// background value, which becomes [`RawSdf::clamp`]. Bounds as for [`read_sdf`], the grid's
/// transform being the file's own.
///
/// # Errors
/// As [`read_sdf`]; [`Error::Parse`] naming the grids the file holds when none is `grid`.
pub fn read_vdb(path: &Path, grid: Option<&str>, bounds: Option<GridBounds>) -> Result<RawSdf> {
    decode_vdb(&read_bytes(path)?, grid, path, bounds)
}

fn decode_vdb(
    bytes: &[u8],
    grid: Option<&str>,
    path: &Path,
    bounds: Option<GridBounds>,
) -> Result<RawSdf> {
    let set = vdb::parse(bytes, grid).map_err(|e| e.at(path))?;
    let (grid, source) = resolve_grid(path, set.dims, bounds, Some((set.origin, set.spacing)))?;
    Ok(RawSdf {
        layout: Layout::Grid(grid),
        values: set.values,
        description: set.description,
        bounds_source: source,
        clamp: Some(set.background),
    })
}

fn resolve_grid(
    path: &Path,
    dims: [usize; 3],
    bounds: Option<GridBounds>,
    from_file: Option<(DVec3, DVec3)>,
) -> Result<(Grid, &'static str)> {
    let geom = |source| Error::Geom {
        path: path.to_path_buf(),
        source,
    };
    // A volume needs two points along every axis: a flat slice has no spacing across it, and
    // closing it into a "watertight" mesh would invent one. (A single sample is left to the
    // sample count's own error.)
    if dims.iter().product::<usize>() >= 2
        && let Some(axis) = dims.iter().position(|&d| d < 2)
    {
        return Err(Error::Parse {
            path: path.to_path_buf(),
            line: None,
            detail: format!(
                "a 3D grid needs at least 2 points along every axis, but shape {dims:?} has {} along \
                 axis {axis} (a 2D grid is an (nx, ny) array)",
                dims[axis]
            ),
        });
    }
    if let Some(b) = bounds {
        return Ok((
            Grid::from_bounds(dims, b.min, b.max).map_err(geom)?,
            "command line",
        ));
    }
    let side = sidecar_path(path);
    if side.exists() {
        let text = crate::read_bytes(&side)?;
        let car: Sidecar = serde_json::from_slice(&text).map_err(|e| Error::Parse {
            path: side.clone(),
            line: Some(e.line()),
            detail: format!("invalid sidecar: {e}"),
        })?;
        let sgeom = |source| Error::Geom {
            path: side.clone(),
            source,
        };
        let grid = match (car.min, car.max, car.origin, car.spacing) {
            (Some(lo), Some(hi), None, None) => {
                Grid::from_bounds(dims, DVec3::from_array(lo), DVec3::from_array(hi))
                    .map_err(sgeom)?
            }
            (None, None, Some(o), Some(s)) => {
                Grid::new(dims, DVec3::from_array(o), DVec3::from_array(s)).map_err(sgeom)?
            }
            _ => {
                return Err(Error::Parse {
                    path: side,
                    line: None,
                    detail:
                        "the sidecar needs either \"min\" and \"max\" or \"origin\" and \"spacing\""
                            .into(),
                });
            }
        };
        // A file that carries its own bounds (EXR) and a sidecar that says otherwise: one of them
        // is stale (a sidecar left from an older `.npy` of the same name), and which is not ours
        // to guess.
        if let Some((origin, spacing)) = from_file {
            let close = |a: DVec3, b: DVec3| {
                (a - b).abs().max_element() <= 1e-9 * a.abs().max(b.abs()).max_element().max(1e-300)
            };
            if !(close(origin, grid.origin()) && close(spacing, grid.spacing())) {
                return Err(Error::Parse {
                    path: side,
                    line: None,
                    detail: format!(
                        "this sidecar (origin {}, spacing {}) disagrees with {}'s own attributes \
                         (origin {origin}, spacing {spacing}); remove the stale one or pass --bounds",
                        grid.origin(),
                        grid.spacing(),
                        path.display()
                    ),
                });
            }
        }
        return Ok((grid, "sidecar"));
    }
    if let Some((origin, spacing)) = from_file {
        return Ok((Grid::new(dims, origin, spacing).map_err(geom)?, "file"));
    }
    let b = GridBounds::default();
    Ok((
        Grid::from_bounds(dims, b.min, b.max).map_err(geom)?,
        "default [-1, 1]^3",
    ))
}

/// Rows of `k` numbers separated by commas, semicolons or whitespace; the first line may be a header.
fn parse_numeric_rows(bytes: &[u8], k: usize, names: &str) -> ParseResult<Vec<Vec<f64>>> {
    let text = as_text(bytes)?;
    let mut rows = Vec::new();
    for (n, (line, l)) in content_lines(text).enumerate() {
        let toks: Vec<&str> = l
            .split([',', ';', ' ', '\t'])
            .filter(|t| !t.is_empty())
            .collect();
        let parsed: std::result::Result<Vec<f64>, _> =
            toks.iter().map(|t| t.parse::<f64>()).collect();
        match parsed {
            Ok(vals) if vals.len() == k => rows.push(vals),
            Ok(vals) => {
                return Err(ParseError::at_line(
                    line,
                    format!("expected {k} values ({names}), found {}", vals.len()),
                ));
            }
            // A first line of names is a header.
            Err(_) if n == 0 => {}
            Err(_) => {
                let bad = toks
                    .iter()
                    .find(|t| t.parse::<f64>().is_err())
                    .copied()
                    .unwrap_or("");
                return Err(ParseError::at_line(
                    line,
                    format!("'{bad}' is not a number"),
                ));
            }
        }
    }
    Ok(rows)
}

fn parse_rows(bytes: &[u8]) -> ParseResult<(Vec<DVec3>, Vec<f64>)> {
    let rows = parse_numeric_rows(bytes, 4, "x y z s")?;
    Ok(rows
        .iter()
        .map(|r| (DVec3::new(r[0], r[1], r[2]), r[3]))
        .unzip())
}

/// Writes a grid of SDF values: `.npy` (float64, C order, with a JSON sidecar holding the
/// bounds) or `.exr` (float32, bounds in the file's attributes), atomically.
///
/// # Errors
/// [`Error::UnknownFormat`] for other extensions, [`Error::Geom`] for a non-finite value (nothing
/// is written), [`Error::Io`] if writing fails.
pub fn write_sdf_grid(path: &Path, grid: &Grid, values: &[f64]) -> Result<()> {
    if let Some((index, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(Error::Geom {
            path: path.to_path_buf(),
            source: rfta_geom::Error::NonFiniteValue { index, value },
        });
    }
    let ext = extension(path);
    match ext.as_deref() {
        Some("npy") => {
            let dims = grid.dims();
            write_atomic(path, |w| npy::write_npy_f64(w, &dims, values))?;
            let b = grid.bounds();
            let car = Sidecar {
                min: Some(b.min.to_array()),
                max: Some(b.max.to_array()),
                origin: None,
                spacing: None,
            };
            let side = sidecar_path(path);
            let text = serde_json::to_string_pretty(&car).map_err(|e| Error::Parse {
                path: side.clone(),
                line: None,
                detail: e.to_string(),
            })?;
            write_atomic(&side, |w| writeln!(w, "{text}"))
        }
        Some("exr") => {
            let bytes = exr_volume::to_bytes(grid, values).map_err(|e| e.at(path))?;
            write_atomic(path, |w| w.write_all(&bytes))
        }
        _ => Err(Error::UnknownFormat {
            path: path.to_path_buf(),
            expected: "an SDF grid: .npy or .exr",
        }),
    }
}

/// Reads oriented points: `.ply` (vertex `x y z nx ny nz`) or text `.xyz`, `.pts`, `.txt`, `.csv`
/// (rows `x y z nx ny nz`, the format PoissonRecon reads as `--in points.xyz`).
///
/// # Errors
/// [`Error::Io`], [`Error::Parse`], [`Error::UnknownFormat`], or [`Error::Geom`] for NaN
/// positions or zero normals.
pub fn read_oriented_points(path: &Path) -> Result<OrientedPoints> {
    let ply = points_are_ply(path)?;
    decode_points(&read_bytes(path)?, ply, path)
}

/// Whether oriented points at `path` are PLY (else text rows), by extension.
fn points_are_ply(path: &Path) -> Result<bool> {
    match extension(path).as_deref() {
        Some("ply") => Ok(true),
        Some("xyz" | "pts" | "txt" | "csv") => Ok(false),
        _ => Err(Error::UnknownFormat {
            path: path.to_path_buf(),
            expected: "oriented points: .ply, .xyz, .pts, .txt, .csv",
        }),
    }
}

/// Decodes oriented points held in memory, as [`read_oriented_points`]; the extension of `path`
/// picks the format and `path` names the data in error messages.
///
/// # Errors
/// As [`read_oriented_points`].
pub fn decode_oriented_points(bytes: &[u8], path: &Path) -> Result<OrientedPoints> {
    decode_points(bytes, points_are_ply(path)?, path)
}

fn decode_points(bytes: &[u8], ply: bool, path: &Path) -> Result<OrientedPoints> {
    let at = |e: ParseError| e.at(path);
    let (positions, normals) = if ply {
        let p = ply::parse(bytes).map_err(at)?;
        (p.positions().map_err(at)?, p.normals().map_err(at)?)
    } else {
        let rows = parse_numeric_rows(bytes, 6, "x y z nx ny nz").map_err(at)?;
        rows.iter()
            .map(|r| (DVec3::new(r[0], r[1], r[2]), DVec3::new(r[3], r[4], r[5])))
            .unzip()
    };
    OrientedPoints::new(positions, normals, None).map_err(|source| Error::Geom {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes oriented points as binary PLY (`x y z nx ny nz` as doubles), atomically.
///
/// # Errors
/// [`Error::Io`] if writing fails.
pub fn write_oriented_points_ply(path: &Path, points: &OrientedPoints) -> Result<()> {
    write_atomic(path, |w| {
        ply::write_points(w, points.positions(), points.normals())
    })
}
