//! Step 6, in three stages with one type between each: the final solve ([`final_solve`]: a
//! [`Solved`] mesh in the samples' coordinates), repair ([`repair`]: components the samples
//! contradict removed, samples on the wrong side dented past, sample spheres cleared, a known
//! genus reached; the repaired mesh) and the verdict ([`verdict`]: the mesh checked, measured
//! against every sample, and what the caller should know put in the report).
//!
//! The repair steps are `rfta-repair`'s; `islands.rs` holds the verdicts it removes components
//! by.

mod islands;
#[cfg(test)]
mod tests;

use std::sync::OnceLock;
use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::{SdfSamples, TriMesh};
use rfta_sphere_tree::SphereTree;

use crate::normalize::UnitBox;
use crate::rounds::Rounds;
use crate::{Params, Reconstruction, Report, Result, Stage, Step, check, consistency};

use islands::{inverted_and_unenclosed, judge};
use rfta_repair::{
    CLEAR_BELOW, Island, PUSH_DEPTH, clear_spheres, dent_wrong_side, face_components,
    push_out_of_spheres, remove_islands, signed_volume, to_genus,
};

/// The last solve on the final points, and the [`Reconstruction`] in the input's coordinates.
pub(crate) fn finish(
    samples: &SdfSamples,
    unit: &UnitBox,
    params: &Params,
    rounds: Rounds,
    mut report: Report,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<Reconstruction> {
    progress(Stage::Final);
    let solved = final_solve(unit, params, rounds, &mut report)?;
    let mesh = repair(
        samples,
        unit,
        params,
        &solved.tree,
        solved.mesh,
        &mut report,
    );
    verdict(params, samples, &mesh, unit.len(), &mut report)?;
    Ok(Reconstruction {
        mesh,
        points: solved.points,
        report,
    })
}

/// What the final solve hands to repair.
struct Solved {
    /// The screened Poisson surface of the final points, in the samples' coordinates.
    mesh: TriMesh,
    /// The final tangency points, in the samples' coordinates.
    points: TangentPoints,
    /// Every sample sphere's tree: the rounds' when they built one, else built on first use.
    tree: OnceLock<SphereTree>,
}

/// The final screened Poisson solve (every sample a side point, [`UnitBox::sides`]) and the
/// counts of the spheres that own no point.
fn final_solve(
    unit: &UnitBox,
    params: &Params,
    rounds: Rounds,
    report: &mut Report,
) -> Result<Solved> {
    let cloud = rounds.cloud;
    report.points_per_round.push(cloud.len());
    crate::pool::waiters_back();
    let t = Instant::now();
    let sides = unit.sides();
    let solved = crate::rounds::solve(&cloud, &sides, &params.spsr_params(Some(unit.spacing())))?;
    report.side_errors = solved.report.side_errors;
    let mut mesh = solved.mesh;
    report.timings.push((Step::FinalSolve, t.elapsed()));
    let n = unit.len();
    let mut owners = cloud.owners.clone();
    owners.dedup();
    report.far_spheres = unit.far_spheres(params);
    report.spheres_without_point = n.saturating_sub(owners.len() + report.far_spheres);
    mesh.map_vertices(|v| unit.to_input(v));
    let tree = OnceLock::new();
    if let Some(all) = rounds.all {
        let _ = tree.set(all);
    }
    let points = TangentPoints {
        points: cloud.points.iter().map(|&p| unit.to_input(p)).collect(),
        normals: cloud.normals,
        owners: cloud.owners,
    };
    Ok(Solved { mesh, points, tree })
}

/// Repair: components the samples contradict or do not witness removed, samples near the
/// surface on the wrong side dented past, vertices inside near sample spheres pushed out and
/// every sphere up to [`CLEAR_BELOW`] owner radii cleared, dents again, a known genus reached,
/// the cavities counted.
fn repair(
    samples: &SdfSamples,
    unit: &UnitBox,
    params: &Params,
    tree: &OnceLock<SphereTree>,
    mut mesh: TriMesh,
    report: &mut Report,
) -> TriMesh {
    crate::pool::waiters_back();
    let t = Instant::now();
    // The largest component in the unit box and the whole mesh, indexed on first use.
    let (main, whole) = (OnceLock::new(), OnceLock::new());
    let (kept, removed) = remove_islands(
        &mesh,
        |faces| inverted_and_unenclosed(&mesh, faces, &whole),
        |faces, bounds, largest| {
            let main = main.get_or_init(|| {
                let part = TriMesh {
                    vertices: mesh.vertices.iter().map(|&v| unit.to_unit(v)).collect(),
                    faces: largest.iter().map(|&f| mesh.faces[f]).collect(),
                };
                rfta_mesh::MeshIndex::new(&part).ok()
            });
            judge(unit, params, tree, main.as_ref(), &mesh, faces, bounds)
        },
    );
    mesh = kept;
    report.islands_removed = removed[Island::Small as usize];
    report.unsupported_removed = removed[Island::Unsupported as usize];
    report.timings.push((Step::Components, t.elapsed()));
    crate::pool::waiters_back();
    let t = Instant::now();
    // First radially out of the spheres that own points (near the surface and small, so the
    // tree prunes well), then out of every sphere up to CLEAR_BELOW owner radii, along the normal
    // where that is shorter, with faces split where they cut a sphere no vertex is in.
    let r_own = unit.owner_radius(params);
    let near: Vec<u32> = (0..unit.len() as u32)
        .filter(|&i| unit.spheres[i as usize].radius < r_own)
        .collect();
    let near = SphereTree::with_indices(&unit.spheres, &near);
    // Dents before clearing the spheres (which can then clear what a dent's faces enter) and
    // after it (for the samples a move out of a sphere left on the wrong side).
    let h = samples.spacing();
    report.dents = dent_wrong_side(&mut mesh, samples, h, consistency::SIGN_MARGIN);
    let before = mesh.vertices.clone();
    let spheres = unit.sphere_set();
    push_out_of_spheres(&mut mesh, &spheres, &near, PUSH_DEPTH * unit.spacing());
    report.vertices_added = clear_spheres(
        &mut mesh,
        &spheres,
        CLEAR_BELOW * r_own,
        PUSH_DEPTH * unit.spacing(),
    );
    report.vertices_pushed_out = before
        .iter()
        .zip(&mesh.vertices)
        .filter(|(a, b)| a != b)
        .count()
        + report.vertices_added;
    report.dents += dent_wrong_side(&mut mesh, samples, h, consistency::SIGN_MARGIN);
    report.timings.push((Step::SpheresCleared, t.elapsed()));
    if let Some(genus) = params.genus {
        let t = Instant::now();
        (report.components_joined, report.handles_cut) = to_genus(
            &mut mesh,
            genus,
            h,
            consistency::THIN_LOOP,
            consistency::THIN_LOOP_MAX_GENUS,
        );
        report.timings.push((Step::Topology, t.elapsed()));
    }
    report.cavities = face_components(&mesh)
        .iter()
        .filter(|faces| signed_volume(&mesh, faces) < 0.0)
        .count();
    mesh
}

/// The verdict: the mesh checked ([`check::mesh`]) and measured against every sample
/// ([`consistency::measure_with`]), and a warning for each thing the caller should know (`n`:
/// the number of samples).
fn verdict(
    params: &Params,
    samples: &SdfSamples,
    mesh: &TriMesh,
    n: usize,
    report: &mut Report,
) -> Result<()> {
    crate::pool::waiters_back();
    let t = Instant::now();
    let topology = rfta_mesh::Topology::of(mesh);
    report.mesh = check::mesh(mesh, &topology)?;
    report.consistency = consistency::measure_with(samples, mesh, &topology, report.clamp)?;
    report.timings.push((Step::Consistency, t.elapsed()));
    if let Some(genus) = params.genus {
        match topology.genus() {
            Some(g) if g < genus as i64 => report.warnings.push(format!(
                "the mesh has genus {g}, below the {genus} asked: the samples show no more handles (a handle is never added)"
            )),
            Some(g) if g > genus as i64 => report.warnings.push(format!(
                "the mesh has genus {g}, above the {genus} asked: handles are cut on meshes of genus up to {}, along loops up to 64 spacings",
                consistency::THIN_LOOP_MAX_GENUS
            )),
            _ => {}
        }
    }
    let c = &report.consistency;
    if !c.is_consistent() {
        report.warnings.push(format!(
            "the mesh disagrees with the samples: {} on the wrong side of it, {} whose sphere it enters by more than {} spacing (deepest: {:.2} spacings)",
            c.sign_errors,
            c.entered,
            consistency::ENTER_MARGIN,
            c.deepest_entry
        ));
    }
    if report.cavities > 0 {
        report.warnings.push(format!(
            "the mesh encloses {} cavit{} around samples outside the shape: unless the shape is hollow there, a hole or a gap the surface closed around them, which finer samples can open",
            report.cavities,
            if report.cavities == 1 { "y" } else { "ies" }
        ));
    }
    if let Some(&shortest) = c.thin_loops.first() {
        report.warnings.push(format!(
            "the mesh has {} loop(s) around handles shorter than {:.2} spacings (the shortest {shortest:.2}): parts less than about a spacing across, which the samples can neither confirm nor rule out; finer samples can",
            c.thin_loops.len(),
            consistency::THIN_LOOP
        ));
    }
    // A few spheres covered by their neighbours are normal (the reference has them too); a
    // twentieth of them means clamped, zero or inconsistent values and a less certain surface.
    let eligible = n - report.far_spheres;
    if report.spheres_without_point * 20 > eligible {
        report.warnings.push(format!(
            "{} of {eligible} spheres ended without a tangency point (clamped, zero-valued, or covered by other spheres)",
            report.spheres_without_point
        ));
    }
    if !report.mesh.watertight {
        report.warnings.push(format!(
            "the mesh is not watertight: {} boundary and {} non-manifold edges",
            report.mesh.boundary_edges, report.mesh.nonmanifold_edges
        ));
    }
    if report.mesh.zero_area_faces > 0 {
        report.warnings.push(format!(
            "the mesh has {} faces of zero area ({} with a repeated vertex)",
            report.mesh.zero_area_faces, report.mesh.degenerate_faces
        ));
    }
    Ok(())
}
