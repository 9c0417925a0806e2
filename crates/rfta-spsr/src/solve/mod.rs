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
use crate::tree::{Level, Sample, cell_of, hats_in};
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

mod evaluate;
mod relax;
mod stencil;
mod system;
mod transfer;

pub(crate) use evaluate::Evaluator;
use relax::*;
pub(crate) use stencil::*;
pub(crate) use system::*;
use transfer::*;

/// What the down pass computes for one depth on its own: the neighbour table, `∫ ∇B_d · V_d`, and
/// the table of the parents one depth coarser.
struct DownTerms {
    nbr: Vec<u32>,
    g: Vec<f64>,
    parents: Option<Vec<u32>>,
}

/// A previous solution to start the relaxation from: per depth, its coefficients `x_d` (each
/// the correction on top of the coarser depths, so a node's value is a good guess wherever the
/// cloud and the coarser solution changed little) and, when they lie on another octree's nodes,
/// that octree's node index per depth.
#[derive(Debug, Clone, Default)]
pub(crate) struct WarmStart {
    /// `None`: `x` lies on the nodes of the levels solved on, in their order.
    pub nodes: Option<Vec<crate::keys::SparseIndex>>,
    pub x: Vec<Vec<f64>>,
}

impl WarmStart {
    /// The previous coefficients at this depth's nodes (0 at nodes that are new), if the previous
    /// solution reached this depth.
    fn start(&self, d: usize, level: &Level) -> Option<Vec<f64>> {
        let x = self.x.get(d)?;
        if x.is_empty() {
            return None;
        }
        let Some(nodes) = &self.nodes else {
            debug_assert_eq!(x.len(), level.nodes.len());
            return Some(x.clone());
        };
        let index = nodes.get(d)?;
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
            let nbr = Stencil::neighbours(&levels[d]).table();
            let g = apply_g(
                &levels[d],
                &AxisTables::new(d as u32),
                Stencil::Table(&nbr),
                &v[d],
            );
            let parents = (d > 0).then(|| Stencil::parents(&levels[d], &levels[d - 1]).table());
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
            // Read once per node: looked up, no table.
            let nbr = Stencil::neighbours(&levels[d]);
            apply_g(&levels[d], &AxisTables::new(d as u32), nbr, &v[d])
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
        // both prolonged to this depth (they do not depend on this depth's solution). The normal
        // field summed to this depth is needed by the next depth only: made before this depth's
        // relaxation, so that the coarser one is dropped first, and not at the finest depth.
        let u_coarse = if d > 0 {
            let mut store = Vec::new();
            let parents = Stencil::parents(level, &levels[d - 1])
                .or_table(down.parents[d].as_ref(), &mut store);
            let u_prev = &us[d - 1];
            let corr: Vec<f64> = (0..level.nodes.len())
                .into_par_iter()
                .with_min_len(GRAIN)
                .map(|i| {
                    let c = level.nodes[i];
                    let mut acc = 0.0;
                    for_parents(sys, parents.of(i), c, |j, ax, ay, az| {
                        let (k, g) = combine(ax, ay, az);
                        let w = w_prev[j as usize];
                        acc += g[0] * w.x + g[1] * w.y + g[2] * w.z - k * u_prev[j as usize];
                    });
                    acc
                })
                .collect();
            rhs.iter_mut().zip(&corr).for_each(|(r, c)| *r += c);
            w_prev = if d < depth {
                let mut w = prolong(level, parents, &w_prev);
                w.iter_mut().zip(&v[d]).for_each(|(w, v)| *w += *v);
                w
            } else {
                Vec::new()
            };
            prolong(level, parents, u_prev)
        } else {
            let mut w = vec![DVec3::ZERO; level.nodes.len()];
            w.iter_mut().zip(&v[d]).for_each(|(w, v)| *w += *v);
            w_prev = w;
            vec![0.0; level.nodes.len()]
        };
        // Screening toward the target, minus what the coarser solution already gives (that
        // value per screening cell in parallel, added to the right-hand side in order).
        let coarse_values = coarse_at_screening(levels, sys, &us, d);
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
        let mut store = Vec::new();
        let nbr = Stencil::neighbours(level).or_table(down.nbr[d].as_ref(), &mut store);
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
        xs.push(x);
        us.push(u);
    }
    Solution { x: xs, u: us }
}

/// The coarser depths' solution `us` at each screening sample of depth `d` (0 at depth 0).
fn coarse_at_screening(levels: &[Level], sys: &LevelSystem, us: &[Vec<f64>], d: usize) -> Vec<f64> {
    sys.screen
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
        .collect()
}

#[cfg(test)]
mod tests;
