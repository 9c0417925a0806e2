//! Binary glTF 2.0 (GLB): one mesh, one primitive, float32 positions and uint32 indices.
//!
//! Layout per the glTF 2.0 specification: a 12-byte header, a JSON chunk padded with spaces and
//! a BIN chunk padded with zeros, each to a multiple of 4 bytes.

use rfta_geom::{
    TriMesh,
    glam::{DMat4, DQuat, DVec3},
};
use serde_json::json;

use crate::error::{ParseError, ParseResult};

const MAGIC: u32 = 0x4654_6C67; // "glTF"
const CHUNK_JSON: u32 = 0x4E4F_534A; // "JSON"
const CHUNK_BIN: u32 = 0x004E_4942; // "BIN\0"
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

pub(crate) fn to_bytes(mesh: &TriMesh) -> ParseResult<Vec<u8>> {
    if mesh.is_empty() {
        // An accessor needs count >= 1: an empty mesh is a scene without nodes, and no BIN chunk.
        let doc = json!({
            "asset": {"version": "2.0", "generator": "rfta"},
            "scene": 0,
            "scenes": [{"nodes": []}],
        });
        let mut json_bytes =
            serde_json::to_vec(&doc).map_err(|e| ParseError::new(format!("glTF JSON: {e}")))?;
        while json_bytes.len() % 4 != 0 {
            json_bytes.push(b' ');
        }
        let total = (12 + 8 + json_bytes.len()) as u32;
        let mut out = Vec::with_capacity(total as usize);
        for word in [MAGIC, 2, total, json_bytes.len() as u32, CHUNK_JSON] {
            out.extend_from_slice(&word.to_le_bytes());
        }
        out.extend_from_slice(&json_bytes);
        return Ok(out);
    }
    let mut bin = Vec::with_capacity(mesh.n_vertices() * 12 + mesh.n_faces() * 12);
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for v in &mesh.vertices {
        for (axis, c) in v.to_array().into_iter().enumerate() {
            let c = c as f32;
            lo[axis] = lo[axis].min(c);
            hi[axis] = hi[axis].max(c);
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let positions_len = bin.len();
    for f in &mesh.faces {
        for i in f {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let indices_len = bin.len() - positions_len;
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "rfta"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions_len, "target": ARRAY_BUFFER},
            {"buffer": 0, "byteOffset": positions_len, "byteLength": indices_len, "target": ELEMENT_ARRAY_BUFFER}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": FLOAT, "count": mesh.n_vertices(), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": UNSIGNED_INT, "count": mesh.n_faces() * 3, "type": "SCALAR"}
        ]
    });
    let mut json_bytes =
        serde_json::to_vec(&doc).map_err(|e| ParseError::new(format!("glTF JSON: {e}")))?;
    while json_bytes.len() % 4 != 0 {
        json_bytes.push(b' ');
    }
    let total = 12 + 8 + json_bytes.len() + 8 + bin.len();
    let total = u32::try_from(total)
        .map_err(|_| ParseError::new("mesh too large for a GLB file (over 4 GiB)"))?;
    let mut out = Vec::with_capacity(total as usize);
    for word in [MAGIC, 2, total, json_bytes.len() as u32, CHUNK_JSON] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&json_bytes);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
    out.extend_from_slice(&bin);
    Ok(out)
}

/// Reads every triangle primitive of every mesh instance in the default scene (node transforms
/// applied) into one mesh.
///
/// Our own reader, checking every index and byte range against the file: the `gltf` crate (1.4)
/// panics on some malformed files (an unchecked accessor index in its primitive validation hook),
/// which a mutation test found. Supported: GLB with its buffer in the BIN chunk, float32 VEC3
/// positions (with or without a byte stride), u8/u16/u32 indices or none, triangle mode.
pub(crate) fn parse(bytes: &[u8]) -> ParseResult<TriMesh> {
    let word = |at: usize| -> ParseResult<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| ParseError::new(format!("truncated GLB: no 4 bytes at offset {at}")))
    };
    if word(0)? != MAGIC {
        return Err(ParseError::new("not a GLB file: missing the 'glTF' magic"));
    }
    if word(4)? != 2 {
        return Err(ParseError::new(format!(
            "unsupported glTF version {}",
            word(4)?
        )));
    }
    let json_len = word(12)? as usize;
    if word(16)? != CHUNK_JSON {
        return Err(ParseError::new("the first GLB chunk is not JSON"));
    }
    let json = bytes.get(20..20 + json_len).ok_or_else(|| {
        ParseError::new(format!(
            "truncated GLB: the JSON chunk needs {json_len} bytes"
        ))
    })?;
    let bin_at = 20 + json_len;
    let bin: &[u8] = if bytes.len() >= bin_at + 8 && word(bin_at + 4)? == CHUNK_BIN {
        let n = word(bin_at)? as usize;
        bytes.get(bin_at + 8..bin_at + 8 + n).ok_or_else(|| {
            ParseError::new(format!("truncated GLB: the BIN chunk needs {n} bytes"))
        })?
    } else {
        &[]
    };
    let doc: serde_json::Value = serde_json::from_slice(json)
        .map_err(|e| ParseError::new(format!("invalid glTF JSON: {e}")))?;
    let gltf = Doc { doc: &doc, bin };
    let mut mesh = TriMesh::default();
    let scene = match doc.get("scene") {
        Some(v) => gltf.index(v, "scene")?,
        None => 0,
    };
    let roots = match doc.get("scenes").and_then(|s| s.get(scene)) {
        Some(sc) => gltf.indices(sc.get("nodes"), "scene nodes")?,
        // No scene: every node without a parent is a root.
        None => {
            let n = gltf.array("nodes").len();
            let children: Vec<usize> = gltf
                .array("nodes")
                .iter()
                .map(|node| gltf.indices(node.get("children"), "node children"))
                .collect::<ParseResult<Vec<_>>>()?
                .concat();
            (0..n).filter(|i| !children.contains(i)).collect()
        }
    };
    let mut stack: Vec<(usize, DMat4, usize)> =
        roots.into_iter().map(|n| (n, DMat4::IDENTITY, 0)).collect();
    while let Some((n, parent, depth)) = stack.pop() {
        if depth > 64 {
            return Err(ParseError::new(
                "the node hierarchy is deeper than 64 levels (a cycle?)",
            ));
        }
        let node = gltf.item("nodes", n)?;
        let world = parent * gltf.transform(node)?;
        for child in gltf.indices(node.get("children"), "node children")? {
            stack.push((child, world, depth + 1));
        }
        if let Some(m) = node.get("mesh") {
            let m = gltf.item("meshes", gltf.index(m, "node mesh")?)?;
            for prim in m
                .get("primitives")
                .and_then(|p| p.as_array())
                .map(Vec::as_slice)
                .unwrap_or(&[])
            {
                gltf.add_primitive(prim, world, &mut mesh)?;
            }
        }
    }
    Ok(mesh)
}

/// The parsed JSON and the BIN chunk, with bounds-checked lookups.
struct Doc<'a> {
    doc: &'a serde_json::Value,
    bin: &'a [u8],
}

impl Doc<'_> {
    fn array(&self, key: &str) -> &[serde_json::Value] {
        self.doc
            .get(key)
            .and_then(|v| v.as_array())
            .map(Vec::as_slice)
            .unwrap_or(&[])
    }

    fn item(&self, key: &str, i: usize) -> ParseResult<&serde_json::Value> {
        self.array(key).get(i).ok_or_else(|| {
            ParseError::new(format!(
                "{key}[{i}] does not exist ({} present)",
                self.array(key).len()
            ))
        })
    }

    fn index(&self, v: &serde_json::Value, what: &str) -> ParseResult<usize> {
        v.as_u64()
            .map(|i| i as usize)
            .ok_or_else(|| ParseError::new(format!("{what} is not an index: {v}")))
    }

    fn indices(&self, v: Option<&serde_json::Value>, what: &str) -> ParseResult<Vec<usize>> {
        match v {
            None => Ok(Vec::new()),
            Some(serde_json::Value::Array(a)) => a.iter().map(|x| self.index(x, what)).collect(),
            Some(other) => Err(ParseError::new(format!("{what} is not a list: {other}"))),
        }
    }

    fn number(&self, v: Option<&serde_json::Value>, default: f64) -> ParseResult<f64> {
        match v {
            None => Ok(default),
            Some(x) => x
                .as_f64()
                .ok_or_else(|| ParseError::new(format!("expected a number, found {x}"))),
        }
    }

    fn numbers<const N: usize>(&self, v: &serde_json::Value) -> ParseResult<[f64; N]> {
        let a = v
            .as_array()
            .filter(|a| a.len() == N)
            .ok_or_else(|| ParseError::new(format!("expected {N} numbers, found {v}")))?;
        let mut out = [0.0; N];
        for (o, x) in out.iter_mut().zip(a) {
            *o = x
                .as_f64()
                .ok_or_else(|| ParseError::new(format!("expected a number, found {x}")))?;
        }
        Ok(out)
    }

    /// A node's local transform: `matrix` (column-major) or translation * rotation * scale.
    fn transform(&self, node: &serde_json::Value) -> ParseResult<DMat4> {
        if let Some(m) = node.get("matrix") {
            return Ok(DMat4::from_cols_array(&self.numbers::<16>(m)?));
        }
        let t = node
            .get("translation")
            .map(|v| self.numbers::<3>(v))
            .transpose()?
            .unwrap_or([0.0; 3]);
        let r = node
            .get("rotation")
            .map(|v| self.numbers::<4>(v))
            .transpose()?
            .unwrap_or([0.0, 0.0, 0.0, 1.0]);
        let s = node
            .get("scale")
            .map(|v| self.numbers::<3>(v))
            .transpose()?
            .unwrap_or([1.0; 3]);
        let q = DQuat::from_array(r);
        if !(q.length() > 0.0 && q.is_finite()) {
            return Err(ParseError::new("a node rotation is not a valid quaternion"));
        }
        Ok(DMat4::from_scale_rotation_translation(
            DVec3::from_array(s),
            q.normalize(),
            DVec3::from_array(t),
        ))
    }

    /// The bytes of accessor `i` as (data, count, stride, element size, component type, type).
    fn accessor(&self, i: usize) -> ParseResult<(&[u8], usize, usize, u64, String)> {
        let acc = self.item("accessors", i)?;
        if acc.get("sparse").is_some() {
            return Err(ParseError::new(format!(
                "accessors[{i}] is sparse, which is not supported"
            )));
        }
        let count = self.number(acc.get("count"), -1.0)?;
        let component = self.number(acc.get("componentType"), -1.0)? as u64;
        let ty = acc
            .get("type")
            .and_then(|t| t.as_str())
            .unwrap_or("")
            .to_string();
        let comp_size = match component {
            5121 => 1,
            5123 => 2,
            5125 | 5126 => 4,
            other => {
                return Err(ParseError::new(format!(
                    "accessors[{i}] has unsupported component type {other}"
                )));
            }
        };
        let n_comp = match ty.as_str() {
            "SCALAR" => 1,
            "VEC3" => 3,
            other => {
                return Err(ParseError::new(format!(
                    "accessors[{i}] has unsupported type '{other}'"
                )));
            }
        };
        if !(count >= 0.0 && count.fract() == 0.0 && count <= u32::MAX as f64) {
            return Err(ParseError::new(format!(
                "accessors[{i}] has an invalid count"
            )));
        }
        let count = count as usize;
        let elem = comp_size * n_comp;
        let view_index = acc
            .get("bufferView")
            .ok_or_else(|| ParseError::new(format!("accessors[{i}] has no bufferView")))?;
        let view = self.item(
            "bufferViews",
            self.index(view_index, "accessor bufferView")?,
        )?;
        if self.number(view.get("buffer"), 0.0)? != 0.0 {
            return Err(ParseError::new(
                "only the GLB's own buffer (buffer 0) is supported",
            ));
        }
        let view_start = self.number(view.get("byteOffset"), 0.0)? as usize;
        let view_len = self.number(view.get("byteLength"), -1.0)?;
        let stride = self.number(view.get("byteStride"), elem as f64)? as usize;
        if view_len < 0.0 || stride < elem {
            return Err(ParseError::new(format!(
                "accessors[{i}]: its bufferView has an invalid length or stride"
            )));
        }
        let view_data = self
            .bin
            .get(view_start..view_start.saturating_add(view_len as usize))
            .ok_or_else(|| {
                ParseError::new(format!(
                    "accessors[{i}]: its bufferView lies outside the BIN chunk"
                ))
            })?;
        let offset = self.number(acc.get("byteOffset"), 0.0)? as usize;
        let needed = if count == 0 {
            0
        } else {
            offset
                .saturating_add(stride.saturating_mul(count - 1))
                .saturating_add(elem)
        };
        let data = view_data.get(offset..needed.max(offset)).ok_or_else(|| {
            ParseError::new(format!(
                "accessors[{i}] reads past the end of its bufferView"
            ))
        })?;
        Ok((data, count, stride, component, ty))
    }

    fn add_primitive(
        &self,
        prim: &serde_json::Value,
        world: DMat4,
        mesh: &mut TriMesh,
    ) -> ParseResult<()> {
        let mode = self.number(prim.get("mode"), 4.0)?;
        if mode != 4.0 {
            return Err(ParseError::new(format!(
                "primitive mode {mode} is not supported (triangles only)"
            )));
        }
        let pos = prim
            .get("attributes")
            .and_then(|a| a.get("POSITION"))
            .ok_or_else(|| ParseError::new("a primitive has no POSITION attribute"))?;
        let (data, count, stride, component, ty) = self.accessor(self.index(pos, "POSITION")?)?;
        if component != FLOAT as u64 || ty != "VEC3" {
            return Err(ParseError::new("POSITION must be float32 VEC3"));
        }
        let base = mesh.vertices.len();
        for v in 0..count {
            let at = v * stride;
            let f = |k: usize| {
                f32::from_le_bytes([
                    data[at + k],
                    data[at + k + 1],
                    data[at + k + 2],
                    data[at + k + 3],
                ]) as f64
            };
            mesh.vertices
                .push(world.transform_point3(DVec3::new(f(0), f(4), f(8))));
        }
        let indices: Vec<u32> = match prim.get("indices") {
            None => (0..count as u32).collect(),
            Some(ix) => {
                let (data, n, stride, component, ty) = self.accessor(self.index(ix, "indices")?)?;
                if ty != "SCALAR" {
                    return Err(ParseError::new("indices must be SCALAR"));
                }
                (0..n)
                    .map(|k| {
                        let at = k * stride;
                        match component {
                            5121 => data[at] as u32,
                            5123 => u16::from_le_bytes([data[at], data[at + 1]]) as u32,
                            _ => u32::from_le_bytes([
                                data[at],
                                data[at + 1],
                                data[at + 2],
                                data[at + 3],
                            ]),
                        }
                    })
                    .collect()
            }
        };
        if !indices.len().is_multiple_of(3) {
            return Err(ParseError::new(format!(
                "{} indices do not form whole triangles",
                indices.len()
            )));
        }
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= count) {
            return Err(ParseError::new(format!(
                "index {bad} is past the primitive's {count} vertices"
            )));
        }
        let base = u32::try_from(base).map_err(|_| ParseError::new("too many vertices"))?;
        mesh.faces.extend(
            indices
                .chunks_exact(3)
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
        Ok(())
    }
}
