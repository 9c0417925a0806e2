//! 2D formats: SDF samples in (`.npy` grids of shape `(nx, ny)` or rows `(n, 3)` of `x y s`,
//! CSV/text rows `x y s`, 16-bit grayscale PNG images, OpenEXR images (one float channel, or the
//! one named `sdf`; an EXR with `rfta_dims` is a 3D volume)), polylines out (OBJ with `l`
//! elements, SVG for looking, CSV) and back in (OBJ).
//!
//! Grids follow the 3D conventions: `S[i, j]` at `(x_i, y_j)`, bounds from the JSON sidecar
//! (`{"min": [x, y], "max": [x, y]}` or `{"origin": [x, y], "spacing": [x, y]}`), else the
//! caller's, else `[-1, 1]^2`. A PNG's pixel `(row, col)` is `S[col, rows - 1 - row]` (image up is
//! `+y`), and its values need `"values": [lo, hi]` in the sidecar: 0 maps to `lo`, 65535 to `hi`.
//! An EXR image is laid out as a PNG and holds the values themselves.

use std::fmt::Write as _;
use std::path::Path;

use rfta_geom::glam::DVec2;
use rfta_geom::plane::{Grid2, Polylines, SdfSamples2};

use crate::error::{ParseError, ParseResult};
use crate::text::{as_text, parse_f64};
use crate::{Error, Result, exr_volume, extension, npy, read_bytes, sidecar_path, write_atomic};

/// The 2D sidecar beside a grid file.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Sidecar2 {
    min: Option<[f64; 2]>,
    max: Option<[f64; 2]>,
    origin: Option<[f64; 2]>,
    spacing: Option<[f64; 2]>,
    values: Option<[f64; 2]>,
}

/// Is this SDF file 2D? `.npy` of shape `(nx, ny)` or `(n, 3)`, a PNG, or a CSV/text file whose
/// first data row has three numbers.
///
/// # Errors
/// The file cannot be read, or a `.npy` header is malformed.
pub fn is_sdf_2d(path: &Path) -> Result<bool> {
    match extension(path).as_deref() {
        Some("png") => Ok(true),
        Some("exr") => {
            let file = std::fs::File::open(path).map_err(|source| Error::Io {
                path: path.to_path_buf(),
                source,
            })?;
            exr_volume::is_image(std::io::BufReader::new(file)).map_err(|e| e.at(path))
        }
        Some("npy") => {
            use std::io::Read;
            let mut head = Vec::new();
            std::fs::File::open(path)
                .and_then(|f| f.take(1 << 20).read_to_end(&mut head))
                .map_err(|source| Error::Io {
                    path: path.to_path_buf(),
                    source,
                })?;
            let header = npy::parse_header(&head).map_err(|e| e.at(path))?;
            Ok(header.shape.len() == 2 && header.shape[1] != 4)
        }
        Some("csv" | "txt" | "xyz") => {
            // Only up to the first data row (the reader reads the file once more); a file that
            // is not text is left to the 3D reader, which says so.
            use std::io::BufRead;
            let file = std::fs::File::open(path).map_err(|source| Error::Io {
                path: path.to_path_buf(),
                source,
            })?;
            let tokens = |l: &str| -> Vec<String> {
                l.split([',', ';', ' ', '\t'])
                    .filter(|t| !t.is_empty())
                    .map(str::to_string)
                    .collect()
            };
            for line in std::io::BufReader::new(file).lines() {
                let Ok(line) = line else {
                    return Ok(false);
                };
                let line = line.trim();
                if line.is_empty() || line.starts_with('#') {
                    continue;
                }
                let t = tokens(line);
                if t.iter().any(|t| t.parse::<f64>().is_ok()) {
                    return Ok(t.len() == 3);
                }
            }
            Ok(false)
        }
        _ => Ok(false),
    }
}

/// Read 2D SDF samples; `bounds` (first and last grid point) applies to grids without a sidecar.
///
/// # Errors
/// [`Error::Io`], [`Error::Parse`] naming the file (and line), [`Error::UnknownFormat`], or
/// [`Error::Geom`] for samples that fail validation (NaN, all zero, a 1-pixel image).
pub fn read_sdf_2d(path: &Path, bounds: Option<(DVec2, DVec2)>) -> Result<SdfSamples2> {
    let bytes = read_bytes(path)?;
    let geom = |source| Error::Geom {
        path: path.to_path_buf(),
        source,
    };
    let grid = |dims: [usize; 2]| -> Result<(Grid2, Option<[f64; 2]>)> {
        let side = sidecar_path(path);
        let car: Sidecar2 = if side.exists() {
            let text = read_bytes(&side)?;
            serde_json::from_slice(&text).map_err(|e| {
                ParseError::new(format!("2D sidecar: {e} (expected min/max or origin/spacing as [x, y], and values for images)")).at(&side)
            })?
        } else {
            Sidecar2::default()
        };
        let g = match (car.min, car.max, car.origin, car.spacing) {
            (Some(lo), Some(hi), None, None) => {
                Grid2::from_bounds(dims, DVec2::from(lo), DVec2::from(hi))
            }
            (None, None, Some(o), Some(s)) => Grid2::new(dims, DVec2::from(o), DVec2::from(s)),
            (None, None, None, None) => {
                let (lo, hi) = bounds.unwrap_or((DVec2::splat(-1.0), DVec2::splat(1.0)));
                Grid2::from_bounds(dims, lo, hi)
            }
            _ => {
                return Err(ParseError::new(
                    "2D sidecar: give either min and max or origin and spacing",
                )
                .at(&side));
            }
        }
        .map_err(geom)?;
        Ok((g, car.values))
    };
    let samples = match extension(path).as_deref() {
        Some("npy") => {
            let arr = npy::parse(&bytes).map_err(|e| e.at(path))?;
            match arr.shape.as_slice() {
                &[n, 3] => {
                    let (p, v) = (0..n)
                        .map(|r| {
                            (
                                DVec2::new(arr.data[3 * r], arr.data[3 * r + 1]),
                                arr.data[3 * r + 2],
                            )
                        })
                        .unzip();
                    SdfSamples2::scattered(p, v)
                }
                &[nx, ny] => SdfSamples2::grid(grid([nx, ny])?.0, arr.data),
                other => {
                    return Err(ParseError::new(format!(
                        "expected a 2-D grid of shape (nx, ny) or rows of shape (n, 3), found shape {other:?}"
                    ))
                    .at(path));
                }
            }
        }
        Some("csv" | "txt" | "xyz") => {
            let (p, v) = parse_rows(&bytes).map_err(|e| e.at(path))?;
            SdfSamples2::scattered(p, v)
        }
        Some("png") => {
            let (dims, pixels) = decode_png(&bytes).map_err(|e| e.at(path))?;
            let (g, values) = grid(dims)?;
            let [lo, hi] = values.ok_or_else(|| {
                ParseError::new(format!(
                    "a PNG needs the value range in its sidecar {}: {{\"values\": [lo, hi]}} (0 maps to lo, 65535 to hi)",
                    sidecar_path(path).display()
                ))
                .at(path)
            })?;
            SdfSamples2::grid(
                g,
                pixels
                    .iter()
                    .map(|&u| lo + (hi - lo) * f64::from(u) / 65535.0)
                    .collect(),
            )
        }
        Some("exr") => {
            let (dims, values) = exr_volume::parse_image(&bytes).map_err(|e| e.at(path))?;
            SdfSamples2::grid(grid(dims)?.0, values)
        }
        _ => {
            return Err(Error::UnknownFormat {
                path: path.to_path_buf(),
                expected: "2D samples: .npy, .csv/.txt (x y s), .png (16-bit grayscale), .exr (image)",
            });
        }
    };
    samples.map_err(geom)
}

fn parse_rows(bytes: &[u8]) -> ParseResult<(Vec<DVec2>, Vec<f64>)> {
    let text = as_text(bytes)?;
    let (mut p, mut v) = (Vec::new(), Vec::new());
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let toks: Vec<&str> = line
            .split([',', ';', ' ', '\t'])
            .filter(|t| !t.is_empty())
            .collect();
        if toks.iter().all(|t| t.parse::<f64>().is_err()) && p.is_empty() {
            continue; // a header
        }
        if toks.len() != 3 {
            return Err(ParseError::at_line(
                k + 1,
                format!("expected 3 numbers (x y s), found {}", toks.len()),
            ));
        }
        let x = parse_f64(toks[0], k + 1, "x")?;
        let y = parse_f64(toks[1], k + 1, "y")?;
        p.push(DVec2::new(x, y));
        v.push(parse_f64(toks[2], k + 1, "s")?);
    }
    Ok((p, v))
}

/// A 16-bit grayscale PNG as grid values in `S[col, rows - 1 - row]` order.
fn decode_png(bytes: &[u8]) -> ParseResult<([usize; 2], Vec<u16>)> {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder
        .read_info()
        .map_err(|e| ParseError::new(format!("not a readable PNG: {e}")))?;
    let info = reader.info();
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        return Err(ParseError::new(format!(
            "expected a 16-bit grayscale PNG, found {:?} at {:?} bits",
            info.color_type, info.bit_depth
        )));
    }
    let (w, h) = (info.width as usize, info.height as usize);
    let mut buf = vec![0u8; reader.output_buffer_size()];
    reader
        .next_frame(&mut buf)
        .map_err(|e| ParseError::new(format!("PNG data: {e}")))?;
    if buf.len() < w * h * 2 {
        return Err(ParseError::new("PNG data shorter than its size"));
    }
    let px = |row: usize, col: usize| {
        u16::from_be_bytes([buf[2 * (row * w + col)], buf[2 * (row * w + col) + 1]])
    };
    let mut values = Vec::with_capacity(w * h);
    for col in 0..w {
        for j in 0..h {
            values.push(px(h - 1 - j, col));
        }
    }
    Ok(([w, h], values))
}

/// Write polylines by extension: `.obj` (`v x y 0` and `l a b`), `.svg`, `.csv` (one row per
/// edge: `x0,y0,x1,y1`).
///
/// # Errors
/// [`Error::UnknownFormat`] for another extension, [`Error::Io`] if writing fails (the file is
/// then left as it was).
pub fn write_polylines(path: &Path, lines: &Polylines) -> Result<()> {
    match extension(path).as_deref() {
        Some("obj") => write_atomic(path, |w| {
            writeln!(
                w,
                "# rfta: closed polylines, inside on the left of each edge"
            )?;
            for v in &lines.vertices {
                writeln!(w, "v {} {} 0", v.x, v.y)?;
            }
            for &[a, b] in &lines.edges {
                writeln!(w, "l {} {}", a + 1, b + 1)?;
            }
            Ok(())
        }),
        Some("csv") => write_atomic(path, |w| {
            writeln!(w, "x0,y0,x1,y1")?;
            for &e in &lines.edges {
                let s = lines.segment(e);
                writeln!(w, "{},{},{},{}", s.a.x, s.a.y, s.b.x, s.b.y)?;
            }
            Ok(())
        }),
        Some("svg") => {
            let svg = Svg::around(&[lines], &[])
                .curve(lines, "#c0392b", "")
                .finish();
            write_atomic(path, |w| w.write_all(svg.as_bytes()))
        }
        _ => Err(Error::UnknownFormat {
            path: path.to_path_buf(),
            expected: "polylines: .obj, .svg, .csv",
        }),
    }
}

/// Read polylines from an OBJ's `v` and `l` elements (a polyline `l a b c` is split into edges).
///
/// # Errors
/// [`Error::Io`], [`Error::Parse`] naming the line, [`Error::Geom`] for an index out of range.
pub fn read_polylines(path: &Path) -> Result<Polylines> {
    let bytes = read_bytes(path)?;
    let text = as_text(&bytes).map_err(|e| e.at(path))?;
    let (mut vertices, mut edges) = (Vec::new(), Vec::new());
    for (k, line) in text.lines().enumerate() {
        let mut toks = line.split_whitespace();
        match toks.next() {
            Some("v") => {
                let x = parse_f64(toks.next().unwrap_or(""), k + 1, "x").map_err(|e| e.at(path))?;
                let y = parse_f64(toks.next().unwrap_or(""), k + 1, "y").map_err(|e| e.at(path))?;
                vertices.push(DVec2::new(x, y));
            }
            Some("l") => {
                let idx: Vec<u32> = toks
                    .map(|t| {
                        let i: i64 = t.split('/').next().unwrap_or("").parse().map_err(|_| {
                            ParseError::at_line(k + 1, format!("'{t}' is not a vertex index"))
                                .at(path)
                        })?;
                        let n = vertices.len() as i64;
                        let i = if i < 0 { n + i } else { i - 1 };
                        u32::try_from(i).map_err(|_| {
                            ParseError::at_line(k + 1, "vertex index out of range").at(path)
                        })
                    })
                    .collect::<Result<_>>()?;
                edges.extend(idx.windows(2).map(|w| [w[0], w[1]]));
            }
            _ => {}
        }
    }
    Polylines::new(vertices, edges).map_err(|source| Error::Geom {
        path: path.to_path_buf(),
        source,
    })
}

/// An SVG drawing of curves (and sample dots), `y` up, fitted to a 800-pixel square.
#[derive(Debug, Clone)]
pub struct Svg {
    min: DVec2,
    scale: f64,
    size: f64,
    body: String,
}

impl Svg {
    /// A drawing whose view holds the curves and points given.
    pub fn around(curves: &[&Polylines], points: &[DVec2]) -> Self {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in curves.iter().flat_map(|c| c.vertices.iter()).chain(points) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if !lo.is_finite() {
            (lo, hi) = (DVec2::ZERO, DVec2::ONE);
        }
        let extent = (hi - lo).max_element().max(1e-12) * 1.05;
        let centre = (lo + hi) / 2.0;
        let size = 800.0;
        Self {
            min: centre - DVec2::splat(extent / 2.0),
            scale: size / extent,
            size,
            body: String::new(),
        }
    }

    fn map(&self, p: DVec2) -> (f64, f64) {
        let q = (p - self.min) * self.scale;
        (q.x, self.size - q.y)
    }

    /// Draw sample dots coloured by sign (negative inside: blue; positive: grey).
    pub fn samples(mut self, positions: &[DVec2], values: &[f64]) -> Self {
        for (p, v) in positions.iter().zip(values) {
            let (x, y) = self.map(*p);
            let fill = if *v < 0.0 { "#2e86c1" } else { "#aab7b8" };
            let _ = writeln!(
                self.body,
                r#"<circle cx="{x:.2}" cy="{y:.2}" r="2" fill="{fill}"/>"#
            );
        }
        self
    }

    /// Draw a curve in `colour`; `dash` is an SVG dash pattern ("" for solid).
    pub fn curve(mut self, lines: &Polylines, colour: &str, dash: &str) -> Self {
        let mut d = String::new();
        for &e in &lines.edges {
            let s = lines.segment(e);
            let (a, b) = (self.map(s.a), self.map(s.b));
            let _ = write!(d, "M{:.2} {:.2}L{:.2} {:.2}", a.0, a.1, b.0, b.1);
        }
        let dash = if dash.is_empty() {
            String::new()
        } else {
            format!(r#" stroke-dasharray="{dash}""#)
        };
        let _ = writeln!(
            self.body,
            r#"<path d="{d}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>"#
        );
        self
    }

    /// Draw a caption at the top left.
    pub fn caption(mut self, text: &str) -> Self {
        let _ = writeln!(
            self.body,
            r#"<text x="10" y="20" font-family="sans-serif" font-size="14">{}</text>"#,
            text.replace('&', "&amp;").replace('<', "&lt;")
        );
        self
    }

    /// The SVG document.
    pub fn finish(self) -> String {
        format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{s}" height="{s}" viewBox="0 0 {s} {s}"><rect width="100%" height="100%" fill="white"/>
{}</svg>
"#,
            self.body,
            s = self.size
        )
    }
}

/// Write an SVG document atomically.
///
/// # Errors
/// [`Error::Io`] if writing fails.
pub fn write_svg(path: &Path, svg: Svg) -> Result<()> {
    let text = svg.finish();
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(tag: &str) -> std::path::PathBuf {
        let p = std::env::temp_dir().join(format!("rfta-io-plane-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).expect("temp dir");
        p
    }

    #[test]
    fn a_png_is_read_with_image_up_as_plus_y_and_its_value_range() {
        let dir = temp("png");
        let path = dir.join("sdf.png");
        // 3 wide, 2 high; row 0 is the top. Pixel (row, col) = 1000 * (3 * row + col).
        let (w, h) = (3u32, 2u32);
        let pixels: Vec<u16> = (0..6).map(|k| 1000 * k).collect();
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, w, h);
            enc.set_color(png::ColorType::Grayscale);
            enc.set_depth(png::BitDepth::Sixteen);
            let mut writer = enc.write_header().expect("header");
            let data: Vec<u8> = pixels.iter().flat_map(|p| p.to_be_bytes()).collect();
            writer.write_image_data(&data).expect("data");
        }
        std::fs::write(&path, &bytes).expect("write");
        std::fs::write(
            dir.join("sdf.json"),
            r#"{"min": [0, 0], "max": [2, 1], "values": [-1, 1]}"#,
        )
        .expect("sidecar");
        let s = read_sdf_2d(&path, None).expect("read");
        let grid = s.as_grid().expect("grid");
        assert_eq!(grid.dims(), [3, 2]);
        // S[i, j] at (x_i, y_j): (col, rows - 1 - row), so S[0, 1] is the top-left pixel (0) and
        // S[2, 0] the bottom-right one (5000).
        let value = |u: u16| -1.0 + 2.0 * f64::from(u) / 65535.0;
        assert_eq!(s.values()[grid.index(0, 1)], value(0));
        assert_eq!(s.values()[grid.index(2, 0)], value(5000));
        assert_eq!(s.values()[grid.index(1, 0)], value(4000));
        assert_eq!(grid.position(grid.index(2, 1)), DVec2::new(2.0, 1.0));
    }

    #[test]
    fn an_exr_image_is_a_2d_grid_and_an_exr_volume_is_not() {
        use exr::prelude::*;
        let dir = temp("exr");
        // 3 wide, 2 high, one float channel "Y": row 0 is the top; pixel (row, col) = 3 row + col.
        let pixels: Vec<f32> = (0..6).map(|k| k as f32 - 2.5).collect();
        let channel = AnyChannel::new("Y", FlatSamples::F32(pixels));
        let layer = Layer::new(
            (3, 2),
            LayerAttributes::named("sdf"),
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(smallvec::smallvec![channel]),
        );
        let path = dir.join("img.exr");
        Image::from_layer(layer)
            .write()
            .to_file(&path)
            .expect("write exr");
        assert!(is_sdf_2d(&path).expect("peek"));
        let s = read_sdf_2d(&path, Some((DVec2::ZERO, DVec2::new(2.0, 1.0)))).expect("read");
        let g = s.as_grid().expect("grid");
        assert_eq!(g.dims(), [3, 2]);
        // S[i, j] at (col, rows - 1 - row): S[0, 1] is the top-left pixel, S[2, 0] the bottom-right.
        assert_eq!(s.values()[g.index(0, 1)], -2.5);
        assert_eq!(s.values()[g.index(2, 0)], 2.5);
        // A volume written by rfta (rfta_dims) stays 3D.
        let vol = dir.join("vol.exr");
        let grid = rfta_geom::Grid::cube(2, -1.0, 1.0).expect("grid");
        let values: Vec<f64> = (0..grid.len()).map(|i| i as f64 - 13.5).collect();
        crate::write_sdf_grid(&vol, &grid, &values).expect("volume");
        assert!(!is_sdf_2d(&vol).expect("peek"));
    }

    #[test]
    fn npy_csv_and_polylines_round_trip() {
        let dir = temp("rt");
        // A grid of shape (3, 5): S[i, j] = 10 i + j - 15. (Shape (n, 4) is 3D scattered rows.)
        let values: Vec<f64> = (0..15)
            .map(|k| (10 * (k / 5) + k % 5) as f64 - 15.0)
            .collect();
        let npy_path = dir.join("g.npy");
        write_atomic(&npy_path, |w| npy::write_npy_f64(w, &[3, 5], &values)).expect("npy");
        assert!(is_sdf_2d(&npy_path).expect("peek"));
        let s = read_sdf_2d(&npy_path, Some((DVec2::ZERO, DVec2::new(2.0, 3.0)))).expect("read");
        let g = s.as_grid().expect("grid");
        assert_eq!(g.dims(), [3, 5]);
        assert_eq!(s.values()[g.index(2, 1)], 6.0);
        assert_eq!(g.spacing(), DVec2::new(1.0, 0.75));
        let csv = dir.join("s.csv");
        std::fs::write(&csv, "x,y,s\n0,0,-1\n1,0,0.5\n0,1,0.25\n").expect("csv");
        assert!(is_sdf_2d(&csv).expect("peek"));
        let s = read_sdf_2d(&csv, None).expect("csv");
        assert_eq!(s.positions()[2], DVec2::new(0.0, 1.0));
        assert_eq!(s.values(), &[-1.0, 0.5, 0.25]);
        let square = Polylines::new(
            vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y],
            vec![[0, 1], [1, 2], [2, 3], [3, 0]],
        )
        .expect("square");
        let obj = dir.join("c.obj");
        write_polylines(&obj, &square).expect("obj");
        assert_eq!(read_polylines(&obj).expect("back"), square);
        assert!(write_polylines(&dir.join("c.ply"), &square).is_err());
    }
}
