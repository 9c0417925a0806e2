//! Samples near the surface on the wrong side of it: the surface dented past them.

use rfta_geom::glam::DVec3;
use rfta_geom::{SdfSamples, TriMesh};

use crate::edit::Splitter;
use rfta_mesh::Incidence;

/// Samples this close to the surface (in spacings) are the ones [`dent_wrong_side`] looks at.
pub(crate) const DENT_BELOW: f64 = 0.5;

/// How far beyond its sphere a dent's new vertex lands, in sample spacings.
pub(crate) const DENT_MARGIN: f64 = 0.05;

/// A sample less than `DENT_BELOW` (0.5) spacings `h` from the surface (and more than
/// `sign_margin`: nearer, its side is not reliable), with the mesh as near, on the wrong side of
/// the mesh: a face cuts its small sphere, or passes just beyond it (the faces are about a quarter
/// of a spacing across, so no vertex need lie inside, and moving the surface away from the sample
/// would leave it on the wrong side). The mesh's point nearest the sample moves through the sphere
/// to just beyond its far side, on the line from that point through the sample (`DENT_MARGIN`
/// (0.05) past the sphere): a new vertex there ([`Splitter::split`]: the face, or both faces beside
/// the edge, split), or the vertex itself. The sample then lies in a shallow dent, on its own side.
/// Not made where a face would turn over. Samples are taken in order, so the result does not depend
/// on the thread count. Returns how many dents were made.
pub fn dent_wrong_side(
    mesh: &mut TriMesh,
    samples: &SdfSamples,
    h: f64,
    sign_margin: f64,
) -> usize {
    use rayon::prelude::*;
    let Ok(index) = rfta_mesh::MeshIndex::new(mesh) else {
        return 0;
    };
    let values = samples.values();
    let reach = DENT_BELOW * h;
    let wrong: Vec<(usize, rfta_mesh::ClosestPoint)> = (0..values.len())
        .into_par_iter()
        .filter_map(|i| {
            let (p, s) = (samples.position(i), values[i]);
            let r = s.abs();
            if r <= sign_margin * h || r >= reach {
                return None;
            }
            let c = index.closest_point_within(p, reach * reach)?;
            let inside = index.winding_number(p) > 0.5;
            (inside != (s < 0.0)).then_some((i, c))
        })
        .collect();
    let incident = Incidence::of(mesh);
    let mut splitter = Splitter::new(&incident, mesh);
    let mut dents = 0;
    for (i, c) in wrong {
        let n = mesh.face_normal_scaled(c.face as usize).normalize_or_zero();
        if n == DVec3::ZERO {
            continue;
        }
        // The new surface passes beyond the sample, on the line from the mesh's nearest point
        // through it (on a face: along its normal, behind the sample when it is outside).
        let (p, s) = (samples.position(i), values[i]);
        let away = (p - c.point).try_normalize().unwrap_or(-s.signum() * n);
        let apex = p + (s.abs() + DENT_MARGIN * h) * away;
        let f = c.face as usize;
        let made = match c.barycentric.iter().position(|&b| b > 0.98) {
            // Nearest a vertex: the vertex itself goes there.
            Some(j) => splitter.move_vertex(mesh, mesh.faces[f][j], apex),
            None => splitter.split(mesh, f, c.barycentric, apex).is_some(),
        };
        dents += usize::from(made);
    }
    dents
}
