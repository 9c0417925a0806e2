//! Screened Poisson reconstruction in the plane (Kazhdan and Hoppe 2013, in 2D): oriented points
//! in, the closed curve `chi = iso` out.
//!
//! The same finite-element formulation as `rfta-spsr`'s octree, on a complete quadtree: degree-1
//! (bilinear) hats on the nodes of a `2^depth` grid over a square domain, Neumann boundary.
//! `chi` minimizes `int |grad chi - V|^2 + alpha sum_p l_p chi(p)^2`, where `V` is the normals
//! splatted with the length `l_p` each point stands for (from a density estimate) at the depth
//! whose cell matches the point spacing, and `alpha = screening / h` (`h` the finest cell, so the
//! balance between the two terms does not change with depth). The iso-value is the mean of `chi`
//! at the points and the curve is its marching-squares contour, exact on grid edges.
//!
//! Why a complete grid and not an adaptive quadtree: in 2D the complete grid at the depths the
//! pipeline uses (7 to 10) has 17k to 1M nodes and solves in milliseconds to a few tenths of a
//! second; an adaptive tree would save little and cost the grading, the ghost-free couplings and
//! the crack-free extraction that the octree needs.
//!
//! The solver is full multigrid with V-cycles: the coarse spaces are nested in the fine ones, so
//! the operator rediscretized on a coarse grid (stiffness, and the screening splatted there) is
//! exactly the Galerkin product `R A P`. Smoothing is four-colour Gauss-Seidel (nodes of one
//! colour share no matrix entry), so the result does not depend on the thread count.

mod level;

use level::{Hat, Level, Line, NONE, prolong, restrict};
use rayon::prelude::*;
use rfta_geom::glam::DVec2;
use rfta_geom::plane::{Grid2, Polylines};
use rfta_mc::marching_squares;

/// Settings of a 2D solve.
#[derive(Debug, Clone, PartialEq)]
pub struct SpsrParams {
    /// Depth of the finest grid: `2^depth` cells per side (1 to 12).
    pub depth: u32,
    /// Screening weight `alpha h` (see the module documentation).
    pub screening: f64,
    /// V-cycles after the full-multigrid pass.
    pub cycles: usize,
    /// Gauss-Seidel sweeps before and after each coarse correction.
    pub sweeps: usize,
}

impl Default for SpsrParams {
    fn default() -> Self {
        Self {
            depth: 8,
            screening: 4.0,
            cycles: 2,
            sweeps: 2,
        }
    }
}

/// The square the solve covers: `min` to `min + side` along both axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    /// Lower-left corner.
    pub min: DVec2,
    /// Side length.
    pub side: f64,
}

impl Domain {
    /// The square centred on the points' bounding box with `scale` times its longer side.
    pub fn around(points: &[DVec2], scale: f64) -> Self {
        let (lo, hi) = points.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let side = ((hi - lo).max_element() * scale).max(1e-9);
        Self {
            min: (lo + hi) / 2.0 - DVec2::splat(side / 2.0),
            side,
        }
    }
}

/// Why a 2D solve was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// Fewer than two points.
    #[error("screened Poisson needs at least 2 oriented points, got {0}")]
    TooFewPoints(usize),
    /// Positions and normals differ in length.
    #[error("{points} points but {normals} normals")]
    LengthMismatch {
        /// Points.
        points: usize,
        /// Normals.
        normals: usize,
    },
    /// A point or normal is not finite, or a normal has zero length.
    #[error("point {0} or its normal is not finite, or the normal is zero")]
    BadPoint(usize),
    /// A point lies outside the domain.
    #[error("point {0} lies outside the solve's domain")]
    OutsideDomain(usize),
    /// Depth outside 1 to 12 or a screening that is negative or not finite.
    #[error("invalid screened Poisson settings: {0}")]
    InvalidParams(String),
}

/// The solved implicit function on the finest grid.
#[derive(Debug, Clone)]
pub struct Solution {
    /// The finest grid's nodes.
    pub grid: Grid2,
    /// `chi` at every node (grid order).
    pub values: Vec<f64>,
    /// The iso-value: the mean of `chi` at the points.
    pub iso: f64,
}

impl Solution {
    /// The reconstructed curve: closed loops with the inside on their left.
    pub fn curve(&self) -> Polylines {
        marching_squares(&self.grid, &self.values, self.iso)
    }

    /// `chi(p) - iso`: negative inside.
    pub fn value(&self, p: DVec2) -> f64 {
        let n = self.grid.dims()[0] - 1;
        let h = self.grid.spacing().x;
        let Hat { cell, weights } = Hat::at(p, self.grid.origin(), h, n);
        let ny = n + 1;
        let mut v = 0.0;
        for (k, w) in weights.iter().enumerate() {
            let (i, j) = (cell.0 + k / 2, cell.1 + k % 2);
            v += w * self.values[i * ny + j];
        }
        v - self.iso
    }
}

/// Coarsest depth of the multigrid hierarchy, solved by many sweeps.
const COARSEST: u32 = 2;

/// Solve for `chi` from oriented points (normals pointing out of the shape), in `domain`.
///
/// # Errors
/// [`Error`]: too few points, mismatched or non-finite input, a point outside the domain,
/// invalid settings.
pub fn solve(
    points: &[DVec2],
    normals: &[DVec2],
    domain: Domain,
    params: &SpsrParams,
) -> Result<Solution, Error> {
    check(points, normals, domain, params)?;
    let depth = params.depth;
    let coarsest = COARSEST.min(depth);
    let lengths = lengths(points, domain, depth);
    let field = normal_field(points, normals, &lengths, domain, depth, coarsest);
    let levels = systems(points, &lengths, domain, params, coarsest);
    let rhs = right_hand_side(&levels[depth as usize], &field[depth as usize]);
    let x = multigrid(&levels, rhs, depth, coarsest, params);
    let m = levels[depth as usize].line.n + 1;
    let h = cell_side(domain, depth);
    let grid = Grid2::new([m, m], domain.min, DVec2::splat(h))
        .map_err(|e| Error::InvalidParams(e.to_string()))?;
    let mut solution = Solution {
        grid,
        values: x,
        iso: 0.0,
    };
    let total: f64 = lengths.iter().sum();
    solution.iso = points
        .iter()
        .zip(&lengths)
        .map(|(&p, &l)| solution.value(p) * l)
        .sum::<f64>()
        / total;
    Ok(solution)
}

/// The inputs refused: lengths that differ, fewer than 2 points, a depth outside 1 to 12, a
/// negative or non-finite screening, a bad domain, a non-finite point or normal, a zero normal,
/// a point outside the domain.
fn check(
    points: &[DVec2],
    normals: &[DVec2],
    domain: Domain,
    params: &SpsrParams,
) -> Result<(), Error> {
    if points.len() != normals.len() {
        return Err(Error::LengthMismatch {
            points: points.len(),
            normals: normals.len(),
        });
    }
    if points.len() < 2 {
        return Err(Error::TooFewPoints(points.len()));
    }
    let valid = (1..=12).contains(&params.depth)
        && params.screening >= 0.0
        && params.screening.is_finite()
        && domain.side > 0.0
        && domain.side.is_finite()
        && domain.min.is_finite();
    if !valid {
        return Err(Error::InvalidParams(format!(
            "depth {} (1 to 12), screening {}, domain side {}",
            params.depth, params.screening, domain.side
        )));
    }
    let max = domain.min + DVec2::splat(domain.side);
    for (i, (p, n)) in points.iter().zip(normals).enumerate() {
        if !p.is_finite() || !n.is_finite() || n.length_squared() == 0.0 {
            return Err(Error::BadPoint(i));
        }
        if p.cmplt(domain.min).any() || p.cmpgt(max).any() {
            return Err(Error::OutsideDomain(i));
        }
    }
    Ok(())
}

/// The side of a cell at depth `d` of `domain`.
fn cell_side(domain: Domain, d: u32) -> f64 {
    domain.side / (1usize << d) as f64
}

/// The curve length each point stands for: the points near each point, counted with the hats two
/// depths above the finest; a point on a line of points `s` apart counts `h_d / s` of them, so
/// `s = h_d / count`.
fn lengths(points: &[DVec2], domain: Domain, depth: u32) -> Vec<f64> {
    let cells = |d: u32| 1usize << d;
    let h = |d: u32| cell_side(domain, d);
    let density_depth = depth.saturating_sub(2).max(1);
    let (nd, hd) = (cells(density_depth), h(density_depth));
    let mut counts = vec![0.0; (nd + 1) * (nd + 1)];
    let hats: Vec<Hat> = points
        .iter()
        .map(|&p| Hat::at(p, domain.min, hd, nd))
        .collect();
    for hat in &hats {
        for (k, w) in hat.weights.iter().enumerate() {
            counts[(hat.cell.0 + k / 2) * (nd + 1) + hat.cell.1 + k % 2] += w;
        }
    }
    hats.iter()
        .map(|hat| {
            let c: f64 = (0..4)
                .map(|k| {
                    hat.weights[k] * counts[(hat.cell.0 + k / 2) * (nd + 1) + hat.cell.1 + k % 2]
                })
                .sum();
            hd / c.max(1e-12)
        })
        .collect()
}

/// The normal field on every depth's nodes: each point splatted, with its length, at the depth
/// whose cell is about its spacing, then carried to the finer depths (the spaces are nested, so
/// exactly).
fn normal_field(
    points: &[DVec2],
    normals: &[DVec2],
    lengths: &[f64],
    domain: Domain,
    depth: u32,
    coarsest: u32,
) -> Vec<Vec<DVec2>> {
    let cells = |d: u32| 1usize << d;
    let h = |d: u32| cell_side(domain, d);
    let mut field: Vec<Vec<DVec2>> = (0..=depth)
        .map(|d| vec![DVec2::ZERO; (cells(d) + 1) * (cells(d) + 1)])
        .collect();
    for ((&p, &n), &l) in points.iter().zip(normals).zip(lengths) {
        let d = (rfta_geom::math::log2(domain.side / l).floor() as i64)
            .clamp(coarsest as i64, depth as i64) as u32;
        let hat = Hat::at(p, domain.min, h(d), cells(d));
        let m = cells(d) + 1;
        let scale = l / (h(d) * h(d));
        for (k, w) in hat.weights.iter().enumerate() {
            field[d as usize][(hat.cell.0 + k / 2) * m + hat.cell.1 + k % 2] +=
                n.normalize() * (w * scale);
        }
    }
    for d in coarsest..depth {
        let (xs, ys): (Vec<f64>, Vec<f64>) = field[d as usize].iter().map(|v| (v.x, v.y)).unzip();
        let (px, py) = (prolong(&xs, cells(d)), prolong(&ys, cells(d)));
        for (k, v) in field[d as usize + 1].iter_mut().enumerate() {
            *v += DVec2::new(px[k], py[k]);
        }
    }

    field
}

/// The system of every depth: its grid and, from the coarsest solved depth on, the screening
/// stencils of the nodes near points.
fn systems(
    points: &[DVec2],
    lengths: &[f64],
    domain: Domain,
    params: &SpsrParams,
    coarsest: u32,
) -> Vec<Level> {
    let depth = params.depth;
    let cells = |d: u32| 1usize << d;
    let h = |d: u32| cell_side(domain, d);
    let alpha = params.screening / h(depth);
    (0..=depth)
        .map(|d| {
            let line = Line {
                n: cells(d),
                h: h(d),
            };
            let m = line.n + 1;
            let mut slot = vec![NONE; if d >= coarsest { m * m } else { 0 }];
            let mut screening: Vec<[f64; 9]> = Vec::new();
            if d >= coarsest {
                for (&p, &l) in points.iter().zip(lengths) {
                    let hat = Hat::at(p, domain.min, h(d), line.n);
                    for a in 0..4 {
                        let (ai, aj) = (hat.cell.0 + a / 2, hat.cell.1 + a % 2);
                        let k = ai * m + aj;
                        if slot[k] == NONE {
                            slot[k] = screening.len() as u32;
                            screening.push([0.0; 9]);
                        }
                        let stencil = &mut screening[slot[k] as usize];
                        for b in 0..4 {
                            let (di, dj) = (
                                (b / 2) as isize - (a / 2) as isize,
                                (b % 2) as isize - (a % 2) as isize,
                            );
                            stencil[((di + 1) * 3 + dj + 1) as usize] +=
                                alpha * l * hat.weights[a] * hat.weights[b];
                        }
                    }
                }
            }
            Level {
                line,
                slot,
                screening,
            }
        })
        .collect()
}

/// The right-hand side at the finest depth, `fine`: `int grad(phi_i) . V` over the field `v`.
fn right_hand_side(fine: &Level, v: &[DVec2]) -> Vec<f64> {
    let line = fine.line;
    let m = line.n + 1;
    (0..m * m)
        .into_par_iter()
        .with_min_len(256)
        .map(|k| {
            let (i, j) = (k / m, k % m);
            let mut b = 0.0;
            if i > 0 && i < line.n && j > 0 && j < line.n {
                // Away from the border: mixed integrals (1/2, 0, -1/2), masses (h/6, 2h/3, h/6).
                let (hm, hc) = (line.h / 6.0, 2.0 * line.h / 3.0);
                let up = |kk: usize| v[kk];
                let (r0, r2) = (k - m, k + m);
                // d/dx: rows i-1 (+1/2) and i+1 (-1/2), masses along j.
                let mx = |r: usize| up(r - 1).x * hm + up(r).x * hc + up(r + 1).x * hm;
                let my = |c: usize| up(c - m).y * hm + up(c).y * hc + up(c + m).y * hm;
                return 0.5 * (mx(r0) - mx(r2)) + 0.5 * (my(k - 1) - my(k + 1));
            }
            for di in -1..=1isize {
                if !line.exists(i, di) {
                    continue;
                }
                for dj in -1..=1isize {
                    if !line.exists(j, dj) {
                        continue;
                    }
                    let f = v[(i as isize + di) as usize * m + (j as isize + dj) as usize];
                    b += f.x * line.mixed(i, di) * line.mass(j, dj)
                        + f.y * line.mass(i, di) * line.mixed(j, dj);
                }
            }
            b
        })
        .collect()
}

/// Full multigrid: the right-hand side restricted to every depth, solved on the coarsest,
/// prolonged and improved by a V-cycle at each finer depth, then `cycles` more at the finest.
fn multigrid(
    levels: &[Level],
    rhs: Vec<f64>,
    depth: u32,
    coarsest: u32,
    params: &SpsrParams,
) -> Vec<f64> {
    let cells = |d: u32| 1usize << d;
    let mut rhs_at = vec![Vec::new(); depth as usize + 1];
    rhs_at[depth as usize] = rhs;
    for d in (coarsest..depth).rev() {
        rhs_at[d as usize] = restrict(&rhs_at[d as usize + 1], cells(d));
    }
    let mut x = vec![0.0; levels[coarsest as usize].nodes()];
    levels[coarsest as usize].smooth(&mut x, &rhs_at[coarsest as usize], COARSE_SWEEPS);
    for d in coarsest + 1..=depth {
        x = prolong(&x, cells(d - 1));
        v_cycle(
            levels,
            d,
            coarsest,
            &mut x,
            &rhs_at[d as usize],
            params.sweeps,
        );
    }
    for _ in 0..params.cycles {
        v_cycle(
            levels,
            depth,
            coarsest,
            &mut x,
            &rhs_at[depth as usize],
            params.sweeps,
        );
    }

    x
}

/// Sweeps on the coarsest grid (5 x 5 nodes).
const COARSE_SWEEPS: usize = 64;

fn v_cycle(levels: &[Level], d: u32, coarsest: u32, x: &mut [f64], b: &[f64], sweeps: usize) {
    let level = &levels[d as usize];
    if d == coarsest {
        level.smooth(x, b, COARSE_SWEEPS);
        return;
    }
    level.smooth(x, b, sweeps);
    let r = level.residual(x, b);
    let n_coarse = level.line.n / 2;
    let rc = restrict(&r, n_coarse);
    let mut e = vec![0.0; rc.len()];
    v_cycle(levels, d - 1, coarsest, &mut e, &rc, sweeps);
    for (xi, ei) in x.iter_mut().zip(prolong(&e, n_coarse)) {
        *xi += ei;
    }
    level.smooth(x, b, sweeps);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, r: f64) -> (Vec<DVec2>, Vec<DVec2>) {
        (0..n)
            .map(|k| {
                let t = k as f64 / n as f64 * std::f64::consts::TAU;
                let u = DVec2::new(t.cos(), t.sin());
                (u * r, u)
            })
            .unzip()
    }

    #[test]
    fn a_circle_of_points_gives_one_loop_on_it() {
        let (p, n) = circle(400, 0.5);
        let params = SpsrParams {
            depth: 8,
            ..SpsrParams::default()
        };
        let s = solve(&p, &n, Domain::around(&p, 1.5), &params).expect("valid test input");
        let c = s.curve();
        assert_eq!(c.loops(), 1);
        assert!(c.is_closed());
        // Finest cell 0.75 / 256 = 0.0029; the loop stays within two cells of the circle.
        for v in &c.vertices {
            assert!((v.length() - 0.5).abs() < 0.006, "{}", v.length());
        }
        assert!(s.value(DVec2::ZERO) < 0.0 && s.value(DVec2::new(0.7, 0.0)) > 0.0);
    }

    #[test]
    fn the_multigrid_converges() {
        let (p, n) = circle(200, 0.4);
        let domain = Domain::around(&p, 1.5);
        let few = SpsrParams {
            depth: 7,
            cycles: 0,
            ..SpsrParams::default()
        };
        let many = SpsrParams {
            cycles: 30,
            ..few.clone()
        };
        let (a, b) = (
            solve(&p, &n, domain, &few).expect("solves"),
            solve(&p, &n, domain, &many).expect("solves"),
        );
        // One full-multigrid pass is within a small fraction of the converged solution.
        let scale = b.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = a
            .values
            .iter()
            .zip(&b.values)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(err < 0.05 * scale, "{err} vs {scale}");
    }

    #[test]
    fn bad_input_is_refused() {
        let (p, n) = circle(10, 0.5);
        let d = Domain::around(&p, 1.5);
        let params = SpsrParams::default();
        assert!(solve(&p[..1], &n[..1], d, &params).is_err());
        assert!(solve(&p, &n[..5], d, &params).is_err());
        let mut bad = n.clone();
        bad[3] = DVec2::ZERO;
        assert!(solve(&p, &bad, d, &params).is_err());
        let far = Domain {
            min: DVec2::splat(5.0),
            side: 1.0,
        };
        assert!(solve(&p, &n, far, &params).is_err());
    }
}
