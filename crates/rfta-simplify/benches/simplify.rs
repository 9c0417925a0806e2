//! Simplification of a finely tessellated torus (the size of a 50^3 reconstruction's mesh).
//!
//! Workload: an 80,000-triangle torus (R = 0.6, r = 0.25) simplified within 0.001 and within
//! 0.005 (about 1/40 and 1/8 of its edge length), no judge. Baseline in the same run: building
//! the mesh index the simplifier keeps of its input (`MeshIndex::new`), the cost of one look at
//! the whole mesh.

use criterion::{Criterion, criterion_group, criterion_main};
use rfta_geom::shapes;
use rfta_mesh::MeshIndex;
use rfta_simplify::{Options, Patch, simplify};

fn bench(c: &mut Criterion) {
    let mesh = shapes::torus(0.6, 0.25, 400, 100);
    assert_eq!(mesh.n_faces(), 80_000);
    let mut group = c.benchmark_group("simplify");
    group.sample_size(10);
    group.bench_function("baseline/index/tris=80000", |b| {
        b.iter(|| MeshIndex::new(&mesh).expect("valid"))
    });
    for tolerance in [0.001, 0.005] {
        let options = Options {
            tolerance,
            max_faces: None,
        };
        group.bench_function(format!("torus/tris=80000/tol={tolerance}"), |b| {
            b.iter(|| simplify(&mesh, &options, &|_: &Patch<'_>| true).expect("simplified"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
