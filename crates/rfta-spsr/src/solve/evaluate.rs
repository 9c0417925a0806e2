//! The implicit function at points, by an [`Evaluator`] that keeps each depth's last lookup for
//! the next point.

use rfta_geom::glam::DVec3;

use super::{Solution, ic};
use crate::keys::NONE;
use crate::tree::{Level, cell_of, corner, hats_in};

/// What a depth's lookups found for the cell around a point: the cell, or (where the tree does
/// not hold it) the nodes at its corners, `NONE` where absent.
#[derive(Debug, Clone, Copy)]
enum Found {
    Cell(u32),
    Corners([u32; 8]),
}

/// Evaluates one solution at point after point. Each depth's cell lookup (and, outside the tree,
/// its eight corner lookups) is kept for the next point: points taken in an order that keeps
/// neighbours together (a grid's samples row by row, the samples in Morton order) mostly fall in
/// the cells the point before fell in, at every depth but the finest few. The sums are the ones
/// an evaluator made for each point forms, term by term in the same order: the same values to
/// the bit.
pub(crate) struct Evaluator<'a> {
    levels: &'a [Level],
    sol: &'a Solution,
    /// The depth whose nodal values `U` hold every coarser depth's sum (complete grids below).
    base: usize,
    /// Per depth: the last cell looked up, and what was found.
    last: Vec<Option<([u32; 3], Found)>>,
    /// Lookups taken from the point before, since the count was last read (tests only).
    #[cfg(test)]
    reused: usize,
}

impl<'a> Evaluator<'a> {
    pub(crate) fn new(levels: &'a [Level], sol: &'a Solution, base: u32) -> Self {
        Evaluator {
            levels,
            sol,
            base: base.min(levels.len() as u32 - 1) as usize,
            last: vec![None; levels.len()],
            #[cfg(test)]
            reused: 0,
        }
    }

    /// Lookups taken from the point before since the last call.
    #[cfg(test)]
    pub(crate) fn reused(&mut self) -> usize {
        std::mem::take(&mut self.reused)
    }

    /// The implicit function at unit-cube point `p`: the sum over depths of the hats around it.
    pub(crate) fn at(&mut self, p: DVec3) -> f64 {
        let mut f = 0.0;
        // Depths up to `base` are complete grids: their sum is interpolated from U_base.
        for d in self.base..self.levels.len() {
            let level = &self.levels[d];
            let c = cell_of(p, d as u32);
            let found = match self.last[d] {
                Some((last, found)) if last == c => {
                    #[cfg(test)]
                    {
                        self.reused += 1;
                    }
                    found
                }
                _ => {
                    let found = match level.cell(ic(c)) {
                        Some(ci) => Found::Cell(ci),
                        None => Found::Corners(std::array::from_fn(|k| {
                            let o = corner(k);
                            level
                                .node(ic([c[0] + o[0], c[1] + o[1], c[2] + o[2]]))
                                .unwrap_or(NONE)
                        })),
                    };
                    self.last[d] = Some((c, found));
                    found
                }
            };
            let h = hats_in(p, c, d as u32);
            let vals = if d == self.base {
                &self.sol.u[d]
            } else {
                &self.sol.x[d]
            };
            match found {
                Found::Cell(ci) => {
                    let corners = &level.corners[ci as usize];
                    for k in 0..8 {
                        f += h[k] * vals[corners[k] as usize];
                    }
                }
                Found::Corners(nodes) => {
                    let mut any = false;
                    for (hk, &j) in h.iter().zip(&nodes) {
                        if j != NONE {
                            f += hk * vals[j as usize];
                            any = true;
                        }
                    }
                    // Nodes are the corners of cells, and a cell's parent is a cell: a finer
                    // cell touching the one around `p` would have a parent sharing a corner
                    // with this one. With no corner here, no finer depth has a hat over `p`.
                    if !any {
                        break;
                    }
                }
            }
        }
        f
    }
}
