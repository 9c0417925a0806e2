//! Stanford PLY, ascii and binary (both byte orders): a generic element reader, plus the views
//! rfta needs (meshes, oriented points, scattered SDF samples) and a binary writer.

use std::io::Write;

use rfta_geom::{TriMesh, glam::DVec3};

use crate::error::{ParseError, ParseResult};

#[derive(Debug, Clone, Copy, PartialEq)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Ty {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "char" | "int8" => Ty::I8,
            "uchar" | "uint8" => Ty::U8,
            "short" | "int16" => Ty::I16,
            "ushort" | "uint16" => Ty::U16,
            "int" | "int32" => Ty::I32,
            "uint" | "uint32" => Ty::U32,
            "float" | "float32" => Ty::F32,
            "double" | "float64" => Ty::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::F64 => 8,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

#[derive(Debug)]
enum Column {
    Scalar(Vec<f64>),
    /// Flattened lists: `starts[r]..starts[r + 1]` indexes `values` for record `r`.
    List {
        starts: Vec<usize>,
        values: Vec<f64>,
    },
}

#[derive(Debug)]
struct Property {
    name: String,
    /// `(count type, item type)` for lists.
    list: Option<(Ty, Ty)>,
    ty: Ty,
    column: Column,
}

#[derive(Debug)]
pub(crate) struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

/// A parsed PLY file: its elements with their columns.
#[derive(Debug)]
pub(crate) struct Ply {
    elements: Vec<Element>,
}

pub(crate) fn parse(bytes: &[u8]) -> ParseResult<Ply> {
    let (encoding, mut elements, body_start) = parse_header(bytes)?;
    let body = &bytes[body_start..];
    match encoding {
        Encoding::Ascii => read_ascii(body, &mut elements, count_lines(&bytes[..body_start]))?,
        Encoding::Little | Encoding::Big => read_binary(body, &mut elements, encoding)?,
    }
    Ok(Ply { elements })
}

fn count_lines(b: &[u8]) -> usize {
    b.iter().filter(|&&c| c == b'\n').count()
}

fn parse_header(bytes: &[u8]) -> ParseResult<(Encoding, Vec<Element>, usize)> {
    if !bytes.starts_with(b"ply") {
        return Err(ParseError::new(
            "not a PLY file: it does not start with 'ply'",
        ));
    }
    let end = find(bytes, b"end_header")
        .ok_or_else(|| ParseError::new("truncated header: no 'end_header' line"))?;
    // The body starts after the newline that ends 'end_header' (\n or \r\n).
    let mut body_start = end + b"end_header".len();
    if bytes.get(body_start) == Some(&b'\r') {
        body_start += 1;
    }
    if bytes.get(body_start) == Some(&b'\n') {
        body_start += 1;
    }
    let header = std::str::from_utf8(&bytes[..end])
        .map_err(|_| ParseError::new("the header is not text"))?;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, l) in header.lines().enumerate().skip(1) {
        let line = i + 1;
        let toks: Vec<&str> = l.split_whitespace().collect();
        match toks.first().copied() {
            Some("format") => {
                encoding = Some(match toks.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::Little,
                    Some("binary_big_endian") => Encoding::Big,
                    other => {
                        return Err(ParseError::at_line(
                            line,
                            format!("unknown format {:?}", other.unwrap_or("")),
                        ));
                    }
                });
            }
            Some("element") => {
                let (Some(name), Some(count)) = (toks.get(1), toks.get(2)) else {
                    return Err(ParseError::at_line(line, "expected 'element NAME COUNT'"));
                };
                let count = count.parse().map_err(|_| {
                    ParseError::at_line(line, format!("element count '{count}' is not an integer"))
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| ParseError::at_line(line, "a property before any element"))?;
                let bad = || ParseError::at_line(line, format!("malformed property line '{l}'"));
                let (list, ty, name) = if toks.get(1) == Some(&"list") {
                    let c = toks.get(2).and_then(|t| Ty::parse(t)).ok_or_else(bad)?;
                    let it = toks.get(3).and_then(|t| Ty::parse(t)).ok_or_else(bad)?;
                    if matches!(c, Ty::F32 | Ty::F64) {
                        return Err(ParseError::at_line(
                            line,
                            "a list count must be an integer type",
                        ));
                    }
                    (Some((c, it)), it, toks.get(4).ok_or_else(bad)?)
                } else {
                    (
                        None,
                        toks.get(1).and_then(|t| Ty::parse(t)).ok_or_else(bad)?,
                        toks.get(2).ok_or_else(bad)?,
                    )
                };
                let column = if list.is_some() {
                    Column::List {
                        starts: vec![0],
                        values: Vec::new(),
                    }
                } else {
                    Column::Scalar(Vec::new())
                };
                el.props.push(Property {
                    name: name.to_string(),
                    list,
                    ty,
                    column,
                });
            }
            Some("comment") | Some("obj_info") | None => {}
            Some(other) => {
                return Err(ParseError::at_line(
                    line,
                    format!("unknown header keyword '{other}'"),
                ));
            }
        }
    }
    let encoding = encoding.ok_or_else(|| ParseError::new("the header has no 'format' line"))?;
    Ok((encoding, elements, body_start))
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn push_value(col: &mut Column, v: f64) {
    match col {
        Column::Scalar(vs) => vs.push(v),
        Column::List { values, .. } => values.push(v),
    }
}

fn end_list(col: &mut Column) {
    if let Column::List { starts, values } = col {
        starts.push(values.len());
    }
}

fn read_ascii(body: &[u8], elements: &mut [Element], header_lines: usize) -> ParseResult<()> {
    let text =
        std::str::from_utf8(body).map_err(|_| ParseError::new("ascii PLY body is not text"))?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    for el in elements.iter_mut() {
        for r in 0..el.count {
            let (i, l) = lines.next().ok_or_else(|| {
                ParseError::new(format!(
                    "truncated: element '{}' has {r} of {} records",
                    el.name, el.count
                ))
            })?;
            let line = header_lines + i + 1;
            let mut toks = l.split_whitespace();
            let mut next = |what: &str| -> ParseResult<f64> {
                let tok = toks.next().ok_or_else(|| {
                    ParseError::at_line(line, format!("missing value for {what}"))
                })?;
                tok.parse::<f64>().map_err(|_| {
                    ParseError::at_line(line, format!("{what}: '{tok}' is not a number"))
                })
            };
            for p in &mut el.props {
                if p.list.is_some() {
                    let n = next(&p.name)?;
                    if !(n >= 0.0 && n.fract() == 0.0 && n < 1e6) {
                        return Err(ParseError::at_line(
                            line,
                            format!("list length {n} of '{}' is invalid", p.name),
                        ));
                    }
                    for _ in 0..n as usize {
                        let v = next(&p.name)?;
                        push_value(&mut p.column, v);
                    }
                    end_list(&mut p.column);
                } else {
                    let v = next(&p.name)?;
                    push_value(&mut p.column, v);
                }
            }
            if toks.next().is_some() {
                return Err(ParseError::at_line(
                    line,
                    format!("more values than element '{}' has properties", el.name),
                ));
            }
        }
    }
    // Records beyond the header's counts would be dropped without a word.
    if let Some((i, _)) = lines.next() {
        return Err(ParseError::at_line(
            header_lines + i + 1,
            "more records than the header's element counts announce",
        ));
    }
    Ok(())
}

fn read_binary(body: &[u8], elements: &mut [Element], enc: Encoding) -> ParseResult<()> {
    let mut pos = 0usize;
    for el in elements.iter_mut() {
        // Refuse counts the remaining bytes cannot possibly hold before allocating.
        let min_record: usize = el
            .props
            .iter()
            .map(|p| p.list.map_or(p.ty.size(), |(c, _)| c.size()))
            .sum();
        if el.count.saturating_mul(min_record) > body.len() - pos {
            return Err(ParseError::new(format!(
                "truncated: element '{}' announces {} records but only {} bytes remain",
                el.name,
                el.count,
                body.len() - pos
            )));
        }
        if el.props.is_empty() {
            // Records without properties take no bytes (a count of 10^18 must not loop).
            continue;
        }
        for p in &mut el.props {
            if let Column::Scalar(v) = &mut p.column {
                v.reserve(el.count);
            }
        }
        for r in 0..el.count {
            for p in &mut el.props {
                let truncated = || {
                    ParseError::new(format!(
                        "truncated: element '{}' record {r} of {} is cut off",
                        el.name, el.count
                    ))
                };
                if let Some((count_ty, item_ty)) = p.list {
                    let n = read_num(body, &mut pos, count_ty, enc).ok_or_else(truncated)?;
                    if n.is_nan() || n < 0.0 {
                        return Err(ParseError::new(format!(
                            "negative list length in element '{}' record {r}",
                            el.name
                        )));
                    }
                    for _ in 0..n as usize {
                        let v = read_num(body, &mut pos, item_ty, enc).ok_or_else(truncated)?;
                        push_value(&mut p.column, v);
                    }
                    end_list(&mut p.column);
                } else {
                    let v = read_num(body, &mut pos, p.ty, enc).ok_or_else(truncated)?;
                    push_value(&mut p.column, v);
                }
            }
        }
    }
    // Bytes beyond the counted records (a final line break aside): counts lower than the data,
    // or an ASCII body under a binary header, read as garbage.
    let rest = &body[pos..];
    if !matches!(rest, b"" | b"\n" | b"\r\n") {
        let ascii = body
            .iter()
            .all(|b| b.is_ascii_graphic() || b.is_ascii_whitespace());
        return Err(ParseError::new(if ascii {
            "the header says binary but the body is ASCII text (format ascii 1.0?)".to_string()
        } else {
            format!(
                "{} bytes after the records the header's element counts announce",
                rest.len()
            )
        }));
    }
    Ok(())
}

fn read_num(b: &[u8], pos: &mut usize, ty: Ty, enc: Encoding) -> Option<f64> {
    let n = ty.size();
    let s = b.get(*pos..*pos + n)?;
    *pos += n;
    let mut buf = [0u8; 8];
    buf[..n].copy_from_slice(s);
    if enc == Encoding::Big {
        buf[..n].reverse();
    }
    Some(match ty {
        Ty::I8 => buf[0] as i8 as f64,
        Ty::U8 => buf[0] as f64,
        Ty::I16 => i16::from_le_bytes([buf[0], buf[1]]) as f64,
        Ty::U16 => u16::from_le_bytes([buf[0], buf[1]]) as f64,
        Ty::I32 => i32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
        Ty::U32 => u32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
        Ty::F32 => f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
        Ty::F64 => f64::from_le_bytes(buf),
    })
}

impl Ply {
    fn element(&self, name: &str) -> Option<&Element> {
        self.elements.iter().find(|e| e.name == name)
    }

    /// The scalar column `prop` of element `el` (the first of `names` that exists).
    fn scalar(&self, el: &str, names: &[&str]) -> Option<&[f64]> {
        let e = self.element(el)?;
        names.iter().find_map(|n| {
            e.props
                .iter()
                .find(|p| p.name == *n)
                .and_then(|p| match &p.column {
                    Column::Scalar(v) => Some(v.as_slice()),
                    Column::List { .. } => None,
                })
        })
    }

    fn require(&self, el: &str, names: &[&str]) -> ParseResult<&[f64]> {
        self.scalar(el, names).ok_or_else(|| {
            ParseError::new(format!(
                "element '{el}' has no scalar property {}",
                names.join(" / ")
            ))
        })
    }

    /// Vertex positions from `vertex` x, y, z.
    pub(crate) fn positions(&self) -> ParseResult<Vec<DVec3>> {
        let (x, y, z) = (
            self.require("vertex", &["x"])?,
            self.require("vertex", &["y"])?,
            self.require("vertex", &["z"])?,
        );
        Ok((0..x.len()).map(|i| DVec3::new(x[i], y[i], z[i])).collect())
    }

    /// Vertex normals from `vertex` nx, ny, nz.
    pub(crate) fn normals(&self) -> ParseResult<Vec<DVec3>> {
        let (x, y, z) = (
            self.require("vertex", &["nx"])?,
            self.require("vertex", &["ny"])?,
            self.require("vertex", &["nz"])?,
        );
        Ok((0..x.len()).map(|i| DVec3::new(x[i], y[i], z[i])).collect())
    }

    /// The per-vertex scalar named by the first of `names` that exists.
    pub(crate) fn vertex_scalar(&self, names: &[&str]) -> ParseResult<Vec<f64>> {
        Ok(self.require("vertex", names)?.to_vec())
    }

    /// Triangles (polygons fanned) from `face` vertex_indices / vertex_index.
    pub(crate) fn faces(&self) -> ParseResult<Vec<[u32; 3]>> {
        let Some(e) = self.element("face") else {
            return Ok(Vec::new());
        };
        let prop = e
            .props
            .iter()
            .find(|p| p.name == "vertex_indices" || p.name == "vertex_index")
            .ok_or_else(|| ParseError::new("element 'face' has no 'vertex_indices' list"))?;
        let Column::List { starts, values } = &prop.column else {
            return Err(ParseError::new(
                "face property 'vertex_indices' is not a list",
            ));
        };
        let mut faces = Vec::with_capacity(e.count);
        let mut corners = Vec::new();
        for r in 0..starts.len() - 1 {
            corners.clear();
            for &v in &values[starts[r]..starts[r + 1]] {
                if !(v >= 0.0 && v <= u32::MAX as f64 && v.fract() == 0.0) {
                    return Err(ParseError::new(format!(
                        "face {r} has an invalid vertex index {v}"
                    )));
                }
                corners.push(v as u32);
            }
            if corners.len() < 3 {
                return Err(ParseError::new(format!(
                    "face {r} has {} vertices, at least 3 needed",
                    corners.len()
                )));
            }
            for k in 1..corners.len() - 1 {
                faces.push([corners[0], corners[k], corners[k + 1]]);
            }
        }
        Ok(faces)
    }
}

pub(crate) fn parse_mesh(bytes: &[u8]) -> ParseResult<TriMesh> {
    let ply = parse(bytes)?;
    Ok(TriMesh {
        vertices: ply.positions()?,
        faces: ply.faces()?,
    })
}

fn write_header(
    w: &mut dyn Write,
    n_vertices: usize,
    vertex_props: &[&str],
    n_faces: Option<usize>,
) -> std::io::Result<()> {
    writeln!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment written by rfta"
    )?;
    writeln!(w, "element vertex {n_vertices}")?;
    for p in vertex_props {
        writeln!(w, "property double {p}")?;
    }
    if let Some(n) = n_faces {
        writeln!(
            w,
            "element face {n}\nproperty list uchar int vertex_indices"
        )?;
    }
    writeln!(w, "end_header")
}

pub(crate) fn write_mesh(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    write_header(w, mesh.n_vertices(), &["x", "y", "z"], Some(mesh.n_faces()))?;
    for v in &mesh.vertices {
        for c in v.to_array() {
            w.write_all(&c.to_le_bytes())?;
        }
    }
    for f in &mesh.faces {
        w.write_all(&[3u8])?;
        for i in f {
            w.write_all(&(*i as i32).to_le_bytes())?;
        }
    }
    Ok(())
}

pub(crate) fn write_points(
    w: &mut dyn Write,
    positions: &[DVec3],
    normals: &[DVec3],
) -> std::io::Result<()> {
    write_header(w, positions.len(), &["x", "y", "z", "nx", "ny", "nz"], None)?;
    for (p, n) in positions.iter().zip(normals) {
        for c in p.to_array().into_iter().chain(n.to_array()) {
            w.write_all(&c.to_le_bytes())?;
        }
    }
    Ok(())
}
