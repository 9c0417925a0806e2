//! The 2D stages on a circle's samples: the free arcs and initial points, and the screened
//! Poisson solve at the depths the pipeline uses for 33^2 and 65^2 grids (8 and 9). The whole 2D
//! pipeline against gpytoolbox's is `cargo xtask eval plane` (CPU per shape in its report).

use criterion::{Criterion, criterion_group, criterion_main};
use rfta_geom::glam::DVec2;
use rfta_plane::arcs::Circle;
use rfta_plane::{initial_points, spsr};

/// The SDF of a circle of radius 0.3 around (0.5, 0.5) on an `n x n` grid over the unit square.
fn circles(n: usize) -> (Vec<Circle>, Vec<f64>) {
    let mut c = Vec::new();
    let mut v = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let p = DVec2::new(i as f64, j as f64) / (n - 1) as f64;
            let s = (p - DVec2::splat(0.5)).length() - 0.3;
            c.push(Circle {
                center: p,
                radius: s.abs(),
            });
            v.push(s);
        }
    }
    (c, v)
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("plane");
    group.sample_size(20);
    for n in [33, 65] {
        let (circles, values) = circles(n);
        let band = 3.0 / (n - 1) as f64;
        let owners: Vec<usize> = (0..circles.len())
            .filter(|&i| circles[i].radius < band)
            .collect();
        group.bench_function(format!("initial_points/grid={n}"), |b| {
            b.iter(|| initial_points(&circles, &values, &owners, 1e-4, 128, DVec2::ZERO, 1.0))
        });
        let cloud = initial_points(&circles, &values, &owners, 1e-4, 128, DVec2::ZERO, 1.0);
        let (points, normals) = cloud.oriented(&circles, &values);
        let domain = spsr::Domain {
            min: DVec2::splat(-0.25),
            side: 1.5,
        };
        let depth = if n == 33 { 8 } else { 9 };
        for cycles in [0, 2] {
            let params = spsr::SpsrParams {
                depth,
                cycles,
                ..spsr::SpsrParams::default()
            };
            group.bench_function(
                format!("spsr/grid={n}/depth={depth}/cycles={cycles}"),
                |b| b.iter(|| spsr::solve(&points, &normals, domain, &params).expect("solves")),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
