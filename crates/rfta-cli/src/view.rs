//! `rfta view` (a mesh, and what its SDF samples say of it, as one HTML page) and the page
//! `rfta reconstruct --html` writes: the scene `rfta_view` draws.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use rfta::geom::{SdfSamples, TriMesh};
use rfta_view::{Curves, Layer, Marks, Scene};

use crate::ui::{Ui, parse_bounds};

#[derive(Debug, clap::Args)]
pub(crate) struct Args {
    /// The mesh (.obj .off .ply .stl .glb).
    mesh: PathBuf,
    /// SDF samples the mesh was made from (as for `reconstruct`): samples on the wrong side and
    /// spheres entered are marked, and marching cubes' mesh of a grid is a layer to compare.
    #[arg(long, value_name = "SDF")]
    sdf: Option<PathBuf>,
    /// Grid bounds for an .npy grid, overriding its sidecar (as for `sample`).
    #[arg(long, value_name = "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX", value_parser = parse_bounds)]
    bounds: Option<rfta_io::GridBounds>,
    /// The page (.html).
    #[arg(short, long)]
    output: PathBuf,
}

pub(crate) fn run(args: Args, ui: &Ui) -> Result<()> {
    let mut files = crate::paths::Files::new();
    files
        .read("the mesh", &args.mesh)
        .write("the page (-o)", &args.output);
    if let Some(sdf) = &args.sdf {
        files.read_sdf("--sdf", sdf);
    }
    files.check()?;
    let mesh = rfta_io::read_mesh(&args.mesh)?;
    let samples = match &args.sdf {
        Some(path) => Some(rfta_io::read_sdf(path, args.bounds)?.validate(path)?),
        None => None,
    };
    let topology = rfta_mesh::Topology::of(&mesh);
    let mut figures = vec![
        ("vertices".to_string(), mesh.n_vertices().to_string()),
        ("faces".into(), mesh.n_faces().to_string()),
        ("components".into(), topology.components.to_string()),
        ("watertight".into(), topology.is_watertight().to_string()),
        (
            "genus".into(),
            topology.genus().map_or("-".into(), |g| g.to_string()),
        ),
    ];
    if let Some(s) = &samples {
        let c = rfta::consistency::measure(s, &mesh, None)?;
        figures.extend([
            ("samples".to_string(), s.len().to_string()),
            ("on the wrong side".into(), c.sign_errors.to_string()),
            ("spheres entered".into(), c.entered.to_string()),
            ("thin loops".into(), c.thin_loops.len().to_string()),
        ]);
    }
    let title = args.mesh.display().to_string();
    let scene = scene(&title, &mesh, samples.as_ref(), None, figures)?;
    write(&args.output, &scene)?;
    ui.say(format!("wrote {}", args.output.display()));
    Ok(())
}

/// The page of `mesh`: its faces classed (the largest component, cavities, other components);
/// with `samples`, the samples on the wrong side and the spheres entered marked, the loops
/// around thin handles drawn, and on a grid marching cubes' mesh as a hidden layer.
pub(crate) fn scene(
    title: &str,
    mesh: &TriMesh,
    samples: Option<&SdfSamples>,
    clamp: Option<f64>,
    figures: Vec<(String, String)>,
) -> Result<Scene> {
    let mut layers = vec![Layer {
        face_class: face_classes(mesh),
        ..Layer::plain("mesh", mesh.clone())
    }];
    let mut marks = Vec::new();
    let mut curves = Vec::new();
    if let Some(s) = samples {
        if let Some(grid) = s.as_grid() {
            let mc = rfta_mc::marching_cubes(grid, s.values(), 0.0);
            layers.push(Layer {
                visible: false,
                ..Layer::plain("marching cubes (same samples)", mc)
            });
        }
        let found = rfta::consistency::marked(s, mesh, clamp)?;
        marks.push(Marks {
            name: "samples on the wrong side".into(),
            color: [220, 30, 30],
            points: found.wrong_side.iter().map(|&i| s.position(i)).collect(),
        });
        marks.push(Marks {
            name: "samples whose sphere the mesh enters".into(),
            color: [230, 180, 0],
            points: found.entered.iter().map(|&i| s.position(i)).collect(),
        });
        curves.push(Curves {
            name: "loops around thin handles".into(),
            color: [0, 150, 60],
            loops: found
                .thin_loops
                .iter()
                .map(|l| l.iter().map(|&v| mesh.vertices[v as usize]).collect())
                .collect(),
        });
    }
    Ok(Scene {
        title: title.into(),
        layers,
        marks,
        curves,
        figures,
    })
}

/// Per face: 0 in the largest component, 1 in a cavity (a component facing inward), 2 in
/// another component.
fn face_classes(mesh: &TriMesh) -> Vec<u8> {
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

/// Writes the page atomically.
pub(crate) fn write(path: &Path, scene: &Scene) -> Result<()> {
    let page = rfta_view::html(scene);
    rfta_io::write_atomic(path, |w| w.write_all(page.as_bytes()))
        .with_context(|| format!("{}: cannot write the page", path.display()))?;
    Ok(())
}
