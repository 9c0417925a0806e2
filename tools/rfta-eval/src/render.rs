//! A small software rasterizer for the contact sheet: orthographic view, z-buffer, flat shading,
//! each face coloured by its distance to the ground truth, written as an 8-bit RGB PNG (our own
//! encoder: stored deflate blocks, CRC-32, Adler-32, per the PNG and zlib specifications, RFC
//! 2083 and RFC 1950/1951), with an HTML page beside it that labels every tile.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use rfta_geom::{TriMesh, glam::DVec3};
use rfta_mesh::MeshIndex;

const TILE: usize = 260;

/// A face this far from the ground truth, as a fraction of its bounding-box diagonal, is drawn
/// red; nearer, the colour runs from blue-grey (on it) through yellow.
pub(crate) const FAR: f64 = 0.01;

/// The ground truth's colour.
const GT: [f64; 3] = [185.0, 185.0, 185.0];

/// The colour of a face `t` of the way to [`FAR`] (clamped).
fn ramp(t: f64) -> [f64; 3] {
    let t = t.clamp(0.0, 1.0);
    let (near, mid, far) = (
        [150.0, 170.0, 205.0],
        [240.0, 205.0, 60.0],
        [215.0, 35.0, 35.0],
    );
    let mix = |a: [f64; 3], b: [f64; 3], u: f64| [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * u);
    if t < 0.5 {
        mix(near, mid, 2.0 * t)
    } else {
        mix(mid, far, 2.0 * t - 1.0)
    }
}

/// One row per shape, one tile per mesh in it, the ground truth first: `path` (the PNG) and the
/// same name with `.html`, a table that labels every tile and explains the colours.
pub(crate) fn write_contact_sheet(path: &Path, rows: &[Vec<(String, TriMesh)>]) -> Result<()> {
    let cols = rows.iter().map(Vec::len).max().unwrap_or(1).max(1);
    let (w, h) = (cols * TILE, rows.len().max(1) * TILE);
    let mut img = vec![255u8; 3 * w * h];
    for (r, meshes) in rows.iter().enumerate() {
        // One framing per row, from the ground truth (the first mesh), so tiles compare.
        let Some((_, gt)) = meshes.first() else {
            continue;
        };
        let b = gt.bounds();
        if b.is_empty() {
            continue;
        }
        let index = MeshIndex::new(gt).ok();
        let far = FAR * (b.max - b.min).length();
        for (c, (_, mesh)) in meshes.iter().enumerate() {
            let colour = |f: usize| -> [f64; 3] {
                match &index {
                    Some(index) if c > 0 => {
                        let [p, q, s] = mesh.triangle(f);
                        ramp(index.unsigned_distance((p + q + s) / 3.0) / far)
                    }
                    _ => GT,
                }
            };
            let tile = Tile {
                center: b.center(),
                size: b.longest_side().max(1e-9) * 1.15,
                stride: w,
                origin: (c * TILE, r * TILE),
            };
            tile.draw(mesh, &colour, &mut img);
        }
    }
    let png = encode_png(&img, w, h);
    rfta_io::write_atomic(path, |out| out.write_all(&png))?;
    let page = labels(path, rows, cols);
    rfta_io::write_atomic(&path.with_extension("html"), |out| {
        out.write_all(page.as_bytes())
    })?;
    Ok(())
}

/// The page that shows the sheet tile by tile, each with its label.
fn labels(png: &Path, rows: &[Vec<(String, TriMesh)>], cols: usize) -> String {
    let name = png
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let mut s = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>contact sheet</title>\n<style>body{font:13px system-ui,sans-serif} td{vertical-align:top;text-align:center} .t{display:inline-block}</style></head><body>\n",
    );
    let _ = write!(
        s,
        "<p>Each row one shape: the ground truth (grey), then each method's mesh, every face coloured by its distance to the ground truth: <span style=\"color:rgb(150,170,205)\">on it</span>, <span style=\"color:rgb(200,160,0)\">{:.1}%</span>, <span style=\"color:rgb(215,35,35)\">{:.0}% or more</span> of the ground truth's bounding-box diagonal.</p>\n<table>\n",
        50.0 * FAR,
        100.0 * FAR
    );
    for (r, meshes) in rows.iter().enumerate() {
        s.push_str("<tr>");
        for c in 0..cols {
            let label = meshes.get(c).map_or("", |(l, _)| l.as_str());
            let _ = write!(
                s,
                "<td><div class=\"t\" style=\"width:{TILE}px;height:{TILE}px;background:url('{name}') -{}px -{}px\"></div><br>{}</td>",
                c * TILE,
                r * TILE,
                label.replace('&', "&amp;").replace('<', "&lt;")
            );
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table></body></html>\n");
    s
}

/// Where one tile goes in the sheet, and what it frames.
struct Tile {
    center: DVec3,
    size: f64,
    stride: usize,
    origin: (usize, usize),
}

impl Tile {
    fn draw(&self, mesh: &TriMesh, colour: &dyn Fn(usize) -> [f64; 3], img: &mut [u8]) {
        // View from (1, -1.2, 0.8), z up; light from the viewer's upper left.
        let view = DVec3::new(1.0, -1.2, 0.8).normalize();
        let right = DVec3::Z.cross(view).normalize();
        let up = view.cross(right);
        let light = (view + 0.5 * up - 0.3 * right).normalize();
        let mut depth = vec![f64::NEG_INFINITY; TILE * TILE];
        let project = |p: DVec3| {
            let q = p - self.center;
            let s = TILE as f64 / self.size;
            (
                TILE as f64 / 2.0 + q.dot(right) * s,
                TILE as f64 / 2.0 - q.dot(up) * s,
                q.dot(view),
            )
        };
        let (ox, oy) = self.origin;
        for f in 0..mesh.n_faces() {
            let [a, b, c] = mesh.triangle(f);
            let n = (b - a).cross(c - a).normalize_or_zero();
            let light_share = 0.25 + 0.75 * n.dot(light).abs();
            let rgb = colour(f).map(|v| (v * light_share).min(255.0) as u8);
            let (pa, pb, pc) = (project(a), project(b), project(c));
            let area = (pb.0 - pa.0) * (pc.1 - pa.1) - (pb.1 - pa.1) * (pc.0 - pa.0);
            if area.abs() < 1e-12 {
                continue;
            }
            let (x0, x1) = (
                pa.0.min(pb.0).min(pc.0).floor().max(0.0) as usize,
                (pa.0.max(pb.0).max(pc.0).ceil() as usize).min(TILE - 1),
            );
            let (y0, y1) = (
                pa.1.min(pb.1).min(pc.1).floor().max(0.0) as usize,
                (pa.1.max(pb.1).max(pc.1).ceil() as usize).min(TILE - 1),
            );
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let w0 = ((pb.0 - px) * (pc.1 - py) - (pb.1 - py) * (pc.0 - px)) / area;
                    let w1 = ((pc.0 - px) * (pa.1 - py) - (pc.1 - py) * (pa.0 - px)) / area;
                    let w2 = 1.0 - w0 - w1;
                    if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                        continue;
                    }
                    let z = w0 * pa.2 + w1 * pb.2 + w2 * pc.2;
                    let i = y * TILE + x;
                    if z > depth[i] {
                        depth[i] = z;
                        let at = 3 * ((oy + y) * self.stride + ox + x);
                        img[at..at + 3].copy_from_slice(&rgb);
                    }
                }
            }
        }
    }
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut table = [0u32; 256];
    for (n, t) in table.iter_mut().enumerate() {
        let mut c = n as u32;
        for _ in 0..8 {
            c = if c & 1 == 1 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
        *t = c;
    }
    !bytes.iter().fold(!0u32, |c, &b| {
        table[((c ^ b as u32) & 0xFF) as usize] ^ (c >> 8)
    })
}

fn encode_png(rgb: &[u8], w: usize, h: usize) -> Vec<u8> {
    // Scanlines, each with filter type 0.
    let mut raw = Vec::with_capacity((3 * w + 1) * h);
    for row in rgb.chunks(3 * w) {
        raw.push(0);
        raw.extend_from_slice(row);
    }
    // zlib stream of stored (uncompressed) deflate blocks.
    let mut z = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = raw.chunks(65_535).collect();
    for (i, block) in blocks.iter().enumerate() {
        z.push(u8::from(i + 1 == blocks.len()));
        let len = block.len() as u16;
        z.extend_from_slice(&len.to_le_bytes());
        z.extend_from_slice(&(!len).to_le_bytes());
        z.extend_from_slice(block);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &byte in &raw {
        a = (a + byte as u32) % 65_521;
        b = (b + a) % 65_521;
    }
    z.extend_from_slice(&((b << 16) | a).to_be_bytes());
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8; 4], data: &[u8]| {
        png.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        png.extend_from_slice(&body);
        png.extend_from_slice(&crc32(&body).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&(w as u32).to_be_bytes());
    ihdr.extend_from_slice(&(h as u32).to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]); // 8-bit RGB, deflate, no filter, no interlace
    chunk(b"IHDR", &ihdr);
    chunk(b"IDAT", &z);
    chunk(b"IEND", &[]);
    png
}

#[cfg(test)]
mod tests {
    #[test]
    fn crc_matches_the_png_specification_check_value() {
        // The CRC-32 of "123456789" is 0xCBF43926 (the standard check value).
        assert_eq!(super::crc32(b"123456789"), 0xCBF4_3926);
    }

    /// The ramp runs from blue-grey on the surface through yellow to red at FAR and beyond.
    #[test]
    fn the_colours_run_from_on_the_surface_to_far() {
        assert_eq!(super::ramp(0.0), [150.0, 170.0, 205.0]);
        assert_eq!(super::ramp(0.5), [240.0, 205.0, 60.0]);
        assert_eq!(super::ramp(1.0), [215.0, 35.0, 35.0]);
        assert_eq!(super::ramp(7.0), super::ramp(1.0));
    }
}
