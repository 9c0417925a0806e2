//! Property and example tests of the kernels.

use glam::DVec3;
use proptest::prelude::*;

use super::*;
use crate::Sphere;

fn vec3(range: f64) -> impl Strategy<Value = DVec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn sphere() -> impl Strategy<Value = Sphere> {
    (vec3(2.0), 0.01f64..2.0).prop_map(|(c, r)| Sphere::new(c, r))
}

/// Relative tolerance for "lies on the sphere": 1e-12 of the configuration's size.
fn on_sphere(s: &Sphere, p: DVec3, size: f64) -> bool {
    s.signed_distance(p).abs() <= 1e-12 * size.max(1.0) * 8.0
}

proptest! {
    #[test]
    fn circle_points_lie_on_both_spheres(a in sphere(), b in sphere(), x in vec3(4.0)) {
        if let SphereSphere::Circle(circle) = sphere_sphere_circle(&a, &b) {
            let p = closest_point_on_circle(&circle, x);
            let size = a.radius + b.radius + a.center.length() + b.center.length();
            prop_assert!(on_sphere(&a, p, size), "off a by {}", a.signed_distance(p));
            prop_assert!(on_sphere(&b, p, size), "off b by {}", b.signed_distance(p));
            prop_assert!((circle.normal.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn circle_classification_matches_distances(a in sphere(), b in sphere()) {
        let d = a.center.distance(b.center);
        match sphere_sphere_circle(&a, &b) {
            SphereSphere::Separate => prop_assert!(d > a.radius + b.radius),
            SphereSphere::Nested => prop_assert!(d < (a.radius - b.radius).abs()),
            SphereSphere::Coincident => prop_assert!(d == 0.0 && a.radius == b.radius),
            SphereSphere::Circle(c) => {
                prop_assert!(d <= a.radius + b.radius && d >= (a.radius - b.radius).abs());
                prop_assert!(c.radius <= a.radius.min(b.radius) + 1e-12);
            }
        }
    }

    #[test]
    fn closest_point_on_circle_beats_other_circle_points(
        c in vec3(2.0), n in vec3(1.0), r in 0.0f64..2.0, x in vec3(4.0), t in 0.0f64..std::f64::consts::TAU
    ) {
        prop_assume!(n.length() > 1e-3);
        let circle = Circle { center: c, normal: n.normalize(), radius: r };
        let p = closest_point_on_circle(&circle, x);
        prop_assert!(((p - c).length() - r).abs() < 1e-12 * 8.0);
        prop_assert!((p - c).dot(circle.normal).abs() < 1e-12 * 8.0);
        // Any other point of the circle is at least as far from x.
        let u = fallback_perpendicular(circle.normal);
        let v = circle.normal.cross(u);
        let q = c + r * (u * t.cos() + v * t.sin());
        prop_assert!(x.distance(p) <= x.distance(q) + 1e-12);
    }

    #[test]
    fn trilateration_points_lie_on_all_three(a in sphere(), b in sphere(), c in sphere()) {
        if let Some(points) = trilaterate(&a, &b, &c) {
            let size = [a, b, c].iter().map(|s| s.radius + s.center.length()).sum::<f64>();
            for p in points {
                prop_assert!(p.is_finite());
                for s in [&a, &b, &c] {
                    // Trilateration divides by the frame's j, so conditioning costs digits: allow
                    // 1e-9 relative (stated tolerance for the worst conditioned random triples).
                    prop_assert!(s.signed_distance(p).abs() <= 1e-9 * size, "off by {}", s.signed_distance(p));
                }
            }
        }
    }

    #[test]
    fn trilateration_recovers_constructed_points(p in vec3(1.0), c1 in vec3(1.0), c2 in vec3(1.0), c3 in vec3(1.0)) {
        // Three spheres through p with well-separated, non-collinear centres must return p.
        let (b2, b3) = (c2 - c1, c3 - c1);
        prop_assume!(b2.length() > 0.1 && b3.length() > 0.1 && b2.cross(b3).length() > 0.05);
        let s = |c: DVec3| Sphere::new(c, c.distance(p));
        let found = trilaterate(&s(c1), &s(c2), &s(c3));
        prop_assert!(found.is_some());
        let [q1, q2] = found.unwrap_or([DVec3::NAN; 2]);
        prop_assert!(q1.distance(p).min(q2.distance(p)) < 1e-6, "{q1} {q2} vs {p}");
    }

    #[test]
    fn projection_lands_on_sphere(s in sphere(), x in vec3(4.0)) {
        let p = project_onto_sphere(&s, x);
        prop_assert!(on_sphere(&s, p, s.radius + s.center.length()));
    }

    #[test]
    fn transport_keeps_radius_and_moves_the_arc_length(
        s in sphere(), a in vec3(4.0), q in vec3(4.0), arc in 0.0f64..3.0
    ) {
        let p = transport_on_sphere(&s, a, q, arc);
        prop_assert!(p.is_finite());
        prop_assert!(on_sphere(&s, p, s.radius + s.center.length()));
        let start = project_onto_sphere(&s, a);
        let target = project_onto_sphere(&s, q);
        let angle = |u: DVec3, v: DVec3| {
            let (u, v) = (u - s.center, v - s.center);
            u.cross(v).length().atan2(u.dot(v))
        };
        let total = angle(start, target);
        let moved = angle(start, p);
        let expected = (arc / s.radius).min(total);
        prop_assert!((moved - expected).abs() < 1e-7, "moved {moved} expected {expected}");
        // Moving along the great circle towards the target never increases the angle to it.
        prop_assert!(angle(p, target) <= total + 1e-9);
    }

    #[test]
    fn segment_triangle_agrees_with_orientation_predicates(
        a in vec3(2.0), b in vec3(2.0), p0 in vec3(1.0), p1 in vec3(1.0), p2 in vec3(1.0)
    ) {
        // The segment crosses the triangle when its ends lie on opposite sides of the
        // triangle's plane and the three tetrahedra it forms with the edges agree in sign.
        let orient = |p: DVec3, q: DVec3, r: DVec3, s: DVec3| (q - p).cross(r - p).dot(s - p);
        let (sa, sb) = (orient(p0, p1, p2, a), orient(p0, p1, p2, b));
        let edges = [orient(a, b, p0, p1), orient(a, b, p1, p2), orient(a, b, p2, p0)];
        // Skip configurations within rounding of a boundary, where either answer is right.
        let tiny = 1e-9;
        prop_assume!(sa.abs() > tiny && sb.abs() > tiny && edges.iter().all(|e| e.abs() > tiny));
        let crosses = (sa > 0.0) != (sb > 0.0)
            && (edges.iter().all(|&e| e > 0.0) || edges.iter().all(|&e| e < 0.0));
        let hit = segment_triangle(a, b, p0, p1, p2);
        prop_assert_eq!(hit.is_some(), crosses);
        if let Some(t) = hit {
            // The crossing point lies in the triangle's plane.
            let x = a + t * (b - a);
            let n = (p1 - p0).cross(p2 - p0).normalize();
            prop_assert!((x - p0).dot(n).abs() < 1e-9);
        }
    }

    #[test]
    fn closest_point_on_triangle_beats_brute_force(
        p in vec3(3.0), a in vec3(1.0), b in vec3(1.0), c in vec3(1.0)
    ) {
        let (q, bary) = closest_point_on_triangle(p, a, b, c);
        prop_assert!(bary.iter().all(|w| *w >= -1e-12 && *w <= 1.0 + 1e-12));
        prop_assert!((bary.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        prop_assert!(q.distance(bary[0] * a + bary[1] * b + bary[2] * c) < 1e-9);
        // Brute force over a barycentric lattice: none is closer.
        let n = 40;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let x = a + u * (b - a) + v * (c - a);
                prop_assert!(p.distance(q) <= p.distance(x) + 1e-12);
            }
        }
    }
}

#[test]
fn transport_handles_antipodal_and_coincident_points() {
    let s = Sphere::new(DVec3::new(0.5, 0.5, 0.5), 0.25);
    let a = s.center + DVec3::new(0.0, 0.0, 0.25);
    let q = s.center - DVec3::new(0.0, 0.0, 0.25);
    let quarter = 0.25 * std::f64::consts::FRAC_PI_2;
    let p = transport_on_sphere(&s, a, q, quarter);
    assert!(p.is_finite());
    assert!(
        (p - s.center).z.abs() < 1e-15,
        "a quarter turn from the pole reaches the equator: {p}"
    );
    assert_eq!(transport_on_sphere(&s, a, a, 1.0), a);
    // A point at the centre has no direction: it is projected along +x, never NaN.
    assert!(transport_on_sphere(&s, s.center, q, 0.1).is_finite());
    // Zero radius: the centre.
    assert_eq!(
        transport_on_sphere(&Sphere::new(DVec3::ONE, 0.0), DVec3::ZERO, DVec3::X, 1.0),
        DVec3::ONE
    );
}

#[test]
fn degenerate_sphere_pairs_and_triples() {
    let a = Sphere::new(DVec3::ZERO, 1.0);
    assert_eq!(sphere_sphere_circle(&a, &a), SphereSphere::Coincident);
    assert_eq!(
        sphere_sphere_circle(&a, &Sphere::new(DVec3::ZERO, 0.5)),
        SphereSphere::Nested
    );
    assert_eq!(
        sphere_sphere_circle(&a, &Sphere::new(DVec3::X * 3.0, 1.0)),
        SphereSphere::Separate
    );
    // Touching spheres meet in a circle of radius zero at the touching point.
    let touch = sphere_sphere_circle(&a, &Sphere::new(DVec3::X * 2.0, 1.0)).circle();
    assert_eq!(touch.map(|c| (c.center, c.radius)), Some((DVec3::X, 0.0)));
    // Collinear and coincident centres have no isolated common points.
    let b = Sphere::new(DVec3::X, 1.0);
    assert_eq!(trilaterate(&a, &b, &Sphere::new(DVec3::X * 2.0, 1.0)), None);
    assert_eq!(trilaterate(&a, &a, &b), None);
    // Three unit spheres around the origin's octant meet at two mirror points.
    let pts = trilaterate(
        &Sphere::new(DVec3::X, 1.0),
        &Sphere::new(DVec3::Y, 1.0),
        &Sphere::new(DVec3::Z, 1.0),
    );
    let pts = pts.expect("three unit spheres at the axes meet");
    // The common points are (0,0,0) and (2/3,2/3,2/3).
    let expected = [DVec3::ZERO, DVec3::splat(2.0 / 3.0)];
    for e in expected {
        assert!(
            pts.iter().any(|p| p.distance(e) < 1e-14),
            "{pts:?} misses {e}"
        );
    }
}

#[test]
fn closest_point_on_degenerate_triangles() {
    let (a, b) = (DVec3::ZERO, DVec3::X);
    // Collinear vertices: the closest point of the segment.
    let (q, _) = closest_point_on_triangle(DVec3::new(0.5, 1.0, 0.0), a, b, DVec3::X * 0.5);
    assert!(q.distance(DVec3::new(0.5, 0.0, 0.0)) < 1e-15);
    // All three vertices equal.
    let (q, _) = closest_point_on_triangle(DVec3::ONE, a, a, a);
    assert_eq!(q, a);
}

#[test]
fn solid_angles_of_a_closed_octahedron_sum_to_4pi_inside_and_0_outside() {
    let mesh = crate::shapes::octahedron(1.0);
    let total = |p: DVec3| -> f64 {
        mesh.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| mesh.vertices[i as usize]);
                solid_angle(p, a, b, c)
            })
            .sum()
    };
    assert!((total(DVec3::new(0.1, -0.2, 0.05)) - 4.0 * std::f64::consts::PI).abs() < 1e-12);
    assert!(total(DVec3::new(2.0, 0.3, 0.1)).abs() < 1e-12);
}
