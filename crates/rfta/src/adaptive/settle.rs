//! What the samples leave undecided, settled by asking the function: small components and thin
//! handles.
//!
//! A component other than the largest, smaller than `small` across, is a part of the shape or a
//! void only if the function says so: inside by at least an eighth of its diagonal at its centre
//! for a part outside the largest component; outside by as much for a void (an inward shell) in
//! it, with material in the wall around it. Otherwise it is an island the solve left at the
//! surface (the outlying tangency points' bubbles, a shell nested in the solid, a pocket the
//! surface sealed) and is removed.
//!
//! A loop around a handle thinner than the samples resolve is a bar of material or a tunnel
//! through it, and the function at the loop's centre says which it should be. The loop around a
//! bar has its centre inside the bar, the loop around a tunnel in the tunnel's empty space; the
//! mesh's own signed distance at the centre says which the mesh made. A real bar or tunnel of
//! radius `r` (its loop `2 pi r` long) has the function about `r` deep on its side at its centre.
//! Where the function is on the other side (a bar where it is outside, a tunnel where it is
//! inside), less than `r / 4` deep, or more than `4 r` (a handle far thinner than what the
//! function has there: a sample at its centre cannot tell it from the surface it sits on, and
//! the function's depth belongs to something else), the handle is an artifact of the
//! reconstruction and is cut along its loop (`rfta_mesh::cut_along`: the bar cut through, the
//! tunnel filled, both sides capped); otherwise it is the shape's and stays.

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

/// A small component is kept when the function at its centre is this fraction of its
/// diagonal on its side (a ball's centre is a third of its box's diagonal deep).
const DEPTH: f64 = 1.0 / 8.0;

/// Asks `ask` at the centre of every component of `mesh` but the largest that is smaller than
/// `small` across, and removes those the function does not confirm: a part must lie outside the
/// largest component with the function inside at its centre, a void (an inward shell) inside it
/// with the function outside at its centre and inside in the wall between it and the largest
/// component's nearest point (else it is a pocket the surface sealed). Two questions each, at
/// most `max_asks` in all. Returns (components asked about, removed).
///
/// # Errors
/// The oracle's.
pub(crate) fn settle_components(
    mesh: &mut TriMesh,
    samples: &SdfSamples,
    small: f64,
    max_asks: usize,
    ask: &mut dyn FnMut(&[DVec3]) -> Result<Vec<f64>>,
) -> Result<(usize, usize)> {
    let components = rfta_mesh::face_components(mesh);
    let Some(largest) =
        (0..components.len()).max_by_key(|&c| (components[c].len(), usize::MAX - c))
    else {
        return Ok((0, 0));
    };
    // The largest component alone: where the others lie against it.
    let main = MeshIndex::new(&mesh.part(&components[largest]))?;
    let mut questions = Vec::new();
    for (c, faces) in components.iter().enumerate() {
        if c == largest {
            continue;
        }
        let part = mesh.part(faces);
        let bounds = part.bounds();
        let diagonal = (bounds.max - bounds.min).length();
        let void = part.signed_volume() < 0.0;
        if diagonal < small && !witnessed(&part, bounds, void, samples)? {
            let centre = part.vertices.iter().sum::<DVec3>() / part.vertices.len() as f64;
            // A part must lie outside the main body, a void inside it.
            let nested = main.signed_distance(centre) < 0.0;
            // The wall between a void and the outside: halfway from the shell to the main
            // body's nearest point.
            let towards = main.closest_point(centre).point;
            let reach = (towards - centre).length();
            let wall =
                centre + (towards - centre) * ((0.5 * diagonal / reach).min(1.0) + 1.0) / 2.0;
            questions.push((c, centre, wall, diagonal, void, nested));
        }
    }
    questions.truncate(max_asks / 2);
    if questions.is_empty() {
        return Ok((0, 0));
    }
    let points: Vec<DVec3> = questions.iter().flat_map(|q| [q.1, q.2]).collect();
    let truth = ask(&points)?;
    let mut gone = vec![false; components.len()];
    for (&(c, _, _, diagonal, void, nested), f) in questions.iter().zip(truth.chunks_exact(2)) {
        let (centre, wall) = (f[0], f[1]);
        let confirmed = if void {
            nested && centre > DEPTH * diagonal && wall < 0.0
        } else {
            !nested && centre < -DEPTH * diagonal
        };
        gone[c] = !confirmed;
    }
    let removed = gone.iter().filter(|&&g| g).count();
    if removed > 0 {
        let mut keep = vec![true; mesh.faces.len()];
        for (c, faces) in components.iter().enumerate() {
            if gone[c] {
                for &f in faces {
                    keep[f] = false;
                }
            }
        }
        let mut k = keep.iter();
        mesh.faces.retain(|_| k.next().copied().unwrap_or(true));
        mesh.remove_unreferenced_vertices();
    }
    Ok((questions.len(), removed))
}

/// Whether a sample of the component's inside sign lies in it (negative in a part, positive in a
/// void): the samples themselves support it, and removing it would put that sample on the wrong
/// side.
fn witnessed(
    part: &TriMesh,
    bounds: rfta_geom::Aabb,
    void: bool,
    samples: &SdfSamples,
) -> Result<bool> {
    let inside: Vec<DVec3> = (0..samples.len())
        .filter(|&i| (samples.values()[i] > 0.0) == void && samples.values()[i] != 0.0)
        .map(|i| samples.position(i))
        .filter(|&p| p.cmpge(bounds.min).all() && p.cmple(bounds.max).all())
        .collect();
    if inside.is_empty() {
        return Ok(false);
    }
    let index = MeshIndex::new(part)?;
    Ok(inside.iter().any(|&p| index.winding_number(p).abs() > 0.5))
}

/// What [`settle`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Settled {
    /// Loops whose centre the function was asked at.
    pub(crate) asked: usize,
    /// Handles cut: the function put their centre on the other side.
    pub(crate) cut: usize,
}

/// Asks `ask` at the centres of `mesh`'s loops shorter than `bound` (at most `max_asks` points in
/// all) and cuts the handles the answers contradict, the two sides `gap` apart.
///
/// # Errors
/// The oracle's.
pub(crate) fn settle(
    mesh: &mut TriMesh,
    samples: &SdfSamples,
    bound: f64,
    gap: f64,
    max_asks: usize,
    ask: &mut dyn FnMut(&[DVec3]) -> Result<Vec<f64>>,
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
        cycles.truncate(max_asks - settled.asked);
        if cycles.is_empty() {
            break;
        }
        let centres: Vec<DVec3> = cycles
            .iter()
            .map(|c| c.iter().map(|&v| mesh.vertices[v as usize]).sum::<DVec3>() / c.len() as f64)
            .collect();
        let truth = ask(&centres)?;
        settled.asked += centres.len();
        let made = MeshIndex::new(mesh)?.signed_distances(&centres);
        // A handle is an artifact unless the function or a sample confirms it.
        let artifact = |k: usize| {
            let (Some(&f), Some(&d)) = (truth.get(k), made.get(k)) else {
                return false;
            };
            // A real bar or tunnel of radius r = length / 2 pi has the function about r deep on
            // its side at its centre: between r / 4 and 4 r is asked for.
            let r = loops.lengths[k] / std::f64::consts::TAU;
            let deep = if d < 0.0 { -f } else { f };
            // A sample of the handle's own side near its centre (material in a bar, empty space
            // in a tunnel) supports it too: cutting would put that sample on the wrong side.
            let witness = (0..samples.len()).any(|i| {
                let v = samples.values()[i];
                v != 0.0
                    && (v < 0.0) == (d < 0.0)
                    && samples.position(i).distance(centres[k]) < WITNESS_REACH * r
            });
            !(witness || (DEPTH_RANGE[0] * r..=DEPTH_RANGE[1] * r).contains(&deep))
        };
        let cut = rfta_repair::cut_disjoint(mesh, &cycles, gap, |k, _| artifact(k));
        settled.cut += cut;
        if cut == 0 {
            break;
        }
    }
    Ok(settled)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    /// Two samples far from every test shape: nothing witnessed.
    fn far() -> SdfSamples {
        SdfSamples::scattered(
            vec![DVec3::splat(10.0), DVec3::splat(-10.0)],
            vec![1.0, -1.0],
        )
        .expect("samples")
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
        let s = settle(&mut confirmed, &far(), 1.0, 0.01, 100, &mut tube).expect("settle");
        assert_eq!(s, Settled { asked: 1, cut: 0 });
        assert_eq!(rfta_mesh::Topology::of(&confirmed).genus(), Some(1));

        let mut contradicted = torus.clone();
        let mut empty = |p: &[DVec3]| -> Result<Vec<f64>> { Ok(vec![0.5; p.len()]) };
        let s = settle(&mut contradicted, &far(), 1.0, 0.01, 100, &mut empty).expect("settle");
        assert_eq!(s, Settled { asked: 1, cut: 1 });
        assert_eq!(rfta_mesh::Topology::of(&contradicted).genus(), Some(0));
        assert!(rfta_mesh::Topology::of(&contradicted).is_watertight());

        // No loop shorter than the bound: nothing asked.
        let mut long = torus;
        let s = settle(&mut long, &far(), 0.5, 0.01, 100, &mut empty).expect("settle");
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
        let s = settle(&mut witnessed, &inside, 1.0, 0.01, 100, &mut empty).expect("settle");
        assert_eq!(s, Settled { asked: 1, cut: 0 });
    }

    /// Beside a large sphere, a small ball the function puts outside is removed, one it puts
    /// inside kept; in the sphere, a small inward shell where the function says material is
    /// removed, one around the function's own void kept; nothing larger than `small` is asked
    /// about.
    #[test]
    fn small_components_stay_where_the_function_confirms_them() {
        let big = shapes::icosphere(1.0, 3);
        let ball = |c: DVec3| {
            let mut b = shapes::icosphere(0.05, 1);
            b.map_vertices(|v| v + c);
            b
        };
        let mut inward = ball(DVec3::new(0.0, 0.5, 0.0));
        inward.flip();
        let void = DVec3::new(0.0, -0.5, 0.0);
        let mut hollow = ball(void);
        hollow.flip();
        let mut mesh = big.clone();
        mesh.append(&ball(DVec3::new(3.0, 0.0, 0.0)));
        mesh.append(&ball(DVec3::new(-3.0, 0.0, 0.0)));
        mesh.append(&inward);
        mesh.append(&hollow);
        // Material in the big sphere but a void of radius 0.05 at `void`, and around x = -3 (a
        // second small ball).
        let mut truth = |p: &[DVec3]| -> Result<Vec<f64>> {
            Ok(p.iter()
                .map(|q| {
                    let shell = (q.length() - 1.0).max(0.05 - (*q - void).length());
                    shell.min((*q - DVec3::new(-3.0, 0.0, 0.0)).length() - 0.05)
                })
                .collect())
        };
        let (asked, removed) =
            settle_components(&mut mesh, &far(), 0.5, 100, &mut truth).expect("settle");
        assert_eq!((asked, removed), (4, 2));
        assert_eq!(rfta_mesh::face_components(&mesh).len(), 3);
        assert!(mesh.vertices.iter().any(|v| (*v - void).length() < 0.1));
        assert!(mesh.vertices.iter().any(|v| (v.x + 3.0).abs() < 0.1));
        assert_eq!(mesh.unreferenced_vertices(), 0);
        // Too large to ask about: nothing asked.
        let mut twice = big.clone();
        twice.append(&ball(DVec3::new(3.0, 0.0, 0.0)));
        let none = settle_components(&mut twice, &far(), 0.05, 100, &mut truth).expect("settle");
        assert_eq!(none, (0, 0));
        // A ball the function puts outside but an inside sample holds: kept, not asked about.
        let mut held = big;
        held.append(&ball(DVec3::new(3.0, 0.0, 0.0)));
        let witness = SdfSamples::scattered(
            vec![DVec3::new(3.0, 0.0, 0.0), DVec3::splat(10.0)],
            vec![-0.01, 1.0],
        )
        .expect("samples");
        let kept = settle_components(&mut held, &witness, 0.5, 100, &mut truth).expect("settle");
        assert_eq!(kept, (0, 0));
    }
}
