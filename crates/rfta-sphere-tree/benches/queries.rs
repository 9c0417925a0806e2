//! Containment queries on real SDF grids: the tree, the reference's traversal order, and the
//! brute-force oracle, measured in one run (queries per second; `Throughput::Elements`).
//!
//! Workload: the exact SDF of the bunny (`../shared/data/inputs/bunny`): the shipped 21^3 grid
//! (about 10^4 spheres) and 51^3 grid (about 10^5), and a 100^3 grid (10^6) sampled here from
//! `gt.obj` with the same exact distance. Coordinates are normalised to the unit box as the
//! reference does, and each query is a point on a random sphere's surface with that sphere
//! ignored, the reconstruction's feasibility test (`t = -1e-4`) and candidate search
//! (`t = +1e-4`, `k = ceil(2 n^(1/3))`).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rfta_geom::{Grid, Sphere, glam::DVec3, rng::Rng};
use rfta_sphere_tree::{SphereTree, naive};

/// Spheres of an SDF grid over [-1, 1]^3, normalised to [0, 1]^3 (scale 2).
fn spheres_of(grid: &Grid, values: &[f64]) -> Vec<Sphere> {
    (0..grid.len())
        .map(|i| Sphere::new((grid.position(i) + DVec3::ONE) * 0.5, values[i].abs() * 0.5))
        .collect()
}

fn workloads() -> Vec<(String, Vec<Sphere>)> {
    let data =
        rfta_testkit::data_dir().expect("the benchmark needs ../shared/data (or RFTA_DATA_DIR)");
    let bunny = data.join("inputs/bunny");
    let mut out = Vec::new();
    for n in [20, 50] {
        let raw = rfta_io::read_sdf(&bunny.join(format!("sdf_n{n}.npy")), None).expect("grid");
        let rfta_geom::Layout::Grid(grid) = raw.layout else {
            panic!("not a grid")
        };
        out.push((format!("{}", grid.len()), spheres_of(&grid, &raw.values)));
    }
    let mesh = rfta_io::read_mesh(&bunny.join("gt.obj")).expect("mesh");
    let sdf = rfta_mesh::MeshSdf::new(&mesh).expect("sdf");
    let grid = Grid::cube(99, -1.0, 1.0).expect("grid");
    let values = sdf.signed_distance_grid(&grid, &|| {});
    out.push((format!("{}", grid.len()), spheres_of(&grid, &values)));
    out
}

fn surface_queries(spheres: &[Sphere], n: usize) -> Vec<(DVec3, u32)> {
    let mut rng = Rng::new(1);
    (0..n)
        .map(|_| {
            let i = rng.below(spheres.len() as u64) as usize;
            let d = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            )
            .normalize_or(DVec3::X);
            (spheres[i].center + spheres[i].radius * d, i as u32)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("sphere_tree");
    g.sample_size(10);
    for (n, spheres) in workloads() {
        let queries = surface_queries(&spheres, 2000);
        let k = (2.0 * (spheres.len() as f64).cbrt()).ceil() as usize;
        g.throughput(Throughput::Elements(queries.len() as u64));
        g.bench_function(BenchmarkId::new("build", &n), |b| {
            b.iter(|| SphereTree::new(&spheres))
        });
        let tree = SphereTree::new(&spheres);
        let batch = SphereTree::batch(&spheres, 10_000, 7);
        g.bench_function(BenchmarkId::new("inside_any/tree", &n), |b| {
            b.iter(|| {
                queries
                    .iter()
                    .filter(|(x, i)| tree.inside_any(*x, -1e-4, Some(*i)))
                    .count()
            })
        });
        g.bench_function(BenchmarkId::new("inside_any/reference_order", &n), |b| {
            b.iter(|| {
                queries
                    .iter()
                    .filter(|(x, i)| tree.inside_any_reference_order(*x, -1e-4, Some(*i)))
                    .count()
            })
        });
        g.bench_function(BenchmarkId::new("inside_any/batch_10k_tree", &n), |b| {
            b.iter(|| {
                queries
                    .iter()
                    .filter(|(x, i)| batch.inside_any(*x, -1e-4, Some(*i)))
                    .count()
            })
        });
        g.bench_function(BenchmarkId::new("spheres_containing/tree", &n), |b| {
            let mut hits = Vec::new();
            b.iter(|| {
                queries
                    .iter()
                    .map(|(x, i)| {
                        tree.spheres_containing_into(*x, k, 1e-4, Some(*i), &mut hits);
                        hits.len()
                    })
                    .sum::<usize>()
            })
        });
        // The oracle is O(n) per query: a tenth of the queries (throughput scaled to match).
        let few = &queries[..200];
        g.throughput(Throughput::Elements(few.len() as u64));
        g.bench_function(BenchmarkId::new("inside_any/oracle", &n), |b| {
            b.iter(|| {
                few.iter()
                    .filter(|(x, i)| naive::inside_any(&spheres, *x, -1e-4, Some(*i)))
                    .count()
            })
        });
        g.bench_function(BenchmarkId::new("spheres_containing/oracle", &n), |b| {
            b.iter(|| {
                few.iter()
                    .map(|(x, i)| naive::spheres_containing(&spheres, *x, k, 1e-4, Some(*i)).len())
                    .sum::<usize>()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
