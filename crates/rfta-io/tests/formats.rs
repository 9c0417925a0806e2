//! Round trips, malformed files and truncations for every reader.

use std::path::{Path, PathBuf};

use rfta_geom::{Grid, Layout, glam::DVec3, shapes};
use rfta_io::{Error, GridBounds, read_mesh, read_sdf, write_mesh, write_sdf_grid};

struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Self {
        let p = std::env::temp_dir().join(format!("rfta-io-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).expect("temp dir");
        Self(p)
    }
    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
    fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let p = self.path(name);
        std::fs::write(&p, bytes).expect("write");
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn err_text(r: Result<impl std::fmt::Debug, Error>) -> String {
    match r {
        Ok(v) => panic!("expected an error, got {v:?}"),
        Err(e) => e.to_string(),
    }
}

fn assert_meshes_close(a: &rfta_geom::TriMesh, b: &rfta_geom::TriMesh, tol: f64) {
    assert_eq!(a.faces, b.faces);
    assert_eq!(a.n_vertices(), b.n_vertices());
    for (p, q) in a.vertices.iter().zip(&b.vertices) {
        assert!(p.distance(*q) <= tol, "{p} vs {q}");
    }
}

#[test]
fn mesh_round_trips() {
    let dir = TempDir::new("roundtrip");
    let mesh = shapes::torus(0.6, 0.25, 12, 8);
    for (name, tol) in [
        ("m.obj", 0.0),
        ("m.ply", 0.0),
        ("m.glb", 1e-7),
        ("m.stl", 1e-7),
    ] {
        let path = dir.path(name);
        write_mesh(&path, &mesh).expect("write");
        let back = read_mesh(&path).expect("read");
        if name.ends_with("stl") {
            // STL stores soup; welding restores the vertex count but renumbers vertices.
            assert_eq!(
                (back.n_vertices(), back.n_faces()),
                (mesh.n_vertices(), mesh.n_faces())
            );
            assert!((back.area() - mesh.area()).abs() < 1e-6);
        } else {
            assert_meshes_close(&mesh, &back, tol);
        }
        // No temporary file is left behind.
        let leftovers: Vec<_> = std::fs::read_dir(&dir.0)
            .expect("list")
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
    }
}

#[test]
fn text_and_ascii_variants_parse() {
    let dir = TempDir::new("variants");
    // OBJ with normals/texture references, negative indices, comments and a quad.
    let obj = "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1/1/1 2//1 -2 -1\n";
    let m = read_mesh(&dir.write("q.obj", obj.as_bytes())).expect("obj");
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
    // OFF with counts on the header line and a colour after the face.
    let off = "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 255 0 0\n";
    assert_eq!(
        read_mesh(&dir.write("t.off", off.as_bytes()))
            .expect("off")
            .faces,
        vec![[0, 1, 2]]
    );
    // ASCII PLY with extra properties and a uint index list.
    let ply = "ply\nformat ascii 1.0\ncomment hi\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n0 0 0 1\n1 0 0 2\n0 1 0 3\n3 0 1 2\n";
    let m = read_mesh(&dir.write("t.ply", ply.as_bytes())).expect("ply");
    assert_eq!(
        (m.vertices[1], m.faces.clone()),
        (DVec3::X, vec![[0, 1, 2]])
    );
    // Big-endian binary PLY.
    let mut be = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    for v in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]] {
        for c in v {
            be.extend_from_slice(&f64::to_be_bytes(c));
        }
    }
    be.push(3);
    for i in [0i32, 1, 2] {
        be.extend_from_slice(&i.to_be_bytes());
    }
    let m = read_mesh(&dir.write("be.ply", &be)).expect("be ply");
    assert_eq!(m.vertices[2], DVec3::new(0.0, 2.0, 0.0));
    // ASCII STL: two facets sharing an edge are welded into 4 vertices.
    let stl = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid s\n";
    let m = read_mesh(&dir.write("a.stl", stl.as_bytes())).expect("stl");
    assert_eq!((m.n_vertices(), m.n_faces()), (4, 2));
}

#[test]
fn malformed_meshes_get_clear_errors() {
    let dir = TempDir::new("malformed");
    let cases: Vec<(&str, &[u8], &str)> = vec![
        ("a.obj", b"v 0 0 0\nv 1 0\n", "line 2: a vertex needs 3 coordinates"),
        ("b.obj", b"v 0 0 0\nv 1 0 x\n", "line 2: z: 'x' is not a number"),
        ("c.obj", b"v 0 0 0\nf 1 2\n", "line 2: a face needs at least 3 vertices"),
        ("d.obj", b"v 0 0 0\nf 1 2 3\n", "face 0 refers to vertex 1"),
        ("e.obj", b"v 0 0 0\nf 0 1 1\n", "index 0 is out of range"),
        ("f.obj", b"\xff\xfe\x00", "not a text file"),
        ("g.off", b"PLY\n", "expected an 'OFF' header"),
        ("h.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n", "truncated: 2 of 3 vertices"),
        ("i.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "fewer than 4 vertices"),
        ("j.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "no 'end_header'"),
        ("k.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0", "announces 1000 records but only 4 bytes remain"),
        ("l.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n", "no scalar property y"),
        ("m.ply", b"ply\nformat foo 1.0\nend_header\n", "unknown format"),
        ("n.ply", b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n", "truncated: element 'vertex' has 1 of 2 records"),
        ("o.stl", &[0u8; 100], "announces 0 triangles"),
        ("p.stl", b"solid x\nfacet\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n", "not closed"),
        ("q.glb", b"glTF\x02\0\0\0garbage", "truncated GLB"),
        ("r.xyz", b"0 0 0", "unsupported file type"),
    ];
    for (name, bytes, needle) in cases {
        let msg = err_text(read_mesh(&dir.write(name, bytes)));
        assert!(
            msg.contains(needle),
            "{name}: '{msg}' should contain '{needle}'"
        );
        assert!(msg.contains(name), "{name}: '{msg}' should name the file");
    }
    assert!(err_text(read_mesh(&dir.path("missing.obj"))).contains("missing.obj"));
}

/// Every prefix of a valid file is read without a panic: an error, or (for text formats cut at a
/// line boundary) a smaller mesh that is still valid.
fn every_prefix_is_safe(
    dir: &TempDir,
    name: &str,
    bytes: &[u8],
    read: impl Fn(&Path) -> Result<(), Error>,
) -> usize {
    let mut n_errors = 0;
    let step = (bytes.len() / 300).max(1);
    for len in (0..bytes.len()).step_by(step) {
        let p = dir.write(name, &bytes[..len]);
        if read(&p).is_err() {
            n_errors += 1;
        }
    }
    n_errors
}

/// One valid file of every readable format, with whether it is a binary format whose counts make
/// every strict prefix invalid.
fn valid_files(dir: &TempDir) -> Vec<(String, Vec<u8>, bool)> {
    let mesh = shapes::icosphere(1.0, 1);
    let grid = Grid::cube(4, -1.0, 1.0).expect("grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| grid.position(i).length() - 0.5)
        .collect();
    let mut files = Vec::new();
    for (name, binary) in [
        ("m.obj", false),
        ("m.ply", true),
        ("m.stl", true),
        ("m.glb", true),
    ] {
        let p = dir.path(&format!("orig-{name}"));
        write_mesh(&p, &mesh).expect("write");
        files.push((name.to_string(), std::fs::read(&p).expect("read"), binary));
    }
    for name in ["g.npy", "g.exr"] {
        let p = dir.path(&format!("orig-{name}"));
        write_sdf_grid(&p, &grid, &values).expect("write");
        files.push((name.to_string(), std::fs::read(&p).expect("read"), true));
    }
    // OFF is read-only: the text by hand.
    let mut off = format!("OFF\n{} {} 0\n", mesh.n_vertices(), mesh.n_faces());
    mesh.vertices
        .iter()
        .for_each(|v| off += &format!("{} {} {}\n", v.x, v.y, v.z));
    mesh.faces
        .iter()
        .for_each(|f| off += &format!("3 {} {} {}\n", f[0], f[1], f[2]));
    files.push(("m.off".into(), off.into_bytes(), false));
    files.push((
        "s.csv".into(),
        b"x,y,z,s\n0,0,0,-1\n1,1,1,2\n0.5,0.25,0,0.1\n".to_vec(),
        false,
    ));
    files
}

/// Reads `path` with the reader its extension selects, validating SDF samples too.
fn read_any(path: &Path) -> Result<(), Error> {
    let name = path.to_string_lossy();
    if name.ends_with("npy") || name.ends_with("exr") || name.ends_with("csv") {
        read_sdf(path, None)?.validate(path).map(|_| ())
    } else {
        read_mesh(path).map(|_| ())
    }
}

#[test]
fn truncated_files_never_panic() {
    let dir = TempDir::new("truncated");
    for (name, bytes, binary) in valid_files(&dir) {
        let n_err = every_prefix_is_safe(&dir, &name, &bytes, read_any);
        // Binary formats carry counts and sizes: every strict prefix is an error.
        if binary {
            assert_eq!(
                n_err,
                bytes.len().div_ceil((bytes.len() / 300).max(1)),
                "{name}"
            );
        }
    }
}

#[test]
fn sdf_grids_round_trip_with_bounds() {
    let dir = TempDir::new("grids");
    let grid = Grid::from_bounds(
        [3, 4, 5],
        DVec3::new(-1.0, -2.0, 0.0),
        DVec3::new(1.0, 1.0, 2.0),
    )
    .expect("grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| grid.position(i).length() - 1.0)
        .collect();
    let npy = dir.path("g.npy");
    write_sdf_grid(&npy, &grid, &values).expect("npy");
    let raw = read_sdf(&npy, None).expect("read");
    assert_eq!(
        (raw.layout.clone(), raw.values.clone(), raw.bounds_source),
        (Layout::Grid(grid), values.clone(), "sidecar")
    );
    // The command line beats the sidecar.
    let cli = GridBounds {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    };
    let raw = read_sdf(&npy, Some(cli)).expect("read");
    assert_eq!(raw.bounds_source, "command line");
    // Without a sidecar: [-1, 1]^3.
    std::fs::remove_file(rfta_io::sidecar_path(&npy)).expect("rm");
    let raw = read_sdf(&npy, None).expect("read");
    let default = Grid::from_bounds([3, 4, 5], DVec3::splat(-1.0), DVec3::ONE).expect("grid");
    assert_eq!(raw.layout, Layout::Grid(default));
    // EXR stores float32 values and double bounds.
    let exr = dir.path("g.exr");
    write_sdf_grid(&exr, &grid, &values).expect("exr");
    let raw = read_sdf(&exr, None).expect("read");
    assert_eq!(
        (raw.layout, raw.bounds_source),
        (Layout::Grid(grid), "file")
    );
    for (a, b) in raw.values.iter().zip(&values) {
        assert!((a - b).abs() <= 1e-7 * b.abs().max(1.0));
    }
}

#[test]
fn sidecars_and_scattered_samples() {
    let dir = TempDir::new("scattered");
    let grid = Grid::cube(2, -1.0, 1.0).expect("grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| grid.position(i).length() - 1.0)
        .collect();
    let npy = dir.path("s.npy");
    write_sdf_grid(&npy, &grid, &values).expect("npy");
    let side = rfta_io::sidecar_path(&npy);
    std::fs::write(
        &side,
        r#"{"origin": [0, 0, 0], "spacing": [0.5, 0.5, 0.5]}"#,
    )
    .expect("w");
    let raw = read_sdf(&npy, None).expect("origin/spacing sidecar");
    assert_eq!(
        raw.layout,
        Layout::Grid(Grid::new([3; 3], DVec3::ZERO, DVec3::splat(0.5)).expect("g"))
    );
    for (text, needle) in [
        (
            r#"{"min": [1, 1, 1], "max": [0, 0, 0]}"#,
            "inverted or of zero size",
        ),
        (
            r#"{"min": [0, 0, 0], "max": [0, 1, 1]}"#,
            "inverted or of zero size",
        ),
        (r#"{"min": [0, 0, 0]}"#, "either \"min\" and \"max\""),
        (r#"{"bounds": 1}"#, "unknown field"),
        (r#"{"min": [0, 0"#, "invalid sidecar"),
    ] {
        std::fs::write(&side, text).expect("w");
        let msg = err_text(read_sdf(&npy, None));
        assert!(
            msg.contains(needle) && msg.contains("s.json"),
            "'{msg}' should contain '{needle}'"
        );
    }
    // CSV with a header, XYZ with whitespace, PLY with an `sdf` property.
    let csv = dir.write("p.csv", b"x,y,z,sdf\n0,0,0,-0.5\n1,0,0,0.5\n");
    let raw = read_sdf(&csv, None).expect("csv");
    assert_eq!(raw.values, vec![-0.5, 0.5]);
    assert!(raw.validate(&csv).is_ok());
    let bad = dir.write("q.xyz", b"0 0 0 -1\n1 0 0\n");
    assert!(
        err_text(read_sdf(&bad, None)).contains("line 2: expected 4 values (x y z s), found 3")
    );
    let ply = dir.write(
        "p.ply",
        b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty float sdf\nend_header\n0 0 0 -1\n1 1 1 nan\n",
    );
    let raw = read_sdf(&ply, None).expect("ply parses");
    assert!(err_text(raw.validate(&ply)).contains("SDF value at sample 1 is not finite"));
    // A 2-D array is neither a grid nor rows.
    let mut two_d = Vec::new();
    rfta_io::write_npy_f64(&mut two_d, &[2, 3], &[0.0; 6]).expect("w");
    assert!(err_text(read_sdf(&dir.write("t.npy", &two_d), None)).contains("found shape [2, 3]"));
}

#[test]
fn oriented_points_round_trip() {
    let dir = TempDir::new("points");
    let pts = rfta_geom::OrientedPoints::new(
        vec![DVec3::ZERO, DVec3::ONE],
        vec![DVec3::X, DVec3::new(0.0, 2.0, 0.0)],
        None,
    )
    .expect("valid");
    let p = dir.path("p.ply");
    rfta_io::write_oriented_points_ply(&p, &pts).expect("write");
    assert_eq!(rfta_io::read_oriented_points(&p).expect("read"), pts);
    let xyz = dir.write("p.xyz", b"0 0 0 1 0 0\n1 1 1 0 0 0\n");
    assert!(err_text(rfta_io::read_oriented_points(&xyz)).contains("normal 1 has zero"));
}

/// Seeded random corruptions of valid files (byte flips, insertions, deletions, overwritten
/// counts) must give an error or a valid result, never a panic: a cheap stand-in for fuzzing that
/// runs in every test run.
#[test]
fn mutated_files_never_panic() {
    use rfta_geom::rng::Rng;
    let dir = TempDir::new("mutated");
    let originals = valid_files(&dir);
    let mut rng = Rng::new(2026);
    for (name, bytes, _) in &originals {
        for _ in 0..300 {
            let mut b = bytes.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(b.len().max(1) as u64) as usize;
                match rng.below(4) {
                    0 if !b.is_empty() => {
                        let i = at.min(b.len() - 1);
                        b[i] ^= 1 << rng.below(8);
                    }
                    1 => b.insert(at.min(b.len()), rng.below(256) as u8),
                    2 if !b.is_empty() => {
                        b.remove(at.min(b.len() - 1));
                    }
                    _ => {
                        // Overwrite four bytes with an extreme count (0xFF.. or a large ASCII number).
                        let junk: &[u8] = if rng.below(2) == 0 {
                            &[0xFF; 4]
                        } else {
                            b"9999"
                        };
                        for (k, j) in junk.iter().enumerate() {
                            if let Some(x) = b.get_mut(at + k) {
                                *x = *j;
                            }
                        }
                    }
                }
            }
            let _ = read_any(&dir.write(name, &b));
        }
    }
}

/// Our GLB writer's output is valid for an independent implementation (the `gltf` crate, which
/// validates the document on load) and carries the same mesh.
#[test]
fn written_glb_is_valid_gltf() {
    let dir = TempDir::new("glb-valid");
    let mesh = shapes::torus(0.6, 0.25, 10, 6);
    let path = dir.path("t.glb");
    write_mesh(&path, &mesh).expect("write");
    let bytes = std::fs::read(&path).expect("read");
    let g = gltf::Gltf::from_slice(&bytes).expect("valid glTF");
    let prim = g
        .meshes()
        .next()
        .and_then(|m| m.primitives().next())
        .expect("one primitive");
    let reader = prim.reader(|_| g.blob.as_deref());
    let positions: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
    let indices: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
    assert_eq!(positions.len(), mesh.n_vertices());
    assert_eq!(
        indices,
        mesh.faces.iter().flatten().copied().collect::<Vec<_>>()
    );
    for (p, v) in positions.iter().zip(&mesh.vertices) {
        assert_eq!(*p, v.as_vec3().to_array());
    }
}

/// Regression: a GLB whose primitive names a missing accessor made the `gltf` crate panic (found
/// by `mutated_files_never_panic`); our reader reports it.
#[test]
fn glb_with_a_missing_accessor_is_an_error() {
    let dir = TempDir::new("glb-missing");
    let path = dir.path("m.glb");
    write_mesh(&path, &shapes::octahedron(1.0)).expect("write");
    let bytes = std::fs::read(&path).expect("read");
    let text = String::from_utf8_lossy(&bytes).into_owned();
    assert!(
        text.contains("\"POSITION\":0"),
        "the writer's JSON names accessor 0 for POSITION"
    );
    // Same length, so the chunk sizes stay right: accessor 0 becomes accessor 7.
    let bad = bytes
        .windows(12)
        .position(|w| w == b"\"POSITION\":0")
        .expect("found");
    let mut corrupted = bytes.clone();
    corrupted[bad + 11] = b'7';
    let msg = err_text(read_mesh(&dir.write("bad.glb", &corrupted)));
    assert!(msg.contains("accessors[7] does not exist"), "{msg}");
}

/// A GLB from a JSON document and a BIN chunk, assembled per the glTF 2.0 container layout.
fn assemble_glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = (12 + 8 + j.len() + 8 + b.len()) as u32;
    let mut out = Vec::new();
    for w in [0x4654_6C67u32, 2, total, j.len() as u32, 0x4E4F_534A] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&b);
    out
}

#[test]
fn glb_node_transforms_are_applied() {
    let dir = TempDir::new("glb-trs");
    // One triangle (0,0,0) (1,0,0) (0,1,0), no index accessor; a parent node translates by (0,0,5)
    // and its child rotates 90 degrees about z (quaternion (0,0,sin 45,cos 45)) and scales by 2.
    let mut bin = Vec::new();
    for c in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"translation":[0,0,5],"children":[1]}},{{"mesh":0,"rotation":[0,0,{h},{h}],"scale":[2,2,2]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "buffers":[{{"byteLength":36}}],"bufferViews":[{{"buffer":0,"byteLength":36}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}}]}}"#
    );
    let mesh = read_mesh(&dir.write("t.glb", &assemble_glb(&json, &bin))).expect("valid GLB");
    assert_eq!(mesh.faces, vec![[0, 1, 2]]);
    // x -> y and y -> -x under the rotation, times 2, then up by 5.
    let expected = [
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::new(0.0, 2.0, 5.0),
        DVec3::new(-2.0, 0.0, 5.0),
    ];
    for (v, e) in mesh.vertices.iter().zip(expected) {
        assert!(v.distance(e) < 1e-12, "{v} vs {e}");
    }
    // A node cycle is an error, not a hang.
    let cyclic = json.replace(
        r#""children":[1]},{"mesh":0"#,
        r#""children":[1]},{"children":[0],"mesh":0"#,
    );
    assert_ne!(cyclic, json);
    assert!(
        err_text(read_mesh(&dir.write("c.glb", &assemble_glb(&cyclic, &bin)))).contains("cycle")
    );
}

#[test]
fn grid_headers_give_the_sample_count_without_the_data() {
    let dir = TempDir::new("peek");
    let grid = Grid::new([5, 6, 7], DVec3::ZERO, DVec3::splat(0.1)).expect("grid");
    let values: Vec<f64> = (0..grid.len()).map(|i| i as f64 - 100.0).collect();
    for name in ["g.npy", "g.exr"] {
        let p = dir.path(name);
        write_sdf_grid(&p, &grid, &values).expect("written");
        assert_eq!(
            rfta_io::peek_sdf_len(&p, None).expect(name),
            Some(210),
            "{name}"
        );
    }
    // (n, 4) rows count rows; text formats have no header to read.
    let rows = dir.path("rows.npy");
    let mut f = Vec::new();
    rfta_io::write_npy_f64(&mut f, &[3, 4], &[0.0; 12]).expect("npy");
    std::fs::write(&rows, f).expect("write");
    assert_eq!(rfta_io::peek_sdf_len(&rows, None).expect("rows"), Some(3));
    let csv = dir.write("s.csv", b"0,0,0,-1\n1,0,0,1\n");
    assert_eq!(rfta_io::peek_sdf_len(&csv, None).expect("csv"), None);
    let bad = dir.write("bad.exr", b"not an exr");
    assert!(err_text(rfta_io::peek_sdf_len(&bad, None)).contains("invalid OpenEXR header"));
}
