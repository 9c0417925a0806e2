//! The sphere tree and the rasterizer on the real SDF grids: the tree agrees with brute force on
//! the reconstruction's own queries, and empty-space samples lie outside the spheres of their sign.

use rfta_geom::{Layout, Sphere, glam::DVec3, rng::Rng};
use rfta_raster::{Backend, RasterParams, rasterize};
use rfta_sphere_tree::{SphereTree, naive};

/// The spheres of one input's `sdf_n20.npy`, normalised to the unit box as the reference does.
fn spheres(name: &str) -> Option<Vec<(Sphere, bool)>> {
    let data = rfta_testkit::data_dir_or_skip("spheres")?;
    let raw =
        rfta_io::read_sdf(&data.join("inputs").join(name).join("sdf_n20.npy"), None).expect("grid");
    let Layout::Grid(grid) = raw.layout else {
        panic!("not a grid")
    };
    Some(
        raw.values
            .iter()
            .enumerate()
            .map(|(i, s)| {
                (
                    Sphere::new((grid.position(i) + DVec3::ONE) * 0.5, s.abs() * 0.5),
                    *s < 0.0,
                )
            })
            .collect(),
    )
}

#[test]
fn tree_agrees_with_oracle_on_real_grids() {
    for name in ["bunny", "thingi54725"] {
        let Some(all) = spheres(name) else { return };
        let set: Vec<Sphere> = all.iter().map(|(s, _)| *s).collect();
        let tree = SphereTree::new(&set);
        let batch = SphereTree::batch(&set, 2000, 3);
        let batch_ids = batch.indices();
        let batch_set: Vec<Sphere> = batch_ids.iter().map(|&i| set[i as usize]).collect();
        let mut rng = Rng::new(1);
        for _ in 0..400 {
            let i = rng.below(set.len() as u64) as usize;
            let dir = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            )
            .normalize_or(DVec3::X);
            let x = set[i].center + set[i].radius * dir;
            let ignore = Some(i as u32);
            assert_eq!(
                tree.inside_any(x, -1e-4, ignore),
                naive::inside_any(&set, x, -1e-4, ignore),
                "{name}"
            );
            assert_eq!(
                tree.spheres_containing(x, 42, 1e-4, ignore),
                naive::spheres_containing(&set, x, 42, 1e-4, ignore)
            );
            // Over a batch: the oracle on the batch's spheres, with the ignored sphere mapped into it.
            let local_ignore = batch_ids.binary_search(&(i as u32)).ok().map(|j| j as u32);
            let expect: Vec<u32> = naive::spheres_containing(&batch_set, x, 42, 1e-4, local_ignore)
                .iter()
                .map(|&j| batch_ids[j as usize])
                .collect();
            assert_eq!(
                batch.spheres_containing(x, 42, 1e-4, ignore),
                expect,
                "{name} batch"
            );
        }
    }
}

#[test]
fn empty_space_samples_lie_outside_their_sign_set() {
    let Some(all) = spheres("bob") else { return };
    for inside in [true, false] {
        let (centers, radii): (Vec<DVec3>, Vec<f64>) = all
            .iter()
            .filter(|(_, neg)| *neg == inside)
            .map(|(s, _)| (s.center, s.radius))
            .unzip();
        let params = RasterParams {
            res: rfta_raster::default_resolution(all.len()),
            seed: 5,
        };
        let out = rasterize(&centers, &radii, &params, Backend::Cpu).expect("raster");
        assert!(!out.points.is_empty());
        let set: Vec<Sphere> = centers
            .iter()
            .zip(&radii)
            .map(|(c, r)| Sphere::new(*c, 0.95f64.sqrt() * r))
            .collect();
        let tree = SphereTree::new(&set);
        // Outside every shrunk sphere, up to the lattice step by which centres are rounded.
        let step = 1.0 / (params.res as f64 * rfta_raster::SUBCELLS as f64);
        for p in &out.points {
            assert!(
                !tree.inside_any(*p, -step, None),
                "sample {p} is inside a sphere of its sign"
            );
        }
        // The GPU path (when present) emits the same samples.
        if let Ok(gpu) = rasterize(&centers, &radii, &params, Backend::Gpu) {
            assert_eq!(gpu.points, out.points);
        }
    }
}
