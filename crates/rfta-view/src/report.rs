//! The page of a reconstruction: its mesh with each face classed, and what its samples found.

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;

use crate::{Curves, Layer, Marks, Scene};

/// What the samples say of a mesh, for [`reconstruction`].
#[derive(Debug, Clone, Default)]
pub struct Found {
    /// Samples on the wrong side of the mesh.
    pub wrong_side: Vec<DVec3>,
    /// Samples whose sphere the mesh enters.
    pub entered: Vec<DVec3>,
    /// Loops around the mesh's thin handles, as cycles of its vertices.
    pub thin_loops: Vec<Vec<u32>>,
    /// Another method's mesh of the same samples (marching cubes), shown as a hidden layer.
    pub compare: Option<(String, TriMesh)>,
}

#[cfg(feature = "samples")]
impl Found {
    /// What `samples` find on `mesh` (feature `samples`): `rfta::consistency::marked`'s samples
    /// and loops, and on a grid marching cubes' mesh of the same samples.
    ///
    /// # Errors
    /// As `rfta::consistency::marked`.
    pub fn of(
        samples: &rfta_geom::SdfSamples,
        mesh: &TriMesh,
        clamp: Option<f64>,
    ) -> Result<Self, rfta::Error> {
        Ok(Self {
            compare: samples.as_grid().map(|grid| {
                (
                    "marching cubes (same samples)".to_string(),
                    rfta_mc::marching_cubes(grid, samples.values(), 0.0),
                )
            }),
            ..Self::marks(samples, mesh, clamp)?
        })
    }

    /// [`Found::of`] without a mesh to compare with (feature `samples`): for a caller that has
    /// its own.
    ///
    /// # Errors
    /// As `rfta::consistency::marked`.
    pub fn marks(
        samples: &rfta_geom::SdfSamples,
        mesh: &TriMesh,
        clamp: Option<f64>,
    ) -> Result<Self, rfta::Error> {
        let marked = rfta::consistency::marked(samples, mesh, clamp)?;
        let at = |i: &[usize]| i.iter().map(|&i| samples.position(i)).collect();
        Ok(Self {
            wrong_side: at(&marked.wrong_side),
            entered: at(&marked.entered),
            thin_loops: marked.thin_loops,
            compare: None,
        })
    }
}

/// The report's figures for a page (feature `samples`): [`figures`] of its serde form, with what
/// the repair did ([`rfta::Report::answers`], [`rfta::Report::changes`]) after the warnings.
#[cfg(feature = "samples")]
pub fn report_figures(report: &rfta::Report) -> Vec<(String, String)> {
    let value = serde_json::to_value(report).unwrap_or_default();
    let mut out = figures(&value);
    let at = out.iter().take_while(|(k, _)| k != "all figures").count();
    let changes = (report.answers().into_iter())
        .chain(report.changes())
        .map(|c| ("repair".to_string(), c))
        .chain(report.field_quality().map(|f| ("field".to_string(), f)));
    out.splice(at..at, changes);
    out
}

/// The figures of a report's serde form (the JSON report, Python's report dict), for a page:
/// first what a person reads (genus, components, watertight, samples on the wrong side, spheres
/// entered, thin handles, cavities, time) and the warnings, then every number, flag and short
/// list by its name.
#[cfg(feature = "samples")]
pub fn figures(report: &serde_json::Value) -> Vec<(String, String)> {
    use serde_json::Value;
    let field = |k: &str| report.get(k).cloned().unwrap_or(Value::Null);
    let count = |k: &str| match field(k) {
        Value::Array(a) => a.len().to_string(),
        Value::Null => "?".into(),
        v => v.to_string(),
    };
    let seconds: f64 = match field("timings") {
        Value::Object(t) => t.values().filter_map(Value::as_f64).sum(),
        _ => f64::NAN,
    };
    let mut out: Vec<(String, String)> = [
        (
            "genus",
            match field("genus") {
                Value::Null => "undefined (not closed)".into(),
                g => g.to_string(),
            },
        ),
        ("components", count("components")),
        (
            "watertight",
            if field("watertight") == Value::Bool(true) {
                "yes"
            } else {
                "no"
            }
            .into(),
        ),
        ("samples on the wrong side", count("sign_errors")),
        ("spheres entered", count("entered")),
        ("thin handles", count("thin_loops")),
        (
            "cavities",
            format!(
                "{} left, {} opened",
                count("cavities"),
                count("cavities_opened")
            ),
        ),
        ("time", format!("{seconds:.2} s")),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    if let Value::Array(warnings) = field("warnings") {
        out.extend(
            warnings
                .iter()
                .filter_map(Value::as_str)
                .map(|w| ("warning".to_string(), w.to_string())),
        );
    }
    out.push(("all figures".to_string(), String::new()));
    if let Value::Object(all) = report {
        out.extend(all.iter().filter_map(|(k, v)| match v {
            Value::Number(n) => Some((k.clone(), n.to_string())),
            Value::Bool(b) => Some((k.clone(), b.to_string())),
            Value::Array(a) if a.len() <= 12 && a.iter().all(Value::is_number) => {
                let items: Vec<String> = a.iter().map(ToString::to_string).collect();
                Some((k.clone(), items.join(", ")))
            }
            _ => None,
        }));
    }
    out
}

/// The scene of `mesh`: its faces classed (the largest component, cavities: components facing
/// inward, other components), with `found` marked on it, and the `figures`.
pub fn reconstruction(
    title: &str,
    mesh: &TriMesh,
    found: Option<&Found>,
    figures: Vec<(String, String)>,
) -> Scene {
    let mut layers = vec![Layer {
        face_class: face_classes(mesh),
        ..Layer::plain("mesh", mesh.clone())
    }];
    let mut marks = Vec::new();
    let mut curves = Vec::new();
    if let Some(f) = found {
        if let Some((name, other)) = &f.compare {
            layers.push(Layer {
                visible: false,
                ..Layer::plain(name, other.clone())
            });
        }
        marks.push(Marks {
            name: "samples on the wrong side".into(),
            color: [220, 30, 30],
            points: f.wrong_side.clone(),
        });
        marks.push(Marks {
            name: "samples whose sphere the mesh enters".into(),
            color: [230, 180, 0],
            points: f.entered.clone(),
        });
        curves.push(Curves {
            name: "loops around thin handles".into(),
            color: [0, 150, 60],
            loops: f
                .thin_loops
                .iter()
                .map(|l| {
                    l.iter()
                        .filter_map(|&v| mesh.vertices.get(v as usize).copied())
                        .collect()
                })
                .collect(),
        });
    }
    Scene {
        title: title.into(),
        layers,
        marks,
        curves,
        figures,
    }
}

/// Per face: 0 in the largest component, 1 in a cavity (a component facing inward), 2 in
/// another component.
pub fn face_classes(mesh: &TriMesh) -> Vec<u8> {
    let parts = rfta_mesh::face_components(mesh);
    let largest = (0..parts.len()).max_by_key(|&k| (parts[k].len(), std::cmp::Reverse(k)));
    let mut class = vec![0u8; mesh.n_faces()];
    for (k, faces) in parts.iter().enumerate() {
        let c = if Some(k) == largest {
            0
        } else if rfta_mesh::signed_volume(mesh, faces) < 0.0 {
            1
        } else {
            2
        };
        for &f in faces {
            class[f] = c;
        }
    }
    class
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    /// A ball with a bubble inside and a small ball beside it: the faces of each in their class.
    #[test]
    fn faces_are_classed_by_component() {
        let mut mesh = shapes::icosphere(1.0, 2);
        let mut bubble = shapes::icosphere(0.3, 1);
        for f in &mut bubble.faces {
            f.swap(1, 2);
        }
        let mut beside = shapes::icosphere(0.2, 1);
        beside.map_vertices(|p| p + DVec3::new(2.0, 0.0, 0.0));
        let n = [mesh.n_faces(), bubble.n_faces(), beside.n_faces()];
        mesh.append(&bubble);
        mesh.append(&beside);
        let classes = face_classes(&mesh);
        let count = |c: u8| classes.iter().filter(|&&k| k == c).count();
        assert_eq!([count(0), count(1), count(2)], n);
    }

    /// A report's serde form shows what a person reads first, in order, then the warnings, then
    /// the figures by name; a mesh that is not closed has no genus.
    #[test]
    #[cfg(feature = "samples")]
    fn a_report_opens_with_its_summary() {
        let report = serde_json::json!({
            "genus": 2, "components": 1, "watertight": true, "sign_errors": 0, "entered": 3,
            "thin_loops": [0.5], "cavities": 0, "cavities_opened": 1,
            "warnings": ["the values look noisy"], "timings": {"a": 0.25, "b": 0.5}
        });
        let f = figures(&report);
        let names: Vec<&str> = f.iter().map(|(k, _)| k.as_str()).take(10).collect();
        assert_eq!(
            names,
            [
                "genus",
                "components",
                "watertight",
                "samples on the wrong side",
                "spheres entered",
                "thin handles",
                "cavities",
                "time",
                "warning",
                "all figures"
            ]
        );
        let value = |k: &str| f.iter().find(|(n, _)| n == k).map(|(_, v)| v.as_str());
        assert_eq!(value("genus"), Some("2"));
        assert_eq!(value("thin handles"), Some("1"));
        assert_eq!(value("cavities"), Some("0 left, 1 opened"));
        assert_eq!(value("time"), Some("0.75 s"));
        assert_eq!(value("entered"), Some("3"));
        let open = figures(&serde_json::json!({"genus": null}));
        assert_eq!(open[0].1, "undefined (not closed)");
    }
}
