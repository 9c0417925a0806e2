//! Handles thinner than the samples resolve, cut unless something confirms them: a sample of the
//! handle's own side next to it, or, in an adaptive run, the function at its centre.
//!
//! A loop around a handle thinner than the samples resolve is a bar of material or a tunnel
//! through it. The loop around a bar has its centre inside the bar, the loop around a tunnel in
//! the tunnel's empty space; the mesh's own signed distance at the centre says which the mesh
//! made. A sample of that side within `WITNESS_REACH` (2) handle radii of the centre (material
//! in a bar, empty space in a tunnel) confirms the handle: the samples show it, and cutting it
//! would put that sample on the wrong side. Without such a sample the samples cannot tell the
//! handle from none (marching cubes of the same samples makes none: a bar between samples is
//! broken, a tunnel between them closed), and the simplest surface they allow has none.
//!
//! An adaptive run asks its function at the centre too: a real bar or tunnel of radius `r` (its
//! loop `2 pi r` long) has the function about `r` deep on its side there. Where the function is on
//! the other side (a bar where it is outside, a tunnel where it is inside), less than `r / 4`
//! deep, or more than `4 r` (a handle far thinner than what the function has there: a sample at
//! its centre cannot tell it from the surface it sits on, and the function's depth belongs to
//! something else), the handle is an artifact of the reconstruction.
//!
//! A handle neither confirms is cut along its loop (`rfta_mesh::cut_along`: the bar cut through,
//! the tunnel filled, both sides capped).

use rfta_geom::glam::DVec3;
use rfta_geom::{SdfSamples, TriMesh};
use rfta_mesh::MeshIndex;

use crate::Result;

/// The depths, in handle radii, at which the function confirms a thin handle at its centre.
const DEPTH_RANGE: [f64; 2] = [0.25, 4.0];

/// A sample within this many handle radii of a thin handle's centre, on the
/// handle's side, keeps the handle.
const WITNESS_REACH: f64 = 2.0;

/// Rounds of loops searched, asked and cut at most (each cut changes the loops left).
const ROUNDS: usize = 12;

/// The function of an adaptive run, asked at the centres of thin handles: at most `max_asks`
/// points in all.
pub(crate) struct Oracle<'a> {
    pub(crate) ask: &'a mut dyn FnMut(&[DVec3]) -> Result<Vec<f64>>,
    pub(crate) max_asks: usize,
}

/// What [`settle`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Settled {
    /// Loops whose centre the function was asked at.
    pub(crate) asked: usize,
    /// The lengths of the loops of the handles cut (nothing confirmed them), in the mesh's units.
    pub(crate) cut: Vec<f64>,
}

/// Cuts the handles of `mesh` whose loops are shorter than `bound` that neither a sample of
/// `samples` nor `oracle` confirms, the two sides `gap` apart.
///
/// # Errors
/// The oracle's.
pub(crate) fn settle(
    mesh: &mut TriMesh,
    samples: &SdfSamples,
    bound: f64,
    gap: f64,
    mut oracle: Option<Oracle<'_>>,
) -> Result<Settled> {
    let mut settled = Settled::default();
    for _ in 0..ROUNDS {
        let genus = rfta_mesh::Topology::of(mesh).genus();
        if genus.is_none_or(|g| g <= 0 || g > crate::consistency::THIN_LOOP_MAX_GENUS) {
            break;
        }
        let Some(loops) = rfta_mesh::short_loops(mesh, bound) else {
            break;
        };
        let mut cycles = loops.loops;
        if let Some(o) = &oracle {
            cycles.truncate(o.max_asks - settled.asked);
        }
        if cycles.is_empty() {
            break;
        }
        let centres: Vec<DVec3> = cycles
            .iter()
            .map(|c| c.iter().map(|&v| mesh.vertices[v as usize]).sum::<DVec3>() / c.len() as f64)
            .collect();
        let truth = match &mut oracle {
            Some(o) => {
                settled.asked += centres.len();
                Some((o.ask)(&centres)?)
            }
            None => None,
        };
        let mut index = MeshIndex::new(mesh)?;
        let made = index.signed_distances(&centres);
        // A handle is an artifact unless a sample or the function confirms it.
        let artifact = |k: usize| {
            let Some(&d) = made.get(k) else {
                return false;
            };
            let r = loops.lengths[k] / std::f64::consts::TAU;
            if witnessed(samples, centres[k], WITNESS_REACH * r, d < 0.0) {
                return false;
            }
            let Some(truth) = &truth else {
                return true;
            };
            let Some(&f) = truth.get(k) else {
                return false;
            };
            // A real bar or tunnel of radius r has the function about r deep on its side at its
            // centre: between r / 4 and 4 r is asked for.
            let deep = if d < 0.0 { -f } else { f };
            !(DEPTH_RANGE[0] * r..=DEPTH_RANGE[1] * r).contains(&deep)
        };
        // A cut is kept only if it puts no sample with a side on the wrong side; the index of
        // the mesh before it is rebuilt after each cut kept.
        let mut stale = false;
        let mut keeps = |before: &TriMesh, after: &TriMesh, k: usize| {
            if stale {
                match MeshIndex::new(before) {
                    Ok(i) => index = i,
                    Err(_) => return false,
                }
            }
            stale = keeps_sides(before, &index, after, &cycles[k], samples);
            stale
        };
        let cut =
            rfta_repair::cut_disjoint(mesh, &cycles, gap, |k, _| artifact(k), Some(&mut keeps));
        settled.cut.extend(cut.iter().map(|&k| loops.lengths[k]));
        if cut.is_empty() {
            break;
        }
    }
    Ok(settled)
}

/// Whether cutting `before` (indexed by `index`) along `cycle` into `after` leaves every sample
/// with a side (`|s| > SIGN_MARGIN h`) that was on its side on it. The cut changes only the faces
/// at the loop's vertices (moved apart) and the caps (new vertices), so the winding number
/// changes by theirs after less theirs before, and only for samples within their reach.
fn keeps_sides(
    before: &TriMesh,
    index: &MeshIndex,
    after: &TriMesh,
    cycle: &[u32],
    samples: &SdfSamples,
) -> bool {
    let n = before.vertices.len() as u32;
    let on_loop = {
        let mut on = vec![false; before.vertices.len()];
        for &v in cycle {
            on[v as usize] = true;
        }
        on
    };
    let changed = |mesh: &TriMesh| -> Vec<[DVec3; 3]> {
        (0..mesh.n_faces())
            .filter(|&f| mesh.faces[f].iter().any(|&v| v >= n || on_loop[v as usize]))
            .map(|f| mesh.triangle(f))
            .collect()
    };
    let (old, new) = (changed(before), changed(after));
    let c = cycle
        .iter()
        .map(|&v| before.vertices[v as usize])
        .sum::<DVec3>()
        / cycle.len() as f64;
    let reach = old
        .iter()
        .chain(&new)
        .flatten()
        .map(|p| p.distance(c))
        .fold(0.0, f64::max)
        * (1.0 + 1e-9)
        + 1e-12;
    let margin = crate::consistency::SIGN_MARGIN * samples.spacing();
    let turned = |i: usize| {
        let (p, v) = (samples.position(i), samples.values()[i]);
        if v.abs() <= margin {
            return false;
        }
        let omega = |tris: &[[DVec3; 3]]| {
            tris.iter()
                .map(|&[a, b, t]| rfta_geom::kernels::solid_angle(p, a, b, t))
                .sum::<f64>()
        };
        let delta = (omega(&new) - omega(&old)) / (4.0 * std::f64::consts::PI);
        let w = index.winding_number(p);
        let right = |w: f64| (w > 0.5) == (v < 0.0);
        right(w) && !right(w + delta)
    };
    !any_near(samples, c, reach, turned)
}

/// Whether a sample of the handle's side (inside for a bar, `inside`; outside for a tunnel)
/// lies within `reach` of its centre `c`: on a grid the samples in the box around it, else all.
fn witnessed(samples: &SdfSamples, c: DVec3, reach: f64, inside: bool) -> bool {
    any_near(samples, c, reach, |i| {
        let v = samples.values()[i];
        v != 0.0 && (v < 0.0) == inside
    })
}

/// Whether `pred` holds for a sample within `reach` of `c`: on a grid the samples in the box
/// around it, else all.
fn any_near(
    samples: &SdfSamples,
    c: DVec3,
    reach: f64,
    mut pred: impl FnMut(usize) -> bool,
) -> bool {
    let mut of_side = |i: usize| samples.position(i).distance(c) < reach && pred(i);
    match samples.as_grid() {
        Some(grid) => {
            let (o, h, dims) = (grid.origin(), grid.spacing(), grid.dims());
            let lo = ((c - reach - o) / h).floor().max(DVec3::ZERO);
            let hi = ((c + reach - o) / h).ceil();
            let last = |k: usize| dims[k] as f64 - 1.0;
            if (0..3).any(|k| hi[k] < 0.0 || lo[k] > last(k)) {
                return false;
            }
            let range = |k: usize| (lo[k] as usize)..=(hi[k].min(last(k)) as usize);
            range(0).any(|i| range(1).any(|j| range(2).any(|l| of_side(grid.index(i, j, l)))))
        }
        None => (0..samples.len()).any(of_side),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rfta_geom::{Grid, shapes};

    /// Two samples far from every test shape: nothing witnessed (the adaptive mode's tests use
    /// it too).
    pub(crate) fn far() -> SdfSamples {
        SdfSamples::scattered(
            vec![DVec3::splat(10.0), DVec3::splat(-10.0)],
            vec![1.0, -1.0],
        )
        .expect("samples")
    }

    /// `ask` as an oracle of 100 questions.
    fn asking<'a>(ask: &'a mut dyn FnMut(&[DVec3]) -> Result<Vec<f64>>) -> Option<Oracle<'a>> {
        Some(Oracle { ask, max_asks: 100 })
    }

    /// A torus whose tube the function says is empty space loses its handle; a torus the
    /// function agrees with keeps it.
    #[test]
    fn a_handle_the_function_contradicts_is_cut_and_one_it_confirms_stays() {
        let torus = shapes::torus(1.0, 0.1, 64, 16);
        // The torus's own signed distance: the loop around the tube (length 0.63, radius 0.1)
        // has its centre on the tube's centre line, 0.1 deep.
        let mut confirmed = torus.clone();
        let mut tube = |p: &[DVec3]| -> Result<Vec<f64>> {
            Ok(p.iter()
                .map(|q| (DVec3::new(q.x, q.y, 0.0).length() - 1.0).hypot(q.z) - 0.1)
                .collect())
        };
        let s = settle(&mut confirmed, &far(), 1.0, 0.01, asking(&mut tube)).expect("settle");
        assert_eq!((s.asked, s.cut.len()), (1, 0));
        assert_eq!(rfta_mesh::Topology::of(&confirmed).genus(), Some(1));

        let mut contradicted = torus.clone();
        let mut empty = |p: &[DVec3]| -> Result<Vec<f64>> { Ok(vec![0.5; p.len()]) };
        let s = settle(&mut contradicted, &far(), 1.0, 0.01, asking(&mut empty)).expect("settle");
        assert_eq!((s.asked, s.cut.len()), (1, 1));
        assert!((s.cut[0] - 0.628).abs() < 0.01, "{:?}", s.cut);
        assert_eq!(rfta_mesh::Topology::of(&contradicted).genus(), Some(0));
        assert!(rfta_mesh::Topology::of(&contradicted).is_watertight());

        // No loop shorter than the bound: nothing asked.
        let mut long = torus;
        let s = settle(&mut long, &far(), 0.5, 0.01, asking(&mut empty)).expect("settle");
        assert_eq!(s, Settled::default());

        // Inside samples along the tube, where the function says empty space: the samples keep
        // the handle (cutting would put one of them on the wrong side).
        let mut witnessed = shapes::torus(1.0, 0.1, 64, 16);
        let mut along: Vec<DVec3> = (0..64)
            .map(|i| {
                let t = f64::from(i) * std::f64::consts::TAU / 64.0;
                DVec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        along.push(DVec3::splat(10.0));
        let mut values = vec![-0.1; 64];
        values.push(1.0);
        let inside = SdfSamples::scattered(along, values).expect("samples");
        let s = settle(&mut witnessed, &inside, 1.0, 0.01, asking(&mut empty)).expect("settle");
        assert_eq!((s.asked, s.cut.len()), (1, 0));
    }

    /// Two close parts joined by a thread: a ring of radius 0.5 around the z axis at height `z`,
    /// its tube of radius `0.025 + 0.05 (1 - cos theta)`, a thick C (1.25 spacings across where
    /// widest) whose two ends meet in a thread 0.025 thick (its loop 0.157 around) where it crosses
    /// the x axis.
    fn ring(z: f64) -> TriMesh {
        let mut ring = shapes::torus(0.5, 0.02, 96, 16);
        ring.map_vertices(|v| {
            let theta = v.y.atan2(v.x);
            let core = DVec3::new(0.5 * theta.cos(), 0.5 * theta.sin(), 0.0);
            let r = 0.025 + 0.05 * (1.0 - theta.cos());
            core + (v - core) * (r / 0.02) + DVec3::new(0.0, 0.0, z)
        });
        ring
    }

    /// The ring's own signed distance on a grid of spacing 0.1 over [-1, 1]^3.
    fn sampled(ring: &TriMesh) -> SdfSamples {
        let grid = Grid::cube(20, -1.0, 1.0).expect("grid");
        let points: Vec<DVec3> = (0..grid.len()).map(|i| grid.position(i)).collect();
        let values = MeshIndex::new(ring)
            .expect("index")
            .signed_distances(&points);
        SdfSamples::grid(grid, values).expect("samples")
    }

    /// On a grid, with no function to ask: the thread between the C's two ends, when a sample
    /// lies in it (its core passes through the grid point (0.5, 0, 0)), keeps its handle; the
    /// same shape half a spacing higher, where the thread holds no sample (the C's thick parts
    /// hold many), is cut at the thread, and the result is closed and of genus 0.
    #[test]
    fn on_a_grid_a_thin_handle_stays_only_where_a_sample_of_its_side_lies_in_it() {
        let h = 0.1;
        let bound = crate::consistency::THIN_LOOP * h;
        let mut held = ring(0.0);
        let samples = sampled(&held);
        assert!(
            samples.values().iter().any(|&v| v < 0.0),
            "a sample in the tube"
        );
        let s = settle(&mut held, &samples, bound, 0.05 * h, None).expect("settle");
        assert_eq!(s, Settled::default());
        assert_eq!(rfta_mesh::Topology::of(&held).genus(), Some(1));

        let mut free = ring(0.05);
        let samples = sampled(&free);
        assert!(
            samples.values().iter().filter(|&&v| v < 0.0).count() > 20,
            "samples in the thick parts"
        );
        let s = settle(&mut free, &samples, bound, 0.05 * h, None).expect("settle");
        assert_eq!(s.asked, 0);
        assert_eq!(s.cut.len(), 1);
        // The loop around the thinnest part: 2 pi 0.025 = 0.157, a little longer on the mesh.
        assert!((0.15..0.2).contains(&s.cut[0]), "{:?}", s.cut);
        let topology = rfta_mesh::Topology::of(&free);
        assert_eq!(topology.genus(), Some(0));
        assert!(topology.is_watertight());
        // Cut where it is thinnest: every new vertex (on the caps) near the x axis.
        let before = ring(0.05).vertices.len();
        assert!(
            free.vertices[before..]
                .iter()
                .all(|v| v.y.abs() < 0.1 && v.x > 0.0),
            "the cut is where the ring is thinnest"
        );
    }

    /// A cut through the thread leaves an inside sample at the thread's centre in the gap between
    /// the caps, outside: refused; inside samples elsewhere in the C keep their side: kept.
    #[test]
    fn a_cut_that_turns_a_sample_is_refused() {
        let before = ring(0.0);
        let loops = rfta_mesh::short_loops(&before, 0.3).expect("closed");
        assert_eq!(loops.loops.len(), 1);
        let cycle = &loops.loops[0];
        let mut after = before.clone();
        assert!(rfta_mesh::cut_along(&mut after, cycle, 0.005));
        let index = MeshIndex::new(&before).expect("index");
        let centre = cycle
            .iter()
            .map(|&v| before.vertices[v as usize])
            .sum::<DVec3>()
            / cycle.len() as f64;
        // The sample, and one far outside (samples come two or more).
        let at = |p: DVec3| {
            SdfSamples::scattered(vec![p, DVec3::splat(10.0)], vec![-0.02, 1.0])
                .and_then(|s| s.with_spacing(0.1))
                .expect("samples")
        };
        assert!(!keeps_sides(&before, &index, &after, cycle, &at(centre)));
        assert!(keeps_sides(
            &before,
            &index,
            &after,
            cycle,
            &at(DVec3::new(-0.5, 0.0, 0.0))
        ));
    }

    /// The grid's witness search finds the samples a search of all of them finds.
    #[test]
    fn the_grid_search_for_a_witness_agrees_with_a_search_of_every_sample() {
        let samples = sampled(&ring(0.0));
        let scattered =
            SdfSamples::scattered(samples.positions(), samples.values().to_vec()).expect("samples");
        for (k, c) in [
            DVec3::new(0.5, 0.0, 0.0),
            DVec3::new(0.47, 0.03, 0.02),
            DVec3::new(0.0, 0.55, 0.0),
            DVec3::new(-0.95, -0.99, 1.0),
            DVec3::new(1.3, 0.0, 0.0),
            DVec3::new(-2.0, 5.0, 0.0),
        ]
        .into_iter()
        .enumerate()
        {
            for reach in [0.01, 0.05, 0.12, 0.3] {
                for inside in [true, false] {
                    assert_eq!(
                        witnessed(&samples, c, reach, inside),
                        witnessed(&scattered, c, reach, inside),
                        "point {k} {c}, reach {reach}, inside {inside}"
                    );
                }
            }
        }
    }
}
