//! Object File Format: `OFF` header (also `COFF`, `NOFF`, `CNOFF`), counts, vertices, polygons.

use rfta_geom::{TriMesh, glam::DVec3};

use crate::error::{ParseError, ParseResult};
use crate::text::{as_text, content_lines, fan, parse_count, parse_f64};

pub(crate) fn parse(bytes: &[u8]) -> ParseResult<TriMesh> {
    let text = as_text(bytes)?;
    let mut lines = content_lines(text);
    let (line, header) = lines
        .next()
        .ok_or_else(|| ParseError::new("empty file: expected an 'OFF' header"))?;
    let mut header_toks = header.split_whitespace();
    let keyword = header_toks.next().unwrap_or("");
    if !keyword.ends_with("OFF") {
        return Err(ParseError::at_line(
            line,
            format!("expected an 'OFF' header, found '{keyword}'"),
        ));
    }
    // Counts may follow the keyword on the same line.
    let rest: Vec<&str> = header_toks.collect();
    let (count_line, counts): (usize, Vec<&str>) = if rest.is_empty() {
        let (l, c) = lines
            .next()
            .ok_or_else(|| ParseError::new("missing the vertex and face counts"))?;
        (l, c.split_whitespace().collect())
    } else {
        (line, rest)
    };
    if counts.len() < 2 {
        return Err(ParseError::at_line(
            count_line,
            "expected vertex and face counts",
        ));
    }
    let n_vertices = parse_count(counts[0], count_line, "vertex count")?;
    let n_faces = parse_count(counts[1], count_line, "face count")?;
    let cap = bytes.len() / 4;
    let mut vertices = Vec::with_capacity(n_vertices.min(cap));
    for i in 0..n_vertices {
        let (line, l) = lines.next().ok_or_else(|| {
            ParseError::new(format!("truncated: {i} of {n_vertices} vertices present"))
        })?;
        let toks: Vec<&str> = l.split_whitespace().collect();
        if toks.len() < 3 {
            return Err(ParseError::at_line(line, "a vertex needs 3 coordinates"));
        }
        vertices.push(DVec3::new(
            parse_f64(toks[0], line, "x")?,
            parse_f64(toks[1], line, "y")?,
            parse_f64(toks[2], line, "z")?,
        ));
    }
    let mut faces = Vec::with_capacity(n_faces.min(cap));
    let mut corners = Vec::new();
    for i in 0..n_faces {
        let (line, l) = lines
            .next()
            .ok_or_else(|| ParseError::new(format!("truncated: {i} of {n_faces} faces present")))?;
        let mut toks = l.split_whitespace();
        let n = parse_count(toks.next().unwrap_or(""), line, "face size")?;
        corners.clear();
        for _ in 0..n {
            let tok = toks.next().ok_or_else(|| {
                ParseError::at_line(line, format!("face lists fewer than {n} vertices"))
            })?;
            let idx: u32 = tok.parse().map_err(|_| {
                ParseError::at_line(line, format!("face vertex '{tok}' is not an index"))
            })?;
            corners.push(idx);
        }
        fan(&corners, line, &mut faces)?;
    }
    // A header that counts fewer records than the file holds: reading only the counted ones
    // would drop the rest without a word.
    if let Some((line, _)) = lines.next() {
        return Err(ParseError::at_line(
            line,
            format!(
                "more data than the header's counts ({n_vertices} vertices, {n_faces} faces) announce"
            ),
        ));
    }
    Ok(TriMesh { vertices, faces })
}
