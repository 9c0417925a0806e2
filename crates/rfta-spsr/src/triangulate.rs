//! Minimal-area triangulation of an extracted loop without new vertices, whose diagonals stay
//! inside its octree cell (Kazhdan, Klein, Dalal and Hoppe 2007).

use crate::glam::DVec3;

/// Longest loop [`triangulate`] takes; a longer one gets a fan around its centre.
pub(crate) const MAX_LOOP: usize = 12;

/// Minimal-area triangulation of a loop of at most [`MAX_LOOP`] vertices whose diagonals may not
/// join two vertices on a common face of the cell, into `tris` (corner indices; `spans`: scratch
/// space); `false` when no such triangulation exists. No allocation once the scratch has grown:
/// the extraction calls this for most leaves of every solve, on every thread.
pub(crate) fn triangulate(
    pos: &[DVec3],
    masks: &[u8],
    tris: &mut Vec<[usize; 3]>,
    spans: &mut Vec<(usize, usize)>,
) -> bool {
    let n = pos.len();
    if n > MAX_LOOP {
        return false;
    }
    let allowed =
        |i: usize, j: usize| j == i + 1 || (i == 0 && j == n - 1) || masks[i] & masks[j] == 0;
    let mut cost = [f64::INFINITY; MAX_LOOP * MAX_LOOP];
    let mut pick = [usize::MAX; MAX_LOOP * MAX_LOOP];
    for i in 0..n - 1 {
        cost[i * n + i + 1] = 0.0;
    }
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !allowed(i, j) {
                continue;
            }
            for k in i + 1..j {
                let (a, b) = (cost[i * n + k], cost[k * n + j]);
                if !a.is_finite() || !b.is_finite() {
                    continue;
                }
                let area = (pos[k] - pos[i]).cross(pos[j] - pos[i]).length();
                let c = a + b + area;
                if c < cost[i * n + j] {
                    cost[i * n + j] = c;
                    pick[i * n + j] = k;
                }
            }
        }
    }
    if !cost[n - 1].is_finite() {
        return false;
    }
    tris.clear();
    spans.clear();
    spans.push((0, n - 1));
    while let Some((i, j)) = spans.pop() {
        if j <= i + 1 {
            continue;
        }
        let k = pick[i * n + j];
        tris.push([i, k, j]);
        spans.push((i, k));
        spans.push((k, j));
    }
    true
}
