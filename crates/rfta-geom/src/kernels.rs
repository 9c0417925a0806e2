//! Robust geometric kernels on spheres, circles and triangles.
//!
//! Every function here returns a finite result for finite input, including the degenerate
//! configurations the reconstruction runs into: coincident or concentric spheres, collinear
//! centres, a point at a sphere's centre or on a circle's axis, antipodal transport, and
//! zero-area triangles. Where a direction is undefined, the functions pick a fixed one
//! (see [`fallback_perpendicular`]), so results are deterministic.

use glam::DVec3;

use crate::Sphere;

/// A circle in space: centre, unit normal of its plane, radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    /// The centre.
    pub center: DVec3,
    /// Unit normal of the circle's plane.
    pub normal: DVec3,
    /// The radius (non-negative; zero when two spheres touch in one point).
    pub radius: f64,
}

/// How two spheres meet; see [`sphere_sphere_circle`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SphereSphere {
    /// The spheres are identical (same centre, same radius): they share every point.
    Coincident,
    /// The spheres are apart: the distance between centres exceeds the sum of radii.
    Separate,
    /// One sphere lies strictly inside the other (this includes concentric spheres of different radii).
    Nested,
    /// The spheres' surfaces meet in this circle (of radius zero when they touch).
    Circle(Circle),
}

impl SphereSphere {
    /// The intersection circle, if the surfaces meet in one.
    pub fn circle(self) -> Option<Circle> {
        match self {
            SphereSphere::Circle(c) => Some(c),
            _ => None,
        }
    }
}

/// The circle where the surfaces of two spheres meet.
///
/// With `d = |b.c - a.c|`, the circle's plane is at distance `(ra^2 - rb^2 + d^2) / (2 d)` from
/// `a.c` along the line of centres, and its radius is `sqrt(ra^2 - that^2)`.
/// Surfaces that touch give a circle of radius zero.
pub fn sphere_sphere_circle(a: &Sphere, b: &Sphere) -> SphereSphere {
    let delta = b.center - a.center;
    let d = delta.length();
    if d == 0.0 {
        return if a.radius == b.radius {
            SphereSphere::Coincident
        } else {
            SphereSphere::Nested
        };
    }
    if d > a.radius + b.radius {
        return SphereSphere::Separate;
    }
    if d < (a.radius - b.radius).abs() {
        return SphereSphere::Nested;
    }
    let normal = delta / d;
    // Distance from a's centre to the circle's plane, clamped to [-ra, ra] against rounding.
    let along = ((a.radius * a.radius - b.radius * b.radius + d * d) / (2.0 * d))
        .clamp(-a.radius, a.radius);
    // ra^2 - along^2, factored to limit cancellation.
    let h2 = (a.radius - along) * (a.radius + along);
    SphereSphere::Circle(Circle {
        center: a.center + along * normal,
        normal,
        radius: h2.max(0.0).sqrt(),
    })
}

/// The points common to three spheres' surfaces (trilateration, Fang 1986).
///
/// Returns `None` when there are none, and also when the configuration is degenerate (two
/// centres coincide or the three are collinear), where the common set is a circle or undefined.
/// When the spheres touch in a single point, both entries are that point.
///
/// In the frame with `a.c` at the origin, `ex` towards `b.c` and `ey` in the plane of the
/// three centres, the points are `(X, Y, +-Z)` with
/// `X = (ra^2 - rb^2 + d^2) / 2d`, `Y = (ra^2 - rc^2 + i^2 + j^2) / 2j - (i/j) X`,
/// `Z^2 = ra^2 - X^2 - Y^2`, where `d = |b.c - a.c|` and `(i, j)` are the frame coordinates of `c.c`.
///
/// B. T. Fang, "Trilateration and extension to Global Positioning System navigation",
/// Journal of Guidance, Control, and Dynamics 9(6), 1986.
pub fn trilaterate(a: &Sphere, b: &Sphere, c: &Sphere) -> Option<[DVec3; 2]> {
    let b2 = b.center - a.center;
    let b3 = c.center - a.center;
    let d = b2.length();
    let scale = d.max(b3.length());
    if d <= f64::EPSILON * scale.max(f64::MIN_POSITIVE) || !scale.is_finite() {
        return None;
    }
    let ex = b2 / d;
    let i = ex.dot(b3);
    let perp = b3 - i * ex;
    let j = perp.length();
    // Collinear (or c coincides with a): relative threshold on the off-line component.
    if j <= 1e-12 * scale {
        return None;
    }
    let ey = perp / j;
    let ez = ex.cross(ey);
    let (ra2, rb2, rc2) = (
        a.radius * a.radius,
        b.radius * b.radius,
        c.radius * c.radius,
    );
    let x = (ra2 - rb2 + d * d) / (2.0 * d);
    let y = (ra2 - rc2 + i * i + j * j) / (2.0 * j) - (i / j) * x;
    let mut z2 = ra2 - x * x - y * y;
    // Accept a rounding-level negative as tangency.
    let slack = 1e-12 * (ra2 + x * x + y * y);
    if z2 < -slack {
        return None;
    }
    z2 = z2.max(0.0);
    let z = z2.sqrt();
    let base = a.center + x * ex + y * ey;
    Some([base + z * ez, base - z * ez])
}

/// The point of `circle` closest to `x`.
///
/// When `x` lies on the circle's axis every point is equally close; the point in the direction
/// [`fallback_perpendicular`]`(normal)` from the centre is returned.
pub fn closest_point_on_circle(circle: &Circle, x: DVec3) -> DVec3 {
    let v = x - circle.center;
    let in_plane = v - circle.normal * v.dot(circle.normal);
    let len = in_plane.length();
    let dir = if len > 0.0 && len.is_finite() {
        in_plane / len
    } else {
        fallback_perpendicular(circle.normal)
    };
    circle.center + circle.radius * dir
}

/// Radial projection of `x` onto the sphere's surface.
///
/// A point at the centre projects in the `+x` direction.
pub fn project_onto_sphere(sphere: &Sphere, x: DVec3) -> DVec3 {
    let v = x - sphere.center;
    let len = v.length();
    let dir = if len > 0.0 && len.is_finite() {
        v / len
    } else {
        DVec3::X
    };
    sphere.center + sphere.radius * dir
}

/// Transport along a great circle: the point reached by moving from `from` towards `to` on the
/// sphere by arc length `arc_length` (capped at the whole arc, so `to`'s projection is never passed).
///
/// Both points are first projected radially onto the sphere. When they coincide the start is
/// returned; when they are antipodal every great circle joins them, and the one turning about
/// [`fallback_perpendicular`] of the start direction is used. A negative `arc_length` counts as zero.
/// This is the paper's transport step (Sellán et al. 2024, §4.3) without its antipodal NaN.
pub fn transport_on_sphere(sphere: &Sphere, from: DVec3, to: DVec3, arc_length: f64) -> DVec3 {
    let start = project_onto_sphere(sphere, from);
    if sphere.radius <= 0.0 {
        return start;
    }
    let u = (start - sphere.center) / sphere.radius;
    let w = (project_onto_sphere(sphere, to) - sphere.center) / sphere.radius;
    let cross = u.cross(w);
    let sin = cross.length();
    let cos = u.dot(w);
    let total = crate::math::atan2(sin, cos);
    let theta = (arc_length.max(0.0) / sphere.radius).min(total);
    if theta.is_nan() || theta <= 0.0 {
        return start;
    }
    let axis = if sin > 1e-300 {
        cross / sin
    } else {
        fallback_perpendicular(u)
    };
    // Rodrigues' rotation of u about an axis perpendicular to it.
    let rotated = u * crate::math::cos(theta) + axis.cross(u) * crate::math::sin(theta);
    sphere.center + sphere.radius * rotated.normalize_or(u)
}

/// A unit vector perpendicular to `n`, fixed for each direction (for degenerate cases).
///
/// `n` need not be normalised; for a zero vector the result is `+x`.
pub fn fallback_perpendicular(n: DVec3) -> DVec3 {
    let a = n.abs();
    // Cross with the axis least aligned with n.
    let axis = if a.x <= a.y && a.x <= a.z {
        DVec3::X
    } else if a.y <= a.z {
        DVec3::Y
    } else {
        DVec3::Z
    };
    n.cross(axis).normalize_or(DVec3::X)
}

/// The point of triangle `(a, b, c)` closest to `p`, with its barycentric coordinates.
///
/// Region-based: the closest feature (vertex, edge or face) is found from the signs of a few dot
/// products, as in Ericson, *Real-Time Collision Detection* (2005), §5.1.5. Zero-area triangles
/// fall back to the closest of the three edges.
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, [f64; 3]) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let t = d1 / (d1 - d3);
        if t.is_finite() {
            return (a + t * ab, [1.0 - t, t, 0.0]);
        }
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let t = d2 / (d2 - d6);
        if t.is_finite() {
            return (a + t * ac, [1.0 - t, 0.0, t]);
        }
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        if t.is_finite() {
            return (b + t * (c - b), [0.0, 1.0 - t, t]);
        }
    }
    let denom = va + vb + vc;
    let (v, w) = (vb / denom, vc / denom);
    if denom > 0.0 && v.is_finite() && w.is_finite() {
        return (a + ab * v + ac * w, [1.0 - v - w, v, w]);
    }
    closest_on_edges(p, a, b, c)
}

/// Closest point on the three edges of a (degenerate) triangle.
fn closest_on_edges(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, [f64; 3]) {
    let seg = |u: DVec3, v: DVec3| -> (DVec3, f64) {
        let e = v - u;
        let len2 = e.length_squared();
        let t = if len2 > 0.0 {
            ((p - u).dot(e) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (u + t * e, t)
    };
    let (q_ab, t_ab) = seg(a, b);
    let (q_bc, t_bc) = seg(b, c);
    let (q_ca, t_ca) = seg(c, a);
    let cands = [
        (q_ab, [1.0 - t_ab, t_ab, 0.0]),
        (q_bc, [0.0, 1.0 - t_bc, t_bc]),
        (q_ca, [t_ca, 0.0, 1.0 - t_ca]),
    ];
    let mut best = cands[0];
    for cand in &cands[1..] {
        if p.distance_squared(cand.0) < p.distance_squared(best.0) {
            best = *cand;
        }
    }
    best
}

/// Where the segment from `a` to `b` crosses the triangle `(p0, p1, p2)`: the parameter `t` in
/// `[0, 1]` of the crossing point `a + t (b - a)`, or `None` when they do not meet.
///
/// The triangle includes its edges. A segment in the triangle's plane, or a degenerate triangle,
/// counts as not crossing (there is no single crossing point). Moeller and Trumbore, "Fast,
/// minimum storage ray-triangle intersection", Journal of Graphics Tools 2(1), 1997, with the
/// ray's parameter limited to the segment.
pub fn segment_triangle(a: DVec3, b: DVec3, p0: DVec3, p1: DVec3, p2: DVec3) -> Option<f64> {
    let dir = b - a;
    let (e1, e2) = (p1 - p0, p2 - p0);
    let pv = dir.cross(e2);
    let det = e1.dot(pv);
    // Parallel to the plane (relative to the sizes involved), or a degenerate triangle.
    let scale = dir.length() * e1.length() * e2.length();
    // (Written so that a NaN determinant also returns.)
    if det.abs().partial_cmp(&(1e-14 * scale)) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let inv = 1.0 / det;
    let tv = a - p0;
    let u = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = dir.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv;
    (0.0..=1.0).contains(&t).then_some(t)
}

/// Signed solid angle subtended at `p` by triangle `(a, b, c)`, in steradians (in `[-2pi, 2pi]`).
///
/// Positive when the triangle is seen counter-clockwise, i.e. `p` is on the side its normal
/// `(b - a) x (c - a)` points away from. Van Oosterom and Strackee, "The solid angle of a plane
/// triangle", IEEE Trans. Biomedical Engineering 30(2), 1983:
/// `tan(omega/2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|)` with `a, b, c` relative to `p`.
pub fn solid_angle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (a, b, c) = (a - p, b - p, c - p);
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let det = a.dot(b.cross(c));
    let div = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * crate::math::atan2(det, div)
}

#[cfg(test)]
mod tests;
