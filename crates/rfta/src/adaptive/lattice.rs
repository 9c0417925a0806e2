//! The samples an adaptive run has asked for: a subset of a fine lattice, organized as an octree
//! of cells whose corners are all sampled.
//!
//! Every sample position is a point of the finest lattice (`FINEST` levels below the base grid),
//! named by integer coordinates, so a point two cells share is asked for once and the positions
//! are exact. The leaves of the octree tile the box; refining a leaf asks for the 27 points of its
//! 2 x 2 x 2 subdivision that are not known yet (at most 19).

use std::collections::HashMap;

use rfta_geom::glam::DVec3;
use rfta_geom::{Aabb, SdfSamples};

/// Levels of refinement below the base grid's cells (a cell of level `FINEST` is 1/64 of a base
/// cell across).
pub(crate) const FINEST: u8 = 6;

/// A leaf of the octree: its lowest corner on the finest lattice and its level (0: a base cell).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct Cell {
    pub(crate) corner: [u32; 3],
    pub(crate) level: u8,
}

impl Cell {
    /// The cell's side on the finest lattice.
    pub(crate) fn side(self) -> u32 {
        1 << (FINEST - self.level)
    }

    /// The lattice point `(i, j, k)` of the cell's `(n + 1)^3` subdivision points, `n` = 1 (its
    /// corners) or 2 (with the midpoints).
    fn point(self, n: u32, i: u32, j: u32, k: u32) -> [u32; 3] {
        let d = self.side() / n;
        [
            self.corner[0] + i * d,
            self.corner[1] + j * d,
            self.corner[2] + k * d,
        ]
    }

    /// The 8 corners.
    pub(crate) fn corners(self) -> impl Iterator<Item = [u32; 3]> {
        (0..8).map(move |c| self.point(1, c >> 2, (c >> 1) & 1, c & 1))
    }

    /// The centre (a lattice point of the next level).
    pub(crate) fn centre(self) -> [u32; 3] {
        self.point(2, 1, 1, 1)
    }

    /// The 27 points of the subdivision.
    fn subdivision(self) -> impl Iterator<Item = [u32; 3]> {
        (0..27).map(move |c| self.point(2, c / 9, (c / 3) % 3, c % 3))
    }

    /// The 8 children.
    fn children(self) -> impl Iterator<Item = Cell> {
        let half = self.side() / 2;
        (0..8).map(move |c| Cell {
            corner: [
                self.corner[0] + (c >> 2) * half,
                self.corner[1] + ((c >> 1) & 1) * half,
                self.corner[2] + (c & 1) * half,
            ],
            level: self.level + 1,
        })
    }
}

/// The asked-for samples and the octree of cells over them.
#[derive(Debug, Clone)]
pub(crate) struct Lattice {
    /// Position of lattice point `(0, 0, 0)`.
    origin: DVec3,
    /// Distance between neighbouring points of the finest lattice, per axis.
    step: DVec3,
    /// The box's longest side.
    extent: f64,
    /// Lattice points with a value, in the order they were asked for.
    keys: Vec<[u32; 3]>,
    values: Vec<f64>,
    index: HashMap<[u32; 3], u32>,
    /// The leaves, in a deterministic order (sorted after each refinement).
    leaves: Vec<Cell>,
    /// The base grid's cells per axis.
    base: [u32; 3],
}

impl Lattice {
    /// The base grid over `bounds`: `cells` cells along the longest side, as many along the others
    /// as keep the cells closest to cubes (at least one). No sample is asked for yet
    /// ([`Lattice::missing`] lists the base grid's points).
    pub(crate) fn new(bounds: Aabb, cells: u32) -> Self {
        let extent = bounds.max - bounds.min;
        let side = extent.max_element() / f64::from(cells);
        let per_axis = extent
            .to_array()
            .map(|e| ((e / side).round() as u32).max(1));
        let step = DVec3::from_array(
            [0, 1, 2].map(|a| extent[a] / f64::from(per_axis[a]) / f64::from(1u32 << FINEST)),
        );
        let mut leaves = Vec::new();
        for i in 0..per_axis[0] {
            for j in 0..per_axis[1] {
                for k in 0..per_axis[2] {
                    leaves.push(Cell {
                        corner: [i, j, k].map(|c| c << FINEST),
                        level: 0,
                    });
                }
            }
        }
        Self {
            origin: bounds.min,
            step,
            extent: extent.max_element(),
            keys: Vec::new(),
            values: Vec::new(),
            index: HashMap::new(),
            leaves,
            base: per_axis,
        }
    }

    /// The base grid and its values (`NAN` where not asked for yet).
    pub(crate) fn base_grid(&self) -> rfta_geom::Result<(rfta_geom::Grid, Vec<f64>)> {
        let dims = self.base.map(|c| c as usize + 1);
        let grid = rfta_geom::Grid::new(dims, self.origin, self.step * f64::from(1u32 << FINEST))?;
        let values = (0..grid.len())
            .map(|i| {
                let key = grid.ijk(i).map(|c| (c as u32) << FINEST);
                self.value(key).unwrap_or(f64::NAN)
            })
            .collect();
        Ok((grid, values))
    }

    /// Position of a lattice point.
    pub(crate) fn position(&self, key: [u32; 3]) -> DVec3 {
        self.origin
            + DVec3::new(f64::from(key[0]), f64::from(key[1]), f64::from(key[2])) * self.step
    }

    /// The value at a lattice point, if asked for.
    pub(crate) fn value(&self, key: [u32; 3]) -> Option<f64> {
        self.index.get(&key).map(|&i| self.values[i as usize])
    }

    /// The leaves.
    pub(crate) fn leaves(&self) -> &[Cell] {
        &self.leaves
    }

    /// Samples asked for so far.
    pub(crate) fn len(&self) -> usize {
        self.keys.len()
    }

    /// The diagonal of a cell.
    pub(crate) fn diagonal(&self, cell: Cell) -> f64 {
        (self.step * f64::from(cell.side())).length()
    }

    /// The box's longest side: the extent of every pass's samples.
    pub(crate) fn extent(&self) -> f64 {
        self.extent
    }

    /// The side of a base cell (its longest axis).
    pub(crate) fn base_spacing(&self) -> f64 {
        self.step.max_element() * f64::from(1u32 << FINEST)
    }

    /// The spacing of the finest level any leaf has reached: the sample spacing near the surface.
    pub(crate) fn finest_spacing(&self) -> f64 {
        let level = self.leaves.iter().map(|c| c.level).max().unwrap_or(0);
        (self.step * f64::from(1u32 << (FINEST - level))).max_element()
    }

    /// The base grid's points not asked for yet (all of them before the first batch).
    pub(crate) fn missing_corners(&self) -> Vec<[u32; 3]> {
        let mut out: Vec<[u32; 3]> = self
            .leaves
            .iter()
            .flat_map(|c| c.corners())
            .filter(|k| !self.index.contains_key(k))
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The points refining `cells` would ask for, each once, sorted.
    pub(crate) fn refinement_points(&self, cells: &[Cell]) -> Vec<[u32; 3]> {
        let mut out: Vec<[u32; 3]> = cells
            .iter()
            .flat_map(|c| c.subdivision())
            .filter(|k| !self.index.contains_key(k))
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Records the oracle's values at `keys` (points not known yet).
    pub(crate) fn insert(&mut self, keys: &[[u32; 3]], values: &[f64]) {
        for (&k, &v) in keys.iter().zip(values) {
            if let std::collections::hash_map::Entry::Vacant(e) = self.index.entry(k) {
                e.insert(self.keys.len() as u32);
                self.keys.push(k);
                self.values.push(v);
            }
        }
    }

    /// Replaces the leaves `cells` (whose subdivision points are all known) by their children.
    pub(crate) fn refine(&mut self, cells: &[Cell]) {
        let mut gone: Vec<Cell> = cells.to_vec();
        gone.sort_unstable();
        gone.dedup();
        self.leaves.retain(|c| gone.binary_search(c).is_err());
        self.leaves.extend(
            gone.iter()
                .filter(|c| c.level < FINEST)
                .flat_map(|c| c.children()),
        );
        self.leaves.sort_unstable();
    }

    /// Whether the surface may pass through `cell`'s interior: for a distance, a corner whose
    /// value is at least the cell's diagonal holds the whole cell in its empty ball.
    pub(crate) fn may_hold_surface(&self, cell: Cell) -> bool {
        let diagonal = self.diagonal(cell);
        cell.corners()
            .all(|k| self.value(k).is_none_or(|v| v.abs() < diagonal))
    }

    /// The samples, in the order asked for, at the finest spacing the leaves reached.
    ///
    /// # Errors
    /// As [`SdfSamples::scattered`] (all one sign of zero values: no surface).
    pub(crate) fn samples(&self) -> rfta_geom::Result<SdfSamples> {
        let positions = self.keys.iter().map(|&k| self.position(k)).collect();
        SdfSamples::scattered(positions, self.values.clone())?.with_spacing(self.finest_spacing())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Refining a cell asks for the 19 points its corners lack, and its children tile it.
    #[test]
    fn a_refined_cell_asks_for_nineteen_points_and_its_children_tile_it() {
        let mut lattice = Lattice::new(Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)), 2);
        let corners = lattice.missing_corners();
        assert_eq!(corners.len(), 27);
        lattice.insert(&corners, &[1.0; 27]);
        let cell = lattice.leaves()[0];
        let points = lattice.refinement_points(&[cell]);
        assert_eq!(points.len(), 19);
        lattice.insert(&points, &[1.0; 19]);
        lattice.refine(&[cell]);
        assert_eq!(lattice.leaves().len(), 8 - 1 + 8);
        let children: Vec<Cell> = lattice
            .leaves()
            .iter()
            .filter(|c| c.level == 1)
            .copied()
            .collect();
        let volume: u64 = children.iter().map(|c| u64::from(c.side()).pow(3)).sum();
        assert_eq!(volume, u64::from(cell.side()).pow(3));
        assert!(
            children
                .iter()
                .all(|c| c.corners().all(|k| lattice.value(k).is_some()))
        );
        // A neighbour's refinement reuses the shared face's points: 27 - 9 - 8 + 4 = 12 new ones
        // (the shared face's 9 are known, and the corners not on it are the 4 base ones more).
        let neighbour = *lattice
            .leaves()
            .iter()
            .find(|c| c.level == 0)
            .expect("a base cell");
        assert!(lattice.refinement_points(&[neighbour]).len() < 19);
        assert_eq!(lattice.finest_spacing(), 0.5);
    }

    /// A corner whose value reaches past the cell's diagonal clears it; small values do not.
    #[test]
    fn a_corner_ball_holding_the_cell_rules_the_surface_out() {
        let mut lattice = Lattice::new(Aabb::new(DVec3::ZERO, DVec3::ONE), 1);
        let corners = lattice.missing_corners();
        let diag = 3f64.sqrt();
        let mut values = vec![0.1; 8];
        assert!({
            lattice.insert(&corners, &values);
            lattice.may_hold_surface(lattice.leaves()[0])
        });
        let mut far = Lattice::new(Aabb::new(DVec3::ZERO, DVec3::ONE), 1);
        values[3] = -diag;
        far.insert(&corners, &values);
        assert!(!far.may_hold_surface(far.leaves()[0]));
    }
}
