//! Shapes whose exact signed distance is known (negative inside), for examples, demos and tests
//! that compare against the shape rather than against rfta's own output.

use glam::DVec3;

/// Shapes with exact signed distance functions (negative inside).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Analytic {
    /// Sphere about the origin.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// Torus about the z axis.
    Torus {
        /// Distance from the axis to the tube's centre.
        major: f64,
        /// Tube radius.
        minor: f64,
    },
    /// Axis-aligned box about the origin.
    Box {
        /// Half side lengths.
        half: DVec3,
    },
    /// Two tori about the z axis (R = 0.35, r = 0.15) centred at x = -0.4 and 0.4, overlapping:
    /// genus 2, `rfta demo`'s shape. The least of their exact signed distances is exact outside
    /// and a lower bound on the distance inside, so its spheres never cross the surface.
    TwoTori,
}

impl Analytic {
    /// The exact signed distance at `p`.
    pub fn sdf(&self, p: DVec3) -> f64 {
        match *self {
            Analytic::Sphere { radius } => p.length() - radius,
            Analytic::Torus { major, minor } => {
                let ring = (p.x * p.x + p.y * p.y).sqrt() - major;
                (ring * ring + p.z * p.z).sqrt() - minor
            }
            Analytic::Box { half } => {
                let q = p.abs() - half;
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
            }
            Analytic::TwoTori => {
                let [a, b] = Self::TWO_TORI;
                a.1.sdf(p - a.0).min(b.1.sdf(p - b.0))
            }
        }
    }

    /// The two tori of [`Analytic::TwoTori`], each with its centre.
    const TWO_TORI: [(DVec3, Analytic); 2] = [
        (
            DVec3::new(-0.4, 0.0, 0.0),
            Analytic::Torus {
                major: 0.35,
                minor: 0.15,
            },
        ),
        (
            DVec3::new(0.4, 0.0, 0.0),
            Analytic::Torus {
                major: 0.35,
                minor: 0.15,
            },
        ),
    ];

    /// `n` seeded, area-uniform points on the surface with outward unit normals (sphere: uniform
    /// directions; torus: rejection on the tube angle; box: faces chosen by area; two tori: either
    /// torus, rejecting the part inside the other).
    pub fn oriented_samples(&self, n: usize, seed: u64) -> (Vec<DVec3>, Vec<DVec3>) {
        let mut rng = crate::rng::Rng::new(seed);
        let (mut p, mut nn) = (Vec::with_capacity(n), Vec::with_capacity(n));
        while p.len() < n {
            if let Some((q, m)) = self.sample(&mut rng) {
                p.push(q);
                nn.push(m);
            }
        }
        (p, nn)
    }

    /// One try at a surface point and its normal (`None`: rejected, try again).
    fn sample(&self, rng: &mut crate::rng::Rng) -> Option<(DVec3, DVec3)> {
        let unit = |rng: &mut crate::rng::Rng| {
            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - DVec3::ONE
        };
        match *self {
            Analytic::Sphere { radius } => {
                let v = unit(rng);
                let l = v.length();
                (l > 0.1 && l <= 1.0).then(|| (v / l * radius, v / l))
            }
            Analytic::Torus { major, minor } => {
                let th = rng.next_f64() * std::f64::consts::TAU;
                let ph = rng.next_f64() * std::f64::consts::TAU;
                if rng.next_f64() * (major + minor) >= major + minor * ph.cos() {
                    return None;
                }
                let normal = DVec3::new(ph.cos() * th.cos(), ph.cos() * th.sin(), ph.sin());
                Some((
                    DVec3::new(major * th.cos(), major * th.sin(), 0.0) + minor * normal,
                    normal,
                ))
            }
            Analytic::Box { half } => {
                let areas = [half.y * half.z, half.x * half.z, half.x * half.y];
                let mut t = rng.next_f64() * areas.iter().sum::<f64>();
                let mut axis = 0;
                while axis < 2 && t >= areas[axis] {
                    t -= areas[axis];
                    axis += 1;
                }
                let side = if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
                let mut q = unit(rng) * half;
                q[axis] = side * half[axis];
                let mut normal = DVec3::ZERO;
                normal[axis] = side;
                Some((q, normal))
            }
            Analytic::TwoTori => {
                let i = usize::from(rng.next_f64() >= 0.5);
                let ((centre, torus), (other_centre, other)) =
                    (Self::TWO_TORI[i], Self::TWO_TORI[1 - i]);
                let (q, m) = torus.sample(rng)?;
                let q = q + centre;
                (other.sdf(q - other_centre) > 0.0).then_some((q, m))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_lie_on_each_surface_with_outward_normals() {
        let shapes = [
            Analytic::Sphere { radius: 0.5 },
            Analytic::Torus {
                major: 0.6,
                minor: 0.25,
            },
            Analytic::Box {
                half: DVec3::new(0.6, 0.4, 0.3),
            },
            Analytic::TwoTori,
        ];
        for shape in shapes {
            let (p, n) = shape.oriented_samples(500, 7);
            assert_eq!(p.len(), 500);
            for (p, n) in p.iter().zip(&n) {
                assert!(shape.sdf(*p).abs() < 1e-9, "{shape:?} at {p}");
                assert!(shape.sdf(*p + 1e-3 * *n) > 0.0, "{shape:?}: normal at {p}");
            }
        }
        // The demo's shape: exact outside far from the overlap (the one torus's distance).
        let q = DVec3::new(1.5, 0.0, 0.0);
        assert!((Analytic::TwoTori.sdf(q) - (1.1 - 0.35 - 0.15)).abs() < 1e-12);
    }
}
