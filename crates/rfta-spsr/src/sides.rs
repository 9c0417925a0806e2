//! Side points: points the surface must leave inside or outside, and the screening terms a
//! re-solve gives those on the wrong side ([`crate::reconstruct_with_sides`]).

use rayon::prelude::*;

use crate::glam::DVec3;
use crate::solve::ValueConstraint;
use crate::tree;

/// A point the surface must leave on one side: inside (`inside: true`) or outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SidePoint {
    /// Where, in the points' coordinates.
    pub position: DVec3,
    /// Whether it lies inside the surface.
    pub inside: bool,
}

/// Side points as [`crate::reconstruct_with_sides`] reads them: by index, so that a caller with
/// millions of them (every sample of a 257^3 grid) need not gather them into a list first.
pub trait SideSet: Sync {
    /// How many indices there are.
    fn len(&self) -> usize;
    /// The side point at index `i < len()`; `None` when that index holds none.
    fn get(&self, i: usize) -> Option<SidePoint>;
    /// Whether there are no indices.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl SideSet for &[SidePoint] {
    fn len(&self) -> usize {
        <[SidePoint]>::len(self)
    }
    fn get(&self, i: usize) -> Option<SidePoint> {
        <[SidePoint]>::get(self, i).copied()
    }
}

impl SideSet for Vec<SidePoint> {
    fn len(&self) -> usize {
        self.as_slice().len()
    }
    fn get(&self, i: usize) -> Option<SidePoint> {
        self.as_slice().get(i).copied()
    }
}

impl<const N: usize> SideSet for [SidePoint; N] {
    fn len(&self) -> usize {
        N
    }
    fn get(&self, i: usize) -> Option<SidePoint> {
        self.as_slice().get(i).copied()
    }
}

/// No side points: the plain solve's.
pub(crate) const NO_SIDES: &[SidePoint; 0] = &[];

/// Re-solves after the first at most, in [`crate::reconstruct_with_sides`].
pub(crate) const SIDE_PASSES: usize = 4;

/// A side point counts as wrong unless the function is at least this far on its side of the
/// iso-value (in the indicator's units: 1 inside, 0 outside): the extracted surface follows the
/// function only approximately, and a point right at the iso-value is on neither side.
pub(crate) const SIDE_MARGIN: f64 = 0.02;

/// Between the first solve and the last, only the side points within this of being wrong after
/// the first solve (in the indicator's units, beyond [`SIDE_MARGIN`]) are evaluated again; the
/// solve whose surface is returned is checked at every side point. A re-solve changes the
/// function near the points it adds, which lie near the surface; far from it the indicator stays
/// near its far value (at 129^3 samples of a shape, 2,071 of 2.1 million side points are within
/// 0.1 after the first solve, 2.0 million within 0.3).
pub(crate) const SIDE_RECHECK: f64 = 0.1;

/// A wrong side point is screened toward the iso-value plus (inside) or minus (outside) this: a
/// target just past the surface moves it no farther than needed (measured on the Reach for the
/// Arcs dev set, docs/faithfulness.md: targets of 1/2 past it, the indicator's own values,
/// dig pits and tunnels around the points).
pub(crate) const SIDE_TARGET: f64 = 0.1;

/// Weight of a side constraint in its first re-solve, in units of the mean screening weight of
/// one merged sample; each later re-solve that still finds it wrong multiplies it by
/// [`SIDE_WEIGHT_GROWTH`].
pub(crate) const SIDE_WEIGHT: f64 = 1.0;

/// Growth of a still-wrong side constraint's weight from one re-solve to the next.
pub(crate) const SIDE_WEIGHT_GROWTH: f64 = 4.0;

/// Gauss-Seidel sweeps per depth of a re-solve with side points. A re-solve runs on the same
/// octree with a few more screening terms, so it starts from the solution before it (exactly
/// the same nodes) and needs fewer sweeps than a cold solve ([`crate::SpsrParams::iterations`]).
/// Measured in the Reach for the Arcs pipeline (docs/speed.md): the dev set's mean Chamfer at
/// N = 10, 20, 30 the same or lower than with cold 8-sweep re-solves, and the final solve of
/// the 129^3 bunny 29% shorter.
pub(crate) const SIDE_RESOLVE_SWEEPS: usize = 2;

/// The side points in the reconstruction cube and the screening terms of those found wrong. The
/// points stay the caller's (a 257^3 grid has 17 million): each is moved into the cube when it is
/// looked at, and only those found wrong keep state here.
pub(crate) struct Sides<'a> {
    /// The caller's side points, in the points' coordinates.
    points: &'a (dyn SideSet + 'a),
    frame: &'a tree::Frame,
    /// Whether any side point lies in the cube.
    any: bool,
    constraints: Vec<ValueConstraint>,
    /// Side point to its constraint's index, once it has one.
    active: std::collections::HashMap<usize, u32>,
    /// Side points on the wrong side after each pass.
    errors: Vec<usize>,
    /// The side points the re-solves between the first and the last look at again.
    recheck: Option<Vec<usize>>,
}

impl<'a> Sides<'a> {
    /// The side points; those outside the cube of `frame` are ignored.
    pub(crate) fn in_cube(points: &'a (dyn SideSet + 'a), frame: &'a tree::Frame) -> Self {
        let mut sides = Self {
            points,
            frame,
            any: false,
            constraints: Vec::new(),
            active: std::collections::HashMap::new(),
            errors: Vec::new(),
            recheck: None,
        };
        sides.any = (0..points.len()).any(|i| sides.point(i).is_some());
        sides
    }

    /// Side point `i` in the unit cube, with whether it is inside; `None` outside the cube.
    fn point(&self, i: usize) -> Option<(DVec3, bool)> {
        let s = self.points.get(i)?;
        let u = self.frame.to_unit(s.position);
        (u.cmpge(DVec3::ZERO).all() && u.cmplt(DVec3::ONE).all()).then_some((u, s.inside))
    }

    pub(crate) fn is_empty(&self) -> bool {
        !self.any
    }

    /// The screening terms so far.
    pub(crate) fn constraints(&self) -> &[ValueConstraint] {
        &self.constraints
    }

    /// Wrong side points after each pass so far.
    pub(crate) fn errors(&self) -> &[usize] {
        &self.errors
    }

    pub(crate) fn into_errors(self) -> Vec<usize> {
        self.errors
    }

    /// The side points on the wrong side of the function at `iso` (within [`SIDE_MARGIN`]),
    /// counted in [`Sides::errors`]. The function is read by evaluators `at` makes, one per run
    /// of consecutive points (each keeps what it looked up for the next point). The first pass
    /// measures every point and notes those within [`SIDE_RECHECK`] of wrong; the passes between
    /// look at those again; the `last` (and one that finds none wrong) counts every point, for
    /// the surface returned.
    pub(crate) fn wrong<E: FnMut(DVec3) -> f64>(
        &mut self,
        at: &(impl Fn() -> E + Sync),
        iso: f64,
        last: bool,
    ) -> Vec<usize> {
        // How far each side point in the cube is on its side beyond the margin (negative:
        // wrong); `None` outside the cube.
        let slack = |f: &mut E, i: usize| {
            let (p, inside) = self.point(i)?;
            let f = f(p);
            Some(if inside {
                f - iso - SIDE_MARGIN
            } else {
                iso - SIDE_MARGIN - f
            })
        };
        let n = self.points.len();
        // The side points less than `limit` on their side, with how far.
        let below = |limit: f64| -> Vec<(usize, f64)> {
            (0..n)
                .into_par_iter()
                .map_init(at, |f, i| {
                    slack(f, i).filter(|&s| s < limit).map(|s| (i, s))
                })
                .flatten()
                .collect()
        };
        let wrong: Vec<usize> = match &self.recheck {
            None => {
                let near = below(SIDE_RECHECK);
                let wrong = near.iter().filter(|p| p.1 < 0.0).map(|p| p.0).collect();
                self.recheck = Some(near.into_iter().map(|p| p.0).collect());
                wrong
            }
            Some(near) => {
                let w: Vec<usize> = near
                    .par_iter()
                    .map_init(at, |f, &i| {
                        slack(f, i).is_some_and(|s| s < 0.0).then_some(i)
                    })
                    .flatten()
                    .collect();
                if last || w.is_empty() {
                    // The surface returned: its count over every side point.
                    below(0.0).into_iter().map(|p| p.0).collect()
                } else {
                    w
                }
            }
        };
        self.errors.push(wrong.len());
        wrong
    }

    /// The `wrong` side points whose cell of depth `depth` is not in `finest`, the octree's
    /// finest level.
    pub(crate) fn in_coarse_cells(
        &self,
        wrong: &[usize],
        finest: &tree::Level,
        depth: u32,
    ) -> Vec<DVec3> {
        wrong
            .iter()
            .filter_map(|&i| self.point(i).map(|(p, _)| p))
            .filter(|&p| {
                let c = tree::cell_of(p, depth);
                finest
                    .cell([i64::from(c[0]), i64::from(c[1]), i64::from(c[2])])
                    .is_none()
            })
            .collect()
    }

    /// A screening term for each `wrong` side point without one (target iso +- [`SIDE_TARGET`],
    /// weight [`SIDE_WEIGHT`] times the samples' mean weight, `total_w` over `n`), and the weight
    /// of those that have one multiplied by [`SIDE_WEIGHT_GROWTH`].
    pub(crate) fn constrain(&mut self, wrong: &[usize], iso: f64, total_w: f64, n: usize) {
        for &i in wrong {
            match self.active.get(&i) {
                Some(&c) => self.constraints[c as usize].weight *= SIDE_WEIGHT_GROWTH,
                None => {
                    let Some((pos, inside)) = self.point(i) else {
                        continue;
                    };
                    self.active.insert(i, self.constraints.len() as u32);
                    self.constraints.push(ValueConstraint {
                        pos,
                        target: if inside {
                            iso + SIDE_TARGET
                        } else {
                            iso - SIDE_TARGET
                        },
                        weight: SIDE_WEIGHT * total_w / n as f64,
                    });
                }
            }
        }
    }
}
