//! Reach for the Arcs end to end on an analytic torus sampled at 16^3 cells.

use rfta::Params;
use rfta_geom::{Grid, SdfSamples, TriMesh};
use rfta_mesh::Topology;
use rfta_testkit::Analytic;

/// The largest connected component (by faces) of a mesh.
fn largest_component(mesh: &TriMesh) -> TriMesh {
    let n = mesh.vertices.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for f in &mesh.faces {
        let a = root(&mut parent, f[0] as usize);
        for &v in &f[1..] {
            let b = root(&mut parent, v as usize);
            parent[b] = a;
        }
    }
    let mut count = vec![0usize; n];
    for f in &mesh.faces {
        count[root(&mut parent, f[0] as usize)] += 1;
    }
    let best = (0..n).max_by_key(|&r| count[r]).unwrap_or(0);
    let faces: Vec<[u32; 3]> = mesh
        .faces
        .iter()
        .copied()
        .filter(|f| root(&mut parent, f[0] as usize) == best)
        .collect();
    TriMesh {
        vertices: mesh.vertices.clone(),
        faces,
    }
}

#[test]
fn torus_at_16_cubed_is_genus_one_and_closer_than_marching_cubes() {
    let torus = Analytic::Torus {
        major: 0.6,
        minor: 0.25,
    };
    let grid = Grid::cube(16, -1.0, 1.0).expect("grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| torus.sdf(grid.position(i)))
        .collect();
    let samples = SdfSamples::grid(grid, values.clone()).expect("samples");
    let out = rfta::reconstruct(&samples, &Params::default()).expect("reconstruction");

    let topo = Topology::of(&out.mesh);
    assert!(
        topo.is_watertight() && topo.is_manifold() && topo.is_consistently_oriented(),
        "{topo:?}"
    );
    assert!(out.mesh.signed_volume() > 0.0, "inward-facing");
    // Screened Poisson can leave a few tiny closed bubbles next to outlying tangency points (the
    // reference's outputs have them too); the surface itself is the largest component.
    let main = largest_component(&out.mesh);
    assert!(
        main.faces.len() * 100 >= out.mesh.faces.len() * 99,
        "main component too small"
    );
    assert_eq!(
        Topology::of(&main).genus(),
        Some(1),
        "genus of the main component"
    );

    // Hausdorff to the true surface, over vertices (libigl's definition, one-sided to the exact
    // torus): below half the grid spacing (2/16 / 2 = 0.0625) everywhere, bubbles included.
    let err: Vec<f64> = out
        .mesh
        .vertices
        .iter()
        .map(|&v| torus.sdf(v).abs())
        .collect();
    let max = err.iter().copied().fold(0.0, f64::max);
    assert!(max < 0.0625, "max vertex distance {max}");
    // And on average closer than marching cubes on the same grid, over the surfaces (vertices
    // and faces' centroids: marching cubes' vertices lie on the surface's crossings of grid
    // edges and its faces cut the corners between them; a simplified mesh's vertices sit where
    // its faces fit best).
    let mc = rfta_mc::marching_cubes(&grid, &values, 0.0);
    let surface_mean = |m: &TriMesh| {
        let centroids =
            (0..m.n_faces()).map(|f| m.triangle(f).iter().sum::<rfta_geom::glam::DVec3>() / 3.0);
        let d: Vec<f64> = (m.vertices.iter().copied().chain(centroids))
            .map(|v| torus.sdf(v).abs())
            .collect();
        d.iter().sum::<f64>() / d.len() as f64
    };
    let (mean, mc_mean) = (surface_mean(&out.mesh), surface_mean(&mc));
    assert!(
        mean < mc_mean,
        "rfta mean {mean} vs marching cubes {mc_mean}"
    );
    // A 17^3 grid takes the paper's ten rounds (3 only beyond 80 cells a side).
    assert_eq!(out.report.rounds.points_per_round.len(), 10 + 1);
}
