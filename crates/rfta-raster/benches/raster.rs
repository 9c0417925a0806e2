//! Empty-space rasterization on real SDF grids: CPU (rayon) against GPU (wgpu; lavapipe on a
//! machine without a GPU), at the reference's resolutions 128, 256 and 512.
//!
//! Workload: the bunny's exact SDF on the shipped 51^3 grid (`../shared/data/inputs/bunny`),
//! normalised to the unit box as the reference does (`(p + 1) / 2`, `s / 2`), split by sign:
//! the inside set (about 3,100 small spheres) and the outside set (about 129,500, many large).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use rfta_geom::glam::DVec3;
use rfta_raster::{Backend, RasterParams, rasterize};

fn sign_sets() -> Vec<(&'static str, Vec<DVec3>, Vec<f64>)> {
    let data =
        rfta_testkit::data_dir().expect("the benchmark needs ../shared/data (or RFTA_DATA_DIR)");
    let raw = rfta_io::read_sdf(&data.join("inputs/bunny/sdf_n50.npy"), None).expect("grid");
    let rfta_geom::Layout::Grid(grid) = raw.layout else {
        panic!("not a grid")
    };
    let mut sets = vec![
        ("inside", Vec::new(), Vec::new()),
        ("outside", Vec::new(), Vec::new()),
    ];
    for (i, s) in raw.values.iter().enumerate() {
        let set = &mut sets[usize::from(*s >= 0.0)];
        set.1.push((grid.position(i) + DVec3::ONE) * 0.5);
        set.2.push(s.abs() * 0.5);
    }
    sets
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("raster");
    g.sample_size(10);
    let backends: &[(&str, Backend)] =
        if cfg!(feature = "gpu") && std::env::var_os("RFTA_BENCH_NO_GPU").is_none() {
            &[("cpu", Backend::Cpu), ("gpu", Backend::Gpu)]
        } else {
            &[("cpu", Backend::Cpu)]
        };
    for (name, centers, radii) in sign_sets() {
        for res in [128, 256, 512] {
            for (label, backend) in backends {
                // lavapipe (software Vulkan) needs 13-43 s per outside-set run (10 samples each);
                // on a real GPU set RFTA_BENCH_GPU_ALL=1 to include it, or use examples/raster_timing.
                if *label == "gpu"
                    && name == "outside"
                    && std::env::var_os("RFTA_BENCH_GPU_ALL").is_none()
                {
                    continue;
                }
                let params = RasterParams { res, seed: 1 };
                let id = BenchmarkId::new(format!("{label}/{name}"), format!("res={res}"));
                g.bench_function(id, |b| {
                    b.iter(|| {
                        rasterize(&centers, &radii, &params, *backend)
                            .expect("raster")
                            .points
                            .len()
                    })
                });
            }
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
