//! A small software rasterizer for the contact sheet: orthographic view, z-buffer, flat shading,
//! written as an 8-bit greyscale PNG (our own encoder: stored deflate blocks, CRC-32, Adler-32,
//! per the PNG and zlib specifications, RFC 2083 and RFC 1950/1951).

use std::path::Path;

use anyhow::Result;
use rfta_geom::{TriMesh, glam::DVec3};

const TILE: usize = 200;

/// One row per shape, one tile per mesh in it.
pub(crate) fn write_contact_sheet(path: &Path, rows: &[Vec<(String, TriMesh)>]) -> Result<()> {
    let cols = rows.iter().map(Vec::len).max().unwrap_or(1).max(1);
    let (w, h) = (cols * TILE, rows.len().max(1) * TILE);
    let mut img = vec![255u8; w * h];
    for (r, meshes) in rows.iter().enumerate() {
        // One framing per row, from the ground truth (the first mesh), so tiles compare.
        let frame = meshes
            .first()
            .map(|(_, m)| m.bounds())
            .filter(|b| !b.is_empty());
        for (c, (_, mesh)) in meshes.iter().enumerate() {
            if let Some(b) = frame {
                draw(
                    mesh,
                    b.center(),
                    b.longest_side().max(1e-9) * 1.15,
                    &mut img,
                    w,
                    c * TILE,
                    r * TILE,
                );
            }
        }
    }
    let png = encode_png(&img, w, h);
    rfta_io::write_atomic(path, |out| out.write_all(&png))?;
    Ok(())
}

fn draw(
    mesh: &TriMesh,
    center: DVec3,
    size: f64,
    img: &mut [u8],
    stride: usize,
    ox: usize,
    oy: usize,
) {
    // View from (1, -1.2, 0.8), z up; light from the viewer's upper left.
    let view = DVec3::new(1.0, -1.2, 0.8).normalize();
    let right = DVec3::Z.cross(view).normalize();
    let up = view.cross(right);
    let light = (view + 0.5 * up - 0.3 * right).normalize();
    let mut depth = vec![f64::NEG_INFINITY; TILE * TILE];
    let project = |p: DVec3| {
        let q = p - center;
        let s = TILE as f64 / size;
        (
            TILE as f64 / 2.0 + q.dot(right) * s,
            TILE as f64 / 2.0 - q.dot(up) * s,
            q.dot(view),
        )
    };
    for f in 0..mesh.n_faces() {
        let [a, b, c] = mesh.triangle(f);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let shade = (40.0 + 200.0 * n.dot(light).abs()).min(255.0) as u8;
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
                    img[(oy + y) * stride + ox + x] = shade;
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

fn encode_png(gray: &[u8], w: usize, h: usize) -> Vec<u8> {
    // Scanlines, each with filter type 0.
    let mut raw = Vec::with_capacity((w + 1) * h);
    for row in gray.chunks(w) {
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
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]); // 8-bit greyscale, deflate, no filter, no interlace
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
}
