//! The adaptive octree: the unit-cube frame, per-leaf sample merging, the density estimate that
//! gives every sample its depth and area, and the graded per-depth cell and node sets.

use rayon::prelude::*;
use rfta_geom::{OrientedPoints, glam::DVec3};

use crate::keys::{KeyMap, SparseIndex, demorton, key_map, morton};
use crate::{Error, SpsrParams};

/// The similarity that maps the input into the unit cube `[0, 1]^3` the octree lives in.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    /// World position of the cube's minimum corner.
    pub origin: DVec3,
    /// World length of the cube's side.
    pub side: f64,
}

impl Frame {
    /// A cube `scale` times the largest side of `points`' bounding box, centred on it.
    pub(crate) fn around(points: &OrientedPoints, scale: f64) -> Result<Self, Error> {
        let b = points.bounds();
        let extent = (b.max - b.min).max_element();
        if extent.is_nan() || extent <= 0.0 {
            return Err(Error::DegenerateInput(
                "all points are identical: there is no surface to reconstruct".into(),
            ));
        }
        let side = extent * scale;
        let centre = 0.5 * (b.min + b.max);
        Ok(Self {
            origin: centre - DVec3::splat(0.5 * side),
            side,
        })
    }

    pub(crate) fn to_unit(self, p: DVec3) -> DVec3 {
        (p - self.origin) / self.side
    }

    pub(crate) fn to_world(self, u: DVec3) -> DVec3 {
        self.origin + u * self.side
    }
}

/// One merged sample: all input points that fall into the same finest cell.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sample {
    /// Morton key of the finest cell (samples are sorted by it).
    pub key: u64,
    /// Weighted mean position, unit-cube coordinates.
    pub pos: DVec3,
    /// Weighted sum of unit normals.
    pub normal: DVec3,
    /// Summed input weight (point count when no weights were given).
    pub weight: f64,
    /// Fractional depth at which the sample's normal is splatted.
    pub depth: f64,
    /// Surface area the sample stands for (per unit weight times `weight`).
    pub area: f64,
}

/// Cell coordinates of unit-cube point `u` at depth `d`.
pub(crate) fn cell_of(u: DVec3, d: u32) -> [u32; 3] {
    let n = f64::from(1u32 << d);
    let top = (1u32 << d) - 1;
    let c = |v: f64| ((v * n).floor().max(0.0) as u32).min(top);
    [c(u.x), c(u.y), c(u.z)]
}

/// Merge points per finest cell, in Morton order. Weights of zero drop a point.
pub(crate) fn merge(points: &OrientedPoints, frame: &Frame, depth: u32) -> Vec<Sample> {
    let weights = points.weights();
    let mut keyed: Vec<(u64, u32)> = points
        .positions()
        .par_iter()
        .enumerate()
        .map(|(i, &p)| (morton(cell_of(frame.to_unit(p), depth)), i as u32))
        .collect();
    keyed.par_sort_unstable();
    let mut out: Vec<Sample> = Vec::new();
    for &(key, i) in &keyed {
        let i = i as usize;
        let w = weights.map_or(1.0, |w| w[i]);
        if w <= 0.0 {
            continue;
        }
        let p = frame.to_unit(points.positions()[i]);
        let n = points.normals()[i];
        match out.last_mut() {
            Some(s) if s.key == key => {
                s.pos += w * p;
                s.normal += w * n;
                s.weight += w;
            }
            _ => out.push(Sample {
                key,
                pos: w * p,
                normal: w * n,
                weight: w,
                depth: 0.0,
                area: 0.0,
            }),
        }
    }
    for s in &mut out {
        s.pos /= s.weight;
    }
    out
}

/// Trilinear (degree-1) weights of unit-cube point `u` in its depth-`d` cell: the cell and the
/// eight hat values at its corners (corner `k` is offset `(k & 1, k >> 1 & 1, k >> 2 & 1)`).
pub(crate) fn hat_weights(u: DVec3, d: u32) -> ([u32; 3], [f64; 8]) {
    let c = cell_of(u, d);
    (c, hats_in(u, c, d))
}

/// Hat values at the eight corners of the given depth-`d` cell, at unit-cube point `u`.
pub(crate) fn hats_in(u: DVec3, cell: [u32; 3], d: u32) -> [f64; 8] {
    let n = f64::from(1u32 << d);
    let t = [
        (u.x * n - f64::from(cell[0])).clamp(0.0, 1.0),
        (u.y * n - f64::from(cell[1])).clamp(0.0, 1.0),
        (u.z * n - f64::from(cell[2])).clamp(0.0, 1.0),
    ];
    let mut w = [0.0; 8];
    for (k, wk) in w.iter_mut().enumerate() {
        let f = |axis: usize| {
            if (k >> axis) & 1 == 1 {
                t[axis]
            } else {
                1.0 - t[axis]
            }
        };
        *wk = f(0) * f(1) * f(2);
    }
    w
}

/// Offset of corner `k` of a cell.
pub(crate) fn corner(k: usize) -> [u32; 3] {
    [(k & 1) as u32, ((k >> 1) & 1) as u32, ((k >> 2) & 1) as u32]
}

/// Density estimate (Kazhdan and Hoppe 2013, §4.1 of Kazhdan, Bolitho and Hoppe 2006): sample
/// weights are splatted onto the hats of the kernel depth (`depth - 2`) and of every coarser
/// depth down to `base`; the field read back at a sample is its number of samples per node there.
/// Starting at the kernel depth and moving coarser while that count is below
/// `samples_per_node` (a sparse sample would otherwise mostly see itself), the count at the first
/// depth where it suffices, falling by 4 per finer depth because samples lie on a surface, gives
/// the sample's fractional depth and the surface area it stands for.
pub(crate) fn estimate_density(samples: &mut [Sample], params: &SpsrParams, base: u32) {
    let depth = params.depth;
    let kd = depth.saturating_sub(2).max(1).min(depth);
    let lowest = base.min(kd).max(1);
    let levels: Vec<u32> = (lowest..=kd).rev().collect();
    let fields: Vec<KeyMap<f64>> = levels
        .par_iter()
        .map(|&d| {
            let mut field: KeyMap<f64> = key_map(samples.len() * 2);
            for s in samples.iter() {
                let (c, w) = hat_weights(s.pos, d);
                for (k, wk) in w.iter().enumerate() {
                    let o = corner(k);
                    let key = morton([c[0] + o[0], c[1] + o[1], c[2] + o[2]]);
                    *field.entry(key).or_insert(0.0) += s.weight * wk;
                }
            }
            field
        })
        .collect();
    let spn = params.samples_per_node;
    samples.par_iter_mut().for_each(|s| {
        let mut chosen = (kd, 1e-12);
        for (&d, field) in levels.iter().zip(&fields) {
            let (c, w) = hat_weights(s.pos, d);
            let mut rho = 0.0;
            for (k, wk) in w.iter().enumerate() {
                let o = corner(k);
                let key = morton([c[0] + o[0], c[1] + o[1], c[2] + o[2]]);
                rho += wk * field.get(&key).copied().unwrap_or(0.0);
            }
            // A surface through a node's cells meets its hat with mean weight 2/3 of a plane
            // through the node (the mean of t^2 + (1 - t)^2 over the offset t), so the raw field
            // under-counts samples per node by that factor.
            let rho = (1.5 * rho).max(1e-12);
            chosen = (d, rho);
            if rho >= spn {
                break;
            }
        }
        let (d, rho) = chosen;
        let h2 = (1.0 / f64::from(1u32 << d)).powi(2);
        let fd = f64::from(d) + 0.5 * rfta_geom::math::log2(rho / spn);
        s.depth = fd.clamp(f64::from(base), f64::from(depth));
        s.area = s.weight * h2 / rho;
    });
}

/// One depth of the octree: its cells (sorted Morton keys, each flagged refined or leaf), and
/// the hat functions living on the corners of those cells.
#[derive(Debug, Clone)]
pub(crate) struct Level {
    pub depth: u32,
    pub cells: Vec<u64>,
    pub refined: Vec<bool>,
    pub cell_index: SparseIndex,
    /// Node index of each cell corner.
    pub corners: Vec<[u32; 8]>,
    /// Node coordinates, ordered by colour (coordinate parities) and then Morton key.
    pub nodes: Vec<[u32; 3]>,
    pub node_index: SparseIndex,
    /// `colors[c]..colors[c + 1]` are the nodes of colour `c`: no two share a cell or a stencil.
    pub colors: [usize; 9],
}

impl Level {
    pub(crate) fn n(&self) -> u32 {
        1 << self.depth
    }

    /// Node index of level coordinates, if that hat is active.
    #[inline]
    pub(crate) fn node(&self, c: [i64; 3]) -> Option<u32> {
        self.node_index.get(c)
    }

    /// Cell index of level coordinates, if the cell is in the tree.
    #[inline]
    pub(crate) fn cell(&self, c: [i64; 3]) -> Option<u32> {
        self.cell_index.get(c)
    }
}

fn color(c: [u32; 3]) -> u64 {
    u64::from((c[0] & 1) | ((c[1] & 1) << 1) | ((c[2] & 1) << 2))
}

/// Parents of the 3x3x3 block of cells around cell `c` of a depth with `n` cells per axis.
fn parent_block(c: [u32; 3], n: u32, out: &mut Vec<u64>) {
    let r = |v: u32| (v.saturating_sub(1) >> 1)..=((v + 1).min(n - 1) >> 1);
    for z in r(c[2]) {
        for y in r(c[1]) {
            for x in r(c[0]) {
                out.push(morton([x, y, z]));
            }
        }
    }
}

fn sort_dedup(v: &mut Vec<u64>) {
    v.par_sort_unstable();
    v.dedup();
}

/// Build the graded octree.
///
/// `R_d` (the refined cells of depth `d`) holds the parents of the 3x3x3 block around every
/// sample's cell at the sample's top depth (so the normal field's support is in the tree) and the
/// parents of the block around every refined cell one depth finer (so every hat one depth
/// coarser than an active hat, and overlapping it, is active too: the prolongation and the
/// parent-child coupling stay exact). Depths up to `base` are complete grids; deeper cells are
/// the children of refined ones, in broods of eight. `seeds` (unit cube) are refined as samples
/// whose top depth is `depth`.
pub(crate) fn build_levels(
    samples: &[Sample],
    seeds: &[DVec3],
    depth: u32,
    base: u32,
) -> Vec<Level> {
    let base = base.min(depth);
    let mut refined: Vec<Vec<u64>> = vec![Vec::new(); depth as usize + 1];
    // Marks from samples and seeds.
    let tops = samples
        .iter()
        .map(|s| (s.pos, (s.depth.ceil() as u32).clamp(base, depth)))
        .chain(seeds.iter().map(|&p| (p, depth)));
    for (pos, top) in tops {
        if top == 0 || top <= base {
            continue;
        }
        let c = cell_of(pos, top);
        parent_block(c, 1 << top, &mut refined[top as usize - 1]);
    }
    for d in (base..depth).rev() {
        let finer = std::mem::take(&mut refined[d as usize + 1]);
        let mut mine = std::mem::take(&mut refined[d as usize]);
        for &k in &finer {
            parent_block(demorton(k), 1 << (d + 1), &mut mine);
        }
        sort_dedup(&mut mine);
        refined[d as usize + 1] = finer;
        refined[d as usize] = mine;
    }
    // Each depth's cells, nodes and indices depend only on the refined sets: built side by side.
    (0..=depth)
        .into_par_iter()
        .map(|d| {
            let cells: Vec<u64> = if d <= base {
                (0..1u64 << (3 * d)).collect()
            } else {
                let parents = &refined[d as usize - 1];
                let mut v = Vec::with_capacity(parents.len() * 8);
                for &p in parents {
                    v.extend((0..8).map(|c| p * 8 + c));
                }
                v
            };
            let is_refined: Vec<bool> = if d < base {
                vec![true; cells.len()]
            } else if d == depth {
                vec![false; cells.len()]
            } else {
                let r = &refined[d as usize];
                cells
                    .par_iter()
                    .map(|k| r.binary_search(k).is_ok())
                    .collect()
            };
            make_level(d, cells, is_refined)
        })
        .collect()
}

fn make_level(depth: u32, cells: Vec<u64>, refined: Vec<bool>) -> Level {
    // The cells' index (a serial pass) is built beside the nodes.
    let (cell_index, (nodes, node_index, colors)) = rayon::join(
        || SparseIndex::new(cells.iter().map(|&k| demorton(k)), 1 << depth, cells.len()),
        || level_nodes(depth, &cells),
    );
    let corners: Vec<[u32; 8]> = cells
        .par_iter()
        .map(|&k| {
            let c = demorton(k);
            let mut out = [0u32; 8];
            for (q, slot) in out.iter_mut().enumerate() {
                let o = corner(q);
                let q = [
                    i64::from(c[0] + o[0]),
                    i64::from(c[1] + o[1]),
                    i64::from(c[2] + o[2]),
                ];
                *slot = node_index.get(q).unwrap_or(u32::MAX);
            }
            out
        })
        .collect();
    Level {
        depth,
        cells,
        refined,
        cell_index,
        corners,
        nodes,
        node_index,
        colors,
    }
}

/// The corner nodes of a depth's `cells`, sorted by (colour, Morton), their index and the
/// colours' starts.
fn level_nodes(depth: u32, cells: &[u64]) -> (Vec<[u32; 3]>, SparseIndex, [usize; 9]) {
    // Corner nodes, sorted by (colour, Morton). Cells come in broods of eight (Morton-sorted, so
    // each brood is contiguous), whose 27 distinct corners are listed once.
    let key_of = |nc: [u32; 3]| (color(nc) << 60) | morton(nc);
    let mut keys: Vec<u64> = if cells.len().is_multiple_of(8)
        && cells
            .chunks(8)
            .all(|b| b[0].is_multiple_of(8) && b[7] == b[0] + 7)
    {
        let mut keys = vec![0u64; cells.len() / 8 * 27];
        keys.par_chunks_mut(27)
            .zip(cells.par_chunks(8))
            .for_each(|(out, brood)| {
                let c = demorton(brood[0]);
                for (q, k) in out.iter_mut().enumerate() {
                    let o = [(q % 3) as u32, ((q / 3) % 3) as u32, (q / 9) as u32];
                    *k = key_of([c[0] + o[0], c[1] + o[1], c[2] + o[2]]);
                }
            });
        keys
    } else {
        let mut keys = vec![0u64; cells.len() * 8];
        keys.par_chunks_mut(8).zip(cells).for_each(|(out, &k)| {
            let c = demorton(k);
            for (q, key) in out.iter_mut().enumerate() {
                let o = corner(q);
                *key = key_of([c[0] + o[0], c[1] + o[1], c[2] + o[2]]);
            }
        });
        keys
    };
    sort_dedup(&mut keys);
    let mask = (1u64 << 60) - 1;
    let nodes: Vec<[u32; 3]> = keys.par_iter().map(|&k| demorton(k & mask)).collect();
    let mut colors = [0usize; 9];
    for &k in &keys {
        colors[(k >> 60) as usize + 1] += 1;
    }
    for c in 0..8 {
        colors[c + 1] += colors[c];
    }
    let node_index = SparseIndex::new(nodes.iter().copied(), (1 << depth) + 1, nodes.len());
    (nodes, node_index, colors)
}
