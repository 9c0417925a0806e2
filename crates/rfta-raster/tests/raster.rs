//! The rasterizer against brute force, across thread counts, and CPU against GPU.

use rfta_geom::{glam::DVec3, rng::Rng};
use rfta_raster::{Backend, RasterParams, SUBCELLS, cell_sample, occupancy, rasterize};

fn random_spheres(n: usize, seed: u64, max_r: f64) -> (Vec<DVec3>, Vec<f64>) {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            (
                DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()),
                rng.next_f64() * max_r,
            )
        })
        .unzip()
}

/// The brute-force oracle for one cell, written from the documented rule: the cell's sample
/// point lies on a lattice of `L = 16 res` steps (`x = (X + 0.5) / L`), and it is occupied when the
/// squared lattice distance to some centre rounded to the lattice is at most `floor(0.95 (r L)^2)`.
/// Every quantity is an integer below 2^53, so this f64 evaluation is exact.
fn brute_occupied(res: usize, centers: &[DVec3], radii: &[f64], sample: DVec3) -> bool {
    let l = (res as u32 * SUBCELLS) as f64;
    let x = sample * l - DVec3::splat(0.5);
    centers.iter().zip(radii).any(|(c, r)| {
        let q = (*c * l - DVec3::splat(0.5)).round();
        (x - q).length_squared() <= (0.95 * (r * l) * (r * l)).floor()
    })
}

fn has_occupied_neighbour(occ: &rfta_raster::BitGrid, i: usize, j: usize, k: usize) -> bool {
    let res = occ.res();
    (i.saturating_sub(1)..=(i + 1).min(res - 1)).any(|a| {
        (j.saturating_sub(1)..=(j + 1).min(res - 1))
            .any(|b| (k.saturating_sub(1)..=(k + 1).min(res - 1)).any(|c| occ.get(a, b, c)))
    })
}

/// Occupancy at every cell equals the oracle at its sample, and the band (empty with an occupied
/// neighbour) is exactly what was emitted, in grid order.
fn assert_matches_brute_force(centers: &[DVec3], radii: &[f64], params: &RasterParams) {
    let res = params.res;
    let occ = occupancy(centers, radii, params, Backend::Cpu).expect("occupancy");
    let out = rasterize(centers, radii, params, Backend::Cpu).expect("rasterize");
    assert_eq!(out.n_occupied, occ.count_ones());
    let mut expected_points = Vec::new();
    for i in 0..res {
        for j in 0..res {
            for k in 0..res {
                let sample = cell_sample(params, [i as u32, j as u32, k as u32]);
                let lo = DVec3::new(i as f64, j as f64, k as f64) / res as f64;
                assert!(
                    sample.cmpge(lo).all()
                        && sample.cmplt(lo + DVec3::splat(1.0 / res as f64)).all()
                );
                let occupied = brute_occupied(res, centers, radii, sample);
                assert_eq!(occ.get(i, j, k), occupied, "res={res} cell {i} {j} {k}");
                if !occupied && has_occupied_neighbour(&occ, i, j, k) {
                    expected_points.push(sample);
                }
            }
        }
    }
    // The spheres' bounding box widened by one cell holds every band cell.
    assert_eq!(out.points, expected_points, "res={res}");
    assert!(centers.is_empty() || !out.points.is_empty());
}

#[test]
fn occupancy_and_band_match_brute_force_at_every_cell() {
    for (n, max_r, res, seed) in [
        (1, 0.3, 16, 1),
        (12, 0.2, 24, 2),
        (60, 0.12, 33, 3),
        (5, 0.9, 20, 4),
        (25, 0.25, 12, 77),
        (40, 0.5, 97, 6),
    ] {
        let (centers, radii) = random_spheres(n, seed, max_r);
        assert_matches_brute_force(&centers, &radii, &RasterParams { res, seed });
    }
}

/// Grids of several superblocks (64 cells; at 130 the last is partial): one sphere holds the
/// superblock of cells 64..127 on every axis (its farthest corner is 0.43 from the centre, inside
/// the shrunk radius 0.49), others hold blocks or cut it, small ones sit in the open space.
#[test]
fn held_superblocks_and_blocks_match_brute_force() {
    let (mut centers, mut radii) = random_spheres(30, 8, 0.12);
    centers.extend([
        DVec3::splat(0.74),
        DVec3::new(0.2, 0.3, 0.8),
        DVec3::new(0.9, 0.1, 0.2),
    ]);
    radii.extend([0.5, 0.3, 0.35]);
    for res in [128, 130] {
        assert_matches_brute_force(&centers, &radii, &RasterParams { res, seed: 5 });
    }
}

#[test]
fn same_points_at_any_thread_count() {
    let (centers, radii) = random_spheres(300, 11, 0.15);
    let params = RasterParams { res: 48, seed: 3 };
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| rasterize(&centers, &radii, &params, Backend::Cpu).expect("rasterize"))
    };
    assert_eq!(run(1), run(2));
    assert_eq!(run(1), run(4));
}

#[test]
fn bad_input_is_an_error() {
    let p = RasterParams { res: 16, seed: 0 };
    assert!(rasterize(&[DVec3::ZERO], &[0.1, 0.2], &p, Backend::Cpu).is_err());
    assert!(rasterize(&[DVec3::NAN], &[0.1], &p, Backend::Cpu).is_err());
    assert!(rasterize(&[DVec3::ZERO], &[-0.1], &p, Backend::Cpu).is_err());
    assert!(
        rasterize(
            &[DVec3::ZERO],
            &[0.1],
            &RasterParams { res: 0, seed: 0 },
            Backend::Cpu
        )
        .is_err()
    );
    assert!(
        rasterize(
            &[DVec3::ZERO],
            &[0.1],
            &RasterParams { res: 2048, seed: 0 },
            Backend::Cpu
        )
        .is_err()
    );
    // No spheres: nothing occupied, nothing emitted.
    let empty = rasterize(&[], &[], &p, Backend::Cpu).expect("empty");
    assert!(empty.points.is_empty() && empty.n_occupied == 0);
}

#[test]
fn default_resolution_follows_the_reference_heuristic() {
    // 64 * ceil(n^(1/3) / 16) on the paper's grids of (N + 1)^3 samples (rfta-reference.md table).
    for (n, r) in [
        (7, 64),
        (11, 64),
        (21, 128),
        (31, 128),
        (41, 192),
        (51, 256),
        (61, 256),
        (81, 384),
        (101, 448),
    ] {
        assert_eq!(rfta_raster::default_resolution(n * n * n), r, "N + 1 = {n}");
    }
}

/// CPU and GPU produce the same occupancy bits and points. Under CI the GPU (lavapipe) must be
/// present; elsewhere the test says it was skipped.
#[cfg(feature = "gpu")]
#[test]
#[expect(
    clippy::print_stderr,
    reason = "the test names the adapter it ran on, or says it was skipped"
)]
fn gpu_matches_cpu() {
    let Some(gpu) = rfta_raster::GpuRasterizer::shared() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "no GPU adapter under CI: install lavapipe (mesa-vulkan-drivers)"
        );
        eprintln!("SKIPPED gpu_matches_cpu: no GPU adapter");
        return;
    };
    eprintln!("gpu_matches_cpu on {}", gpu.describe());
    for (n, max_r, res, seed) in [
        (1, 0.3, 16, 1),
        (500, 0.1, 64, 2),
        (2000, 0.3, 96, 3),
        (50, 1.5, 40, 4),
    ] {
        let (centers, radii) = random_spheres(n, seed, max_r);
        let params = RasterParams { res, seed };
        let cpu = occupancy(&centers, &radii, &params, Backend::Cpu).expect("cpu");
        let gpu_bits = occupancy(&centers, &radii, &params, Backend::Gpu).expect("gpu");
        assert_eq!(cpu.count_ones(), gpu_bits.count_ones(), "n={n} res={res}");
        assert!(cpu == gpu_bits, "occupancy differs for n={n} res={res}");
        let a = rasterize(&centers, &radii, &params, Backend::Cpu).expect("cpu");
        let b = rasterize(&centers, &radii, &params, Backend::Gpu).expect("gpu");
        assert_eq!(b.backend, Backend::Gpu);
        assert_eq!(a.points, b.points);
    }
}
