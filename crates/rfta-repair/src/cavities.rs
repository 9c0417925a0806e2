//! Cavities the samples leave open: where a closed surface seals a bubble around outside samples
//! that the grid connects to the outside through outside samples only.
//!
//! When a reconstruction closes a gap or a hole, it keeps an inward-facing shell around the
//! outside samples that were in it: a sealed cavity. A grid's samples decide the side of each
//! grid point, not where the surface runs between two outside points less than a spacing apart;
//! so a wall with no inside sample in it is one the samples leave undecided, and real shapes (a
//! scan, a CAD part, a neural field's object) almost never hold a sealed bubble. Such a wall is
//! opened where it crosses a grid edge between an outside sample in the cavity and an outside
//! sample beyond the surface: [`cavity_openings`] returns a point in the gap between the two
//! samples' spheres for each such edge, for the caller to keep outside (the pipeline re-solves
//! its screened Poisson surface with them as side points). A cavity that no such edge leaves,
//! because inside samples wall it in all round (a hollow ball, a bottle), is a genuine void and
//! is left as it is.

use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{Grid, TriMesh};
use rfta_mesh::MeshIndex;

use crate::Spheres;

/// What [`cavity_openings`] found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Openings {
    /// Cavities: components of the mesh that face inward.
    pub cavities: usize,
    /// Of those, the ones around outside samples that no grid edge between outside samples
    /// leaves (inside samples all round: genuine voids), and those around no sample at all.
    pub sealed: usize,
    /// The grid edges from an outside sample in a cavity to an outside sample beyond the mesh
    /// (sphere indices), in the order of the cavities, then of the samples.
    pub edges: Vec<[usize; 2]>,
    /// Points in the spheres' frame that the surface should leave outside: `GAP_POINTS` per
    /// edge, spread over the gap between the two spheres (where they overlap, at the point
    /// between them), edge by edge.
    pub points: Vec<DVec3>,
}

/// Points per opened edge, at these fractions of the gap between the two spheres: one in the
/// middle held a wall open on most of the dev shapes, three on all but the coarsest.
pub(crate) const GAP_POINTS: [f64; 3] = [0.25, 0.5, 0.75];

/// The openings of `mesh`'s cavities (closed, outward-oriented `mesh`, in its own coordinates;
/// `spheres` in `grid` order, `grid` the samples' grid in any frame: only its index order is
/// used). See the module's documentation.
pub fn cavity_openings(mesh: &TriMesh, spheres: &Spheres<'_>, grid: &Grid) -> Openings {
    let walls = rfta_mesh::cavities(mesh);
    let mut out = Openings {
        cavities: walls.len(),
        ..Openings::default()
    };
    if walls.is_empty() || grid.len() != spheres.spheres.len() {
        out.sealed = walls.len();
        return out;
    }
    let Ok(whole) = MeshIndex::new(mesh) else {
        out.sealed = walls.len();
        return out;
    };
    // Each wall alone: inside it (winding number -1, it faces inward) is the cavity.
    let parts: Vec<Option<(MeshIndex, rfta_geom::Aabb)>> = walls
        .iter()
        .map(|faces| {
            let part = mesh.part(faces);
            MeshIndex::new(&part)
                .ok()
                .map(|index| (index, part.bounds()))
        })
        .collect();
    let centre = |i: usize| spheres.frame.to_mesh(spheres.spheres.sphere(i).center);
    let outside = |i: usize| spheres.values[i] > 0.0;
    let in_wall = |w: usize, p: DVec3| {
        parts[w]
            .as_ref()
            .is_some_and(|(index, bounds)| bounds.contains(p) && index.winding_number(p) < -0.5)
    };
    // Outside the solid: beyond the surface or in a cavity.
    let unenclosed = |p: DVec3| whole.winding_number(p) < 0.5;
    // Beyond the surface: outside the solid and in no cavity.
    let beyond = |p: DVec3| unenclosed(p) && (0..parts.len()).all(|w| !in_wall(w, p));
    let linked = OutsideLinks::new(grid, &outside);
    for (w, part) in parts.iter().enumerate() {
        let Some((_, bounds)) = part else {
            out.sealed += 1;
            continue;
        };
        let held: Vec<usize> = (0..grid.len())
            .into_par_iter()
            .filter(|&i| outside(i) && bounds.contains(centre(i)) && in_wall(w, centre(i)))
            .collect();
        // Open when the outside samples it holds are linked to one beyond the surface; then
        // through every wall between them and the outside samples next to them that it does not
        // hold (beyond the surface, or in a cavity the same links open).
        let reaches_beyond = held
            .first()
            .is_some_and(|&i| linked.members(i).any(|j| beyond(centre(j))));
        let edges: Vec<[usize; 2]> = if reaches_beyond {
            held.par_iter()
                .flat_map_iter(|&i| {
                    neighbours(grid, i)
                        .into_iter()
                        .flatten()
                        .filter(|&j| outside(j) && !in_wall(w, centre(j)) && unenclosed(centre(j)))
                        .map(move |j| [i, j])
                        .collect::<Vec<_>>()
                })
                .collect()
        } else {
            Vec::new()
        };
        if edges.is_empty() {
            out.sealed += 1;
        }
        out.points.extend(
            edges
                .iter()
                .flat_map(|&[i, j]| GAP_POINTS.map(|t| gap_point(spheres, i, j, t))),
        );
        out.edges.extend(edges);
    }
    out
}

/// The outside samples grouped by grid edges between outside samples: the samples' own
/// connectivity of the outside, which no surface between two of them can change.
struct OutsideLinks {
    /// Per sample, the first sample of its group (itself when inside).
    root: Vec<usize>,
    /// The samples of each group, by root.
    groups: std::collections::HashMap<usize, Vec<usize>>,
}

impl OutsideLinks {
    fn new(grid: &Grid, outside: &(impl Fn(usize) -> bool + Sync)) -> Self {
        let n = grid.len();
        let mut sets = rfta_mesh::UnionFind::new(n);
        for i in 0..n {
            if !outside(i) {
                continue;
            }
            // The neighbours above along each axis: every edge once.
            for j in neighbours(grid, i).into_iter().skip(1).step_by(2).flatten() {
                if outside(j) {
                    sets.union(i, j);
                }
            }
        }
        let root: Vec<usize> = (0..n).map(|i| sets.find(i)).collect();
        let mut groups: std::collections::HashMap<usize, Vec<usize>> =
            std::collections::HashMap::new();
        for (i, &r) in root.iter().enumerate() {
            if outside(i) {
                groups.entry(r).or_default().push(i);
            }
        }
        Self { root, groups }
    }

    /// The outside samples linked to `i` (itself included), in index order.
    fn members(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.groups
            .get(&self.root[i])
            .into_iter()
            .flatten()
            .copied()
    }
}

/// The six neighbours of grid point `i` along the axes, where they exist (below, then above,
/// along x, y, z).
fn neighbours(grid: &Grid, i: usize) -> [Option<usize>; 6] {
    let [x, y, z] = grid.ijk(i);
    let d = grid.dims();
    let step = |v: usize, n: usize, up: bool| {
        if up {
            (v + 1 < n).then_some(v + 1)
        } else {
            v.checked_sub(1)
        }
    };
    [
        step(x, d[0], false).map(|x| grid.index(x, y, z)),
        step(x, d[0], true).map(|x| grid.index(x, y, z)),
        step(y, d[1], false).map(|y| grid.index(x, y, z)),
        step(y, d[1], true).map(|y| grid.index(x, y, z)),
        step(z, d[2], false).map(|z| grid.index(x, y, z)),
        step(z, d[2], true).map(|z| grid.index(x, y, z)),
    ]
}

/// The point at fraction `t` of the part of the segment between spheres `i` and `j` that neither
/// covers, or, where they overlap, the point that divides the segment as their radii do (frame
/// coordinates).
fn gap_point(spheres: &Spheres<'_>, i: usize, j: usize, t: f64) -> DVec3 {
    let (a, b) = (spheres.spheres.sphere(i), spheres.spheres.sphere(j));
    let along = b.center - a.center;
    let length = along.length();
    if length == 0.0 {
        return a.center;
    }
    let (ra, rb) = (a.radius, b.radius);
    let at = if ra + rb < length {
        ra + t * (length - rb - ra)
    } else if ra + rb > 0.0 {
        length * ra / (ra + rb)
    } else {
        0.5 * length
    };
    a.center + along * (at / length)
}
