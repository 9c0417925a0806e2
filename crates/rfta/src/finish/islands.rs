//! The verdicts [`rfta_repair::remove_islands`] removes components by: an inward shell around
//! nothing, a part inside sample spheres, a small component no sample supports.

use std::sync::OnceLock;

use rfta_geom::glam::DVec3;
use rfta_geom::kernels::solid_angle;
use rfta_geom::{Aabb, TriMesh};
use rfta_sphere_tree::SphereTree;

use rfta_repair::{Island, signed_volume};

use super::reach::Reach;
use crate::normalize::UnitBox;
use crate::{Params, consistency};

/// Whether the component `faces` of `mesh` faces inward (negative volume) and no other component
/// encloses it: a cavity with no solid around it, which no bounded set of samples describes. With
/// few samples away from the surface, screened Poisson can close such a shell far out in its box.
pub(super) fn inverted_and_unenclosed(
    mesh: &TriMesh,
    faces: &[usize],
    whole: &OnceLock<Option<rfta_mesh::MeshIndex>>,
) -> bool {
    if signed_volume(mesh, faces) >= 0.0 {
        return false;
    }
    let Some(&first) = faces.first() else {
        return false;
    };
    let p = mesh.vertices[mesh.faces[first][0] as usize];
    let angle = |f: usize| {
        let [a, b, c] = mesh.triangle(f);
        solid_angle(p, a, b, c)
    };
    let own: f64 = faces.iter().map(|&f| angle(f)).sum();
    // The other components' winding number at `p`: the whole mesh's (hierarchical, the mesh
    // indexed once) less the component's own solid angles.
    let all = match whole.get_or_init(|| rfta_mesh::MeshIndex::new(mesh).ok()) {
        Some(index) => index.winding_number(p),
        None => (0..mesh.faces.len()).map(angle).sum::<f64>() / (4.0 * std::f64::consts::PI),
    };
    all - own / (4.0 * std::f64::consts::PI) < 0.5
}

/// The verdict on one component (`faces` of `mesh`, in the samples' coordinates, within
/// `bounds`); `blocks` holds `unit`'s spheres in blocks, `main` indexes the largest component in
/// the unit box.
pub(super) fn judge(
    unit: &UnitBox,
    params: &Params,
    blocks: &Reach<'_>,
    main: Option<&rfta_mesh::MeshIndex>,
    mesh: &TriMesh,
    faces: &[usize],
    bounds: Aabb,
) -> Option<Island> {
    use rayon::prelude::*;
    let h = unit.input_spacing;
    let diag = (bounds.max - bounds.min).length();
    // The surface may not enter a sample sphere: a component inside them is not there.
    let mut vertices: Vec<u32> = faces.iter().flat_map(|&f| mesh.faces[f]).collect();
    vertices.sort_unstable();
    vertices.dedup();
    // The spheres the tests below can meet: those that reach the component's box, or come
    // within the gap margin of it (closes_gap).
    let margin = consistency::GAP_MARGIN * unit.spacing();
    let tree = SphereTree::with_indices(unit, &blocks.spheres_reaching(bounds, margin));
    let tol = params.tolerance;
    // A closed component stands for a solid (outward) or a cavity (inward): a sample inside it
    // of that sign witnesses it, however small it is. Computed at most once.
    let mut witnessed: Option<bool> = None;
    let mut encloses_witness = || {
        *witnessed.get_or_insert_with(|| {
            unit.samples_within(bounds).into_iter().any(|i| {
                let p = unit.to_input(unit.center(i));
                let w: f64 = faces
                    .iter()
                    .map(|&f| {
                        let [a, b, c] = mesh.faces[f].map(|v| mesh.vertices[v as usize]);
                        solid_angle(p, a, b, c)
                    })
                    .sum::<f64>()
                    / (4.0 * std::f64::consts::PI);
                let v = unit.values[i];
                (w > 0.5 && v < 0.0) || (w < -0.5 && v > 0.0)
            })
        })
    };
    // A component wholly beyond the samples' box is where no sample was taken: the solve's
    // extrapolation (hostile test E16: a second cow-sized piece past the box an adaptive run
    // sampled), kept only where sample spheres at the box's edge need it to close their gaps.
    if !bounds.overlaps(&unit.samples_box())
        && !closes_gap(unit, &tree, main, mesh, faces, &vertices)
    {
        return Some(Island::Unsupported);
    }
    // The surface may not enter a sample sphere: a component inside them is not there, unless
    // it encloses a sample of its inside's sign (a cavity the side re-solves opened around a
    // sample the first solve enclosed, still inside that sample's sphere: the clearing below
    // widens it to the sphere).
    if vertices
        .par_iter()
        .all(|&v| tree.inside_any(unit.to_unit(mesh.vertices[v as usize]), -tol, None))
        && !encloses_witness()
    {
        return Some(Island::Unsupported);
    }
    // A small closed component needs a witness: a sample inside it, or, for a part (not a
    // cavity) at least a spacing across, some sample's sphere that reaches it and no farther
    // part of the surface: a thin part between the samples, which no sample lies in, is where the
    // spheres around it touch (without it they would have gaps). A part less than a spacing
    // across that no sample lies in is below what the samples resolve (marching cubes of them
    // makes none): it goes, unless thin parts are kept ([`Params::keep_thin_handles`]). A cavity
    // no sample lies in is a sealed bubble the samples do not show, whatever spheres its wall
    // touches.
    let resolved = params.keep_thin_handles || diag >= h;
    if diag < params.min_island * h
        && !encloses_witness()
        && (signed_volume(mesh, faces) < 0.0
            || !resolved
            || !closes_gap(unit, &tree, main, mesh, faces, &vertices))
    {
        return Some(Island::Small);
    }
    None
}

/// A small component that no sample lies in stays when it closes the gaps of at least this many
/// samples ([`closes_gap`]). A gap at one or two samples is within what the method leaves on
/// most shapes, and a stray blob next to such a gap would stay for it (the demo's two tori: a
/// blob 0.6 spacings off the surface, closing one sample's gap); a thin part the grid misses is
/// the nearest surface of many samples (the knight's tips at N = 30: 955, 1,210 and 1,332).
pub(super) const GAP_WITNESSES: usize = 3;

/// Whether the component (`faces` of `mesh`, with its `vertices`) touches the spheres of at
/// least [`GAP_WITNESSES`] unclamped samples, its nearest point to each sample within the margins
/// of [`crate::consistency`] (entered by at most [`consistency::ENTER_MARGIN`] spacings, at most
/// [`consistency::GAP_MARGIN`] beyond), while `main` (the largest component) is farther from
/// those samples than the gap margin: without the component, they would have gaps
/// ([`crate::Consistency::gaps`]).
pub(super) fn closes_gap(
    unit: &UnitBox,
    tree: &SphereTree,
    main: Option<&rfta_mesh::MeshIndex>,
    mesh: &TriMesh,
    faces: &[usize],
    vertices: &[u32],
) -> bool {
    let h = unit.spacing();
    let (enter, gap) = (consistency::ENTER_MARGIN * h, consistency::GAP_MARGIN * h);
    let mut near = Vec::new();
    let mut reached = Vec::new();
    for &v in vertices {
        tree.spheres_within_into(
            unit.to_unit(mesh.vertices[v as usize]),
            gap,
            None,
            &mut near,
        );
        reached.extend_from_slice(&near);
    }
    reached.sort_unstable();
    reached.dedup();
    let triangles: Vec<[DVec3; 3]> = faces
        .iter()
        .map(|&f| mesh.triangle(f).map(|v| unit.to_unit(v)))
        .collect();
    let witnesses = reached.iter().filter(|&&i| {
        let (c, r) = (unit.center(i as usize), unit.values[i as usize].abs());
        let d = triangles
            .iter()
            .map(|[a, b, t]| {
                c.distance(rfta_geom::kernels::closest_point_on_triangle(c, *a, *b, *t).0)
            })
            .fold(f64::INFINITY, f64::min);
        let reach = r + gap;
        r < unit.clamp
            && d >= r - enter
            && d <= reach
            && main.is_none_or(|m| m.closest_point_within(c, reach * reach).is_none())
    });
    witnesses.take(GAP_WITNESSES).count() == GAP_WITNESSES
}
