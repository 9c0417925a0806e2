//! Which cells the extraction takes as leaves (the tree's leaves, or, given a tolerance, also the
//! refined cells whose piece of the surface lies within it of a plane, taken whole), and which
//! of them it cuts.
//!
//! The octree is refined where the samples are dense, not where the surface bends, so a flat
//! stretch of surface comes out in many small triangles that say no more than a few large ones.
//! A refined cell a few depths above the finest is taken whole when the crossings of every edge
//! of the leaves below it (the vertices a full extraction would place there) lie within
//! `tolerance` of their least-squares plane. The surface the cell then gives has its vertices
//! where the full extraction's are on the same edges (`Ctx::bracket` in `extract.rs`) and stays
//! in that slab, as the full one's triangles do, hence within twice the tolerance of them.
//! The cells taken whole and the leaves left form an octree like any other, which the extraction
//! cuts crack-free as it does the tree's own.

use rayon::prelude::*;
use rfta_geom::glam::DVec3;

use crate::keys::demorton;
use crate::tree::{Level, corner};

/// How many depths above the finest a cell may be taken whole: at most 8^3 of the finest cells.
const WHOLE_DEPTHS: u32 = 3;

/// Which cells the extraction splits and which it never visits.
pub(crate) struct Leaves {
    /// Per depth, per cell: refined, and split by the extraction (neither taken whole nor
    /// hidden).
    split: Vec<Vec<bool>>,
    /// Per depth, per cell: inside a cell taken whole.
    hidden: Vec<Vec<bool>>,
    /// Whether any refined cell is taken whole.
    pub merged: bool,
}

impl Leaves {
    /// The tree's own leaves.
    pub(crate) fn of_tree(levels: &[Level]) -> Self {
        Self {
            split: levels.iter().map(|l| l.refined.clone()).collect(),
            hidden: levels.iter().map(|l| vec![false; l.cells.len()]).collect(),
            merged: false,
        }
    }

    /// The tree's leaves, and the refined cells whose surface `χ = iso` is flat within
    /// `tolerance` (unit-cube units) taken whole, coarsest first.
    pub(crate) fn merged(levels: &[Level], values: &[Vec<f64>], iso: f64, tolerance: f64) -> Self {
        let mut leaves = Self::of_tree(levels);
        let depth = levels.len() as u32 - 1;
        for d in depth.saturating_sub(WHOLE_DEPTHS)..depth {
            let level = &levels[d as usize];
            let (split, hidden) = (&leaves.split[d as usize], &leaves.hidden[d as usize]);
            let whole: Vec<bool> = (0..level.cells.len())
                .into_par_iter()
                .with_min_len(crate::solve::GRAIN)
                .map_init(Scratch::default, |scratch, i| {
                    split[i] && !hidden[i] && flat(levels, values, iso, d, i, tolerance, scratch)
                })
                .collect();
            leaves.merged |= whole.iter().any(|&w| w);
            // A child is hidden when its parent is taken whole or hidden itself.
            let finer = &levels[d as usize + 1];
            let parent_hidden: Vec<bool> = finer
                .cells
                .par_iter()
                .map(|&k| {
                    let p = level.cells.partition_point(|&c| c < k >> 3);
                    whole[p] || hidden[p]
                })
                .collect();
            for (s, w) in leaves.split[d as usize].iter_mut().zip(&whole) {
                *s &= !w;
            }
            // A hidden cell is split by nothing: the edges beside it are cut as the cell taken
            // whole above it cuts them.
            for (s, h) in leaves.split[d as usize + 1].iter_mut().zip(&parent_hidden) {
                *s &= !h;
            }
            leaves.hidden[d as usize + 1] = parent_hidden;
        }
        leaves
    }

    /// Whether cell `i` of depth `d` is split by the extraction.
    #[inline]
    pub(crate) fn is_split(&self, d: u32, i: u32) -> bool {
        self.split[d as usize][i as usize]
    }

    /// The leaves to extract, as (depth, cell) sorted and once each: those with a sign change
    /// among their corners, and the coarser leaves that share an edge or a face with them (their
    /// boundary may be cut by the finer leaf's corners).
    pub(crate) fn cut(&self, levels: &[Level], values: &[Vec<f64>], iso: f64) -> Vec<(u32, u32)> {
        let inside = |v: f64| v > iso;
        let mut cand: Vec<(u32, u32)> = levels
            .par_iter()
            .flat_map(|level| {
                let d = level.depth;
                let vals = &values[d as usize];
                (0..level.cells.len())
                    .into_par_iter()
                    .with_min_len(crate::solve::GRAIN)
                    .flat_map_iter(move |ci| {
                        // The cell and at most the 18 coarser leaves beside its faces and edges.
                        let mut out = [(0u32, 0u32); 19];
                        let mut len = 0;
                        let corners = &level.corners[ci];
                        let leaf = !self.is_split(d, ci as u32) && !self.is_hidden(d, ci as u32);
                        let cut = leaf && {
                            let first = inside(vals[corners[0] as usize]);
                            corners.iter().any(|&k| inside(vals[k as usize]) != first)
                        };
                        if !cut {
                            return out.into_iter().take(len);
                        }
                        out[len] = (d, ci as u32);
                        len += 1;
                        let c = demorton(level.cells[ci]);
                        let c = [i64::from(c[0]), i64::from(c[1]), i64::from(c[2])];
                        let n = 1i64 << d;
                        for o in 0..27 {
                            let off = [
                                (o % 3) as i64 - 1,
                                ((o / 3) % 3) as i64 - 1,
                                (o / 9) as i64 - 1,
                            ];
                            let nz = off.iter().filter(|&&v| v != 0).count();
                            if nz == 0 || nz == 3 {
                                continue;
                            }
                            let mut k = [c[0] + off[0], c[1] + off[1], c[2] + off[2]];
                            if k.iter().any(|&v| v < 0 || v >= n) {
                                continue;
                            }
                            // A cell of this depth there is taken on its own (or its children are);
                            // else the finest cell holding the place that is in the tree and not
                            // hidden: a coarser leaf, or a cell taken whole.
                            let mut dd = d;
                            loop {
                                if let Some(i) = levels[dd as usize].cell(k)
                                    && !self.is_hidden(dd, i)
                                {
                                    if dd < d {
                                        out[len] = (dd, i);
                                        len += 1;
                                    }
                                    break;
                                }
                                if dd == 0 {
                                    break;
                                }
                                dd -= 1;
                                k = k.map(|v| v >> 1);
                            }
                        }
                        out.into_iter().take(len)
                    })
            })
            .collect();
        cand.par_sort_unstable();
        cand.dedup();
        cand
    }

    /// Whether cell `i` of depth `d` lies inside a cell taken whole.
    #[inline]
    pub(crate) fn is_hidden(&self, d: u32, i: u32) -> bool {
        self.hidden[d as usize][i as usize]
    }
}

/// What [`flat`] gathers for one cell, kept from cell to cell of a task (no allocation per cell).
#[derive(Default)]
struct Scratch {
    points: Vec<DVec3>,
    stack: Vec<(u32, u64)>,
}

/// The eight values at cell `i`'s corners (depth `d`), if every corner is a node.
fn corner_values(levels: &[Level], values: &[Vec<f64>], d: u32, i: usize) -> Option<[f64; 8]> {
    let corners = &levels[d as usize].corners[i];
    let vals = &values[d as usize];
    let mut out = [0.0; 8];
    for (o, &n) in out.iter_mut().zip(corners) {
        *o = *vals.get(n as usize)?;
    }
    Some(out)
}

/// Whether the surface `χ = iso` crosses refined cell `i` of depth `d` and every crossing of an
/// edge of the leaves below it lies within `tolerance` of the crossings' least-squares plane.
fn flat(
    levels: &[Level],
    values: &[Vec<f64>],
    iso: f64,
    d: u32,
    i: usize,
    tolerance: f64,
    scratch: &mut Scratch,
) -> bool {
    let Some(f) = corner_values(levels, values, d, i) else {
        return false;
    };
    let inside = |v: f64| v > iso;
    if f.iter().all(|&v| inside(v) == inside(f[0])) {
        return false;
    }
    let Scratch { points, stack } = scratch;
    points.clear();
    stack.clear();
    stack.push((d, levels[d as usize].cells[i]));
    while let Some((dd, key)) = stack.pop() {
        let level = &levels[dd as usize];
        let Ok(j) = level.cells.binary_search(&key) else {
            return false;
        };
        if level.refined[j] {
            stack.extend((0..8).map(|c| (dd + 1, key * 8 + c)));
            continue;
        }
        let Some(f) = corner_values(levels, values, dd, j) else {
            return false;
        };
        let side = 1.0 / f64::from(1u32 << dd);
        let c = demorton(key);
        let origin = DVec3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2])) * side;
        for a in 0..3 {
            for k in (0..8).filter(|k| k & (1 << a) == 0) {
                let (va, vb) = (f[k], f[k | 1 << a]);
                if inside(va) == inside(vb) {
                    continue;
                }
                let o = corner(k);
                let mut p = DVec3::new(f64::from(o[0]), f64::from(o[1]), f64::from(o[2]));
                p[a] += (iso - va) / (vb - va);
                points.push(origin + p * side);
            }
        }
    }
    let Some(n) = plane_normal(points) else {
        return false;
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in points.iter() {
        let h = n.dot(*p);
        lo = lo.min(h);
        hi = hi.max(h);
    }
    hi - lo <= 2.0 * tolerance
}

/// The normal of the least-squares plane through `points`: the eigenvector of the smallest
/// eigenvalue of their covariance, by power iteration on its complement (trace minus it), from
/// the axis along which they spread least. `None` for fewer than three points.
fn plane_normal(points: &[DVec3]) -> Option<DVec3> {
    if points.len() < 3 {
        return None;
    }
    let c = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    let mut m = [DVec3::ZERO; 3];
    for p in points {
        let q = *p - c;
        m[0] += q * q.x;
        m[1] += q * q.y;
        m[2] += q * q.z;
    }
    let trace = m[0].x + m[1].y + m[2].z;
    if trace <= 0.0 {
        return None;
    }
    let diagonal = DVec3::new(m[0].x, m[1].y, m[2].z);
    let mut n = DVec3::ZERO;
    n[diagonal.min_position()] = 1.0;
    for _ in 0..PLANE_ITERATIONS {
        let mn = DVec3::new(m[0].dot(n), m[1].dot(n), m[2].dot(n));
        n = (trace * n - mn).try_normalize()?;
    }
    Some(n)
}

/// Power iterations of [`plane_normal`]: each shrinks the error by the ratio of the two largest
/// eigenvalues of the complement, at most about a half for points spread over a patch of a plane.
const PLANE_ITERATIONS: usize = 32;
