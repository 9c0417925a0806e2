//! The input surface's nearest face to a point a collapse places, found by walking from a face
//! near it: a collapse's new vertex lies within a few input faces of the face its edge's kept end
//! was placed on, and each new face's centroid within a few of the face found for that face's
//! centroid before (`deviation.rs` keeps both). The walk steps to a neighbouring face while one
//! is nearer; where it ends farther than the tolerance (a fold, a thin part), the index answers.
//! A walk that ends within the tolerance proves that the input is that near, so what passes is
//! what the index alone would pass.

use rayon::prelude::*;
use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;
use rfta_geom::kernels::closest_point_on_triangle;
use rfta_mesh::{Incidence, MeshIndex};

/// A walk that has not ended after this many steps hands over to the index.
const MAX_STEPS: usize = 64;

/// The input mesh with each vertex's faces and the face across each edge, and its index.
pub(crate) struct Nearest<'a> {
    index: &'a MeshIndex,
    vertices: &'a [DVec3],
    faces: &'a [[u32; 3]],
    incidence: Incidence,
    /// The face across the edge opposite corner `k` of face `f` is `across[3 f + k]`
    /// (`u32::MAX`: none, or more than one).
    across: Vec<u32>,
}

impl<'a> Nearest<'a> {
    /// `mesh`, whose index is `index`.
    pub(crate) fn new(mesh: &'a TriMesh, index: &'a MeshIndex) -> Self {
        let incidence = Incidence::of(mesh);
        let across = (0..3 * mesh.n_faces())
            .into_par_iter()
            .map(|i| {
                let (f, k) = (i / 3, i % 3);
                let face = mesh.faces[f];
                let (u, v) = (face[(k + 1) % 3], face[(k + 2) % 3]);
                let mut beside = incidence
                    .faces(u)
                    .iter()
                    .filter(|&&g| g as usize != f && mesh.faces[g as usize].contains(&v));
                match (beside.next(), beside.next()) {
                    (Some(&g), None) => g,
                    _ => u32::MAX,
                }
            })
            .collect();
        Self {
            index,
            vertices: &mesh.vertices,
            faces: &mesh.faces,
            incidence,
            across,
        }
    }

    /// A face of input vertex `v` (`u32::MAX` when it has none): where a walk from it starts.
    pub(crate) fn a_face_of(&self, v: u32) -> u32 {
        self.incidence.faces(v).first().copied().unwrap_or(u32::MAX)
    }

    /// The input face nearest `p` and the squared distance to it, when within `tolerance_squared`:
    /// walked to from face `from` (`u32::MAX`: none; the index), else the index's.
    pub(crate) fn within(&self, p: DVec3, from: u32, tolerance_squared: f64) -> Option<(u32, f64)> {
        if from != u32::MAX {
            let (f, d2) = self.walk(p, from);
            if d2 <= tolerance_squared {
                return Some((f, d2));
            }
        }
        self.index
            .closest_point_within(p, tolerance_squared)
            .map(|c| (c.face, c.distance_squared))
    }

    /// From face `f`, steps to the face beside the part of the current face nearest `p` (across
    /// the edge, or the nearest around the corner, that point lies on) while that is nearer; the
    /// face where it stops and its squared distance.
    fn walk(&self, p: DVec3, mut f: u32) -> (u32, f64) {
        let (mut d2, mut bary) = self.distance2(p, f);
        for _ in 0..MAX_STEPS {
            let face = self.faces[f as usize];
            let zeros = bary.iter().filter(|&&b| b <= 0.0).count();
            let mut best = (f, d2, bary);
            let mut offer = |g: u32| {
                if g != u32::MAX && g != f {
                    let (dg, bg) = self.distance2(p, g);
                    if dg < best.1 {
                        best = (g, dg, bg);
                    }
                }
            };
            match zeros {
                // On the edge opposite the corner whose coordinate is zero.
                1 => {
                    let k = bary.iter().position(|&b| b <= 0.0).unwrap_or(0);
                    offer(self.across[3 * f as usize + k]);
                }
                // At the corner whose coordinate is not.
                2 => {
                    let k = bary.iter().position(|&b| b > 0.0).unwrap_or(0);
                    self.incidence.faces(face[k]).iter().for_each(|&g| offer(g));
                }
                _ => break,
            }
            if best.0 == f {
                break;
            }
            (f, d2, bary) = best;
        }
        (f, d2)
    }

    fn distance2(&self, p: DVec3, f: u32) -> (f64, [f64; 3]) {
        let [a, b, c] = self.faces[f as usize].map(|v| self.vertices[v as usize]);
        let (q, bary) = closest_point_on_triangle(p, a, b, c);
        (p.distance_squared(q), bary)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rfta_geom::shapes;

    /// The squared distance from `p` to the nearest face of `mesh`, by trying every face.
    fn brute(mesh: &TriMesh, p: DVec3) -> f64 {
        mesh.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|v| mesh.vertices[v as usize]);
                p.distance_squared(closest_point_on_triangle(p, a, b, c).0)
            })
            .fold(f64::INFINITY, f64::min)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        /// On a torus with a ball in its hole (a walk from the ball's faces cannot reach the
        /// torus), from any face: an answer exactly when some face is within the tolerance, at
        /// a distance no nearer than the nearest face's and within the tolerance, and the
        /// distance of the face it names.
        #[test]
        fn within_answers_as_every_face_would(
            u in 0.0..std::f64::consts::TAU,
            v in 0.0..std::f64::consts::TAU,
            off in -0.3..0.3f64,
            from in 0usize..4096,
            tol in 0.0..0.2f64,
        ) {
            let mut mesh = shapes::torus(1.0, 0.35, 32, 16);
            mesh.append(&shapes::icosphere(0.3, 2));
            let index = MeshIndex::new(&mesh).expect("a torus and a ball have faces");
            let nearest = Nearest::new(&mesh, &index);
            let ring = DVec3::new(u.cos(), u.sin(), 0.0);
            let p = if from % 2 == 0 {
                ring + (0.35 + off) * (v.cos() * ring + DVec3::new(0.0, 0.0, v.sin()))
            } else {
                (0.3 + off) * (v.cos() * ring + DVec3::new(0.0, 0.0, v.sin()))
            };
            let from = (from % mesh.n_faces()) as u32;
            let best = brute(&mesh, p);
            match nearest.within(p, from, tol * tol) {
                Some((f, d2)) => {
                    prop_assert!(best <= tol * tol);
                    prop_assert!(d2 >= best - 1e-15 && d2 <= tol * tol, "{d2} {best}");
                    prop_assert!((nearest.distance2(p, f).0 - d2).abs() <= 1e-15);
                }
                None => prop_assert!(best > tol * tol, "{best} within {}", tol * tol),
            }
        }
    }

    /// Every face's neighbours across its edges share that edge, and a closed mesh has one
    /// across each.
    #[test]
    fn faces_across_share_the_edge() {
        let mesh = shapes::torus(1.0, 0.35, 12, 8);
        let index = MeshIndex::new(&mesh).expect("a torus and a ball have faces");
        let nearest = Nearest::new(&mesh, &index);
        for (f, face) in mesh.faces.iter().enumerate() {
            for k in 0..3 {
                let g = nearest.across[3 * f + k];
                assert_ne!(g, u32::MAX);
                assert_ne!(g as usize, f);
                let other = mesh.faces[g as usize];
                assert!(other.contains(&face[(k + 1) % 3]) && other.contains(&face[(k + 2) % 3]));
            }
        }
    }
}
