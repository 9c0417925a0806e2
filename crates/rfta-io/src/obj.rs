//! Wavefront OBJ: `v` and `f` records; other records (normals, texture coordinates, groups,
//! materials) are skipped.

use std::io::Write;

use rfta_geom::{TriMesh, glam::DVec3};

use crate::error::{ParseError, ParseResult};
use crate::text::{as_text, content_lines, fan, parse_f64};

pub(crate) fn parse(bytes: &[u8]) -> ParseResult<TriMesh> {
    let text = as_text(bytes)?;
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut corners = Vec::new();
    for (line, l) in content_lines(text) {
        let mut toks = l.split_whitespace();
        match toks.next() {
            Some("v") => {
                let mut c = [0.0; 3];
                for (axis, v) in c.iter_mut().enumerate() {
                    let tok = toks
                        .next()
                        .ok_or_else(|| ParseError::at_line(line, "a vertex needs 3 coordinates"))?;
                    *v = parse_f64(tok, line, ["x", "y", "z"][axis])?;
                }
                vertices.push(DVec3::from_array(c));
            }
            Some("f") => {
                corners.clear();
                for tok in toks {
                    let idx = tok.split('/').next().unwrap_or("");
                    let i: i64 = idx.parse().map_err(|_| {
                        ParseError::at_line(line, format!("face vertex '{tok}' is not an index"))
                    })?;
                    // 1-based; negative counts back from the latest vertex.
                    let zero_based = if i > 0 {
                        i - 1
                    } else {
                        vertices.len() as i64 + i
                    };
                    if i == 0 || zero_based < 0 || zero_based > u32::MAX as i64 {
                        return Err(ParseError::at_line(
                            line,
                            format!("face vertex index {i} is out of range"),
                        ));
                    }
                    corners.push(zero_based as u32);
                }
                fan(&corners, line, &mut faces)?;
            }
            _ => {}
        }
    }
    Ok(TriMesh { vertices, faces })
}

pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    writeln!(
        w,
        "# written by rfta: {} vertices, {} faces",
        mesh.n_vertices(),
        mesh.n_faces()
    )?;
    for v in &mesh.vertices {
        // `{}` prints the shortest representation that round-trips exactly.
        writeln!(w, "v {} {} {}", v.x, v.y, v.z)?;
    }
    for f in &mesh.faces {
        writeln!(w, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
    }
    Ok(())
}
