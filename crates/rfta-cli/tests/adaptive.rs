//! `rfta reconstruct --from-mesh MESH --budget N` and `rfta demo --adaptive`: adaptive sampling
//! from the command line.

mod common;

use common::{json, rfta, s, stderr, temp, torus_mesh};

/// A torus mesh's exact SDF asked at most 2,000 times: a watertight genus-1 mesh near the torus,
/// the report's adaptive section counting the evaluations within the budget.
#[test]
fn from_mesh_reconstructs_within_the_budget() {
    let dir = temp("from-mesh");
    let (torus, out, report) = (torus_mesh(&dir), dir.join("out.obj"), dir.join("r.json"));
    let o = rfta(&[
        "reconstruct",
        "--from-mesh",
        s(&torus),
        "--budget",
        "2000",
        "--rounds",
        "2",
        "-o",
        s(&out),
        "--report",
        s(&report),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = json(&report);
    let evaluations = r["adaptive"]["evaluations"].as_u64().expect("evaluations");
    assert!(evaluations > 1_000 && evaluations <= 2_000, "{evaluations}");
    assert!(
        r["adaptive"]["passes"]
            .as_array()
            .is_some_and(|p| p.len() >= 2),
        "{r}"
    );
    assert_eq!(r["watertight"], true);
    let mesh = rfta_io::read_mesh(&out).expect("mesh");
    assert_eq!(rfta_mesh::Topology::of(&mesh).genus(), Some(1));
    // The vertices within a hundredth of the mesh asked about on average, a tenth at most (the
    // torus is 0.5 thick; the box's base cells 0.4 wide).
    let given = rfta_io::read_mesh(&torus).expect("torus");
    let index = rfta_mesh::MeshIndex::new(&given).expect("index");
    let d = index.unsigned_distances(&mesh.vertices);
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    let worst = d.iter().copied().fold(0.0, f64::max);
    assert!(mean < 0.01 && worst < 0.1, "mean {mean}, worst {worst}");
}

/// Without a mesh or an SDF file the command says it needs the input; a budget below the smallest base
/// grid is refused naming the budget, and nothing is written.
#[test]
fn from_mesh_refuses_what_it_cannot_do() {
    let dir = temp("refuse");
    let out = dir.join("out.obj");
    let o = rfta(&["reconstruct", "-o", s(&out)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("<INPUT>"), "{}", stderr(&o));
    let torus = torus_mesh(&dir);
    let o = rfta(&[
        "reconstruct",
        "--from-mesh",
        s(&torus),
        "--budget",
        "50",
        "-o",
        s(&out),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("at least 125"), "{}", stderr(&o));
    assert!(!out.exists());
    // --budget belongs to --from-mesh.
    let o = rfta(&[
        "reconstruct",
        s(&dir.join("t.npy")),
        "--budget",
        "500",
        "-o",
        s(&out),
    ]);
    assert!(!o.status.success());
    assert!(!out.exists());
}

/// `rfta demo --adaptive`: the two tori, genus 2, from at most the budget's evaluations.
#[test]
fn the_adaptive_demo_finds_both_handles() {
    let dir = temp("demo");
    let out = dir.join("demo.obj");
    let o = rfta(&[
        "demo",
        "--adaptive",
        "--budget",
        "3000",
        "--rounds",
        "2",
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("genus 2"), "{}", stderr(&o));
    let mesh = rfta_io::read_mesh(&out).expect("mesh");
    assert_eq!(rfta_mesh::Topology::of(&mesh).genus(), Some(2));
}
