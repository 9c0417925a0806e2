//! One-shot timing of the rasterizer on the bunny's 51^3 grid (see benches/raster.rs for the
//! measured benchmark): `cargo run --release -p rfta-raster --example raster_timing [--features gpu] -- RES [GRID.npy]`
//! (another grid in [-1, 1]^3, e.g. from `rfta sample`, instead of the bunny's).

#![expect(clippy::print_stdout, reason = "an example reports its timing")]

use std::time::Instant;

use rfta_geom::glam::DVec3;
use rfta_raster::{Backend, RasterParams, rasterize};

fn main() {
    let res: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(128);
    let path = match std::env::args().nth(2) {
        Some(p) => p.into(),
        None => rfta_testkit::data_dir()
            .expect("../shared/data")
            .join("inputs/bunny/sdf_n50.npy"),
    };
    let raw = rfta_io::read_sdf(&path, None).expect("grid");
    let rfta_geom::Layout::Grid(grid) = raw.layout else {
        return;
    };
    for positive in [false, true] {
        let (mut c, mut r) = (Vec::new(), Vec::new());
        for (i, s) in raw.values.iter().enumerate() {
            if (*s >= 0.0) == positive {
                c.push((grid.position(i) + DVec3::ONE) * 0.5);
                r.push(s.abs() * 0.5);
            }
        }
        for backend in [Backend::Cpu, Backend::Gpu] {
            if backend == Backend::Gpu
                && (!cfg!(feature = "gpu") || std::env::var_os("NO_GPU").is_some())
            {
                continue;
            }
            let t = Instant::now();
            let out = rasterize(&c, &r, &RasterParams { res, seed: 1 }, backend).expect("raster");
            println!(
                "{} spheres ({}), res {res}, {:?}: {:.3} s, {} occupied, {} points",
                c.len(),
                if positive { "outside" } else { "inside" },
                out.backend,
                t.elapsed().as_secs_f64(),
                out.n_occupied,
                out.points.len()
            );
        }
    }
}
