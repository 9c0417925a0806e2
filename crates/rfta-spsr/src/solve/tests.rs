//! Tests of the solver: refinement around seeds, restriction, evaluation against every hat.

use super::*;
use crate::{OrientedPoints, tree};

/// A thin octree: 4,000 points on a small sphere off-centre, so most of the cube is coarse.
#[allow(clippy::type_complexity)]
fn thin_tree() -> Result<(OrientedPoints, tree::Frame, Vec<Level>, u32), Box<dyn std::error::Error>>
{
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
-> Result<(OrientedPoints, tree::Frame, Vec<tree::Sample>, u32), Box<dyn std::error::Error>> {
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

/// Both stencils, looked up and as tables, are the single node lookups around each node: its
/// neighbours `c + o - 1` on its own depth, its parents `c / 2 + o - 1` one depth coarser.
#[test]
fn stencils_are_the_node_lookups_around_each_node() -> Result<(), Box<dyn std::error::Error>> {
    let (_, _, levels, _) = thin_tree()?;
    let around = |level: &Level, c: [i64; 3]| -> [u32; 27] {
        std::array::from_fn(|o| {
            let off = offset(o);
            level
                .node([c[0] + off[0], c[1] + off[1], c[2] + off[2]])
                .unwrap_or(NONE)
        })
    };
    for d in 0..levels.len() {
        let level = &levels[d];
        let neighbours = Stencil::neighbours(level);
        let table = neighbours.table();
        let parents = (d > 0).then(|| Stencil::parents(level, &levels[d - 1]));
        let parent_table = parents.map(Stencil::table);
        for (i, &c) in level.nodes.iter().enumerate() {
            let want = around(level, ic(c));
            assert_eq!(neighbours.of(i), want, "depth {d} node {c:?}");
            assert_eq!(Stencil::Table(&table).of(i), want);
            if let (Some(p), Some(t)) = (parents, &parent_table) {
                let want = around(&levels[d - 1], ic(c.map(|v| v / 2)));
                assert_eq!(p.of(i), want, "depth {d} node {c:?}");
                assert_eq!(Stencil::Table(t).of(i), want);
            }
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
        let parents = Stencil::parents(fine, coarse).table();
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

/// Arbitrary coefficients on a thin octree: an [`Evaluator`], which stops at the first depth
/// without a hat over the point, gives the sum of every hat of every depth at the point; one that
/// walks from point to point (each followed by a point a little way off, in the cells it looked up
/// last at the coarser depths) gives the same bits as one made for each point.
#[test]
fn evaluators_give_the_sum_of_all_hats() -> Result<(), Box<dyn std::error::Error>> {
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
    let mut walk = Evaluator::new(&levels, &sol, base);
    let mut reused = 0;
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
        let f = Evaluator::new(&levels, &sol, base).at(u);
        assert!((f - sum).abs() < 1e-12, "at {u}: {f} against {sum}");
        for v in [u, u + DVec3::new(3e-3, -2e-3, 1e-3)] {
            let (fresh, walked) = (Evaluator::new(&levels, &sol, base).at(v), walk.at(v));
            assert_eq!(
                fresh.to_bits(),
                walked.to_bits(),
                "at {v}: {walked} against {fresh}"
            );
        }
        reused += walk.reused();
    }
    assert!(deep > 100, "too few points reach the finest depth: {deep}");
    assert!(reused > 2000, "the walk reused {reused} lookups");
    Ok(())
}
