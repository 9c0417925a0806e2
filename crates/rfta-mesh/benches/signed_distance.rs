//! Signed distance of a regular grid to a triangle mesh (the work of `rfta sample`).
//!
//! Workload: a 51^3 grid over [-1, 1]^3 against a 40,000-triangle torus (R = 0.6, r = 0.25),
//! the size of a detailed scanned mesh. The target is under 2 s on 2 cores in release.
//! Baseline in the same run: the unsigned distance alone, to show what the winding number costs.

use criterion::{Criterion, criterion_group, criterion_main};
use rfta_geom::{Grid, shapes};
use rfta_mesh::MeshIndex;

fn grid_points(n_cells: usize) -> Vec<rfta_geom::glam::DVec3> {
    let grid = Grid::cube(n_cells, -1.0, 1.0).expect("valid grid");
    (0..grid.len()).map(|i| grid.position(i)).collect()
}

fn bench(c: &mut Criterion) {
    let mesh = shapes::torus(0.6, 0.25, 200, 100);
    assert_eq!(mesh.n_faces(), 40_000);
    let points = grid_points(50);
    let mut group = c.benchmark_group("mesh");
    group.sample_size(10);
    group.bench_function("build/tris=40000", |b| {
        b.iter(|| MeshIndex::new(&mesh).expect("valid"))
    });
    let index = MeshIndex::new(&mesh).expect("valid");
    group.bench_function("signed_distance/grid=51^3/tris=40000", |b| {
        b.iter(|| index.signed_distances(&points))
    });
    group.bench_function("unsigned_distance/grid=51^3/tris=40000", |b| {
        b.iter(|| index.unsigned_distances(&points))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
