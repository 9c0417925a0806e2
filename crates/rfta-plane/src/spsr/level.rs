//! The complete quadtree's pieces: the bilinear hats at a point, the one-dimensional integrals of
//! a depth's hats, a depth's system, and the transfers between depths.

use rayon::prelude::*;
use rfta_geom::glam::DVec2;

/// The four bilinear hats that are non-zero at a point: its cell and their values, corners in the
/// order (0,0), (0,1), (1,0), (1,1).
pub(super) struct Hat {
    pub(super) cell: (usize, usize),
    pub(super) weights: [f64; 4],
}

impl Hat {
    pub(super) fn at(p: DVec2, min: DVec2, h: f64, n: usize) -> Self {
        let q = (p - min) / h;
        let i = (q.x.floor().max(0.0) as usize).min(n - 1);
        let j = (q.y.floor().max(0.0) as usize).min(n - 1);
        let u = (q.x - i as f64).clamp(0.0, 1.0);
        let v = (q.y - j as f64).clamp(0.0, 1.0);
        Self {
            cell: (i, j),
            weights: [(1.0 - u) * (1.0 - v), (1.0 - u) * v, u * (1.0 - v), u * v],
        }
    }
}

/// One-dimensional integrals of degree-1 hats on `n` cells of size `h` (nodes `0..=n`), between
/// node `i` and node `i + d`, `d` in -1..=1: mass `int phi_i phi_j`, stiffness
/// `int phi_i' phi_j'` and mixed `int phi_i' phi_j`, each cut at the domain's ends.
#[derive(Clone, Copy)]
pub(super) struct Line {
    pub(super) n: usize,
    pub(super) h: f64,
}

impl Line {
    pub(super) fn exists(&self, i: usize, d: isize) -> bool {
        let j = i as isize + d;
        j >= 0 && j <= self.n as isize
    }

    pub(super) fn ends(&self, i: usize) -> f64 {
        if i == 0 || i == self.n { 1.0 } else { 2.0 }
    }

    pub(super) fn mass(&self, i: usize, d: isize) -> f64 {
        if d == 0 {
            self.ends(i) * self.h / 3.0
        } else {
            self.h / 6.0
        }
    }

    pub(super) fn stiffness(&self, i: usize, d: isize) -> f64 {
        if d == 0 {
            self.ends(i) / self.h
        } else {
            -1.0 / self.h
        }
    }

    pub(super) fn mixed(&self, i: usize, d: isize) -> f64 {
        match d {
            -1 => 0.5,
            1 => -0.5,
            _ => (if i == self.n { 0.5 } else { 0.0 }) - (if i == 0 { 0.5 } else { 0.0 }),
        }
    }
}

/// The system at one depth: the Laplacian's integrals and the screening's 3x3 stencils, kept
/// only for the nodes near a point (`slot[k]` indexes `screening`, `NONE` elsewhere).
pub(super) struct Level {
    pub(super) line: Line,
    pub(super) slot: Vec<u32>,
    pub(super) screening: Vec<[f64; 9]>,
}

/// No screening at a node.
pub(super) const NONE: u32 = u32::MAX;

/// The stencil of a node without screening.
pub(super) const ZERO: [f64; 9] = [0.0; 9];

impl Level {
    pub(super) fn nodes(&self) -> usize {
        let m = self.line.n + 1;
        m * m
    }

    /// `(A x)` at node `(i, j)` without its diagonal term, and the diagonal.
    pub(super) fn row(&self, x: &[f64], i: usize, j: usize) -> (f64, f64) {
        let n = self.line.n;
        let m = n + 1;
        let k = i * m + j;
        let s = match self.slot[k] {
            NONE => &ZERO,
            at => &self.screening[at as usize],
        };
        if i > 0 && i < n && j > 0 && j < n {
            if self.slot[k] == NONE {
                let sum = x[k - m - 1]
                    + x[k - m]
                    + x[k - m + 1]
                    + x[k - 1]
                    + x[k + 1]
                    + x[k + m - 1]
                    + x[k + m]
                    + x[k + m + 1];
                return (-sum / 3.0, 8.0 / 3.0);
            }
            // Away from the border the Laplacian's stencil is the same everywhere (in 2D it does
            // not even depend on h): 8/3 at the node, -1/3 at its eight neighbours.
            let mut off = 0.0;
            for (t, &kk) in [
                k - m - 1,
                k - m,
                k - m + 1,
                k - 1,
                k,
                k + 1,
                k + m - 1,
                k + m,
                k + m + 1,
            ]
            .iter()
            .enumerate()
            {
                if t != 4 {
                    off += (s[t] - 1.0 / 3.0) * x[kk];
                }
            }
            return (off, 8.0 / 3.0 + s[4]);
        }
        let (mut off, mut diag) = (0.0, 0.0);
        for di in -1..=1isize {
            if !self.line.exists(i, di) {
                continue;
            }
            let (mi, ki) = (self.line.mass(i, di), self.line.stiffness(i, di));
            for dj in -1..=1isize {
                if !self.line.exists(j, dj) {
                    continue;
                }
                let a = ki * self.line.mass(j, dj)
                    + mi * self.line.stiffness(j, dj)
                    + s[((di + 1) * 3 + dj + 1) as usize];
                if di == 0 && dj == 0 {
                    diag = a;
                } else {
                    let kk = (i as isize + di) as usize * m + (j as isize + dj) as usize;
                    off += a * x[kk];
                }
            }
        }
        (off, diag)
    }

    pub(super) fn residual(&self, x: &[f64], b: &[f64]) -> Vec<f64> {
        let m = self.line.n + 1;
        (0..self.nodes())
            .into_par_iter()
            .with_min_len(256)
            .map(|k| {
                let (off, diag) = self.row(x, k / m, k % m);
                b[k] - off - diag * x[k]
            })
            .collect()
    }

    /// Four-colour Gauss-Seidel: each colour's nodes updated together from the others' values.
    pub(super) fn smooth(&self, x: &mut [f64], b: &[f64], sweeps: usize) {
        let m = self.line.n + 1;
        for _ in 0..sweeps {
            for colour in 0..4 {
                let (pi, pj) = (colour / 2, colour % 2);
                let (rows, cols) = ((m - pi).div_ceil(2), (m - pj).div_ceil(2));
                let updates: Vec<f64> = (0..rows * cols)
                    .into_par_iter()
                    .with_min_len(512)
                    .map(|t| {
                        let (i, j) = (pi + 2 * (t / cols), pj + 2 * (t % cols));
                        let (off, diag) = self.row(x, i, j);
                        (b[i * m + j] - off) / diag
                    })
                    .collect();
                for (t, v) in updates.into_iter().enumerate() {
                    x[(pi + 2 * (t / cols)) * m + pj + 2 * (t % cols)] = v;
                }
            }
        }
    }
}

/// Bilinear prolongation of node values from `n` cells to `2n` cells per side (separable: along
/// y, then along x).
pub(super) fn prolong(coarse: &[f64], n: usize) -> Vec<f64> {
    let (mc, mf) = (n + 1, 2 * n + 1);
    let mut half = vec![0.0; mc * mf];
    for i in 0..mc {
        let (src, dst) = (
            &coarse[i * mc..(i + 1) * mc],
            &mut half[i * mf..(i + 1) * mf],
        );
        for (jj, d) in dst.iter_mut().enumerate() {
            *d = if jj % 2 == 0 {
                src[jj / 2]
            } else {
                0.5 * (src[jj / 2] + src[jj / 2 + 1])
            };
        }
    }
    let mut fine = vec![0.0; mf * mf];
    for (ii, row) in fine.chunks_exact_mut(mf).enumerate() {
        let a = &half[(ii / 2) * mf..(ii / 2 + 1) * mf];
        if ii % 2 == 0 {
            row.copy_from_slice(a);
        } else {
            let b = &half[(ii / 2 + 1) * mf..(ii / 2 + 2) * mf];
            for ((r, x), y) in row.iter_mut().zip(a).zip(b) {
                *r = 0.5 * (x + y);
            }
        }
    }
    fine
}

/// The transpose of [`prolong`]: fine node values summed into the coarse nodes with weights 1
/// and 1/2 per axis.
pub(super) fn restrict(fine: &[f64], n: usize) -> Vec<f64> {
    let (mc, mf) = (n + 1, 2 * n + 1);
    // Along x first: fine rows into coarse rows.
    let mut half = vec![0.0; mc * mf];
    for ii in 0..mf {
        let w = if ii % 2 == 0 { 1.0 } else { 0.5 };
        let row = &fine[ii * mf..(ii + 1) * mf];
        let targets = if ii % 2 == 0 {
            ii / 2..ii / 2 + 1
        } else {
            ii / 2..ii / 2 + 2
        };
        for target in targets {
            for (d, x) in half[target * mf..(target + 1) * mf].iter_mut().zip(row) {
                *d += w * x;
            }
        }
    }
    let mut coarse = vec![0.0; mc * mc];
    for i in 0..mc {
        let (src, dst) = (
            &half[i * mf..(i + 1) * mf],
            &mut coarse[i * mc..(i + 1) * mc],
        );
        for (jj, x) in src.iter().enumerate() {
            if jj % 2 == 0 {
                dst[jj / 2] += x;
            } else {
                dst[jj / 2] += 0.5 * x;
                dst[jj / 2 + 1] += 0.5 * x;
            }
        }
    }
    coarse
}
