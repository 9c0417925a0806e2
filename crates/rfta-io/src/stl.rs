//! STL, binary and ascii. STL stores triangle soup; identical corners are welded into shared
//! vertices so that topology queries see a connected surface.

use std::collections::HashMap;
use std::io::Write;

use rfta_geom::{TriMesh, glam::DVec3};

use crate::error::{ParseError, ParseResult};
use crate::text::{as_text, parse_f64};

pub(crate) fn parse(bytes: &[u8]) -> ParseResult<TriMesh> {
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        if 84 + 50 * count == bytes.len() as u64 {
            return parse_binary(bytes, count as usize);
        }
    }
    let starts_solid = bytes.trim_ascii_start().starts_with(b"solid");
    if starts_solid && std::str::from_utf8(bytes).is_ok() {
        return parse_ascii(bytes);
    }
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        return Err(ParseError::new(format!(
            "binary STL header announces {count} triangles ({} bytes) but the file has {} bytes",
            84 + 50 * count,
            bytes.len()
        )));
    }
    Err(ParseError::new(format!(
        "not an STL file: {} bytes, neither 'solid' text nor a binary header",
        bytes.len()
    )))
}

fn parse_binary(bytes: &[u8], count: usize) -> ParseResult<TriMesh> {
    let mut weld = Welder::default();
    let mut faces = Vec::with_capacity(count);
    for t in 0..count {
        let rec = &bytes[84 + 50 * t..84 + 50 * (t + 1)];
        let f = |o: usize| f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]) as f64;
        let mut tri = [0u32; 3];
        for (c, slot) in tri.iter_mut().enumerate() {
            let o = 12 + 12 * c;
            *slot = weld.id(DVec3::new(f(o), f(o + 4), f(o + 8)));
        }
        faces.push(tri);
    }
    Ok(TriMesh {
        vertices: weld.vertices,
        faces,
    })
}

fn parse_ascii(bytes: &[u8]) -> ParseResult<TriMesh> {
    let text = as_text(bytes)?;
    let mut weld = Welder::default();
    let mut faces = Vec::new();
    let mut corners = Vec::with_capacity(3);
    for (i, l) in text.lines().enumerate() {
        let line = i + 1;
        let mut toks = l.split_whitespace();
        match toks.next() {
            Some("vertex") => {
                let mut c = [0.0; 3];
                for (axis, v) in c.iter_mut().enumerate() {
                    let tok = toks
                        .next()
                        .ok_or_else(|| ParseError::at_line(line, "a vertex needs 3 coordinates"))?;
                    *v = parse_f64(tok, line, ["x", "y", "z"][axis])?;
                }
                corners.push(weld.id(DVec3::from_array(c)));
            }
            Some("endloop") => {
                if corners.len() != 3 {
                    return Err(ParseError::at_line(
                        line,
                        format!("a facet has {} vertices, expected 3", corners.len()),
                    ));
                }
                faces.push([corners[0], corners[1], corners[2]]);
                corners.clear();
            }
            _ => {}
        }
    }
    if !corners.is_empty() {
        return Err(ParseError::new(
            "truncated: the last facet is not closed with 'endloop'",
        ));
    }
    Ok(TriMesh {
        vertices: weld.vertices,
        faces,
    })
}

#[derive(Default)]
struct Welder {
    vertices: Vec<DVec3>,
    ids: HashMap<[u64; 3], u32>,
}

impl Welder {
    fn id(&mut self, p: DVec3) -> u32 {
        // +0.0 and -0.0 are the same point.
        let key = (p + DVec3::ZERO).to_array().map(f64::to_bits);
        *self.ids.entry(key).or_insert_with(|| {
            self.vertices.push(p);
            (self.vertices.len() - 1) as u32
        })
    }
}

pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    let mut header = [b' '; 80];
    let tag = b"binary STL written by rfta";
    header[..tag.len()].copy_from_slice(tag);
    w.write_all(&header)?;
    let n = u32::try_from(mesh.n_faces()).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "too many triangles for STL",
        )
    })?;
    w.write_all(&n.to_le_bytes())?;
    for f in 0..mesh.n_faces() {
        let normal = mesh.face_normal_scaled(f).normalize_or_zero();
        for v in std::iter::once(normal).chain(mesh.triangle(f)) {
            for c in v.to_array() {
                w.write_all(&(c as f32).to_le_bytes())?;
            }
        }
        w.write_all(&0u16.to_le_bytes())?;
    }
    Ok(())
}
