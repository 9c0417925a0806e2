//! Tangency points against brute force and analytic shapes.

use rfta_feasible::{
    Params, TangentPoints, Tested, fine_tune, initial_points, local_search, resolve, transport,
};
use rfta_geom::rng::Rng;
use rfta_geom::{Grid, Sphere, glam::DVec3, shapes};
use rfta_sphere_tree::SphereTree;

/// Signed distance of `x` to the nearest other sphere's surface (brute force).
fn min_clearance(spheres: &[Sphere], i: usize, x: DVec3) -> f64 {
    spheres
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != i)
        .map(|(_, s)| (x - s.center).length() - s.radius)
        .fold(f64::INFINITY, f64::min)
}

fn random_spheres(n: usize, seed: u64) -> Vec<Sphere> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            Sphere::new(c, 0.05 + 0.15 * rng.next_f64())
        })
        .collect()
}

#[test]
fn local_search_results_are_on_their_sphere_and_outside_all_others() {
    let params = Params {
        k_search: 12,
        ..Params::default()
    };
    let mut found = 0;
    for seed in 0..20 {
        let spheres = random_spheres(60, seed);
        let tree = SphereTree::new(&spheres);
        for i in 0..spheres.len() {
            let s = spheres[i];
            let x0 = s.center + s.radius * DVec3::new(1.0, 0.3, -0.2).normalize();
            if let Some(x) = local_search(&spheres, &tree, i as u32, x0, &params) {
                found += 1;
                assert!(
                    ((x - s.center).length() - s.radius).abs() < 1e-9,
                    "off its sphere"
                );
                assert!(
                    min_clearance(&spheres, i, x) >= -params.tol - 1e-12,
                    "inside another"
                );
            }
        }
    }
    // Most spheres of these random sets have a free arc the search reaches.
    assert!(found > 20 * 60 / 2, "only {found} feasible");
}

#[test]
fn one_candidate_resolves_onto_the_intersection_circle() {
    let s = Sphere::new(DVec3::ZERO, 1.0);
    let other = Sphere::new(DVec3::new(1.2, 0.3, 0.0), 0.8);
    let y = resolve(&s, DVec3::new(0.9, 0.4, 0.2), &[other]);
    assert!(((y - s.center).length() - 1.0).abs() < 1e-12);
    assert!(((y - other.center).length() - 0.8).abs() < 1e-12);
}

#[test]
fn transport_stays_on_the_sphere_moves_at_most_tau_and_survives_antipodes() {
    let spheres = [Sphere::new(DVec3::splat(0.5), 0.3)];
    let tree = SphereTree::new(&spheres);
    let params = Params::default();
    let a = DVec3::new(0.8, 0.5, 0.5);
    for q in [DVec3::new(0.5, 0.8, 0.5), DVec3::new(0.2, 0.5, 0.5)] {
        let y = transport(&spheres, &tree, 0, a, q, &params, &mut Vec::new()).point();
        assert!(y.is_finite());
        assert!(((y - spheres[0].center).length() - 0.3).abs() < 1e-12);
        let angle = (a - spheres[0].center).angle_between(y - spheres[0].center);
        assert!(angle * 0.3 <= params.tau + 1e-12, "moved {}", angle * 0.3);
        assert!(angle > 0.0);
    }
}

/// Sphere SDF (radius 0.3 about the box centre) on an 11^3 grid of the unit box.
fn sphere_grid() -> (Vec<Sphere>, Vec<f64>) {
    let grid = Grid::cube(10, 0.0, 1.0).expect("grid");
    let c = DVec3::splat(0.5);
    let values: Vec<f64> = (0..grid.len())
        .map(|i| (grid.position(i) - c).length() - 0.3)
        .collect();
    let spheres = (0..grid.len())
        .map(|i| Sphere::new(grid.position(i), values[i].abs()))
        .collect();
    (spheres, values)
}

fn check_points(points: &TangentPoints, spheres: &[Sphere], params: &Params) {
    for ((&x, &n), &o) in points
        .points
        .iter()
        .zip(&points.normals)
        .zip(&points.owners)
    {
        let s = spheres[o as usize];
        assert!(((x - s.center).length() - s.radius).abs() < 1e-9);
        assert!(min_clearance(spheres, o as usize, x) >= -params.tol - 1e-12);
        assert!((n.length() - 1.0).abs() < 1e-12);
    }
}

/// Empty space: the points of a 40^3 lattice over the unit cube outside every sphere.
fn empty_space(spheres: &[Sphere]) -> Vec<DVec3> {
    (0..40)
        .flat_map(|i| (0..40).flat_map(move |j| (0..40).map(move |k| (i, j, k))))
        .map(|(i, j, k)| (DVec3::new(i as f64, j as f64, k as f64) + 0.5) / 40.0)
        .filter(|p| spheres.iter().all(|s| (*p - s.center).length() > s.radius))
        .collect()
}

#[test]
fn initial_points_of_a_sphere_sdf_are_feasible_and_hug_the_surface() {
    let (spheres, values) = sphere_grid();
    let params = Params {
        k_search: Params::k_search_for(spheres.len()),
        ..Params::default()
    };
    let all: Vec<u32> = (0..spheres.len() as u32).collect();
    let tree = SphereTree::new(&spheres);
    let empty = empty_space(&spheres);
    for set in [
        all.iter()
            .copied()
            .filter(|&i| values[i as usize] < 0.0)
            .collect::<Vec<u32>>(),
        all.iter()
            .copied()
            .filter(|&i| values[i as usize] >= 0.0)
            .collect(),
    ] {
        let pts = initial_points(&spheres, &values, &set, &empty, &tree, &params, None);
        assert!(
            pts.len() > set.len() * 9 / 10,
            "{} of {}",
            pts.len(),
            set.len()
        );
        check_points(&pts, &spheres, &params);
        // Each sphere of an exact SDF touches the surface; its feasible points are near it and
        // the normals agree with the sphere's outward normal there.
        let mean: f64 = pts
            .points
            .iter()
            .map(|&x| ((x - DVec3::splat(0.5)).length() - 0.3).abs())
            .sum::<f64>()
            / pts.len() as f64;
        assert!(mean < 0.02, "mean distance to the surface {mean}");
        let agree = pts
            .points
            .iter()
            .zip(&pts.normals)
            .filter(|&(&x, &n)| n.dot((x - DVec3::splat(0.5)).normalize()) > 0.5)
            .count();
        assert!(
            agree > pts.len() * 9 / 10,
            "{agree} of {} normals point out",
            pts.len()
        );
    }
}

#[test]
fn fine_tuning_against_the_true_surface_pulls_points_onto_it() {
    let (spheres, values) = sphere_grid();
    let params = Params {
        k_search: Params::k_search_for(spheres.len()),
        ..Params::default()
    };
    let tree = SphereTree::new(&spheres);
    let mut mesh = shapes::icosphere(0.3, 4);
    mesh.map_vertices(|v| v + DVec3::splat(0.5));
    // Start from no points at all: every sphere gets its second chance from the mesh.
    let mut cloud = TangentPoints::default();
    for _ in 0..3 {
        cloud = fine_tune(
            &spheres,
            &values,
            &mesh,
            &cloud,
            Tested::No,
            &tree,
            &params,
            None,
        );
        check_points(&cloud, &spheres, &params);
    }
    let d: Vec<f64> = cloud
        .points
        .iter()
        .map(|&x| ((x - DVec3::splat(0.5)).length() - 0.3).abs())
        .collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    assert!(
        cloud.len() >= spheres.len() * 9 / 10,
        "{} points",
        cloud.len()
    );
    assert!(mean < 2e-3, "mean distance {mean}");
}

/// Spheres of a set that keeps every other one as a constraint only.
struct EveryOther<'a>(&'a [Sphere]);

impl rfta_geom::SphereSet for EveryOther<'_> {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn sphere(&self, i: usize) -> Sphere {
        self.0[i]
    }

    fn owns(&self, i: usize) -> bool {
        i.is_multiple_of(2)
    }
}

/// A sphere its set says owns nothing gets no point, initial or fine-tuned, while the others get
/// theirs as with a set that lets every sphere own.
#[test]
fn spheres_the_set_keeps_as_constraints_own_no_point() {
    let (spheres, values) = sphere_grid();
    let params = Params {
        k_search: Params::k_search_for(spheres.len()),
        ..Params::default()
    };
    let tree = SphereTree::new(&spheres);
    let set = EveryOther(&spheres);
    let outside: Vec<u32> = (0..spheres.len() as u32)
        .filter(|&i| values[i as usize] > 0.0)
        .collect();
    let empty = empty_space(&spheres);
    let all = initial_points(&spheres, &values, &outside, &empty, &tree, &params, None);
    let some = initial_points(&set, &values, &outside, &empty, &tree, &params, None);
    let even = |c: &TangentPoints| c.owners.iter().filter(|&&o| o % 2 == 0).count();
    assert!(some.owners.iter().all(|&o| o % 2 == 0), "{:?}", some.owners);
    assert_eq!(some.len(), even(&all));
    assert!(
        some.len() > 10 && some.len() < all.len(),
        "{} of {}",
        some.len(),
        all.len()
    );
    let mut mesh = shapes::icosphere(0.3, 4);
    mesh.map_vertices(|v| v + DVec3::splat(0.5));
    let tuned = fine_tune(
        &set,
        &values,
        &mesh,
        &some,
        Tested::No,
        &tree,
        &params,
        None,
    );
    let tuned_all = fine_tune(
        &spheres,
        &values,
        &mesh,
        &all,
        Tested::No,
        &tree,
        &params,
        None,
    );
    assert!(tuned.owners.iter().all(|&o| o % 2 == 0));
    assert!(tuned.len() > 10 && tuned.len() < tuned_all.len());
}

/// The reference's transport, by brute force: halve the step until no other sphere holds the
/// point by more than `tol`, `q` when every halving fails.
fn transport_by_halving(
    spheres: &[Sphere],
    i: usize,
    a: DVec3,
    q: DVec3,
    params: &Params,
) -> DVec3 {
    let s = spheres[i];
    if (a - q).length() < params.tol
        || s.radius < params.tol
        || (a - s.center).length() < params.tol
    {
        return a;
    }
    let chord = ((a - q).length() / (2.0 * s.radius)).min(1.0);
    let mut arc = (params.tau / s.radius).min(2.0 * rfta_geom::math::asin(chord)) * s.radius;
    for _ in 0..params.halvings {
        let y = rfta_geom::kernels::transport_on_sphere(&s, a, q, arc);
        if min_clearance(spheres, i, y) >= -params.tol {
            return y;
        }
        arc *= 0.5;
    }
    q
}

#[test]
fn transport_equals_the_halving_rule_checked_by_brute_force() {
    // Crowded random spheres, so that many steps land inside a neighbour and get halved.
    let spheres = random_spheres(300, 11);
    let tree = SphereTree::new(&spheres);
    let mut rng = Rng::new(5);
    let mut halved = 0;
    for case in 0..2000 {
        let i = case % spheres.len();
        let s = spheres[i];
        let dir = |rng: &mut Rng| {
            DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            )
            .normalize_or(DVec3::X)
        };
        let a = s.center + s.radius * dir(&mut rng);
        let q = s.center + s.radius * dir(&mut rng);
        let params = Params {
            tau: [0.01, 0.05, 0.2][case % 3],
            ..Params::default()
        };
        let expect = transport_by_halving(&spheres, i, a, q, &params);
        let got = transport(&spheres, &tree, i as u32, a, q, &params, &mut Vec::new()).point();
        assert_eq!(got, expect, "case {case}");
        let full = rfta_geom::kernels::transport_on_sphere(&s, a, q, params.tau);
        halved += usize::from(got != full && got != q);
    }
    assert!(halved > 50, "only {halved} cases needed a halving");
}
