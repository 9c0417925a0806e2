//! What the samples leave undecided, settled by asking the function: small components.
//!
//! A component other than the largest, smaller than `small` across, is a part of the shape or a
//! void only if the function says so: inside by at least an eighth of its diagonal at its centre
//! for a part outside the largest component; outside by as much for a void (an inward shell) in
//! it, with material in the wall around it. Otherwise it is an island the solve left at the
//! surface (the outlying tangency points' bubbles, a shell nested in the solid, a pocket the
//! surface sealed) and is removed.
//!
//! Thin handles are settled the same way ([`crate::finish::handles`], with the function as its
//! oracle).

use rfta_geom::glam::DVec3;
use rfta_geom::{SdfSamples, TriMesh};
use rfta_mesh::MeshIndex;

use crate::Result;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::finish::handles::tests::far;
    use rfta_geom::shapes;

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
