//! The 2D pipeline on analytic shapes with known answers.

use rfta::geom::glam::DVec2;
use rfta::geom::plane::{Grid2, Polylines, SdfSamples2};
use rfta::{Params, plane};
use rfta_mesh::PolylineIndex;

fn grid_samples(n: usize, sdf: impl Fn(DVec2) -> f64) -> SdfSamples2 {
    let grid =
        Grid2::from_bounds([n + 1, n + 1], DVec2::splat(-1.0), DVec2::splat(1.0)).expect("grid");
    let values = (0..grid.len()).map(|i| sdf(grid.position(i))).collect();
    SdfSamples2::grid(grid, values).expect("samples")
}

/// Mean and largest |sdf| over the curve's vertices (the vertices' distance to the true curve for
/// an exact SDF).
fn vertex_error(curve: &Polylines, sdf: impl Fn(DVec2) -> f64) -> (f64, f64) {
    let d: Vec<f64> = curve.vertices.iter().map(|&v| sdf(v).abs()).collect();
    (
        d.iter().sum::<f64>() / d.len() as f64,
        d.iter().copied().fold(0.0, f64::max),
    )
}

fn circle(p: DVec2) -> f64 {
    (p - DVec2::new(0.1, -0.05)).length() - 0.55
}

/// A square of side 1.2 with a round hole of radius 0.25 well inside it: the SDF is exact (inside
/// the material the nearer of the two boundaries, in the hole the hole's, outside the square's).
fn square_with_hole(p: DVec2) -> f64 {
    let q = p.abs() - DVec2::splat(0.6);
    let square = q.max(DVec2::ZERO).length() + q.x.max(q.y).min(0.0);
    let hole = (p - DVec2::new(0.15, 0.1)).length() - 0.25;
    square.max(-hole)
}

#[test]
fn a_circle_comes_back_as_one_loop_on_it() {
    // 33 x 33 samples, spacing 0.0625: the vertices within a tenth of a spacing of the circle,
    // a two-hundredth on average (unsimplified: simplification keeps a subset of them, whose
    // mean is another matter; `the_curve_is_simplified_keeping_every_sample_on_its_side`).
    let params = Params {
        simplify: false,
        ..Params::default()
    };
    let out = plane::reconstruct(&grid_samples(32, circle), &params).expect("curve");
    assert_eq!(out.curve.loops(), 1);
    assert!(out.curve.is_closed());
    let (mean, max) = vertex_error(&out.curve, circle);
    assert!(mean < 0.0625 / 200.0 && max < 0.0625 / 10.0, "{mean} {max}");
    // Counter-clockwise around the inside.
    let index = PolylineIndex::new(&out.curve);
    assert_eq!(index.winding(DVec2::new(0.1, -0.05)), 1);
    assert_eq!(index.winding(DVec2::new(0.9, 0.9)), 0);
    // The tangency points: each sample circle touches the true curve at one point, which the
    // fine-tuning moves its points toward (a small circle's free arc can hold a point a little
    // off it, its normal turned by up to the arc); their normals point out.
    let far = out
        .points
        .iter()
        .map(|(p, _)| circle(*p).abs())
        .fold(0.0, f64::max);
    assert!(far < 0.1 * 0.0625, "{far}");
    let mut alignment = 0.0;
    for (p, n) in &out.points {
        let outward = (*p - DVec2::new(0.1, -0.05)).normalize();
        assert!(n.dot(outward) > 0.5, "{p} {n}");
        alignment += n.dot(outward) / out.points.len() as f64;
    }
    assert!(alignment > 0.99, "{alignment}");
}

#[test]
fn a_square_with_a_hole_has_two_loops_and_beats_marching_squares() {
    let samples = grid_samples(32, square_with_hole);
    let out = plane::reconstruct(&samples, &Params::default()).expect("curve");
    assert_eq!(out.curve.loops(), 2);
    assert!(out.curve.is_closed());
    let index = PolylineIndex::new(&out.curve);
    assert_eq!(
        index.winding(DVec2::new(0.15, 0.1)),
        0,
        "the hole is outside"
    );
    assert_eq!(
        index.winding(DVec2::new(-0.4, -0.4)),
        1,
        "the material is inside"
    );
    let (mean, max) = vertex_error(&out.curve, square_with_hole);
    let grid = *samples.as_grid().expect("grid");
    let ms = rfta_mc::marching_squares(&grid, samples.values(), 0.0);
    // The corners are sharp: the reconstruction rounds them, within a tenth of a spacing.
    assert!(mean < 0.002 && max < 0.1 * 0.0625, "{mean} {max}");
    // Chamfer against the exact boundary, sampled finely: below marching squares' (whose vertices
    // lie on the curve, but whose edges cut the corners).
    let exact = exact_boundary(2000);
    let ours = rfta_metrics::plane::chamfer_2d(&out.curve, &exact, 20_000);
    let theirs = rfta_metrics::plane::chamfer_2d(&ms, &exact, 20_000);
    assert!(ours < theirs, "{ours} vs {theirs}");
}

/// The boundary of [`square_with_hole`] as polylines with `k` vertices per loop.
fn exact_boundary(k: usize) -> Polylines {
    let mut v = Vec::new();
    let mut e = Vec::new();
    for i in 0..k {
        let t = i as f64 / k as f64 * 4.0;
        let side = t.floor();
        let f = t - side;
        let p = match side as u32 {
            0 => DVec2::new(-0.6 + 1.2 * f, -0.6),
            1 => DVec2::new(0.6, -0.6 + 1.2 * f),
            2 => DVec2::new(0.6 - 1.2 * f, 0.6),
            _ => DVec2::new(-0.6, 0.6 - 1.2 * f),
        };
        v.push(p);
        e.push([i as u32, ((i + 1) % k) as u32]);
    }
    for i in 0..k {
        let t = -(i as f64) / k as f64 * std::f64::consts::TAU;
        v.push(DVec2::new(0.15, 0.1) + DVec2::new(t.cos(), t.sin()) * 0.25);
        e.push([(k + i) as u32, (k + (i + 1) % k) as u32]);
    }
    Polylines::new(v, e).expect("valid")
}

#[test]
fn the_curve_is_the_same_at_any_thread_count() {
    let samples = grid_samples(24, square_with_hole);
    let run = |threads| {
        let params = Params {
            threads: Some(threads),
            ..Params::default()
        };
        plane::reconstruct(&samples, &params).expect("curve").curve
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(4));
}

#[test]
fn samples_that_leave_no_room_for_a_curve_are_no_surface() {
    // Every sample 5 away from a curve that is nowhere: circles cover the whole box.
    let samples = grid_samples(8, |_| 5.0);
    match plane::reconstruct(&samples, &Params::default()) {
        Err(rfta::Error::NoSurface { .. }) => {}
        other => panic!("expected NoSurface, got {other:?}"),
    }
}

#[test]
fn scattered_samples_give_the_circle_too() {
    // 800 samples at seeded random positions in [-1, 1]^2: every circle owns points (no owner
    // band off a grid); the vertices stay within a twentieth of the mean sample spacing
    // (about 2 / sqrt(800) = 0.07) of the circle.
    let mut rng = rfta::geom::rng::Rng::new(3);
    let positions: Vec<DVec2> = (0..800)
        .map(|_| DVec2::new(2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0))
        .collect();
    let values = positions.iter().map(|&p| circle(p)).collect();
    let samples = SdfSamples2::scattered(positions, values).expect("samples");
    let out = plane::reconstruct(&samples, &Params::default()).expect("curve");
    assert_eq!(out.curve.loops(), 1);
    let (mean, max) = vertex_error(&out.curve, circle);
    assert!(mean < 0.07 / 100.0 && max < 0.07 / 20.0, "{mean} {max}");
}

#[test]
fn values_that_are_not_a_distance_are_refused_unless_the_check_is_off() {
    // An occupancy image of the disc (+-1) and the disc's SDF in other units (x 3).
    let occupancy = grid_samples(24, |p| if circle(p) < 0.0 { -1.0 } else { 1.0 });
    let scaled = grid_samples(24, |p| 3.0 * circle(p));
    for samples in [&occupancy, &scaled] {
        match plane::reconstruct(samples, &Params::default()) {
            Err(rfta::Error::NotADistance(why)) => assert!(why.contains("--no-check"), "{why}"),
            other => panic!("expected NotADistance, got {other:?}"),
        }
    }
    let unchecked = Params {
        check: false,
        ..Params::default()
    };
    // Without the check the pipeline tries (and, its circles covering the box, finds no points).
    assert!(!matches!(
        plane::reconstruct(&scaled, &unchecked),
        Err(rfta::Error::NotADistance(_))
    ));
}

/// A genus is a surface's: asked of a 2D reconstruction it is refused, not ignored.
#[test]
fn a_genus_asked_in_2d_is_refused() {
    let samples = grid_samples(32, circle);
    let asked = Params {
        genus: Some(0),
        ..Params::default()
    };
    assert!(matches!(
        plane::reconstruct(&samples, &asked),
        Err(rfta::Error::InvalidParams(m)) if m.contains("genus")
    ));
    assert!(plane::reconstruct(&samples, &Params::default()).is_ok());
}

/// A ring 0.24 wide around the circle of radius 0.5, and a 1.2 x 0.6 box: at coarse grids
/// screened Poisson leaves small loops beside them that the island rule removes.
fn ring(p: DVec2) -> f64 {
    (p.length() - 0.5).abs() - 0.12
}

fn flat_box(p: DVec2) -> f64 {
    let q = p.abs() - DVec2::new(0.6, 0.3);
    q.max(DVec2::ZERO).length() + q.x.max(q.y).min(0.0)
}

#[test]
fn removed_loops_take_their_vertices_with_them() {
    // Every output of a sweep of coarse grids uses every vertex it has, and the sweep does
    // remove loops (so the test sees the rule that used to leave vertices behind).
    let mut removed = 0;
    for sdf in [ring as fn(DVec2) -> f64, flat_box, square_with_hole] {
        for n in 6..=14 {
            let params = Params {
                rounds: Some(3),
                ..Params::default()
            };
            let Ok(out) = plane::reconstruct(&grid_samples(n, sdf), &params) else {
                continue;
            };
            assert_eq!(out.curve.unreferenced_vertices(), 0, "n = {n}");
            assert!(out.curve.is_closed());
            removed += out.report.islands_removed;
        }
    }
    assert!(removed > 0, "no loop was removed: the sweep tests nothing");
}

/// A ring whose wall (0.08) is thinner than the spacing (0.125): grid edges cross it from an
/// outside sample in the hole to one beyond, so the samples cannot tell it from a ring cut open,
/// and the default opens the hole the curve closes (one loop); `keep_cavities` keeps it (two
/// loops, the hole counted). Either way every sample stays on its side.
#[test]
fn a_hole_behind_a_wall_no_sample_shows_is_opened_unless_kept() {
    let thin = |p: DVec2| ((p - DVec2::new(0.03, 0.02)).length() - 0.52).abs() - 0.04;
    let samples = grid_samples(16, thin);
    let kept = plane::reconstruct(
        &samples,
        &Params {
            keep_cavities: true,
            ..Params::default()
        },
    )
    .expect("reconstructs");
    let opened = plane::reconstruct(&samples, &Params::default()).expect("reconstructs");
    assert_eq!((kept.curve.loops(), kept.report.holes), (2, 1));
    assert_eq!(kept.report.holes_opened, 0);
    assert_eq!(
        (
            opened.curve.loops(),
            opened.report.holes_opened,
            opened.report.holes
        ),
        (1, 1, 0)
    );
    for out in [&kept, &opened] {
        assert!(out.curve.is_closed());
        let index = PolylineIndex::new(&out.curve);
        for (p, &s) in samples.positions().iter().zip(samples.values()) {
            assert_eq!(index.winding(*p) != 0, s < 0.0, "{p} {s}");
        }
    }
}

#[test]
fn the_curve_is_simplified_keeping_every_sample_on_its_side() {
    let samples = grid_samples(32, square_with_hole);
    let h = 2.0 / 32.0;
    let off = Params {
        simplify: false,
        ..Params::default()
    };
    let full = plane::reconstruct(&samples, &off).expect("unsimplified");
    let out = plane::reconstruct(&samples, &Params::default()).expect("simplified");
    let (c, c0) = (&out.curve, &full.curve);
    assert_eq!(full.report.edges_unsimplified, c0.edges.len());
    assert_eq!(out.report.edges_unsimplified, c0.edges.len());
    assert!(
        c.edges.len() * 2 < c0.edges.len(),
        "{} of {}",
        c.edges.len(),
        c0.edges.len()
    );
    assert!(c.is_closed() && c.loops() == 2);
    // Every sample farther than a hundredth of a spacing keeps its side (winding number).
    let (index, index0) = (PolylineIndex::new(c), PolylineIndex::new(c0));
    for (i, (&p, &s)) in samples.positions().iter().zip(samples.values()).enumerate() {
        if s.abs() > 0.01 * h {
            assert_eq!(index.winding(p), index0.winding(p), "sample {i} at {p}");
        }
    }
    // The simplified curve's vertices are the unsimplified curve's, so they lie as close to
    // the boundary; its edges are within the default tolerance (0.8 / 32 spacings) of it.
    let tol = 0.8 / 32.0 * h;
    assert!(out.report.simplify_deviation <= 0.8 / 32.0 + 1e-9);
    for &[a, b] in &c.edges {
        let mid = 0.5 * (c.vertices[a as usize] + c.vertices[b as usize]);
        assert!(index0.closest(mid).distance <= tol + 1e-12);
    }
    assert!(c.vertices.iter().all(|v| c0.vertices.contains(v)));
}
