//! The tree against the brute-force oracle on random and adversarial sphere sets.

use proptest::prelude::*;
use rfta_geom::{Sphere, glam::DVec3, rng::Rng};
use rfta_sphere_tree::{SphereTree, naive};

fn random_spheres(n: usize, seed: u64, max_r: f64) -> Vec<Sphere> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            Sphere::new(c, rng.next_f64() * max_r)
        })
        .collect()
}

/// Checks every query form at `x` against the oracle.
fn check(spheres: &[Sphere], tree: &SphereTree, x: DVec3, ignore: Option<u32>) {
    for threshold in [-1e-4, 0.0, 1e-4, 0.05] {
        let expect = naive::inside_any(spheres, x, threshold, ignore);
        assert_eq!(
            tree.inside_any(x, threshold, ignore),
            expect,
            "inside_any at {x}, t={threshold}"
        );
        assert_eq!(
            tree.inside_any_reference_order(x, threshold, ignore),
            expect,
            "reference order at {x}"
        );
        let mut within = Vec::new();
        tree.spheres_within_into(x, threshold, ignore, &mut within);
        assert_eq!(
            within,
            naive::spheres_within(spheres, x, threshold, ignore),
            "spheres_within at {x}, t={threshold}"
        );
        for k in [1, 3, 17, usize::MAX] {
            assert_eq!(
                tree.spheres_containing(x, k, threshold, ignore),
                naive::spheres_containing(spheres, x, k, threshold, ignore),
                "spheres_containing at {x}, k={k}, t={threshold}"
            );
        }
    }
}

/// A direction drawn from the cube's corners' box, normalised (x when it is zero).
fn random_direction(rng: &mut Rng) -> DVec3 {
    DVec3::new(
        rng.next_f64() - 0.5,
        rng.next_f64() - 0.5,
        rng.next_f64() - 0.5,
    )
    .normalize_or(DVec3::X)
}

fn queries(spheres: &[Sphere], n: usize, seed: u64) -> Vec<(DVec3, Option<u32>)> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|q| {
            if q % 2 == 0 || spheres.is_empty() {
                // Anywhere around the unit box.
                (
                    DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 1.4
                        - DVec3::splat(0.2),
                    None,
                )
            } else {
                // On a sphere's surface, ignoring it: the reconstruction's query.
                let i = rng.below(spheres.len() as u64) as usize;
                let dir = random_direction(&mut rng);
                (spheres[i].center + spheres[i].radius * dir, Some(i as u32))
            }
        })
        .collect()
}

#[test]
fn agrees_with_oracle_on_random_sets() {
    for (n, max_r, seed) in [(1, 0.3, 1), (7, 0.3, 2), (500, 0.05, 3), (2000, 0.2, 4)] {
        let spheres = random_spheres(n, seed, max_r);
        let tree = SphereTree::new(&spheres);
        assert_eq!(tree.len(), n);
        for (x, ignore) in queries(&spheres, 300, seed + 100) {
            check(&spheres, &tree, x, ignore);
        }
    }
}

#[test]
fn agrees_with_oracle_on_adversarial_sets() {
    // Heavily overlapping: an SDF-like grid of spheres whose radii reach the surface of a ball.
    let mut sdf_like = Vec::new();
    for i in 0..12 {
        for j in 0..12 {
            for k in 0..12 {
                let p = DVec3::new(i as f64, j as f64, k as f64) / 11.0;
                sdf_like.push(Sphere::new(
                    p,
                    ((p - DVec3::splat(0.5)).length() - 0.3).abs(),
                ));
            }
        }
    }
    // Coincident spheres (equal and unequal radii), zero radii, and one huge sphere covering all.
    let mut degenerate = vec![Sphere::new(DVec3::splat(0.5), 0.2); 40];
    degenerate.extend((0..40).map(|i| Sphere::new(DVec3::splat(0.5), 0.005 * i as f64)));
    degenerate.extend((0..40).map(|i| Sphere::new(DVec3::splat(i as f64 / 40.0), 0.0)));
    degenerate.push(Sphere::new(DVec3::splat(0.5), 10.0));
    for (set, seed) in [(sdf_like, 7), (degenerate, 8)] {
        let tree = SphereTree::new(&set);
        for (x, ignore) in queries(&set, 400, seed) {
            check(&set, &tree, x, ignore);
        }
        // Query exactly at centres, including coincident ones.
        for (i, s) in set.iter().enumerate().step_by(7) {
            check(&set, &tree, s.center, Some(i as u32));
        }
    }
}

/// The nodes' bounds are `f32`: far from the origin their rounding is larger than the gap
/// between a query's threshold and a sphere's signed distance. Spheres of one radius around
/// (1000, -2000, 500) (an `f32` ulp there is 6e-5 to 1.2e-4), queried from the sphere farthest
/// along each axis, just beyond it along that axis, at signed distance 1e-9 below each
/// threshold: every node that holds that sphere has it at its centre box's face, so its exact
/// bound is 1e-9 below the threshold. The tree must still find it, as the oracle does; a bound
/// rounded the wrong way prunes it. Then random directions from random spheres of random radii.
#[test]
fn agrees_with_oracle_where_f32_rounding_exceeds_the_margin() {
    let offset = DVec3::new(1000.0, -2000.0, 500.0);
    for (n, seed) in [(40, 1), (3000, 2), (20000, 3)] {
        let mut draw = Rng::new(seed);
        let spheres: Vec<Sphere> = (0..n)
            .map(|_| {
                let c = DVec3::new(draw.next_f64(), draw.next_f64(), draw.next_f64());
                Sphere::new(offset + c, 0.01)
            })
            .collect();
        let tree = SphereTree::new(&spheres);
        for axis in [
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            -DVec3::X,
            -DVec3::Y,
            -DVec3::Z,
        ] {
            let far = (0..n)
                .max_by(|&a, &b| {
                    spheres[a]
                        .center
                        .dot(axis)
                        .total_cmp(&spheres[b].center.dot(axis))
                })
                .expect("spheres");
            for threshold in [-1e-4, 1e-4] {
                let x = spheres[far].center + (0.01 + threshold - 1e-9) * axis;
                assert!(naive::inside_any(&spheres, x, threshold, None));
                check(&spheres, &tree, x, None);
            }
        }
    }
    let mut rng = Rng::new(11);
    let spheres: Vec<Sphere> = (0..3000)
        .map(|_| {
            let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            Sphere::new(offset + c, 0.002 + 0.02 * rng.next_f64())
        })
        .collect();
    let tree = SphereTree::new(&spheres);
    for q in 0..400 {
        let i = rng.below(spheres.len() as u64) as usize;
        let dir = random_direction(&mut rng);
        for threshold in [-1e-4, 1e-4] {
            let x = spheres[i].center + (spheres[i].radius + threshold - 1e-9) * dir;
            let ignore = (q % 2 == 0).then_some(i as u32 ^ 1);
            assert!(naive::inside_any(&spheres, x, threshold, None));
            check(&spheres, &tree, x, ignore);
        }
    }
}

#[test]
fn batches_are_seeded_subsets_drawn_with_replacement() {
    let spheres = random_spheres(1000, 5, 0.1);
    let a = SphereTree::batch(&spheres, 300, 42);
    assert_eq!(a.indices(), SphereTree::batch(&spheres, 300, 42).indices());
    assert_ne!(a.indices(), SphereTree::batch(&spheres, 300, 43).indices());
    // With replacement: about n (1 - exp(-b/n)) = 259 distinct of 300 draws (sd ~ 6).
    assert!((235..285).contains(&a.len()), "{} distinct", a.len());
    assert_eq!(SphereTree::batch(&spheres, 0, 1).len(), 1000);
    assert_eq!(SphereTree::batch(&spheres, 5000, 1).len(), 1000);
    // Queries over a batch see exactly the batch.
    let chosen: Vec<Sphere> = a.indices().iter().map(|&i| spheres[i as usize]).collect();
    let map = a.indices();
    for (x, _) in queries(&spheres, 200, 9) {
        let expect: Vec<u32> = naive::spheres_containing(&chosen, x, 5, 1e-4, None)
            .iter()
            .map(|&j| map[j as usize])
            .collect();
        assert_eq!(a.spheres_containing(x, 5, 1e-4, None), expect);
    }
}

#[test]
fn empty_tree_answers_nothing() {
    let tree = SphereTree::new(&[] as &[Sphere]);
    assert!(tree.is_empty());
    assert!(!tree.inside_any(DVec3::ZERO, 1.0, None));
    assert!(
        tree.spheres_containing(DVec3::ZERO, 3, 1.0, None)
            .is_empty()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn agrees_with_oracle_on_arbitrary_sets(seed in 0u64..100_000, n in 1usize..200, max_r in 0.0f64..0.6) {
        let spheres = random_spheres(n, seed, max_r);
        let tree = SphereTree::new(&spheres);
        for (x, ignore) in queries(&spheres, 20, seed ^ 0xABCD) {
            check(&spheres, &tree, x, ignore);
        }
    }
}
