//! Pieces of a level-set reading joined where the function says they are one solid: a strut
//! thinner than the finest grid's spacing shows in none of its cells' signs, so the reading breaks
//! it, and the pieces on either side end a few spacings apart. Between the nearest points of
//! two pieces that close the function is asked along the segment; when it is inside all along,
//! the pieces' nearest faces are joined by a tube ([`rfta_mesh::join`]), as the values asked say.
//! Only outward pieces (not a cavity's wall) are joined, each pair once, the nearest first.

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;
use rfta_mesh::{MeshIndex, UnionFind, face_components, signed_volume};

use crate::Result;

/// Pieces nearer than this many finest spacings are asked about (on the trained network of
/// thingi54725 asked at MISE's 64,893 evaluations, two of three broken struts had gaps under 2,
/// the third under 3; docs/eval/inexact.md).
const REACH: f64 = 3.0;

/// The points asked along a gap lie at most this many finest spacings apart.
const STEP: f64 = 0.25;

/// Joining is tried on meshes of at most this many pieces (each piece's vertices are looked up
/// against every other's index).
const MAX_PIECES: usize = 64;

/// Joins the outward pieces of `mesh` that lie within [`REACH`] finest spacings `h` of each other
/// and between whose nearest points `ask` (the function, negative inside) is inside at every
/// point [`STEP`] spacings apart, asking at most `left` points. Returns the points asked and the
/// joins made.
pub(super) fn join_where_inside(
    mesh: &mut TriMesh,
    h: f64,
    left: usize,
    ask: &mut dyn FnMut(&[DVec3]) -> Result<Vec<f64>>,
) -> Result<(usize, usize)> {
    let parts = face_components(mesh);
    if parts.len() < 2 || parts.len() > MAX_PIECES {
        return Ok((0, 0));
    }
    let reach = REACH * h;
    let outward: Vec<bool> = parts.iter().map(|p| signed_volume(mesh, p) > 0.0).collect();
    let pieces: Vec<Option<(TriMesh, MeshIndex)>> = parts
        .iter()
        .zip(&outward)
        .map(|(p, &out)| {
            if !out {
                return None;
            }
            let part = mesh.part(p);
            let index = MeshIndex::new(&part).ok()?;
            Some((part, index))
        })
        .collect();
    // The nearest points of each pair within reach: (distance, i, j, face of i, face of j, the
    // point on i, the point on j), faces as the mesh numbers them.
    let mut gaps = Vec::new();
    for (i, a) in pieces.iter().enumerate() {
        for (j, b) in pieces.iter().enumerate().skip(i + 1) {
            let (Some((part_a, index_a)), Some((_, index_b))) = (a, b) else {
                continue;
            };
            let near = index_b.bounds();
            let near = rfta_geom::Aabb::new(near.min - reach, near.max + reach);
            let best = part_a
                .vertices
                .iter()
                .filter(|&&v| near.contains(v))
                .filter_map(|&v| index_b.closest_point_within(v, reach * reach))
                .min_by(|x, y| x.distance_squared.total_cmp(&y.distance_squared));
            let Some(on_b) = best else { continue };
            let on_a = index_a.closest_point(on_b.point);
            let d = on_a.point.distance(on_b.point);
            let (fa, fb) = (parts[i][on_a.face as usize], parts[j][on_b.face as usize]);
            gaps.push((d, i, j, fa as u32, fb as u32, on_a.point, on_b.point));
        }
    }
    gaps.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
    // The points along each gap, in one batch, while they fit.
    let mut points = Vec::new();
    let mut runs = Vec::new();
    for gap in &gaps {
        let n = (gap.0 / (STEP * h)).ceil().max(1.0) as usize;
        if points.len() + n > left {
            break;
        }
        let start = points.len();
        points.extend((1..=n).map(|k| gap.5.lerp(gap.6, k as f64 / (n + 1) as f64)));
        runs.push(start..points.len());
    }
    if points.is_empty() {
        return Ok((0, 0));
    }
    let values = ask(&points)?;
    let mut joined_to = UnionFind::new(parts.len());
    let mut replaced = vec![false; mesh.faces.len()];
    let mut joined = 0;
    for (gap, run) in gaps.iter().zip(runs) {
        let &(_, i, j, fa, fb, _, _) = gap;
        let inside = values[run].iter().all(|&v| v < 0.0);
        if joined_to.find(i) == joined_to.find(j)
            || !inside
            || replaced[fa as usize]
            || replaced[fb as usize]
        {
            continue;
        }
        if rfta_mesh::join(mesh, fa, fb) {
            joined_to.union(i, j);
            replaced[fa as usize] = true;
            replaced[fb as usize] = true;
            joined += 1;
        }
    }
    Ok((points.len(), joined))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;
    use rfta_mesh::Topology;

    /// Two balls of radius 0.4 whose surfaces are 0.05 apart at the origin (centres at
    /// `-0.425 x` and `0.425 x`).
    fn two_balls() -> TriMesh {
        let mut mesh = TriMesh::default();
        for sx in [-1.0, 1.0] {
            let mut ball = shapes::icosphere(0.4, 3);
            ball.map_vertices(|v| v + DVec3::new(sx * 0.425, 0.0, 0.0));
            mesh.append(&ball);
        }
        mesh
    }

    /// The signed distance to the two balls, and, with `rod`, to a rod of radius 0.02 along the
    /// x axis between them.
    fn field(p: DVec3, rod: bool) -> f64 {
        let ball = |c: f64| (p - DVec3::new(c, 0.0, 0.0)).length() - 0.4;
        let mut d = ball(-0.425).min(ball(0.425));
        if rod {
            d = d.min(DVec3::new(0.0, p.y, p.z).length() - 0.02);
        }
        d
    }

    fn join(mesh: &mut TriMesh, h: f64, rod: bool) -> (usize, usize) {
        let mut ask = |p: &[DVec3]| Ok(p.iter().map(|&q| field(q, rod)).collect());
        join_where_inside(mesh, h, 1000, &mut ask).expect("the field answers")
    }

    #[test]
    fn pieces_the_function_joins_are_joined_by_a_tube() {
        // 0.05 apart: within three spacings of 0.02, asked at most 0.005 apart.
        let mut mesh = two_balls();
        let (asked, joined) = join(&mut mesh, 0.02, true);
        assert_eq!(joined, 1);
        assert!((10..=20).contains(&asked), "{asked}");
        let topology = Topology::of(&mesh);
        assert!(topology.is_watertight() && topology.is_manifold());
        assert_eq!(face_components(&mesh).len(), 1);
        assert_eq!(topology.genus(), Some(0));
    }

    #[test]
    fn pieces_apart_in_the_function_or_beyond_reach_stay_apart() {
        // No rod: the gap is outside.
        let mut mesh = two_balls();
        assert_eq!(join(&mut mesh, 0.02, false).1, 0);
        assert_eq!(mesh, two_balls());
        // A rod, but the gap wider than three spacings of 0.01: nothing asked.
        assert_eq!(join(&mut mesh, 0.01, true), (0, 0));
    }

    #[test]
    fn a_cavity_is_not_joined_to_its_outer_wall() {
        // A hollow ball: its wall (between radii 0.3 and 0.35) is inside, but the inner surface
        // bounds a cavity.
        let mut mesh = shapes::icosphere(0.35, 3);
        let mut cavity = shapes::icosphere(0.3, 3);
        cavity.faces.iter_mut().for_each(|f| f.swap(1, 2));
        mesh.append(&cavity);
        let before = mesh.clone();
        let mut ask = |p: &[DVec3]| {
            Ok(p.iter()
                .map(|q| (q.length() - 0.35).max(0.3 - q.length()))
                .collect())
        };
        assert_eq!(
            join_where_inside(&mut mesh, 0.02, 1000, &mut ask).expect("answers"),
            (0, 0)
        );
        assert_eq!(mesh, before);
    }
}
