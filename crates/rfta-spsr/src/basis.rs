//! Degree-1 B-splines (hat functions) on `[0, 1]` and the exact one-dimensional integrals of their
//! products, from which every 3D matrix entry is a tensor product.
//!
//! At depth `d` there are `2^d + 1` hats per axis, `phi_{d,i}(x) = max(0, 1 - |2^d x - i|)`. The
//! integrals are taken over `[0, 1]` only, so the hats on the faces of the cube are halved: that
//! is the natural (Neumann) boundary condition of the finite-element method. Products of two hats
//! are quadratic on every cell of the finer depth, so Simpson's rule on each cell is exact.

/// Value of a hat at depth offset `ratio` (width `ratio` fine cells) centred at `centre`, at `x`
/// (all in units of the finer depth).
fn hat(x: f64, centre: f64, ratio: f64) -> f64 {
    (1.0 - ((x - centre) / ratio).abs()).max(0.0)
}

/// The three integrals that build every entry: `[mass, stiffness, mixed]` =
/// `[∫ φ_i φ_j, ∫ φ_i' φ_j', ∫ φ_i' φ_j]` over `[0, 1]`, where `φ_i` is hat `i` at depth `fine`
/// and `φ_j` is hat `j` at depth `fine - shift` (`shift` 0 or 1).
pub(crate) fn integrals(fine: u32, i: i64, shift: u32, j: i64) -> [f64; 3] {
    let n = 1i64 << fine;
    let r = f64::from(1u32 << shift);
    let cj = j as f64 * r;
    let lo = (i - 1).max(0);
    let hi = (i + 1).min(n);
    let mut acc = [0.0; 3];
    for k in lo..hi {
        let (a, b) = (k as f64, (k + 1) as f64);
        let m = 0.5 * (a + b);
        let fi = [
            hat(a, i as f64, 1.0),
            hat(m, i as f64, 1.0),
            hat(b, i as f64, 1.0),
        ];
        let fj = [hat(a, cj, r), hat(m, cj, r), hat(b, cj, r)];
        // Both are linear on [a, b] (all breakpoints are integers), so slopes are differences.
        let di = fi[2] - fi[0];
        let dj = fj[2] - fj[0];
        let simpson = |f: [f64; 3]| (f[0] + 4.0 * f[1] + f[2]) / 6.0;
        acc[0] += simpson([fi[0] * fj[0], fi[1] * fj[1], fi[2] * fj[2]]);
        acc[1] += di * dj;
        acc[2] += simpson([di * fj[0], di * fj[1], di * fj[2]]);
    }
    // Physical units: x = u / n, so dx = du / n and d/dx = n d/du.
    let h = 1.0 / n as f64;
    [acc[0] * h, acc[1] / h, acc[2]]
}

/// Per-axis integral tables of one depth.
#[derive(Debug, Clone)]
pub(crate) struct AxisTables {
    /// `same[i][o]` = integrals of hat `i` with hat `i + o - 1` of the same depth.
    pub same: Vec<[[f64; 3]; 3]>,
    /// `parent[i][o]` = integrals of hat `i` with hat `(i >> 1) + o - 1` one depth coarser.
    pub parent: Vec<[[f64; 3]; 3]>,
}

impl AxisTables {
    /// Tables for depth `d`.
    pub(crate) fn new(d: u32) -> Self {
        let n = 1i64 << d;
        let mut same = Vec::with_capacity(n as usize + 1);
        let mut parent = Vec::with_capacity(n as usize + 1);
        for i in 0..=n {
            let mut s = [[0.0; 3]; 3];
            let mut p = [[0.0; 3]; 3];
            for o in 0..3i64 {
                let j = i + o - 1;
                if (0..=n).contains(&j) {
                    s[o as usize] = integrals(d, i, 0, j);
                }
                let jp = (i >> 1) + o - 1;
                if d > 0 && (0..=n / 2).contains(&jp) {
                    p[o as usize] = integrals(d, i, 1, jp);
                }
            }
            same.push(s);
            parent.push(p);
        }
        Self { same, parent }
    }
}

/// The Laplacian entry `∫ ∇B_a · ∇B_b` and the three components of `∫ ∇B_a B_b` from per-axis
/// integrals `[mass, stiffness, mixed]`.
#[inline]
pub(crate) fn combine(x: &[f64; 3], y: &[f64; 3], z: &[f64; 3]) -> (f64, [f64; 3]) {
    let k = x[1] * y[0] * z[0] + x[0] * y[1] * z[0] + x[0] * y[0] * z[1];
    let g = [x[2] * y[0] * z[0], x[0] * y[2] * z[0], x[0] * y[0] * z[2]];
    (k, g)
}

/// Weight of coarse hat `j` (depth `d - 1`) on fine hat `i` (depth `d`) in the two-scale relation
/// `φ_{d-1,j} = Σ_i w φ_{d,i}`: 1 for `i = 2j`, 1/2 for `i = 2j ± 1`.
#[inline]
#[cfg(test)]
pub(crate) fn two_scale(i: i64, j: i64) -> f64 {
    match i - 2 * j {
        0 => 1.0,
        -1 | 1 => 0.5,
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interior_integrals_match_the_textbook_values() {
        let d = 4;
        let h = 1.0 / 16.0;
        let [m, s, g] = integrals(d, 5, 0, 5);
        assert!(
            (m - 2.0 * h / 3.0).abs() < 1e-15 && (s - 2.0 / h).abs() < 1e-12 && g.abs() < 1e-15
        );
        let [m, s, g] = integrals(d, 5, 0, 6);
        assert!(
            (m - h / 6.0).abs() < 1e-15 && (s + 1.0 / h).abs() < 1e-12 && (g + 0.5).abs() < 1e-15
        );
        // Boundary hats are halves.
        let [m, s, g] = integrals(d, 0, 0, 0);
        assert!(
            (m - h / 3.0).abs() < 1e-15 && (s - 1.0 / h).abs() < 1e-12 && (g + 0.5).abs() < 1e-15
        );
    }

    #[test]
    fn parent_integrals_follow_from_the_two_scale_relation() {
        // ∫ φ_{d,i} φ_{d-1,j} = Σ_k w(k, j) ∫ φ_{d,i} φ_{d,k}, for all three kinds, boundary included.
        let d = 3;
        let n = 1i64 << d;
        for i in 0..=n {
            for j in 0..=n / 2 {
                let direct = integrals(d, i, 1, j);
                let mut via = [0.0; 3];
                for k in (2 * j - 1)..=(2 * j + 1) {
                    if (0..=n).contains(&k) {
                        let v = integrals(d, i, 0, k);
                        for q in 0..3 {
                            via[q] += two_scale(k, j) * v[q];
                        }
                    }
                }
                for q in 0..3 {
                    assert!((direct[q] - via[q]).abs() < 1e-12, "i {i} j {j} q {q}");
                }
            }
        }
    }

    #[test]
    fn hats_partition_unity_so_the_stiffness_rows_sum_to_zero() {
        let d = 3;
        let t = AxisTables::new(d);
        for row in &t.same {
            let s: f64 = row.iter().map(|v| v[1]).sum();
            let g: f64 = row.iter().map(|v| v[2]).sum();
            let m: f64 = row.iter().map(|v| v[0]).sum();
            assert!(s.abs() < 1e-12);
            // ∫ φ_i' Σ_j φ_j = ∫ φ_i' = φ_i(1) - φ_i(0).
            assert!(g.abs() <= 1.0 + 1e-12);
            assert!(m > 0.0);
        }
    }
}
