//! Moving coefficients between depths: prolongation to the finer depth and restriction to the
//! coarser, with exact parent-child weights.

use super::*;

/// Calls `f(parent node, [mass, stiffness, mixed] per axis)` for every active node one depth
/// coarser whose hat overlaps the hat of the fine node at `c` (its 27 parents `par`).
#[inline]
pub(super) fn for_parents(
    sys: &LevelSystem,
    par: [u32; 27],
    c: [u32; 3],
    mut f: impl FnMut(u32, &[f64; 3], &[f64; 3], &[f64; 3]),
) {
    let p = &sys.tables.parent;
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
pub(super) fn prolongation_parents(c: [u32; 3]) -> ([(usize, f64); 8], usize) {
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
pub(super) fn prolong<T>(fine: &Level, parents: Stencil, u: &[T]) -> Vec<T>
where
    T: Copy + Send + Sync + Default + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    (0..fine.nodes.len())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|i| {
            let (ps, m) = prolongation_parents(fine.nodes[i]);
            let par = parents.of(i);
            let mut acc = T::default();
            for &(slot, w) in &ps[..m] {
                let j = par[slot];
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
pub(super) fn restrict(coarse: &Level, fine: &Level, beta: &[f64]) -> Vec<f64> {
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
