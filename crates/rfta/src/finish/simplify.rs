//! The repaired mesh simplified ([`rfta_simplify`]) so that every sample keeps its verdict: no
//! collapse moves the surface across a sample with a side (`|s| > SIGN_MARGIN h`), and none
//! brings it into a sample's sphere deeper than `ENTER_SLACK h` unless it was deeper already, so
//! a sphere the consistency check ([`crate::consistency`]) does not count as entered stays
//! uncounted, and one it counts is entered no deeper. (A surface within a tolerance of another
//! enters the spheres that one touches by up to that tolerance: a chord of a convex part enters
//! the inside spheres tangent to it. The slack is what the verdict allows, not what repair left.)

use std::collections::HashMap;
use std::time::Instant;

use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{Sphere, SphereSet, TriMesh};
use rfta_mesh::MeshIndex;
use rfta_simplify::{Judge, Options, Patch, Watch};
use rfta_sphere_tree::SphereTree;

use crate::consistency::{ENTER_MARGIN, SIGN_MARGIN};
use crate::plan::Plan;
use crate::report::{Journal, SimplifyReport};
use crate::{Result, Step};

/// A collapse may bring the surface into a sphere up to this many spacings deep (four fifths of
/// the margin at which the consistency check counts a sphere as entered).
const ENTER_SLACK: f64 = 0.8 * ENTER_MARGIN;

/// `mesh` (the samples' coordinates) simplified as [`crate::Params`] say, its tolerance and
/// margins in units of `spacing` (the samples' own, or where the surface is, an adaptive run's
/// finest), with its report; the mesh as it is when simplification is off.
pub(crate) fn simplify(
    plan: &Plan<'_>,
    mesh: TriMesh,
    spacing: f64,
    journal: &mut Journal,
) -> Result<(TriMesh, SimplifyReport)> {
    let params = &plan.params;
    let mut report = SimplifyReport {
        faces_before: mesh.n_faces(),
        faces_after: mesh.n_faces(),
        ..SimplifyReport::default()
    };
    let h = spacing;
    let per_axis = plan.unit.to_input_length(1.0) / h;
    let Some(spacings) = params.simplify_spacings(per_axis) else {
        return Ok((mesh, report));
    };
    if mesh.n_faces() == 0 {
        return Ok((mesh, report));
    }
    let t = Instant::now();
    let tolerance = spacings * h;
    let index = MeshIndex::new(&mesh)?;
    let judge = SampleJudge::new(plan, &mesh, &index, h, tolerance);
    let options = Options {
        tolerance,
        max_faces: params.faces,
    };
    let out =
        rfta_simplify::simplify_indexed(&mesh, &index, &options, &judge).map_err(|e| match e {
            rfta_simplify::Error::Mesh(e) => crate::Error::Consistency(e),
            other => crate::Error::InvalidParams(other.to_string()),
        })?;
    report.largest_deviation = out.largest_deviation / h;
    report.faces_after = out.mesh.n_faces();
    journal.timed(Step::Simplify, t);
    Ok((out.mesh, report))
}

/// The width of the judge's cells in sample spacings: a collapse's patch spans a few spacings
/// once faces have grown, and the watched samples are few (on the 129^3 bunny 4,399 of 2.1
/// million), so wide cells cost fewer look-ups per collapse than they add samples to judge.
const JUDGE_CELL: f64 = 4.0;

/// The samples a collapse could change the verdict of, as spheres in the samples' coordinates,
/// each filed under the cells ([`JUDGE_CELL`] spacings wide) around the part of the mesh it
/// watches.
struct SampleJudge {
    cells: Cells,
    cell: f64,
    spheres: Vec<Sphere>,
    /// Whether each sphere's sample has a side (`|s| > SIGN_MARGIN h`).
    sided: Vec<bool>,
    /// Whether each sphere is a constraint (distances; not a level set's).
    spheres_bind: bool,
    slack: f64,
}

impl SampleJudge {
    /// The samples whose verdict a surface within `tolerance` of `mesh` could change: those
    /// within `w` of it ([`Watch::reach`]), of spheres up to `CLEAR_BELOW` owner radii, the ones
    /// repair clears (a wider sphere the surface touches is entered by a surface within the
    /// tolerance by less than a narrower one there). With the default tolerance, below the
    /// slack, those are the few spheres the mesh already enters and the samples within a
    /// quarter spacing of it. Each is filed under the cells the box of the mesh within `w` of it
    /// touches (its closest point and the vertices there, grown by [`Watch::margin`]): a
    /// collapse elsewhere comes no nearer to it than `w`.
    fn new(plan: &Plan<'_>, mesh: &TriMesh, index: &MeshIndex, h: f64, tolerance: f64) -> Self {
        let unit = &plan.unit;
        let slack = ENTER_SLACK * h;
        let watch = Watch {
            slack,
            tolerance,
            spacing: h,
        };
        let reach = unit.to_input_length(super::CLEAR_BELOW * plan.owner_radius);
        crate::pool::waiters_back();
        let near: Vec<(Sphere, bool, f64, DVec3)> = (0..unit.len())
            .into_par_iter()
            .filter_map(|i| {
                let radius = unit.to_input_length(unit.radius(i));
                if radius > reach {
                    return None;
                }
                let sphere = Sphere::new(unit.to_input(unit.center(i)), radius);
                let sided = unit.to_input_length(unit.values[i].abs()) > SIGN_MARGIN * h;
                let watch = watch.reach(sphere.radius, sided);
                let foot = index.closest_point_within(sphere.center, watch * watch)?;
                Some((sphere, sided, watch, foot.point))
            })
            .collect();
        // The vertices within each watched sphere's reach.
        let reaches: Vec<Sphere> = near.iter().map(|n| Sphere::new(n.0.center, n.2)).collect();
        let tree = SphereTree::new(&reaches);
        let inside: Vec<(u32, DVec3)> = mesh
            .vertices
            .par_iter()
            .flat_map_iter(|&v| {
                let mut hits = Vec::new();
                tree.spheres_within_into(v, 0.0, None, &mut hits);
                hits.into_iter().map(move |j| (j, v))
            })
            .collect();
        let mut boxes: Vec<(DVec3, DVec3)> = near.iter().map(|n| (n.3, n.3)).collect();
        for (j, v) in inside {
            let b = &mut boxes[j as usize];
            *b = (b.0.min(v), b.1.max(v));
        }
        let grow = DVec3::splat(watch.margin());
        let mut cells = Cells::default();
        for (j, (lo, hi)) in boxes.into_iter().enumerate() {
            for key in cells_of(lo - grow, hi + grow, JUDGE_CELL * h) {
                cells.entry(key).or_default().push(j as u32);
            }
        }
        let (spheres, sided): (Vec<Sphere>, Vec<bool>) =
            near.into_iter().map(|n| (n.0, n.1)).unzip();
        Self {
            cells,
            cell: JUDGE_CELL * h,
            spheres,
            sided,
            spheres_bind: plan.field.read_as.spheres_bind(),
            slack,
        }
    }
}

/// The keys of the cells `size` wide that the box `lo..hi` touches.
fn cells_of(lo: DVec3, hi: DVec3, size: f64) -> impl Iterator<Item = [i64; 3]> {
    let key = |x: DVec3| (x / size).floor().as_i64vec3();
    let (a, b) = (key(lo), key(hi));
    (a.x..=b.x)
        .flat_map(move |x| (a.y..=b.y).flat_map(move |y| (a.z..=b.z).map(move |z| [x, y, z])))
}

impl Judge for SampleJudge {
    fn allows(&self, patch: &Patch<'_>) -> bool {
        let (centre, radius) = patch.bounding_ball();
        let corners = || patch.before.iter().chain(patch.after).flatten();
        let (lo, hi) = corners().fold((centre, centre), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        // The slab around the patch's mean plane that holds both fans: a sample outside it is
        // not swept, a sphere that does not reach into it by the slack is not entered by it.
        let normal = patch
            .after
            .iter()
            .map(|t| (t[1] - t[0]).cross(t[2] - t[0]))
            .sum::<DVec3>()
            .normalize_or_zero();
        let height = |x: DVec3| normal.dot(x - centre);
        let (below, above) = corners().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(height(x)), h.max(height(x)))
        });
        // A sample filed under two of the cells is judged twice, the same way.
        let keeps = |j: u32| {
            let s = &self.spheres[j as usize];
            let p: DVec3 = s.center;
            let z = height(p);
            let outside = (below - z).max(z - above);
            if self.sided[j as usize]
                && outside < 0.0
                && p.distance(centre) <= radius
                && patch.sweeps(p)
            {
                return false;
            }
            // Not entered deeper than the slack: beyond the slab, beyond the ball, or no face
            // after within.
            let deep = s.radius - self.slack;
            if !self.spheres_bind
                || deep <= 0.0
                || outside >= deep
                || p.distance(centre) - radius >= deep
                || !patch.after_within(p, deep)
            {
                return true;
            }
            patch.distance_after(p) >= patch.distance_before(p)
        };
        cells_of(lo, hi, self.cell).all(|key| {
            self.cells
                .get(&key)
                .is_none_or(|ids| ids.iter().all(|&j| keeps(j)))
        })
    }
}

/// A hasher for cell keys (three small integers): multiply and rotate, as rustc's FxHasher
/// does; the judge looks up a few cells per collapse, where SipHash's cost showed.
#[derive(Default)]
struct CellHasher(u64);

impl std::hash::Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// The cells' map.
type Cells = HashMap<[i64; 3], Vec<u32>, std::hash::BuildHasherDefault<CellHasher>>;
