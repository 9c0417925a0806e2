//! The swept scenario's input (the paper's Figure 25): the pseudo-SDF of a shape swept along a
//! sampled motion, and the ground truth surface it defines.
//!
//! The shape (a dev shape's ground truth, scaled by [`SCALE`] about its box's centre) moves by
//! `length` along x while turning `length` radians about z, sampled at copies no point of which
//! moves more than [`STEP`] from one copy to the next. The pseudo-SDF is the minimum of the
//! copies' exact signed distances: exact outside the swept volume (the distance to the nearest
//! copy), a lower bound of the distance inside (the depth in the deepest copy), and 1-Lipschitz
//! everywhere, as the swept-volume SDFs of Sellan et al. ("Swept volumes via spacetime numerical
//! continuation", 2021) are.
//!
//! The ground truth is the zero set of the same function, extracted by marching cubes on a grid
//! of [`GT_RES`] cells per axis, evaluated exactly only near the surface ([`band_limited`]).

use anyhow::{Context, Result};
use rayon::prelude::*;
use rfta_geom::glam::{DMat3, DVec3};
use rfta_geom::{Aabb, Grid, TriMesh};
use rfta_mesh::MeshIndex;

/// The moving shape's size against the dev shape's (which fills about [-0.5, 0.5]^3).
const SCALE: f64 = 0.6;
/// The most any point of the shape moves between two consecutive copies.
const STEP: f64 = 0.02;
/// Cells per axis of the ground truth's grid over [-1, 1]^3.
pub(crate) const GT_RES: usize = 256;

/// One placed copy of the shape: `x = offset + rotation (SCALE (y - centre))` for `y` on the
/// shape.
struct Placement {
    rotation: DMat3,
    offset: DVec3,
    /// The copy's bounding box.
    bounds: Aabb,
}

/// A shape swept along the scenario's motion.
pub(crate) struct Sweep<'a> {
    index: &'a MeshIndex,
    centre: DVec3,
    copies: Vec<Placement>,
}

impl<'a> Sweep<'a> {
    /// `shape` (with its `index`) swept by `length` (0: the scaled shape, standing still).
    pub(crate) fn new(shape: &TriMesh, index: &'a MeshIndex, length: f64) -> Self {
        let bounds = index.bounds();
        let centre = bounds.center();
        let radius = shape
            .vertices
            .iter()
            .map(|v| SCALE * (*v - centre).length())
            .fold(0.0, f64::max);
        // A point at distance r from the axis moves by length (1 + r) over the motion.
        let n = 1 + (length * (1.0 + radius) / STEP).ceil() as usize;
        let copies = (0..n)
            .map(|k| {
                let t = if n == 1 {
                    0.5
                } else {
                    k as f64 / (n - 1) as f64
                };
                let rotation = DMat3::from_rotation_z(length * (t - 0.5));
                let offset = DVec3::new(length * (t - 0.5), 0.0, 0.0);
                let placed = shape
                    .vertices
                    .iter()
                    .map(|v| offset + rotation * (SCALE * (*v - centre)))
                    .collect::<Vec<_>>();
                Placement {
                    rotation,
                    offset,
                    bounds: Aabb::from_points(placed.iter()),
                }
            })
            .collect();
        Sweep {
            index,
            centre,
            copies,
        }
    }

    /// Number of copies along the motion.
    pub(crate) fn copies(&self) -> usize {
        self.copies.len()
    }

    /// The pseudo-SDF at `p`: the least of the copies' signed distances.
    pub(crate) fn value(&self, p: DVec3) -> f64 {
        let mut best = f64::INFINITY;
        for c in &self.copies {
            let box_d2 = c.bounds.distance_squared(p);
            // Outside a copy's box, `p` is outside the copy and at least the box's distance from
            // it: that copy cannot lower a best that is negative (inside another copy) or no
            // farther than the box (`best * |best|` is the signed square of `best`).
            if box_d2 > 0.0 && box_d2 >= best * best.abs() {
                continue;
            }
            let local = self.centre + c.rotation.transpose() * (p - c.offset) / SCALE;
            if box_d2 > 0.0 {
                // Outside this copy: only a nearer outside distance matters.
                let limit = (best / SCALE).powi(2);
                if let Some(cp) = self.index.closest_point_within(local, limit) {
                    best = best.min(SCALE * cp.distance_squared.sqrt());
                }
                continue;
            }
            let d = SCALE * self.index.unsigned_distance(local);
            // Only a copy that could beat the best needs its side: outside, a nearer surface;
            // inside, a deeper one.
            if d < best || -d < best {
                let inside = self.index.winding_number(local) > 0.5;
                best = best.min(if inside { -d } else { d });
            }
        }
        best
    }

    /// The pseudo-SDF at every point of `grid`, in parallel (the values do not depend on the
    /// thread count).
    pub(crate) fn grid_values(&self, grid: &Grid) -> Vec<f64> {
        (0..grid.len())
            .into_par_iter()
            .map(|i| self.value(grid.position(i)))
            .collect()
    }

    /// The ground truth: marching cubes of the pseudo-SDF on [`GT_RES`] cells per axis.
    pub(crate) fn ground_truth(&self) -> Result<TriMesh> {
        let (grid, values) = band_limited(&|p| self.value(p), GT_RES)?;
        let mesh = rfta_mc::marching_cubes(&grid, &values, 0.0);
        if mesh.is_empty() {
            anyhow::bail!("the swept shape's ground truth is empty");
        }
        Ok(mesh)
    }
}

/// A 1-Lipschitz function `f` on `linspace(-1, 1, res + 1)^3`, exact at every corner of every
/// cell its zero set crosses, and of the right sign elsewhere.
///
/// `res` must be a power-of-two multiple of a coarse resolution of at least 16. The coarse grid is
/// evaluated everywhere; each finer level halves the spacing. A node `q` whose coarser neighbour
/// `c` (at most a fine cell's diagonal `d` away) has `|f(c)| - |q - c| > d` has `|f(q)| > d`, so
/// the zero set crosses no cell it is a corner of; it keeps that lower bound with `f(c)`'s sign
/// (a bound at a coarser node is as good: it is below `|f|` with the right sign). Every other node
/// is evaluated. Marching cubes on the result equals marching cubes on `f` everywhere.
pub(crate) fn band_limited(
    f: &(dyn Fn(DVec3) -> f64 + Sync),
    res: usize,
) -> Result<(Grid, Vec<f64>)> {
    let mut coarse = res;
    while coarse.is_multiple_of(2) && coarse / 2 >= 16 {
        coarse /= 2;
    }
    let grid = Grid::cube(coarse, -1.0, 1.0)?;
    let mut values: Vec<f64> = (0..grid.len())
        .into_par_iter()
        .map(|i| f(grid.position(i)))
        .collect();
    let mut m = coarse;
    while m < res {
        let fine = Grid::cube(2 * m, -1.0, 1.0)?;
        let coarse_grid = Grid::cube(m, -1.0, 1.0)?;
        let h = fine.spacing().x;
        let diag = h * 3f64.sqrt();
        let prev = &values;
        let next: Vec<f64> = (0..fine.len())
            .into_par_iter()
            .map(|i| {
                let [a, b, c] = fine.ijk(i);
                let ci = coarse_grid.index(a / 2, b / 2, c / 2);
                let q = fine.position(i);
                let vc = prev[ci];
                let bound = vc.abs() - q.distance(coarse_grid.position(ci));
                if bound > diag {
                    vc.signum() * bound
                } else {
                    f(q)
                }
            })
            .collect();
        values = next;
        m *= 2;
    }
    let grid = Grid::cube(m, -1.0, 1.0).context("the ground truth's grid")?;
    Ok((grid, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_limited_sampling_gives_marching_cubes_of_the_exact_function() {
        // A sphere and a torus, exact SDFs: the band-limited grid's mesh equals the full grid's.
        let sphere = |p: DVec3| (p - DVec3::new(0.1, -0.05, 0.02)).length() - 0.55;
        let torus = |p: DVec3| {
            let ring = (p.x * p.x + p.y * p.y).sqrt() - 0.5;
            (ring * ring + p.z * p.z).sqrt() - 0.12
        };
        let cases: [&(dyn Fn(DVec3) -> f64 + Sync); 2] = [&sphere, &torus];
        for f in cases {
            let (grid, banded) = band_limited(f, 64).expect("grid");
            let full: Vec<f64> = (0..grid.len()).map(|i| f(grid.position(i))).collect();
            let exact = banded.iter().zip(&full).filter(|(a, b)| a == b).count();
            // Most nodes were not evaluated (so the test would notice a band as wide as the grid).
            assert!(exact < grid.len() / 3, "{exact} of {} exact", grid.len());
            for (a, b) in banded.iter().zip(&full) {
                assert_eq!(a.signum(), b.signum());
                assert!(a.abs() <= b.abs() + 1e-12);
            }
            let m1 = rfta_mc::marching_cubes(&grid, &banded, 0.0);
            let m2 = rfta_mc::marching_cubes(&grid, &full, 0.0);
            assert_eq!(m1.vertices, m2.vertices);
            assert_eq!(m1.faces, m2.faces);
        }
    }

    #[test]
    fn the_sweep_of_a_sphere_along_x_is_a_capsule() {
        // A sphere of radius 0.5 at the origin, swept: the copies' union is (to the sampling's
        // scallops) a capsule, and the values agree with the capsule's SDF outside it.
        let sphere = rfta_geom::shapes::icosphere(0.5, 4);
        let index = MeshIndex::new(&sphere).expect("mesh");
        let length = 0.4;
        let sweep = Sweep::new(&sphere, &index, length);
        assert!(sweep.copies() > 10);
        let r = SCALE * 0.5;
        // The rotation turns a sphere about its centre: only the translation shows.
        let capsule = |p: DVec3| {
            let x = p.x.clamp(-length / 2.0, length / 2.0);
            (p - DVec3::new(x, 0.0, 0.0)).length() - r
        };
        let mut rng = rfta_geom::rng::Rng::new(7);
        for _ in 0..200 {
            let p = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 1.6
                - DVec3::splat(0.8);
            let (v, c) = (sweep.value(p), capsule(p));
            // The icosphere is within 0.3% of its radius of the sphere; the copies' scallops
            // are below STEP^2 / (8 r).
            let tol = 0.005 * r + STEP * STEP / (8.0 * r);
            if c > 0.0 {
                assert!((v - c).abs() < tol, "outside at {p}: {v} vs {c}");
            } else {
                // Inside, the pseudo-SDF is the depth in the deepest copy: never deeper than the
                // capsule's.
                assert!(v < tol && v > c - tol, "inside at {p}: {v} vs {c}");
            }
        }
    }
}
