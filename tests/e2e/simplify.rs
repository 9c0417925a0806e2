//! The simplification on every dev output (`rfta::Params::simplify`): against the same grid's
//! unsimplified mesh, the same topology (genus, components, closed and manifold), no sample on
//! another side (the samples on the wrong side are the same ones, by
//! `rfta::consistency::marked`), no more spheres entered before the verdict clears what its check
//! finds entered (which can clear more on the finer mesh), fewer faces.

use rfta::Params;
use rfta_mesh::Topology;

#[test]
fn every_dev_output_keeps_its_topology_and_every_sample_its_side() {
    let Some(data) = rfta_testkit::data_dir_or_skip(
        "every_dev_output_keeps_its_topology_and_every_sample_its_side",
    ) else {
        return;
    };
    let off = Params {
        simplify: false,
        ..Params::default()
    };
    let mut checked = 0;
    for (name, n, path) in rfta_testkit::input_grids(&data) {
        let samples = rfta_io::read_sdf(&path, None)
            .expect("readable")
            .validate(&path)
            .expect("valid");
        let full = rfta::reconstruct(&samples, &off).expect("unsimplified");
        let out = rfta::reconstruct(&samples, &Params::default()).expect("simplified");
        let (t, t0) = (Topology::of(&out.mesh), Topology::of(&full.mesh));
        let shape = |t: &Topology| {
            (
                t.genus(),
                t.components,
                t.boundary_edges,
                t.nonmanifold_edges + t.nonmanifold_vertices + t.misoriented_edges,
            )
        };
        assert_eq!(shape(&t), shape(&t0), "{name} N = {n}");
        let clamp = out.report.input.clamp;
        let wrong = rfta::consistency::marked(&samples, &out.mesh, clamp).expect("marked");
        let wrong0 = rfta::consistency::marked(&samples, &full.mesh, clamp).expect("marked");
        assert_eq!(wrong.wrong_side, wrong0.wrong_side, "{name} N = {n}");
        let (c, c0) = (&out.report.consistency, &full.report.consistency);
        let found = |r: &rfta::Report| r.consistency.entered + r.repair.spheres_cleared_at_check;
        assert!(
            found(&out.report) <= found(&full.report),
            "{name} N = {n}: {c:?} {c0:?}"
        );
        assert!(
            out.mesh.n_faces() * 2 < full.mesh.n_faces(),
            "{name} N = {n}"
        );
        checked += 1;
    }
    assert!(checked >= 24, "only {checked} grids");
}
