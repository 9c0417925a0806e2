//! Relaxing one depth's system: the operator applied, conjugate gradients on the complete
//! coarse grids, multi-colour Gauss-Seidel above.

use super::*;

/// Below this many nodes a depth's conjugate-gradient loop runs on one thread: the coarse grids
/// are small and a parallel pass over them costs more in scheduling than in arithmetic. Every sum
/// is taken in the same fixed chunks either way, so the result does not change.
pub(super) const SERIAL_BELOW: usize = 8 * CHUNK;

/// `(K + S) x` on one depth, into `out` (`fs` is scratch for the screening cells).
pub(super) fn apply_a(
    level: &Level,
    sys: &LevelSystem,
    nbr: Stencil,
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
        for (o, j) in nbr.of(i).into_iter().enumerate() {
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
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
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
pub(super) fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    if y.len() < SERIAL_BELOW {
        y.iter_mut().zip(x).for_each(|(y, x)| *y += a * x);
    } else {
        y.par_iter_mut().zip(x).for_each(|(y, x)| *y += a * x);
    }
}

/// Conjugate gradients on one depth (used on the complete coarse grids).
pub(super) fn conjugate_gradients(
    level: &Level,
    sys: &LevelSystem,
    nbr: Stencil,
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
pub(super) fn k_row(sys: &LevelSystem, c: [u32; 3], n: u32) -> [f64; 27] {
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
pub(super) fn gauss_seidel(
    level: &Level,
    sys: &LevelSystem,
    nbr: Stencil,
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
                        let mut acc = 0.0;
                        for (o, j) in nbr.of(i).into_iter().enumerate() {
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
