//! Which sample spheres reach a box: asked once for every component the repair judges, so the
//! spheres are summed up first in blocks (8^3 nodes of a grid, runs of 512 scattered samples),
//! each with the box of its centres and its largest radius, and a question skips every block none
//! of whose spheres can reach its box. On a 257^3 grid with a few hundred components a pass over
//! all 17 million spheres per component took most of the step (docs/speed.md, item 49).

use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{Aabb, Grid, SphereSet};

use crate::normalize::UnitBox;

/// Grid nodes along each side of a block.
const SIDE: usize = 8;

/// Scattered samples (consecutive indices) in a block.
const RUN: usize = 512;

/// The spheres of a [`UnitBox`] in blocks, for [`Reach::spheres_reaching`].
pub(super) struct Reach<'a> {
    unit: &'a UnitBox,
    /// The samples' grid (unit box) and its blocks per axis; `None` for scattered samples (runs
    /// of `RUN`).
    grid: Option<(Grid, [usize; 3])>,
    blocks: Vec<Block>,
}

/// A block's centres' box and largest radius (unit box).
struct Block {
    lo: DVec3,
    hi: DVec3,
    radius: f64,
}

impl<'a> Reach<'a> {
    /// The blocks of `unit`'s spheres: one pass over them.
    pub(super) fn new(unit: &'a UnitBox) -> Self {
        let grid = unit
            .grid()
            .map(|g| (*g, g.dims().map(|d| d.div_ceil(SIDE).max(1))));
        let count = match grid {
            Some((_, [a, b, c])) => a * b * c,
            None => unit.len().div_ceil(RUN),
        };
        let mut reach = Reach {
            unit,
            grid,
            blocks: Vec::new(),
        };
        reach.blocks = (0..count)
            .into_par_iter()
            .map(|b| {
                let mut block = Block {
                    lo: DVec3::INFINITY,
                    hi: DVec3::NEG_INFINITY,
                    radius: 0.0,
                };
                reach.for_members(b, |i| {
                    let c = unit.center(i);
                    block.lo = block.lo.min(c);
                    block.hi = block.hi.max(c);
                    block.radius = block.radius.max(unit.radius(i));
                });
                block
            })
            .collect();
        reach
    }

    /// Calls `f` with the index of every sample in block `b`.
    fn for_members(&self, b: usize, mut f: impl FnMut(usize)) {
        let Some((g, [_, by, bz])) = self.grid else {
            (b * RUN..((b + 1) * RUN).min(self.unit.len())).for_each(f);
            return;
        };
        let dims = g.dims();
        let at = [b / (by * bz), (b / bz) % by, b % bz];
        let range = |a: usize| at[a] * SIDE..((at[a] + 1) * SIDE).min(dims[a]);
        for i in range(0) {
            for j in range(1) {
                for k in range(2) {
                    f(g.index(i, j, k));
                }
            }
        }
    }

    /// The spheres (unit box) that reach within `margin` of `bounds` (a box in the samples'
    /// coordinates), in index order: every sphere that can hold a point of the box, or come
    /// within `margin` of one. A block is read only where the box of its centres comes within its
    /// largest radius and `margin` of `bounds`, which every sphere of it that reaches does.
    pub(super) fn spheres_reaching(&self, bounds: Aabb, margin: f64) -> Vec<u32> {
        let unit = self.unit;
        let (lo, hi) = (unit.to_unit(bounds.min), unit.to_unit(bounds.max));
        // Padded for the rounding of the conversion and of the distances.
        let pad = 1e-9 * (1.0 + hi.abs().max(lo.abs()).max_element());
        let reaches = |c: DVec3, radius: f64| {
            let reach = radius + margin + pad;
            c.clamp(lo, hi).distance_squared(c) < reach * reach
        };
        let mut found: Vec<u32> = (0..self.blocks.len())
            .into_par_iter()
            .filter(|&b| {
                // The box's distance to the nearest centre's box is at most any centre's (each
                // coordinate's gap rounds to no more than a centre's), so a block with a sphere
                // that reaches passes; the slack only lets more blocks be read.
                let k = &self.blocks[b];
                let gap = (k.lo - hi).max(lo - k.hi).max(DVec3::ZERO);
                let reach = k.radius + margin + pad;
                gap.length_squared() < reach * reach * (1.0 + 1e-9)
            })
            .fold(Vec::new, |mut near, b| {
                self.for_members(b, |i| {
                    if reaches(unit.center(i), unit.radius(i)) {
                        near.push(i as u32);
                    }
                });
                near
            })
            .reduce(Vec::new, |mut a, b| {
                a.extend(b);
                a
            });
        found.sort_unstable();
        found
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::{Grid, SdfSamples};

    /// The spheres every sample of `unit` gives, tested one by one as the blocks' members are.
    fn every_sphere_reaching(unit: &UnitBox, bounds: Aabb, margin: f64) -> Vec<u32> {
        let (lo, hi) = (unit.to_unit(bounds.min), unit.to_unit(bounds.max));
        let pad = 1e-9 * (1.0 + hi.abs().max(lo.abs()).max_element());
        (0..unit.len() as u32)
            .filter(|&i| {
                let s = unit.sphere(i as usize);
                let reach = s.radius + margin + pad;
                s.center.clamp(lo, hi).distance_squared(s.center) < reach * reach
            })
            .collect()
    }

    /// An exact distance to a ball of radius 0.6 about (1, 1, 1), on a grid of 19 x 21 x 9 nodes
    /// (blocks cut short at every far side) and at the same points scattered.
    fn ball_samples() -> [SdfSamples; 2] {
        let grid = Grid::new([19, 21, 9], DVec3::ZERO, DVec3::new(0.11, 0.1, 0.25)).expect("grid");
        let values: Vec<f64> = (0..grid.len())
            .map(|i| (grid.position(i) - DVec3::ONE).length() - 0.6)
            .collect();
        let points: Vec<DVec3> = (0..grid.len()).map(|i| grid.position(i)).collect();
        [
            SdfSamples::grid(grid, values.clone()).expect("grid samples"),
            SdfSamples::scattered(points, values).expect("scattered samples"),
        ]
    }

    /// The blocks list exactly the spheres a test of every sphere lists, in index order, for
    /// random boxes inside, across and beyond the samples, on a grid and scattered. Most boxes
    /// reach under half the spheres, so that blocks wrongly skipped would show.
    #[test]
    fn blocks_list_the_spheres_every_sphere_tested_lists() {
        let mut rng = rfta_geom::rng::Rng::new(5);
        let mut r = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        for samples in ball_samples() {
            let unit = UnitBox::new(&samples, None, None);
            let reach = Reach::new(&unit);
            let margin = 0.25 * unit.spacing();
            let (mut listed, mut fewer) = (0, 0);
            for _ in 0..300 {
                let (a, b) = (r() * 3.0 - DVec3::splat(0.5), r() * 0.2);
                let bounds = Aabb::from_points(&[a, a + b]);
                let every = every_sphere_reaching(&unit, bounds, margin);
                assert_eq!(reach.spheres_reaching(bounds, margin), every);
                listed += every.len();
                fewer += usize::from(every.len() < unit.len() / 2);
            }
            assert!(listed > 1000 && fewer > 100, "{listed} {fewer}");
        }
    }

    /// Every sphere that holds a point of the box, or comes within the margin of one, is listed
    /// (points drawn in random boxes, against every sphere).
    #[test]
    fn spheres_reaching_a_box_hold_every_point_any_sphere_holds() {
        let grid = Grid::new([8, 8, 8], DVec3::ZERO, DVec3::splat(0.25)).expect("grid");
        let values = (0..grid.len())
            .map(|i| (grid.position(i) - DVec3::ONE).length() - 0.6)
            .collect();
        let samples = SdfSamples::grid(grid, values).expect("samples");
        let unit = UnitBox::new(&samples, None, None);
        let reach = Reach::new(&unit);
        let margin = 0.25 * unit.spacing();
        let mut rng = rfta_geom::rng::Rng::new(11);
        let mut r = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        let mut held = 0;
        for _ in 0..200 {
            let (a, b) = (r() * 2.0, r() * 0.3);
            let bounds = Aabb::from_points(&[a, a + b]);
            let near = reach.spheres_reaching(bounds, margin);
            let (lo, hi) = (unit.to_unit(bounds.min), unit.to_unit(bounds.max));
            for &i in &near {
                let s = unit.sphere(i as usize);
                let d = s.center.distance(s.center.clamp(lo, hi));
                assert!(d < s.radius + margin + 1e-9, "sphere {i} listed at {d}");
            }
            for _ in 0..50 {
                let x = unit.to_unit(bounds.min + r() * (bounds.max - bounds.min));
                for (i, s) in unit.spheres().enumerate() {
                    if s.center.distance(x) < s.radius + margin {
                        held += 1;
                        assert!(near.binary_search(&(i as u32)).is_ok(), "sphere {i} missed");
                    }
                }
            }
        }
        assert!(held > 1000, "{held}");
    }
}
