//! Empty space in the plane: the cells of a `res x res` raster that no circle of one sign covers
//! and that touch a covered cell (the paper's §4.1 in 2D; the band is one cell, as in the
//! reference).
//!
//! Circles are shrunk to `0.95 r^2` like the reference's, and tested at cell centres (as its GPU
//! path; no jitter, so no seed). Each circle marks one span per raster row it crosses, so the cost
//! is the circles' heights, not their areas.

use rfta_geom::glam::DVec2;

use crate::arcs::Circle;

/// The reference's shrink of the squared radius.
const SHRINK: f64 = 0.95;

/// The centres of the empty cells next to covered ones, for the square `min` to `min + side`
/// divided into `res x res` cells, in row order (y outer).
pub fn empty_space(circles: &[Circle], res: usize, min: DVec2, side: f64) -> Vec<DVec2> {
    let res = res.max(2);
    let h = side / res as f64;
    // Per row, +1 where a span starts and -1 after it ends.
    let mut marks = vec![0i32; res * (res + 1)];
    for c in circles {
        let r2 = SHRINK * c.radius * c.radius;
        let r = r2.sqrt();
        let lo = (((c.center.y - r - min.y) / h - 0.5).ceil().max(0.0)) as usize;
        let hi = ((c.center.y + r - min.y) / h - 0.5).floor();
        if hi < 0.0 {
            continue;
        }
        for row in lo..=(hi as usize).min(res - 1) {
            let y = min.y + (row as f64 + 0.5) * h;
            let w2 = r2 - (y - c.center.y) * (y - c.center.y);
            if w2 < 0.0 {
                continue;
            }
            let w = w2.sqrt();
            let x0 = ((c.center.x - w - min.x) / h - 0.5).ceil().max(0.0);
            let x1 = ((c.center.x + w - min.x) / h - 0.5)
                .floor()
                .min((res - 1) as f64);
            if x1 < x0 {
                continue;
            }
            marks[row * (res + 1) + x0 as usize] += 1;
            marks[row * (res + 1) + x1 as usize + 1] -= 1;
        }
    }
    let mut covered = vec![false; res * res];
    for row in 0..res {
        let mut depth = 0;
        for x in 0..res {
            depth += marks[row * (res + 1) + x];
            covered[row * res + x] = depth > 0;
        }
    }
    let mut out = Vec::new();
    for row in 0..res {
        for x in 0..res {
            if covered[row * res + x] {
                continue;
            }
            let near = (row.saturating_sub(1)..=(row + 1).min(res - 1)).any(|r| {
                (x.saturating_sub(1)..=(x + 1).min(res - 1)).any(|c| covered[r * res + c])
            });
            if near {
                out.push(min + DVec2::new(x as f64 + 0.5, row as f64 + 0.5) * h);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_band_rings_a_disc_and_matches_brute_force() {
        let circles = [
            Circle {
                center: DVec2::new(0.5, 0.5),
                radius: 0.3,
            },
            Circle {
                center: DVec2::new(0.2, 0.7),
                radius: 0.1,
            },
        ];
        let res = 64;
        let band = empty_space(&circles, res, DVec2::ZERO, 1.0);
        let h = 1.0 / res as f64;
        let covered = |p: DVec2| {
            circles
                .iter()
                .any(|c| (p - c.center).length_squared() <= SHRINK * c.radius * c.radius)
        };
        let mut expected = Vec::new();
        for row in 0..res {
            for x in 0..res {
                let p = DVec2::new(x as f64 + 0.5, row as f64 + 0.5) * h;
                let near = (-1..=1).any(|dy: i32| {
                    (-1..=1).any(|dx: i32| {
                        let (r, c) = (row as i32 + dy, x as i32 + dx);
                        (0..res as i32).contains(&r)
                            && (0..res as i32).contains(&c)
                            && covered(DVec2::new(c as f64 + 0.5, r as f64 + 0.5) * h)
                    })
                });
                if !covered(p) && near {
                    expected.push(p);
                }
            }
        }
        assert_eq!(band, expected);
        assert!(!band.is_empty());
    }
}
