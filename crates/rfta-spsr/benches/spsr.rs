//! Screened Poisson reconstruction, end to end (tree, system, solve, extraction).
//!
//! Workloads: area-uniform clouds on the torus R = 0.6, r = 0.25 with exact normals, 10k and 100k
//! points at depth 8 (screening 10, degree 1), and 10k points in the Reach for the Arcs setting
//! (depth 10, box 3.2). The side-by-side comparison with PoissonRecon, in the same run, is
//! `cargo xtask bench spsr` (see the xtask).

use criterion::{Criterion, criterion_group, criterion_main};
use rfta_geom::OrientedPoints;
use rfta_spsr::{SpsrParams, reconstruct};
use rfta_testkit::Analytic;

fn torus(n: usize) -> OrientedPoints {
    let (p, nn) = Analytic::Torus {
        major: 0.6,
        minor: 0.25,
    }
    .oriented_samples(n, 1);
    OrientedPoints::new(p, nn, None).expect("valid cloud")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("spsr");
    group.sample_size(10);
    let d8 = SpsrParams {
        depth: 8,
        screening: 10.0,
        ..SpsrParams::default()
    };
    for n in [10_000, 100_000] {
        let cloud = torus(n);
        group.bench_function(format!("torus/points={n}/depth=8"), |b| {
            b.iter(|| reconstruct(&cloud, &d8).expect("reconstruction"))
        });
    }
    let cloud = torus(10_000);
    let rfta = SpsrParams::rfta_reference();
    group.bench_function("torus/points=10000/rfta_setting", |b| {
        b.iter(|| reconstruct(&cloud, &rfta).expect("reconstruction"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
