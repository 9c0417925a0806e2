//! The finite-element system and its cascadic multigrid solution.
//!
//! The implicit function is a hierarchical sum `χ = Σ_d Σ_{i active at d} x_{d,i} B_{d,i}` of
//! trilinear hats over all depths (Kazhdan and Hoppe 2013, §4). It minimises
//! `∫ |∇χ - V|² + α Σ_s w_s (χ(p_s) - 1/2)²`, where `V` is the splatted inward normal field and
//! the second term screens the samples toward the value 1/2. The solver goes once from the
//! coarsest depth to the finest: at each depth the coarser solution is held fixed, its effect is
//! moved to the right-hand side with exact parent-child integrals, and the depth's own system is
//! relaxed (conjugate gradients on the complete coarse grids, multi-colour Gauss-Seidel above).

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;
use rfta_geom::glam::DVec3;

use crate::basis::{AxisTables, combine};
use crate::tree::{Level, Sample, cell_of, corner, hats_in};
use crate::{Boundary, SpsrParams};

use crate::keys::NONE;
/// The value the screening pulls the function toward at the samples (the indicator is 1 inside
/// and 0 outside, so 1/2 on the surface).
pub(crate) const SAMPLE_TARGET: f64 = 0.5;

/// Chunk length of parallel sums: fixed, so sums never depend on the thread count.
const CHUNK: usize = 2048;

/// Smallest piece a parallel loop is split into. Loops that write each element on its own give
/// the same bits however they are split, so this only trades scheduling against balance: one
/// colour of a depth-8 Gauss-Seidel sweep holds a few hundred to a few thousand nodes, which a
/// grain of [`CHUNK`] (or of 256, as before) would leave on one thread.
pub(crate) const GRAIN: usize = 64;

/// Offset `o` (0..27) of a 3x3x3 stencil as `[-1, 0, 1]` per axis.
#[inline]
fn offset(o: usize) -> [i64; 3] {
    [
        (o % 3) as i64 - 1,
        ((o / 3) % 3) as i64 - 1,
        (o / 9) as i64 - 1,
    ]
}

#[inline]
fn ic(c: [u32; 3]) -> [i64; 3] {
    [i64::from(c[0]), i64::from(c[1]), i64::from(c[2])]
}

/// Aggregated screening sample of one cell (all samples inside it, weight-averaged).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScreenCell {
    /// Cell index in its level.
    pub cell: u32,
    /// Screening weight `α ā Σ w`.
    pub weight: f64,
    /// Weight-averaged position, unit cube.
    pub pos: DVec3,
    /// Hat values at the eight corners.
    pub hats: [f64; 8],
    /// The value the screening pulls the function toward here: 1/2 at the samples, a side's value
    /// at a [`ValueConstraint`].
    pub target: f64,
}

/// A point where the function is screened toward a value of its own (unit cube): the side
/// constraints of [`crate::reconstruct_with_sides`], with a weight in the samples' units
/// ([`Sample::weight`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ValueConstraint {
    pub pos: DVec3,
    pub target: f64,
    pub weight: f64,
}

/// Everything a depth needs to relax its own system.
pub(crate) struct LevelSystem {
    pub tables: AxisTables,
    pub screen: Vec<ScreenCell>,
    /// CSR: for node `i`, `inc[inc_off[i]..inc_off[i + 1]]` = `screen index << 3 | corner`.
    pub inc_off: Vec<u32>,
    pub inc: Vec<u32>,
    pub diag: Vec<f64>,
    /// Dirichlet: nodes on the cube's faces are pinned to 0.
    pub fixed: Vec<bool>,
    interior: [f64; 27],
}

impl LevelSystem {
    /// Laplacian entry between node `c` and its neighbour at offset `o`.
    #[inline]
    fn k(&self, c: [u32; 3], o: usize, n: u32) -> f64 {
        if c.iter().all(|&v| v >= 1 && v < n) {
            return self.interior[o];
        }
        let t = &self.tables.same;
        let off = offset(o);
        let a = |axis: usize| &t[c[axis] as usize][(off[axis] + 1) as usize];
        combine(a(0), a(1), a(2)).0
    }
}

/// Build the per-depth systems: neighbour tables, screening cells and diagonals.
pub(crate) fn build_systems(
    levels: &[Level],
    samples: &[Sample],
    constraints: &[ValueConstraint],
    params: &SpsrParams,
    alpha: f64,
) -> Vec<LevelSystem> {
    let depth = levels.len() as u32 - 1;
    levels
        .par_iter()
        .map(|level| {
            let d = level.depth;
            let n = level.n();
            let tables = AxisTables::new(d);

            // Screening cells: samples grouped by their depth-d cell (Morton order is preserved).
            // As in PoissonRecon (Kazhdan and Hoppe 2013, §4.3; `adaptiveExponent` 1), the
            // screening weight grows as 2^d with depth: the Laplacian's entries shrink with the
            // cell width while a cell's samples keep their weight, and this keeps the pull toward
            // the samples equally strong against the smoothness term at every depth.
            let depth_scale = f64::from(1u32 << d);
            let shift = 3 * (depth - d);
            let mut screen = Vec::new();
            let mut i = 0;
            while i < samples.len() {
                let key = samples[i].key >> shift;
                let mut j = i;
                let (mut w, mut p) = (0.0, DVec3::ZERO);
                while j < samples.len() && samples[j].key >> shift == key {
                    w += samples[j].weight;
                    p += samples[j].weight * samples[j].pos;
                    j += 1;
                }
                let cc = crate::keys::demorton(key);
                if let Some(cell) = level.cell(ic(cc))
                    && alpha > 0.0
                {
                    let pos = p / w;
                    screen.push(ScreenCell {
                        cell,
                        weight: alpha * depth_scale * w,
                        pos,
                        hats: hats_in(pos, cc, d),
                        target: SAMPLE_TARGET,
                    });
                }
                i = j;
            }
            // Value constraints act on the depths whose tree reaches them, each on its own.
            if alpha > 0.0 {
                for c in constraints {
                    let cc = cell_of(c.pos, d);
                    if let Some(cell) = level.cell(ic(cc)) {
                        screen.push(ScreenCell {
                            cell,
                            weight: alpha * depth_scale * c.weight,
                            pos: c.pos,
                            hats: hats_in(c.pos, cc, d),
                            target: c.target,
                        });
                    }
                }
            }
            let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(screen.len() * 8);
            for (s, sc) in screen.iter().enumerate() {
                for (k, &node) in level.corners[sc.cell as usize].iter().enumerate() {
                    pairs.push((node, ((s as u32) << 3) | k as u32));
                }
            }
            pairs.par_sort_unstable();
            let mut inc_off = vec![0u32; level.nodes.len() + 1];
            for &(node, _) in &pairs {
                inc_off[node as usize + 1] += 1;
            }
            for i in 0..level.nodes.len() {
                inc_off[i + 1] += inc_off[i];
            }
            let inc: Vec<u32> = pairs.iter().map(|p| p.1).collect();
            let mut interior = [0.0; 27];
            if n >= 2 {
                for (o, v) in interior.iter_mut().enumerate() {
                    let off = offset(o);
                    let a = |axis: usize| &tables.same[1][(off[axis] + 1) as usize];
                    *v = combine(a(0), a(1), a(2)).0;
                }
            }
            let fixed: Vec<bool> = level
                .nodes
                .par_iter()
                .map(|c| {
                    params.boundary == Boundary::Dirichlet && c.iter().any(|&v| v == 0 || v == n)
                })
                .collect();
            let mut sys = LevelSystem {
                tables,
                screen,
                inc_off,
                inc,
                diag: Vec::new(),
                fixed,
                interior,
            };
            let diag: Vec<f64> = (0..level.nodes.len())
                .into_par_iter()
                .map(|i| {
                    let mut v = sys.k(level.nodes[i], 13, n);
                    for &e in &sys.inc[sys.inc_off[i] as usize..sys.inc_off[i + 1] as usize] {
                        let sc = &sys.screen[(e >> 3) as usize];
                        let h = sc.hats[(e & 7) as usize];
                        v += sc.weight * h * h;
                    }
                    v
                })
                .collect();
            sys.diag = diag;
            sys
        })
        .collect()
}

/// 27 neighbour node indices per node (`NONE` when absent), in [`offset`] order. Built for one
/// depth at a time and dropped after use: it is the largest per-node array.
pub(crate) fn neighbor_table(level: &Level) -> Vec<u32> {
    // Collected into place: no serial fill of the table first.
    level
        .nodes
        .par_iter()
        .with_min_len(GRAIN)
        .map(|&c| level.node_index.block27(ic(c)))
        .collect::<Vec<[u32; 27]>>()
        .into_flattened()
}

/// 27 node indices one depth coarser per node: hat `(c >> 1) + o - 1` per axis.
pub(crate) fn parent_table(fine: &Level, coarse: &Level) -> Vec<u32> {
    fine.nodes
        .par_iter()
        .with_min_len(GRAIN)
        .map(|&c| {
            let p = [
                i64::from(c[0] >> 1),
                i64::from(c[1] >> 1),
                i64::from(c[2] >> 1),
            ];
            coarse.node_index.block27(p)
        })
        .collect::<Vec<[u32; 27]>>()
        .into_flattened()
}

/// Splat the (inward) normal field: each sample's area-weighted normal goes to the hats of the two
/// depths bracketing its fractional depth, linearly weighted. Returns per depth the coefficients
/// of `V` in that depth's hat basis (divided by the cell volume so that `V` integrates to the
/// sample's area times its normal).
pub(crate) fn splat_normals(levels: &[Level], samples: &[Sample]) -> Vec<Vec<DVec3>> {
    // One depth per task: a depth's coefficients receive the samples in their order, as a single
    // pass over the samples would add them.
    levels
        .par_iter()
        .map(|level| {
            let d = level.depth;
            let mut v = vec![DVec3::ZERO; level.nodes.len()];
            let nf = f64::from(1u32 << d);
            let inv_vol = nf.powi(3);
            for s in samples {
                let d0 = s.depth.floor() as u32;
                let t = s.depth - f64::from(d0);
                let w = if d == d0 {
                    1.0 - t
                } else if d == d0 + 1 {
                    t
                } else {
                    continue;
                };
                if w <= 0.0 {
                    continue;
                }
                let normal = -s.normal * (s.area / s.weight);
                // Quadratic B-spline weights of the three nearest nodes per axis: the normal
                // field is the hat interpolation of a degree-2 kernel around the sample (as
                // smooth as PoissonRecon's degree-2 normal splat; the weights sum to 1 so V keeps
                // its integral).
                let mut idx = [[0i64; 3]; 3];
                let mut wts = [[0.0f64; 3]; 3];
                for axis in 0..3 {
                    let x = s.pos[axis] * nf;
                    let r = x.round() as i64;
                    for (k, j) in (r - 1..=r + 1).enumerate() {
                        idx[axis][k] = j;
                        wts[axis][k] = quadratic_bspline(j as f64 - x);
                    }
                }
                for (kz, &jz) in idx[2].iter().enumerate() {
                    for (ky, &jy) in idx[1].iter().enumerate() {
                        for (kx, &jx) in idx[0].iter().enumerate() {
                            let h = wts[0][kx] * wts[1][ky] * wts[2][kz];
                            if h == 0.0 {
                                continue;
                            }
                            if let Some(node) = level.node([jx, jy, jz]) {
                                v[node as usize] += normal * (w * h * inv_vol);
                            }
                        }
                    }
                }
            }
            v
        })
        .collect()
}

/// The centred quadratic B-spline (support `[-1.5, 1.5]`, integral 1).
#[inline]
pub(crate) fn quadratic_bspline(t: f64) -> f64 {
    let a = t.abs();
    if a <= 0.5 {
        0.75 - a * a
    } else if a < 1.5 {
        0.5 * (1.5 - a) * (1.5 - a)
    } else {
        0.0
    }
}

/// `∫ ∇B_i · V_d` for every node of a depth, `V_d` given by same-depth coefficients.
fn apply_g(level: &Level, tables: &AxisTables, nbr: &[u32], v: &[DVec3]) -> Vec<f64> {
    let t = &tables.same;
    (0..level.nodes.len())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|i| {
            let c = level.nodes[i];
            let mut acc = 0.0;
            for o in 0..27 {
                let j = nbr[i * 27 + o];
                if j == NONE {
                    continue;
                }
                let vj = v[j as usize];
                if vj == DVec3::ZERO {
                    continue;
                }
                let off = offset(o);
                let a = |axis: usize| &t[c[axis] as usize][(off[axis] + 1) as usize];
                let (_, g) = combine(a(0), a(1), a(2));
                acc += g[0] * vj.x + g[1] * vj.y + g[2] * vj.z;
            }
            acc
        })
        .collect()
}

/// Calls `f(parent node, [mass, stiffness, mixed] per axis)` for every active node one depth
/// coarser whose hat overlaps the hat of fine node `i` (coordinates `c`).
#[inline]
fn for_parents(
    sys: &LevelSystem,
    parents: &[u32],
    i: usize,
    c: [u32; 3],
    mut f: impl FnMut(u32, &[f64; 3], &[f64; 3], &[f64; 3]),
) {
    let p = &sys.tables.parent;
    let par = &parents[i * 27..i * 27 + 27];
    for oz in 0..3usize {
        let az = &p[c[2] as usize][oz];
        if az[0] == 0.0 && az[2] == 0.0 {
            continue;
        }
        for oy in 0..3usize {
            let ay = &p[c[1] as usize][oy];
            if ay[0] == 0.0 && ay[2] == 0.0 {
                continue;
            }
            for ox in 0..3usize {
                let ax = &p[c[0] as usize][ox];
                if ax[0] == 0.0 && ax[2] == 0.0 {
                    continue;
                }
                let j = par[ox + 3 * oy + 9 * oz];
                if j != NONE {
                    f(j, ax, ay, az);
                }
            }
        }
    }
}

/// The two-scale parents of fine node `c` (up to 8): `(slot in the 27 parents, weight)`.
#[inline]
fn prolongation_parents(c: [u32; 3]) -> ([(usize, f64); 8], usize) {
    let axis = |v: u32| -> ([(usize, f64); 2], usize) {
        if v & 1 == 0 {
            ([(1, 1.0), (0, 0.0)], 1)
        } else {
            ([(1, 0.5), (2, 0.5)], 2)
        }
    };
    let (ax, nx) = axis(c[0]);
    let (ay, ny) = axis(c[1]);
    let (az, nz) = axis(c[2]);
    let mut out = [(0usize, 0.0f64); 8];
    let mut m = 0;
    for &(oz, wz) in &az[..nz] {
        for &(oy, wy) in &ay[..ny] {
            for &(ox, wx) in &ax[..nx] {
                out[m] = (ox + 3 * oy + 9 * oz, wx * wy * wz);
                m += 1;
            }
        }
    }
    (out, m)
}

/// Values of a coarser depth's nodal function at this depth's nodes (exact: the hat spaces nest).
fn prolong<T>(fine: &Level, parents: &[u32], u: &[T]) -> Vec<T>
where
    T: Copy + Send + Sync + Default + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    (0..fine.nodes.len())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|i| {
            let (ps, m) = prolongation_parents(fine.nodes[i]);
            let mut acc = T::default();
            for &(slot, w) in &ps[..m] {
                let j = parents[i * 27 + slot];
                if j != NONE {
                    acc = acc + u[j as usize] * w;
                }
            }
            acc
        })
        .collect()
}

/// Restriction `Σ_children w β_child` of a finer depth's right-hand side onto the coarser nodes
/// (the transpose of [`prolong`]). Each coarse node gathers from the fine nodes at twice its
/// coordinates plus -1, 0 or 1 per axis (weight 1/2 per odd axis), summed in fine node order:
/// the same sum, bit for bit, as scattering the fine nodes in order.
fn restrict(coarse: &Level, fine: &Level, beta: &[f64]) -> Vec<f64> {
    coarse
        .nodes
        .par_iter()
        .with_min_len(GRAIN)
        .map(|&c| {
            let ids = fine.node_index.block27([
                2 * i64::from(c[0]),
                2 * i64::from(c[1]),
                2 * i64::from(c[2]),
            ]);
            let mut terms = [(0u32, 0.0f64); 27];
            let mut m = 0;
            for (o, &i) in ids.iter().enumerate() {
                if i == NONE || beta[i as usize] == 0.0 {
                    continue;
                }
                let odd = [o % 3 != 1, (o / 3) % 3 != 1, o / 9 != 1];
                let w = odd
                    .iter()
                    .fold(1.0, |w, &odd| if odd { w * 0.5 } else { w });
                terms[m] = (i, w * beta[i as usize]);
                m += 1;
            }
            let terms = &mut terms[..m];
            terms.sort_unstable_by_key(|t| t.0);
            terms.iter().fold(0.0, |acc, t| acc + t.1)
        })
        .collect()
}

/// Depths with at most this many nodes keep their index tables in the [`DownPass`], shared by
/// every [`solve`] on the octree instead of built per solve.
const KEEP_TABLES_BELOW: usize = 1 << 17;

/// Below this many nodes a depth's conjugate-gradient loop runs on one thread: the coarse grids
/// are small and a parallel pass over them costs more in scheduling than in arithmetic. Every sum
/// is taken in the same fixed chunks either way, so the result does not change.
const SERIAL_BELOW: usize = 8 * CHUNK;

/// `(K + S) x` on one depth, into `out` (`fs` is scratch for the screening cells).
fn apply_a(
    level: &Level,
    sys: &LevelSystem,
    nbr: &[u32],
    x: &[f64],
    fs: &mut Vec<f64>,
    out: &mut [f64],
) {
    let n = level.n();
    let screen_value = |s: &ScreenCell| {
        let corners = &level.corners[s.cell as usize];
        let mut f = 0.0;
        for k in 0..8 {
            f += s.hats[k] * x[corners[k] as usize];
        }
        f
    };
    let serial = level.nodes.len() < SERIAL_BELOW;
    fs.clear();
    if serial {
        fs.extend(sys.screen.iter().map(screen_value));
    } else {
        sys.screen.par_iter().map(screen_value).collect_into_vec(fs);
    }
    let fs: &[f64] = fs;
    let row = |i: usize| {
        if sys.fixed[i] {
            return x[i];
        }
        let c = level.nodes[i];
        let mut acc = 0.0;
        for o in 0..27 {
            let j = nbr[i * 27 + o];
            if j != NONE && !sys.fixed[j as usize] {
                acc += sys.k(c, o, n) * x[j as usize];
            }
        }
        for &e in &sys.inc[sys.inc_off[i] as usize..sys.inc_off[i + 1] as usize] {
            let s = &sys.screen[(e >> 3) as usize];
            acc += s.weight * s.hats[(e & 7) as usize] * fs[(e >> 3) as usize];
        }
        acc
    };
    if serial {
        out.iter_mut().enumerate().for_each(|(i, o)| *o = row(i));
    } else {
        out.par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(i, o)| *o = row(i));
    }
}

/// `a . b`, summed per fixed chunk and then over the chunks in order (any thread count, same bits).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let chunk = |(a, b): (&[f64], &[f64])| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    if a.len() < SERIAL_BELOW {
        return a.chunks(CHUNK).zip(b.chunks(CHUNK)).map(chunk).sum();
    }
    a.par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(chunk)
        .collect::<Vec<f64>>()
        .iter()
        .sum()
}

/// `y += a x` elementwise (serially on small vectors).
fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    if y.len() < SERIAL_BELOW {
        y.iter_mut().zip(x).for_each(|(y, x)| *y += a * x);
    } else {
        y.par_iter_mut().zip(x).for_each(|(y, x)| *y += a * x);
    }
}

/// Conjugate gradients on one depth (used on the complete coarse grids).
fn conjugate_gradients(
    level: &Level,
    sys: &LevelSystem,
    nbr: &[u32],
    r0: &[f64],
    iters: usize,
    tol: f64,
) -> Vec<f64> {
    let n = r0.len();
    let mut x = vec![0.0; n];
    let mut r: Vec<f64> = r0
        .iter()
        .zip(&sys.fixed)
        .map(|(&v, &f)| if f { 0.0 } else { v })
        .collect();
    let mut p = r.clone();
    let mut ap = vec![0.0; n];
    let mut fs = Vec::new();
    let mut rr = dot(&r, &r);
    let stop = rr * tol * tol;
    for _ in 0..iters {
        if rr <= stop || rr == 0.0 {
            break;
        }
        apply_a(level, sys, nbr, &p, &mut fs, &mut ap);
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            break;
        }
        let a = rr / pap;
        axpy(&mut x, a, &p);
        axpy(&mut r, -a, &ap);
        let rr_new = dot(&r, &r);
        let beta = rr_new / rr;
        rr = rr_new;
        let update = |(p, r): (&mut f64, &f64)| *p = r + beta * *p;
        if n < SERIAL_BELOW {
            p.iter_mut().zip(&r).for_each(update);
        } else {
            p.par_iter_mut().zip(&r).for_each(update);
        }
    }
    x
}

/// Laplacian row of node `c` (27 entries, offsets as in [`offset`]).
#[inline]
fn k_row(sys: &LevelSystem, c: [u32; 3], n: u32) -> [f64; 27] {
    if c.iter().all(|&v| v >= 1 && v < n) {
        return sys.interior;
    }
    let mut row = [0.0; 27];
    for (o, r) in row.iter_mut().enumerate() {
        *r = sys.k(c, o, n);
    }
    row
}

/// Multi-colour Gauss-Seidel: nodes of one colour share no matrix entry, so each colour is
/// relaxed in parallel, in place, and the result does not depend on the thread count. The value
/// of the current iterate at every screening cell is kept up to date: a cell has exactly one
/// corner of each colour, so the node that moves updates its cells' values itself (no other node
/// of its colour reads or writes them), and a node's screening term costs one read per incident
/// cell. One parallel loop per colour and sweep.
fn gauss_seidel(
    level: &Level,
    sys: &LevelSystem,
    nbr: &[u32],
    r: &[f64],
    x: &mut [f64],
    sweeps: usize,
) {
    let n = level.n();
    // Each cell's value, as bits: written only by the one node of the colour being relaxed.
    let fs: Vec<AtomicU64> = sys
        .screen
        .par_iter()
        .map(|s| {
            let corners = &level.corners[s.cell as usize];
            let f: f64 = (0..8).map(|k| s.hats[k] * x[corners[k] as usize]).sum();
            AtomicU64::new(f.to_bits())
        })
        .collect();
    let value = |e: u32| f64::from_bits(fs[(e >> 3) as usize].load(Ordering::Relaxed));
    for _ in 0..sweeps {
        for c in 0..8 {
            let (lo, hi) = (level.colors[c], level.colors[c + 1]);
            // The colour's nodes are contiguous; its neighbours are all outside it.
            let (before, rest) = x.split_at_mut(lo);
            let (mine, after) = rest.split_at_mut(hi - lo);
            let (before, after): (&[f64], &[f64]) = (before, after);
            let at = |j: usize| if j < lo { before[j] } else { after[j - hi] };
            mine.par_iter_mut()
                .with_min_len(GRAIN)
                .enumerate()
                .for_each(|(k, xi)| {
                    let i = lo + k;
                    let old = *xi;
                    let incident = &sys.inc[sys.inc_off[i] as usize..sys.inc_off[i + 1] as usize];
                    let new = if sys.fixed[i] {
                        0.0
                    } else {
                        let row = k_row(sys, level.nodes[i], n);
                        let nb = &nbr[i * 27..i * 27 + 27];
                        let mut acc = 0.0;
                        for o in 0..27 {
                            let j = nb[o];
                            if o != 13 && j != NONE {
                                acc += row[o] * at(j as usize);
                            }
                        }
                        for &e in incident {
                            let s = &sys.screen[(e >> 3) as usize];
                            let h = s.hats[(e & 7) as usize];
                            acc += s.weight * h * (value(e) - h * old);
                        }
                        (r[i] - acc) / sys.diag[i]
                    };
                    *xi = new;
                    for &e in incident {
                        let h = sys.screen[(e >> 3) as usize].hats[(e & 7) as usize];
                        let f = value(e) + h * (new - old);
                        fs[(e >> 3) as usize].store(f.to_bits(), Ordering::Relaxed);
                    }
                });
        }
    }
}

/// What the down pass computes for one depth on its own: the neighbour table, `∫ ∇B_d · V_d`, and
/// the table of the parents one depth coarser.
struct DownTerms {
    nbr: Vec<u32>,
    g: Vec<f64>,
    parents: Option<Vec<u32>>,
}

/// A previous solution to start the relaxation from: per depth, its nodes and their
/// coefficients `x_d` (each the correction on top of the coarser depths, so a node's value is
/// a good guess wherever the cloud and the coarser solution changed little).
#[derive(Debug, Clone, Default)]
pub(crate) struct WarmStart {
    pub nodes: Vec<crate::keys::SparseIndex>,
    pub x: Vec<Vec<f64>>,
}

impl WarmStart {
    /// The previous coefficients at this depth's nodes (0 at nodes that are new), if the previous
    /// solution reached this depth.
    fn start(&self, d: usize, level: &Level) -> Option<Vec<f64>> {
        let (index, x) = (self.nodes.get(d)?, self.x.get(d)?);
        if x.is_empty() {
            return None;
        }
        Some(
            level
                .nodes
                .par_iter()
                .with_min_len(GRAIN)
                .map(|&c| index.get(ic(c)).map_or(0.0, |j| x[j as usize]))
                .collect(),
        )
    }
}

/// Solution: per depth the coefficients `x_d` and the nodal values `U_d` of `Σ_{l ≤ d} χ_l`.
pub(crate) struct Solution {
    pub x: Vec<Vec<f64>>,
    pub u: Vec<Vec<f64>>,
}

/// The normal field's share of every depth's right-hand side, with the index tables of the small
/// depths: what the down pass of the cascadic solve computes. It depends on the octree and the
/// normal field only, not on the screening, so the re-solves of
/// [`crate::reconstruct_with_sides`], which add value constraints to the same octree, reuse it.
pub(crate) struct DownPass {
    /// `β_d = ∫ ∇B_d · Σ_{l ≥ d} V_l` per depth.
    beta: Vec<Vec<f64>>,
    /// Neighbour tables of the depths with at most `KEEP_TABLES_BELOW` nodes.
    nbr: Vec<Option<Vec<u32>>>,
    /// Parent tables of those depths (none at depth 0).
    parents: Vec<Option<Vec<u32>>>,
}

/// The down pass: β_d = ∫ ∇B_d · Σ_{l ≥ d} V_l, that is each depth's own `∫ ∇B_d · V_d` plus the
/// restriction of the finer depth's β. The own terms and the small depths' tables do not depend
/// on each other and are built for all small depths at once; the big depths follow one at a
/// time in the chain of restrictions.
pub(crate) fn down_pass(levels: &[Level], v: &[Vec<DVec3>]) -> DownPass {
    let depth = levels.len() - 1;
    // Index tables the up pass needs (the neighbour tables serve the down pass's own terms too):
    // kept for the depths small enough (at most `KEEP_TABLES_BELOW` nodes, 14 MB a table), so
    // that every solve on this octree shares them; the up pass builds the big ones one depth at a
    // time.
    let small = |d: usize| levels[d].nodes.len() <= KEEP_TABLES_BELOW;
    let mut nbr: Vec<Option<Vec<u32>>> = vec![None; depth + 1];
    let mut parents: Vec<Option<Vec<u32>>> = vec![None; depth + 1];
    let own: Vec<Option<DownTerms>> = (0..=depth)
        .into_par_iter()
        .map(|d| {
            if !small(d) {
                return None;
            }
            let nbr = neighbor_table(&levels[d]);
            let g = apply_g(&levels[d], &AxisTables::new(d as u32), &nbr, &v[d]);
            let parents = (d > 0).then(|| parent_table(&levels[d], &levels[d - 1]));
            Some(DownTerms { nbr, g, parents })
        })
        .collect();
    let mut own_g: Vec<Option<Vec<f64>>> = vec![None; depth + 1];
    for (d, o) in own.into_iter().enumerate() {
        if let Some(DownTerms {
            nbr: n,
            g,
            parents: p,
        }) = o
        {
            nbr[d] = Some(n);
            own_g[d] = Some(g);
            parents[d] = p;
        }
    }
    let mut beta: Vec<Vec<f64>> = vec![Vec::new(); depth + 1];
    for d in (0..=depth).rev() {
        let mut b = own_g[d].take().unwrap_or_else(|| {
            let nbr = neighbor_table(&levels[d]);
            apply_g(&levels[d], &AxisTables::new(d as u32), &nbr, &v[d])
        });
        if d < depth {
            let r = restrict(&levels[d], &levels[d + 1], &beta[d + 1]);
            b.iter_mut().zip(&r).for_each(|(b, r)| *b += r);
        }
        beta[d] = b;
    }
    DownPass { beta, nbr, parents }
}

/// The cascadic solve, coarse to fine (the up pass), from the normal field `v` and its down pass.
pub(crate) fn solve(
    levels: &[Level],
    systems: &[LevelSystem],
    v: &[Vec<DVec3>],
    down: &DownPass,
    params: &SpsrParams,
    base: u32,
    warm: Option<&WarmStart>,
) -> Solution {
    let depth = levels.len() - 1;
    let mut xs: Vec<Vec<f64>> = Vec::with_capacity(depth + 1);
    let mut us: Vec<Vec<f64>> = Vec::with_capacity(depth + 1);
    let mut w_prev: Vec<DVec3> = Vec::new();
    for d in 0..=depth {
        let level = &levels[d];
        let sys = &systems[d];
        let mut rhs = down.beta[d].clone();
        // Coarser normal field and coarser solution, through exact parent-child integrals, and
        // both prolonged to this depth (they do not depend on this depth's solution).
        let (u_coarse, w_coarse) = if d > 0 {
            let built;
            let parents = match &down.parents[d] {
                Some(p) => p,
                None => {
                    built = parent_table(level, &levels[d - 1]);
                    &built
                }
            };
            let u_prev = &us[d - 1];
            let corr: Vec<f64> = (0..level.nodes.len())
                .into_par_iter()
                .with_min_len(GRAIN)
                .map(|i| {
                    let c = level.nodes[i];
                    let mut acc = 0.0;
                    for_parents(sys, parents, i, c, |j, ax, ay, az| {
                        let (k, g) = combine(ax, ay, az);
                        let w = w_prev[j as usize];
                        acc += g[0] * w.x + g[1] * w.y + g[2] * w.z - k * u_prev[j as usize];
                    });
                    acc
                })
                .collect();
            rhs.iter_mut().zip(&corr).for_each(|(r, c)| *r += c);
            (
                prolong(level, parents, u_prev),
                prolong(level, parents, &w_prev),
            )
        } else {
            (
                vec![0.0; level.nodes.len()],
                vec![DVec3::ZERO; level.nodes.len()],
            )
        };
        // Screening toward the target, minus what the coarser solution already gives (that
        // value per screening cell in parallel, added to the right-hand side in order).
        let coarse_values: Vec<f64> = sys
            .screen
            .par_iter()
            .with_min_len(GRAIN)
            .map(|s| {
                if d == 0 {
                    return 0.0;
                }
                let coarse = &levels[d - 1];
                let cc = cell_of(s.pos, d as u32 - 1);
                match coarse.cell(ic(cc)) {
                    Some(ci) => {
                        let h = hats_in(s.pos, cc, d as u32 - 1);
                        let corners = &coarse.corners[ci as usize];
                        (0..8).map(|k| h[k] * us[d - 1][corners[k] as usize]).sum()
                    }
                    None => 0.0,
                }
            })
            .collect();
        for (s, fc) in sys.screen.iter().zip(coarse_values) {
            let corners = &level.corners[s.cell as usize];
            for k in 0..8 {
                rhs[corners[k] as usize] += s.weight * s.hats[k] * (s.target - fc);
            }
        }
        for (r, &f) in rhs.iter_mut().zip(&sys.fixed) {
            if f {
                *r = 0.0;
            }
        }
        let built;
        let nbr = match &down.nbr[d] {
            Some(n) => n,
            None => {
                built = neighbor_table(level);
                &built
            }
        };
        let x = if (d as u32) < base {
            conjugate_gradients(level, sys, nbr, &rhs, params.base_iterations, 1e-6)
        } else {
            let mut x = match warm.and_then(|w| w.start(d, level)) {
                Some(x) => x,
                None => vec![0.0; level.nodes.len()],
            };
            gauss_seidel(level, sys, nbr, &rhs, &mut x, params.iterations);
            x
        };
        let mut u = u_coarse;
        u.iter_mut().zip(&x).for_each(|(u, x)| *u += x);
        let mut w = w_coarse;
        w.iter_mut().zip(&v[d]).for_each(|(w, v)| *w += *v);
        w_prev = w;
        xs.push(x);
        us.push(u);
    }
    Solution { x: xs, u: us }
}

/// Evaluate the implicit function at a unit-cube point: the sum over depths of the hats around it.
pub(crate) fn evaluate(levels: &[Level], sol: &Solution, p: DVec3, base: u32) -> f64 {
    let mut f = 0.0;
    let base = base.min(levels.len() as u32 - 1);
    // Depths up to `base` are complete grids: their sum is interpolated from U_base.
    let start = base as usize;
    for (d, level) in levels.iter().enumerate().skip(start) {
        let c = cell_of(p, d as u32);
        let h = hats_in(p, c, d as u32);
        let vals = if d == start { &sol.u[d] } else { &sol.x[d] };
        match level.cell(ic(c)) {
            Some(ci) => {
                let corners = &level.corners[ci as usize];
                for k in 0..8 {
                    f += h[k] * vals[corners[k] as usize];
                }
            }
            None => {
                let mut any = false;
                for (k, hk) in h.iter().enumerate() {
                    let o = corner(k);
                    let q = [c[0] + o[0], c[1] + o[1], c[2] + o[2]];
                    if let Some(j) = level.node(ic(q)) {
                        f += hk * vals[j as usize];
                        any = true;
                    }
                }
                // Nodes are the corners of cells, and a cell's parent is a cell: a finer cell
                // touching the one around `p` would have a parent sharing a corner with this
                // one. With no corner here, no finer depth has a hat over `p`.
                if !any {
                    break;
                }
            }
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OrientedPoints, tree};

    /// A thin octree: 4,000 points on a small sphere off-centre, so most of the cube is coarse.
    #[allow(clippy::type_complexity)]
    fn thin_tree()
    -> Result<(OrientedPoints, tree::Frame, Vec<Level>, u32), Box<dyn std::error::Error>> {
        let (points, frame, samples, base) = thin_samples()?;
        let levels = tree::build_levels(&samples, &[], THIN_DEPTH, base);
        Ok((points, frame, levels, base))
    }

    /// The depth of [`thin_tree`].
    const THIN_DEPTH: u32 = 7;

    /// The points of [`thin_tree`], their frame, merged samples (densities estimated) and the
    /// base depth.
    #[allow(clippy::type_complexity)]
    fn thin_samples()
    -> Result<(OrientedPoints, tree::Frame, Vec<tree::Sample>, u32), Box<dyn std::error::Error>>
    {
        let n = 4000;
        let dirs: Vec<DVec3> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let phi = i as f64 * 2.399963229728653;
                let s = (1.0 - z * z).sqrt();
                DVec3::new(s * phi.cos(), s * phi.sin(), z)
            })
            .collect();
        let pos: Vec<DVec3> = dirs.iter().map(|d| 0.2 * *d + DVec3::splat(0.3)).collect();
        let points = OrientedPoints::new(pos, dirs, None)?;
        let params = SpsrParams {
            depth: THIN_DEPTH,
            box_scale: 3.0,
            ..SpsrParams::default()
        };
        let base = 3;
        let frame = tree::Frame::around(&points, params.box_scale)?;
        let mut samples = tree::merge(&points, &frame, params.depth);
        tree::estimate_density(&mut samples, &params, base);
        Ok((points, frame, samples, base))
    }

    /// A fixed pseudo-random sequence in [-1/2, 1/2).
    fn sequence(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// A seed is refined to the finest depth as a sample there would be: its finest cell and the
    /// 3x3x3 block of cells around it exist (the block's parents are refined), the depths above
    /// stay graded (every finer cell's parent is a cell), and every cell of the tree without the
    /// seed is still there.
    #[test]
    fn a_seed_is_refined_to_the_finest_depth() -> Result<(), Box<dyn std::error::Error>> {
        let (_, _, samples, base) = thin_samples()?;
        let depth = THIN_DEPTH;
        let plain = tree::build_levels(&samples, &[], depth, base);
        // Far from the samples (a sphere of radius 0.2 around 0.3 in the points' frame).
        let seed = DVec3::new(0.81, 0.77, 0.79);
        let at = |levels: &[Level], d: u32, c: [u32; 3]| {
            levels[d as usize].cell([i64::from(c[0]), i64::from(c[1]), i64::from(c[2])])
        };
        let c = cell_of(seed, depth);
        assert!(
            at(&plain, depth, c).is_none(),
            "the plain tree reaches the seed"
        );
        let seeded = tree::build_levels(&samples, &[seed], depth, base);
        for o in 0..27u32 {
            let q = [c[0] + o % 3 - 1, c[1] + (o / 3) % 3 - 1, c[2] + o / 9 - 1];
            assert!(at(&seeded, depth, q).is_some(), "cell {q:?} of the block");
        }
        for d in 1..=depth as usize {
            for &k in &seeded[d].cells {
                let p = crate::keys::demorton(k >> 3);
                assert!(
                    at(&seeded, d as u32 - 1, p).is_some(),
                    "parent of a depth-{d} cell"
                );
            }
            for &k in &plain[d].cells {
                assert!(
                    seeded[d].cells.binary_search(&k).is_ok(),
                    "lost a depth-{d} cell"
                );
            }
        }
        Ok(())
    }

    /// The parallel restriction (each coarse node gathering) equals, bit for bit, scattering the
    /// fine nodes in order to their prolongation parents, at every depth.
    #[test]
    fn restriction_is_the_ordered_scatter() -> Result<(), Box<dyn std::error::Error>> {
        let (_, _, levels, _) = thin_tree()?;
        let mut next = sequence(7);
        for d in 1..levels.len() {
            let (coarse, fine) = (&levels[d - 1], &levels[d]);
            // Some zeros, as a right-hand side has away from the samples.
            let beta: Vec<f64> = fine
                .nodes
                .iter()
                .map(|_| {
                    let v = next();
                    if v < -0.3 { 0.0 } else { v }
                })
                .collect();
            let parents = parent_table(fine, coarse);
            let mut want = vec![0.0; coarse.nodes.len()];
            for (i, &b) in beta.iter().enumerate() {
                let (ps, m) = prolongation_parents(fine.nodes[i]);
                for &(slot, w) in &ps[..m] {
                    let j = parents[i * 27 + slot];
                    if j != NONE {
                        want[j as usize] += w * b;
                    }
                }
            }
            let got = restrict(coarse, fine, &beta);
            assert!(
                got.iter()
                    .zip(&want)
                    .all(|(g, w)| g.to_bits() == w.to_bits()),
                "depth {d}"
            );
        }
        Ok(())
    }

    /// Arbitrary coefficients on a thin octree: `evaluate`, which stops at the first depth
    /// without a hat over the point, equals the sum of every hat of every depth at the point.
    #[test]
    fn evaluate_is_the_sum_of_all_hats() -> Result<(), Box<dyn std::error::Error>> {
        let (points, frame, levels, base) = thin_tree()?;
        let n = points.len();
        let mut next = sequence(12345);
        let sol = Solution {
            x: levels
                .iter()
                .map(|l| l.nodes.iter().map(|_| next()).collect())
                .collect(),
            u: levels
                .iter()
                .map(|l| l.nodes.iter().map(|_| next()).collect())
                .collect(),
        };
        let hat = |p: DVec3, c: [u32; 3], d: usize| {
            let s = f64::from(1u32 << d);
            (0..3)
                .map(|a| (1.0 - (p[a] * s - f64::from(c[a])).abs()).max(0.0))
                .product::<f64>()
        };
        let mut deep = 0;
        for k in 0..2000 {
            // Unit-cube points; every fourth next to a point of the cloud, where the fine depths
            // have hats.
            let u = DVec3::new(next() + 0.5, next() + 0.5, next() + 0.5);
            let u = if k % 4 == 0 {
                frame.to_unit(points.positions()[k % n] + 0.02 * (u - 0.5))
            } else {
                u
            };
            let mut sum = 0.0;
            for (d, level) in levels.iter().enumerate().skip(base as usize) {
                let vals = if d == base as usize {
                    &sol.u[d]
                } else {
                    &sol.x[d]
                };
                for (i, &c) in level.nodes.iter().enumerate() {
                    let w = hat(u, c, d);
                    if w > 0.0 && d == levels.len() - 1 {
                        deep += 1;
                    }
                    sum += w * vals[i];
                }
            }
            let f = evaluate(&levels, &sol, u, base);
            assert!((f - sum).abs() < 1e-12, "at {u}: {f} against {sum}");
        }
        assert!(deep > 100, "too few points reach the finest depth: {deep}");
        Ok(())
    }
}
