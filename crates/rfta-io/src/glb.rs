//! Binary glTF 2.0 (GLB): one mesh, one primitive, float32 positions and uint32 indices.
//!
//! Layout per the glTF 2.0 specification: a 12-byte header, a JSON chunk padded with spaces and
//! a BIN chunk padded with zeros, each to a multiple of 4 bytes.

use rfta_geom::TriMesh;
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
        return Err(ParseError::new(
            "cannot write an empty mesh as glTF (an accessor needs count >= 1)",
        ));
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
pub(crate) fn parse(bytes: &[u8]) -> ParseResult<TriMesh> {
    let g =
        gltf::Gltf::from_slice(bytes).map_err(|e| ParseError::new(format!("invalid glTF: {e}")))?;
    let blob = g.blob.as_deref();
    let mut mesh = TriMesh::default();
    let scene = g.default_scene().or_else(|| g.scenes().next());
    let mut stack: Vec<(gltf::Node, rfta_geom::glam::DMat4)> = match &scene {
        Some(s) => s
            .nodes()
            .map(|n| (n, rfta_geom::glam::DMat4::IDENTITY))
            .collect(),
        None => Vec::new(),
    };
    while let Some((node, parent)) = stack.pop() {
        let local =
            rfta_geom::glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        for child in node.children() {
            stack.push((child, world));
        }
        let Some(m) = node.mesh() else { continue };
        for prim in m.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                return Err(ParseError::new(format!(
                    "primitive mode {:?} is not supported (triangles only)",
                    prim.mode()
                )));
            }
            let reader = prim.reader(|buffer| match buffer.source() {
                gltf::buffer::Source::Bin => blob,
                gltf::buffer::Source::Uri(_) => None,
            });
            let positions = reader.read_positions().ok_or_else(|| {
                ParseError::new(
                    "a primitive has no readable POSITION (external buffers are not supported)",
                )
            })?;
            let base = mesh.vertices.len() as u32;
            mesh.vertices.extend(
                positions.map(|p| {
                    world.transform_point3(rfta_geom::glam::Vec3::from_array(p).as_dvec3())
                }),
            );
            let n = mesh.vertices.len() as u32 - base;
            let indices: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..n).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(ParseError::new(format!(
                    "{} indices do not form whole triangles",
                    indices.len()
                )));
            }
            mesh.faces.extend(
                indices
                    .chunks_exact(3)
                    .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
            );
        }
    }
    Ok(mesh)
}
