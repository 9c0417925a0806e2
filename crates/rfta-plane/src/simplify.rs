//! The final curve simplified ([`rfta_simplify::simplify_polylines`]) so that every sample keeps
//! its verdict: no removal moves the curve across a sample with a side (`|s| > SIGN_MARGIN h`),
//! and none brings it into a circle deeper than `ENTER_SLACK h` unless it was deeper already
//! (the 3D pipeline's rule, `rfta::finish::simplify`, on circles).

use rfta_geom::glam::DVec2;
use rfta_geom::plane::Polylines;
use rfta_mesh::PolylineIndex;
use rfta_simplify::{Options, Patch2, PolylineJudge, Watch, simplify_polylines};

use crate::PlaneParams;
use crate::arcs::Circle;
use crate::params::ENTER_MARGIN;

/// Samples closer to the curve than this many spacings carry no reliable side.
const SIGN_MARGIN: f64 = 0.01;

/// A removal may bring the curve into a circle up to this many spacings deep (four fifths of
/// the margin at which a circle counts as entered).
const ENTER_SLACK: f64 = 0.8 * ENTER_MARGIN;

/// What simplification did: the edges before and the largest deviation, in spacings.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Simplified {
    pub(crate) edges_before: usize,
    pub(crate) deviation: f64,
}

/// `curve` (unit square, `extent` the samples' box there) simplified as `params` say
/// ([`PlaneParams::simplify`], its tolerance in spacings `spacing` apart, at most
/// [`PlaneParams::max_edges`] edges), judged against the `circles` and their `values`.
pub(crate) fn simplify(
    curve: Polylines,
    circles: &[Circle],
    values: &[f64],
    spacing: f64,
    extent: DVec2,
    params: &PlaneParams,
) -> (Polylines, Simplified) {
    let mut done = Simplified {
        edges_before: curve.edges.len(),
        deviation: 0.0,
    };
    if !params.simplify || curve.edges.is_empty() {
        return (curve, done);
    }
    let tolerance = params
        .simplify_tolerance
        .unwrap_or_else(|| rfta_simplify::default_tolerance(extent.max_element() / spacing));
    let tol = tolerance * spacing;
    let judge = CircleJudge::new(&curve, circles, values, spacing, tol);
    let options = Options {
        tolerance: tol,
        max_faces: params.max_edges,
    };
    match simplify_polylines(&curve, &options, &judge) {
        Ok(out) => {
            done.deviation = out.largest_deviation / spacing;
            (out.curve, done)
        }
        // Only a bad tolerance fails, and the caller's is checked: the curve as it is.
        Err(_) => (curve, done),
    }
}

/// The circles a removal could change the verdict of: those within [`Watch::reach`] of the
/// curve (few: the curve touches most circles from outside).
struct CircleJudge {
    watched: Vec<(Circle, bool)>,
    slack: f64,
}

impl CircleJudge {
    fn new(curve: &Polylines, circles: &[Circle], values: &[f64], h: f64, tol: f64) -> Self {
        let index = PolylineIndex::new(curve);
        let slack = ENTER_SLACK * h;
        let watch = Watch {
            slack,
            tolerance: tol,
            spacing: h,
        };
        let watched = circles
            .iter()
            .zip(values)
            .map(|(c, &s)| (*c, s.abs() > SIGN_MARGIN * h))
            .filter(|(c, sided)| index.closest(c.center).distance < watch.reach(c.radius, *sided))
            .collect();
        Self { watched, slack }
    }
}

impl PolylineJudge for CircleJudge {
    fn allows(&self, patch: &Patch2) -> bool {
        let (lo, hi) = patch
            .before
            .iter()
            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        self.watched.iter().all(|(c, sided)| {
            let p = c.center;
            let outside = (lo - p).max(p - hi).max(DVec2::ZERO).length();
            if outside > c.radius {
                return true;
            }
            if *sided && outside == 0.0 && patch.sweeps(p) {
                return false;
            }
            let after = patch.distance_after(p);
            after >= c.radius - self.slack || after >= patch.distance_before(p)
        })
    }
}
