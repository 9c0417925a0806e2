//! Self-contained HTML views of meshes and what is known about them: one file that opens
//! without a network, with an interactive 3D view (orbit, zoom, pan; a wireframe toggle; each
//! layer shown or hidden) drawn by three.js, embedded in the file, and a table of figures.
//!
//! A [`Scene`] holds meshes (each face in a class with its own colour: the main surface, a
//! cavity, an island), marked points (samples on the wrong side, spheres entered), curves
//! (loops around thin handles) and figures; [`html`] writes it. [`reconstruction`] makes the
//! scene of a reconstructed mesh from what its samples found ([`Found`]).
//!
//! # Example
//! ```
//! use rfta_geom::{glam::DVec3, shapes};
//! use rfta_view::{Layer, Marks, Scene, html};
//!
//! let ball = shapes::icosphere(1.0, 2);
//! let scene = Scene {
//!     title: "a ball".into(),
//!     layers: vec![Layer::plain("rfta", ball)],
//!     marks: vec![Marks {
//!         name: "samples on the wrong side".into(),
//!         color: [220, 40, 40],
//!         points: vec![DVec3::new(0.0, 0.0, 1.2)],
//!     }],
//!     curves: Vec::new(),
//!     figures: vec![("components".into(), "1".into())],
//! };
//! let page = html(&scene);
//! assert!(page.starts_with("<!DOCTYPE html>") && page.contains("a ball"));
//! // Everything it needs is in the file: no script or style is fetched.
//! assert!(!page.contains("src=\"http") && !page.contains("href=\"http"));
//! ```

mod report;

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;

pub use report::{Found, face_classes, reconstruction};
#[cfg(feature = "samples")]
pub use report::{figures, report_figures};

const THREE: &str = include_str!("../vendor/three/three.module.min.js");
const ORBIT: &str = include_str!("../vendor/three/OrbitControls.js");
const VIEWER: &str = include_str!("viewer.js");

/// The classes a face can be in, with their colours (sRGB) and names.
pub(crate) const CLASSES: [(&str, [u8; 3]); 3] = [
    ("surface", [150, 170, 200]),
    ("cavity (faces inward)", [240, 150, 40]),
    ("island (another component)", [170, 110, 200]),
];

/// A mesh to show, each face in one of `CLASSES`.
#[derive(Debug, Clone)]
pub struct Layer {
    /// Its name in the layer list.
    pub name: String,
    /// The mesh.
    pub mesh: TriMesh,
    /// Per face, its index into `CLASSES` (empty: all the first).
    pub face_class: Vec<u8>,
    /// Shown when the page opens.
    pub visible: bool,
}

impl Layer {
    /// A mesh shown, every face of the first class.
    pub fn plain(name: &str, mesh: TriMesh) -> Self {
        Self {
            name: name.into(),
            mesh,
            face_class: Vec::new(),
            visible: true,
        }
    }
}

/// Points marked in one colour.
#[derive(Debug, Clone)]
pub struct Marks {
    /// What they are.
    pub name: String,
    /// sRGB.
    pub color: [u8; 3],
    /// Where.
    pub points: Vec<DVec3>,
}

/// Closed polylines drawn in one colour.
#[derive(Debug, Clone)]
pub struct Curves {
    /// What they are.
    pub name: String,
    /// sRGB.
    pub color: [u8; 3],
    /// Each loop's points, the last joined to the first.
    pub loops: Vec<Vec<DVec3>>,
}

/// Everything one page shows.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// The page's title and heading.
    pub title: String,
    /// The meshes, in the layer list's order.
    pub layers: Vec<Layer>,
    /// Marked points.
    pub marks: Vec<Marks>,
    /// Curves on the surface.
    pub curves: Vec<Curves>,
    /// Name and value of each figure in the table.
    pub figures: Vec<(String, String)>,
}

/// The page: one HTML file holding the scene, three.js and the viewer.
pub fn html(scene: &Scene) -> String {
    let data = scene_json(scene);
    let rows: String = scene
        .figures
        .iter()
        .map(|(k, v)| format!("<tr><th>{}</th><td>{}</td></tr>", escape(k), escape(v)))
        .collect();
    let module = |code: &str| format!("data:text/javascript;base64,{}", base64(code.as_bytes()));
    format!(
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ margin: 0; font: 14px system-ui, sans-serif; display: flex; height: 100vh; }}
#view {{ flex: 1; min-width: 0; position: relative; background: #fff; }}
#side {{ width: 320px; overflow: auto; padding: 12px; border-left: 1px solid #ddd; }}
h1 {{ font-size: 16px; margin: 0 0 8px; }}
table {{ border-collapse: collapse; width: 100%; }}
th, td {{ text-align: left; padding: 2px 4px; border-bottom: 1px solid #eee; }}
td {{ font-variant-numeric: tabular-nums; }}
label {{ display: block; margin: 2px 0; }}
.swatch {{ display: inline-block; width: 12px; height: 12px; margin-right: 4px; vertical-align: middle; }}
#error {{ color: #b00; }}
</style>
<script type="importmap">{{"imports": {{"three": "{three}", "three/addons/controls/OrbitControls.js": "{orbit}"}}}}</script>
</head>
<body>
<div id="view"></div>
<div id="side">
<h1>{title}</h1>
<div id="error"></div>
<div id="layers"></div>
<label><input type="checkbox" id="wireframe"> wireframe</label>
<label><input type="checkbox" id="through"> see through (what the surface encloses)</label>
<table>{rows}</table>
<p>Drag to orbit, scroll to zoom, right-drag to pan.</p>
</div>
<script type="application/json" id="scene">{data}</script>
<script type="module">{viewer}</script>
</body>
</html>
"#,
        title = escape(&scene.title),
        three = module(THREE),
        orbit = module(ORBIT),
        viewer = VIEWER,
    )
}

/// The scene as the viewer reads it: JSON, the arrays as little-endian base64.
fn scene_json(scene: &Scene) -> String {
    let mut data = String::from("{\"layers\":[");
    for (k, layer) in scene.layers.iter().enumerate() {
        if k > 0 {
            data.push(',');
        }
        let positions: Vec<f32> = layer
            .mesh
            .vertices
            .iter()
            .flat_map(|v| [v.x as f32, v.y as f32, v.z as f32])
            .collect();
        let faces: Vec<u32> = layer.mesh.faces.iter().flatten().copied().collect();
        data.push_str(&format!(
            "{{\"name\":{},\"visible\":{},\"positions\":\"{}\",\"faces\":\"{}\",\"classes\":\"{}\"}}",
            json_string(&layer.name),
            layer.visible,
            base64(&f32_bytes(&positions)),
            base64(&u32_bytes(&faces)),
            base64(&layer.face_class),
        ));
    }
    data.push_str("],\"classes\":[");
    for (k, (name, color)) in CLASSES.iter().enumerate() {
        if k > 0 {
            data.push(',');
        }
        data.push_str(&format!(
            "{{\"name\":{},\"color\":{}}}",
            json_string(name),
            rgb(*color)
        ));
    }
    data.push_str("],\"marks\":[");
    for (k, m) in scene.marks.iter().enumerate() {
        if k > 0 {
            data.push(',');
        }
        let p: Vec<f32> = m
            .points
            .iter()
            .flat_map(|v| [v.x as f32, v.y as f32, v.z as f32])
            .collect();
        data.push_str(&format!(
            "{{\"name\":{},\"color\":{},\"count\":{},\"positions\":\"{}\"}}",
            json_string(&m.name),
            rgb(m.color),
            m.points.len(),
            base64(&f32_bytes(&p)),
        ));
    }
    data.push_str("],\"curves\":[");
    for (k, c) in scene.curves.iter().enumerate() {
        if k > 0 {
            data.push(',');
        }
        // Each loop as segments: its points, and the first again.
        let mut p: Vec<f32> = Vec::new();
        for l in c.loops.iter().filter(|l| l.len() > 1) {
            for (a, b) in l.iter().zip(l.iter().cycle().skip(1)) {
                p.extend([a.x, a.y, a.z, b.x, b.y, b.z].map(|v| v as f32));
            }
        }
        data.push_str(&format!(
            "{{\"name\":{},\"color\":{},\"count\":{},\"segments\":\"{}\"}}",
            json_string(&c.name),
            rgb(c.color),
            c.loops.len(),
            base64(&f32_bytes(&p)),
        ));
    }
    data.push_str("]}");
    data
}

fn rgb(c: [u8; 3]) -> String {
    format!("[{},{},{}]", c[0], c[1], c[2])
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn u32_bytes(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// `s` as a JSON string (quotes, backslashes and control characters escaped; `<` too, so that it
/// cannot close the script element it sits in).
fn json_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '<' => out.push_str("\\u003c"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// `s` with HTML's special characters as entities.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Standard base64 with padding (RFC 4648).
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RFC 4648's test vectors.
    #[test]
    fn base64_matches_the_rfc() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
    }

    /// Text from the caller cannot end the script or the markup it is put in.
    #[test]
    fn names_and_figures_are_escaped() {
        assert_eq!(
            json_string("a\"b\\c</script>\n"),
            "\"a\\\"b\\\\c\\u003c/script>\\u000a\""
        );
        assert_eq!(escape("<b>&\""), "&lt;b&gt;&amp;&quot;");
        let scene = Scene {
            title: "</title><script>".into(),
            figures: vec![("<i>".into(), "</table>".into())],
            ..Scene::default()
        };
        let page = html(&scene);
        assert!(!page.contains("</title><script>") && !page.contains("<i>"));
    }
}
