//! Step 6, in stages with one type between each: the final solve ([`final_solve`]: a mesh in
//! the samples' coordinates), repair ([`repair`]: components the samples contradict removed,
//! samples on the wrong side dented past, sample spheres cleared, a known genus reached; the
//! repaired mesh), the cavities the samples leave open opened ([`open_cavities`]: solved and
//! repaired again with points kept outside in their walls) and the verdict ([`verdict`]: the
//! mesh measured against every sample, the spheres it still enters cleared, checked, and what the
//! caller should know put in the report).
//!
//! The repair steps are `rfta-repair`'s; `islands.rs` holds the verdicts it removes components
//! by.

pub(crate) mod handles;
mod islands;
mod reach;
mod simplify;
#[cfg(test)]
mod tests;

use std::sync::OnceLock;
use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::{SdfSamples, SphereSet, TriMesh};
use rfta_sphere_tree::SphereTree;

use crate::normalize::UnitBox;
use crate::plan::Plan;
use crate::report::{FinalSolveReport, Journal, RepairReport};
use crate::{
    Consistency, MeshCheck, Reconstruction, Report, Result, Stage, Step, Warning, check,
    consistency,
};

use islands::{inverted_and_unenclosed, judge};
use rfta_repair::{
    Among, CUT_GAP, Island, clear_spheres, cut_sub_cell_handles, dent_wrong_side,
    push_out_of_spheres, remove_islands, to_genus,
};
pub(crate) use simplify::simplify;

/// Vertices inside a sphere by more than this many sample spacings move out of it: a fifth of the
/// margin at which the consistency check ([`crate::consistency`]) counts a sphere as entered, and
/// large enough that the sphere tree prunes the many spheres the surface merely touches.
pub(crate) const PUSH_DEPTH: f64 = 0.02;

/// [`clear_spheres`](rfta_repair::clear_spheres) looks at spheres smaller than this many owner
/// radii (`rfta::Params::owner_band` spacings on grids). A wider sphere tangent at the same point
/// along the same normal enters a bulge at most by a few hundredths of a spacing more (a bulge `w`
/// wide enters a sphere of radius `t` by about its height less `w^2 / 2t`): below the margin at
/// which the consistency check ([`crate::consistency`]) counts an entry, where the many far
/// spheres' queries would cost most (nine in ten of the 129^3 bunny's samples). Where a wider
/// sphere is entered after all (thingi54725 at 257^3: 42 of 10 to 18 spacings, along an edge),
/// the verdict's check finds it and clears it ([`clear_entered`]).
pub(crate) const CLEAR_BELOW: f64 = 3.0;

/// The last solve on the final points (every sample a side point): its mesh at the working
/// scale, and the counts of the spheres that own no point.
pub(crate) fn final_solve(
    plan: &Plan<'_>,
    cloud: &TangentPoints,
    journal: &mut Journal,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<(TriMesh, FinalSolveReport)> {
    progress(Stage::Final);
    solve_with(plan, cloud, &[], journal)
}

/// The repair of the final solve's mesh ([`repair_once`]); then, unless
/// [`crate::Params::keep_cavities`], the cavities the samples leave open opened
/// ([`open_cavities`]), whose re-solve replaces `final_solve`'s side errors when its surface is
/// kept.
pub(crate) fn repair(
    plan: &Plan<'_>,
    cloud: &TangentPoints,
    mesh: TriMesh,
    final_solve: &mut FinalSolveReport,
    journal: &mut Journal,
) -> Result<(TriMesh, RepairReport)> {
    let (mut mesh, mut repair) = repair_once(plan, mesh, final_solve.finest_cell, journal);
    if !plan.params.keep_cavities
        && repair.cavities > 0
        && let Some(grid) = plan.samples.as_grid()
    {
        let t = Instant::now();
        let opened = open_cavities(plan, grid, cloud, mesh, repair)?;
        (mesh, repair) = (opened.mesh, opened.repair);
        if let Some(side_errors) = opened.side_errors {
            final_solve.side_errors = side_errors;
        }
        journal.timed(Step::Cavities, t);
    }
    Ok((mesh, repair))
}

/// The final screened Poisson solve (every sample a side point, [`UnitBox::sides`], and
/// `extra` ones), its mesh in the samples' coordinates, and the counts of the spheres that own
/// no point.
fn solve_with(
    plan: &Plan<'_>,
    cloud: &TangentPoints,
    extra: &[rfta_spsr::SidePoint],
    journal: &mut Journal,
) -> Result<(TriMesh, FinalSolveReport)> {
    let unit = &plan.unit;
    let mut report = FinalSolveReport::default();
    crate::pool::waiters_back();
    let t = Instant::now();
    let sides = unit.sides(extra);
    let solved = crate::rounds::solve(cloud, &sides, &plan.final_spsr)?;
    report.side_errors = solved.report.side_errors;
    report.finest_cell = unit.to_input_length(solved.report.finest_cell);
    let mut mesh = solved.mesh;
    journal.timed(Step::FinalSolve, t);
    let n = unit.len();
    let mut owners = cloud.owners.clone();
    owners.dedup();
    report.far_spheres = plan.far_spheres;
    report.spheres_without_point = n.saturating_sub(owners.len() + report.far_spheres);
    mesh.map_vertices(|v| unit.to_input(v));
    Ok((mesh, report))
}

/// Re-solves at most to open the cavities the samples leave open ([`open_cavities`]).
pub(crate) const CAVITY_PASSES: usize = 2;

/// What [`open_cavities`] leaves.
struct Opened {
    mesh: TriMesh,
    repair: RepairReport,
    /// The final solve's side errors when its surface was replaced.
    side_errors: Option<Vec<usize>>,
}

/// Re-solves while the repaired mesh has cavities the samples leave open
/// ([`rfta_repair::cavity_openings`]: outside samples in a cavity next to outside samples beyond
/// the surface on the grid), with a point in each such gap kept outside, and repairs again; a
/// result is kept when it has fewer cavities, at most [`CAVITY_PASSES`] times.
fn open_cavities(
    plan: &Plan<'_>,
    grid: &rfta_geom::Grid,
    cloud: &TangentPoints,
    mesh: TriMesh,
    repair_report: RepairReport,
) -> Result<Opened> {
    let unit = &plan.unit;
    let mut best = Opened {
        mesh,
        repair: repair_report,
        side_errors: None,
    };
    let found = best.repair.cavities;
    let mut extra: Vec<rfta_spsr::SidePoint> = Vec::new();
    for _ in 0..CAVITY_PASSES {
        let openings = rfta_repair::cavity_openings(&best.mesh, &unit.sphere_set(), grid);
        if openings.points.is_empty() {
            break;
        }
        extra.extend(
            openings
                .points
                .iter()
                .map(|&position| rfta_spsr::SidePoint {
                    position,
                    inside: false,
                }),
        );
        // The re-solve's and the repair's own steps are timed together as one.
        let mut scratch = Journal::default();
        let (mesh, solve) = solve_with(plan, cloud, &extra, &mut scratch)?;
        let (mesh, repair) = repair_once(plan, mesh, solve.finest_cell, &mut scratch);
        if repair.cavities >= best.repair.cavities {
            break;
        }
        best = Opened {
            mesh,
            repair,
            side_errors: Some(solve.side_errors),
        };
        if best.repair.cavities == 0 {
            break;
        }
    }
    if best.repair.cavities > 0 {
        tunnel(&plan.samples, grid, unit, &mut best);
    }
    best.repair.cavities_opened = found - best.repair.cavities;
    Ok(best)
}

/// The cavities the re-solves closed again, joined to the surface beyond them by a tube through the
/// wall along a grid edge of [`rfta_repair::cavity_openings`] ([`rfta_repair::tunnel_cavities`]),
/// kept only if the mesh stays closed and manifold and puts no more samples on the wrong side nor
/// enters more spheres.
fn tunnel(samples: &SdfSamples, grid: &rfta_geom::Grid, unit: &UnitBox, best: &mut Opened) {
    let openings = rfta_repair::cavity_openings(&best.mesh, &unit.sphere_set(), grid);
    let paths: Vec<_> = openings
        .edges
        .iter()
        .map(|&[i, j]| [grid.position(i), grid.position(j)])
        .collect();
    let mut mesh = best.mesh.clone();
    if rfta_repair::tunnel_cavities(&mut mesh, &paths) == 0 {
        return;
    }
    let topology = rfta_mesh::Topology::of(&mesh);
    if !(topology.is_watertight() && topology.is_manifold() && topology.is_consistently_oriented())
    {
        return;
    }
    let clamp = unit
        .clamp
        .is_finite()
        .then(|| unit.to_input_length(unit.clamp));
    let (Ok(before), Ok(after)) = (
        consistency::measure(samples, &best.mesh, clamp),
        consistency::measure(samples, &mesh, clamp),
    ) else {
        return;
    };
    if after.sign_errors > before.sign_errors || after.entered > before.entered {
        return;
    }
    best.repair.cavities = rfta_mesh::cavities(&mesh).len();
    best.mesh = mesh;
}

/// The components the samples contradict or do not witness removed (`rfta_repair::remove_islands`
/// with the verdicts of `islands.rs`): the mesh left, and how many were removed as small islands
/// and as unsupported.
fn components(plan: &Plan<'_>, mesh: TriMesh, journal: &mut Journal) -> (TriMesh, [usize; 2]) {
    let (unit, params) = (&plan.unit, &plan.params);
    crate::pool::waiters_back();
    let t = Instant::now();
    // The largest component in the unit box, the whole mesh and the spheres' blocks, indexed on
    // first use.
    let (main, whole, blocks) = (OnceLock::new(), OnceLock::new(), OnceLock::new());
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
            let blocks = blocks.get_or_init(|| reach::Reach::new(unit));
            judge(unit, params, blocks, main.as_ref(), &mesh, faces, bounds)
        },
    );
    journal.timed(Step::Components, t);
    (
        kept,
        [
            removed[Island::Small as usize],
            removed[Island::Unsupported as usize],
        ],
    )
}

/// An adaptive guide pass's surface: the final solve on the rounds' points with the components
/// the samples contradict removed; no sphere cleared, no cavity opened, no verdict. It only says
/// where the next samples are asked for.
pub(crate) fn guide(
    plan: &Plan<'_>,
    cloud: &TangentPoints,
    journal: &mut Journal,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<TriMesh> {
    let (mesh, _) = final_solve(plan, cloud, journal, progress)?;
    Ok(components(plan, mesh, journal).0)
}

/// Repair: components the samples contradict or do not witness removed, the handles narrower
/// than the solve's finest cells (`cell`, input coordinates) cut, samples near the surface on the
/// wrong side dented past, vertices inside near sample spheres pushed out and
/// every sphere up to [`CLEAR_BELOW`] owner radii cleared, dents again, a known genus reached,
/// the cavities counted.
fn repair_once(
    plan: &Plan<'_>,
    mut mesh: TriMesh,
    cell: f64,
    journal: &mut Journal,
) -> (TriMesh, RepairReport) {
    let (samples, unit, params) = (&*plan.samples, &plan.unit, &plan.params);
    let mut report = RepairReport::default();
    (mesh, [report.islands_removed, report.unsupported_removed]) = components(plan, mesh, journal);
    // Before the clearing, which then clears what the caps enter.
    let t = Instant::now();
    report.sub_cell_handles_cut = cut_sub_cell_handles(
        &mut mesh,
        cell,
        crate::SUB_CELL_LOOP,
        CUT_GAP * samples.spacing(),
        consistency::THIN_LOOP_MAX_GENUS,
    );
    // Handles thinner than a spacing that no sample confirms (grids; an adaptive run asks its
    // function instead), also before the clearing.
    let h = samples.spacing();
    if !params.keep_thin_handles && samples.as_grid().is_some() {
        let thin = consistency::THIN_LOOP * h;
        if let Ok(s) = handles::settle(&mut mesh, samples, thin, CUT_GAP * h, None) {
            report.thin_handles_cut = s.cut.len();
            report.thin_handle_loops = s.cut.iter().map(|l| l / h).collect();
        }
        if !report.thin_handle_loops.is_empty() {
            journal.warnings.push(Warning::ThinHandlesCut {
                loops: report.thin_handle_loops.clone(),
            });
        }
    }
    let mut topology = t.elapsed();
    crate::pool::waiters_back();
    let t = Instant::now();
    // First radially out of the spheres that own points (near the surface and small, so the
    // tree prunes well), then out of every sphere up to CLEAR_BELOW owner radii, along the normal
    // where that is shorter, with faces split where they cut a sphere no vertex is in.
    let r_own = plan.owner_radius;
    let near: Vec<u32> = (0..unit.len() as u32)
        .filter(|&i| unit.radius(i as usize) < r_own)
        .collect();
    let near = SphereTree::with_indices(unit, &near);
    // A level set's surface onto its interpolant's zero set, before the dents (which then dent
    // past any sample the move left on the wrong side).
    if plan.field.read_as == crate::Reading::LevelSet {
        crate::field::vertices_onto_zero_set(&mut mesh, samples);
    }
    // Dents before clearing the spheres (which can then clear what a dent's faces enter) and
    // after it (for the samples a move out of a sphere left on the wrong side).
    report.dents = dent_wrong_side(&mut mesh, samples, h, consistency::SIGN_MARGIN);
    let before = mesh.vertices.clone();
    // A level set's values are not distances: its spheres guarantee no empty space.
    if plan.field.read_as.spheres_bind() {
        let spheres = unit.sphere_set();
        push_out_of_spheres(&mut mesh, &spheres, &near, PUSH_DEPTH * unit.spacing());
        report.vertices_added = clear_spheres(
            &mut mesh,
            &spheres,
            Among::SmallerThan(CLEAR_BELOW * r_own),
            PUSH_DEPTH * unit.spacing(),
        );
    }
    report.vertices_pushed_out = before
        .iter()
        .zip(&mesh.vertices)
        .filter(|(a, b)| a != b)
        .count()
        + report.vertices_added;
    report.dents += dent_wrong_side(&mut mesh, samples, h, consistency::SIGN_MARGIN);
    journal.timed(Step::SpheresCleared, t);
    if let Some(genus) = params.genus {
        let t = Instant::now();
        (report.components_joined, report.handles_cut) = to_genus(
            &mut mesh,
            genus,
            h,
            consistency::THIN_LOOP,
            consistency::THIN_LOOP_MAX_GENUS,
        );
        topology += t.elapsed();
    }
    journal.took(Step::Topology, topology);
    report.cavities = rfta_mesh::cavities(&mesh).len();
    (mesh, report)
}

/// The verdict on the output mesh ([`measure`]) completes `report` with it and the journal's
/// warnings and timings; the mesh and the points in the caller's coordinates.
pub(crate) fn verdict(
    plan: &Plan<'_>,
    mesh: TriMesh,
    cloud: TangentPoints,
    mut report: Report,
    mut journal: Journal,
) -> Result<Reconstruction> {
    let (mesh, checked, consistency) = measure(plan, mesh, &mut report, &mut journal)?;
    (report.mesh, report.consistency) = (checked, consistency);
    report.warnings = journal.warnings;
    report.timings = journal.timings;
    Ok(plan.to_caller(Reconstruction {
        mesh,
        points: plan.unit.points_to_input(cloud),
        report,
    }))
}

/// The output mesh, read with the stages' reports: measured against every sample
/// ([`consistency::measure_with`]; the spheres it enters cleared, [`clear_entered`]) and checked
/// ([`check::mesh`]), and a warning for each thing the caller should know.
fn measure(
    plan: &Plan<'_>,
    mut mesh: TriMesh,
    report: &mut Report,
    journal: &mut Journal,
) -> Result<(TriMesh, MeshCheck, Consistency)> {
    let (samples, params) = (&*plan.samples, &plan.params);
    crate::pool::waiters_back();
    let t = Instant::now();
    let mut topology = rfta_mesh::Topology::of(&mesh);
    let (mut c, entered) =
        consistency::measure_with(samples, &mesh, &topology, report.input.clamp)?;
    let reading = plan.field.read_as;
    if !entered.is_empty() && reading.spheres_bind() {
        (mesh, topology, c) = clear_entered(plan, (mesh, topology, c), entered, report)?;
    }
    let checked = check::mesh(&mesh, &topology)?;
    journal.timed(Step::Consistency, t);
    let n = samples.len();
    if let Some(genus) = params.genus {
        match topology.genus() {
            Some(g) if g < genus as i64 => journal.warnings.push(Warning::GenusBelow {
                genus: g,
                asked: genus,
            }),
            Some(g) if g > genus as i64 => journal.warnings.push(Warning::GenusAbove {
                genus: g,
                asked: genus,
            }),
            _ => {}
        }
    }
    // A level set's values are not distances: a sphere the surface enters is no disagreement,
    // nor is a sphere without a point (nor for bounds, whose spheres others may cover).
    let disagrees = if !reading.spheres_bind() {
        c.sign_errors > 0
    } else {
        !c.is_consistent()
    };
    if disagrees {
        journal.warnings.push(Warning::Disagrees {
            wrong_side: c.sign_errors,
            entered: c.entered,
            deepest: c.deepest_entry,
        });
    }
    if report.repair.cavities > 0 {
        journal.warnings.push(Warning::Cavities {
            count: report.repair.cavities,
            kept: params.keep_cavities || samples.as_grid().is_none(),
        });
    }
    if let Some(&shortest) = c.thin_loops.first() {
        journal.warnings.push(Warning::ThinHandles {
            loops: c.thin_loops.len(),
            shortest,
            kept_by_samples: !params.keep_thin_handles && samples.as_grid().is_some(),
        });
    }
    // A few spheres covered by their neighbours are normal (the reference has them too); a
    // twentieth of them means clamped, zero or inconsistent values and a less certain surface.
    let eligible = n - report.final_solve.far_spheres;
    if report.final_solve.spheres_without_point * 20 > eligible && reading.fine_tunes() {
        journal.warnings.push(Warning::SpheresWithoutPoint {
            without: report.final_solve.spheres_without_point,
            eligible,
        });
    }
    if !checked.watertight {
        journal.warnings.push(Warning::NotWatertight {
            boundary_edges: checked.boundary_edges,
            nonmanifold_edges: checked.nonmanifold_edges,
        });
    }
    if checked.zero_area_faces > 0 {
        journal.warnings.push(Warning::ZeroAreaFaces {
            faces: checked.zero_area_faces,
            degenerate: checked.degenerate_faces,
        });
    }
    Ok((mesh, checked, c))
}

/// Times [`clear_entered`] clears the spheres the check still finds entered and checks again.
const RECLEARS: usize = 2;

/// The spheres the check of the output (`checked`: the mesh, its topology and the check's counts)
/// found entered, `entered` (of any size: the repair's clearing looks only at those below
/// [`CLEAR_BELOW`] owner radii, and an edge or a corner of a thin part can bulge into wider ones),
/// cleared ([`clear_spheres`]), the samples that leaves on the wrong side dented past, and the
/// mesh checked again: kept, with its topology and counts, when it enters fewer spheres and puts
/// no more samples on the wrong side, at most [`RECLEARS`] times. The repair's counts grow by
/// what was moved, added and cleared.
fn clear_entered(
    plan: &Plan<'_>,
    checked: (TriMesh, rfta_mesh::Topology, Consistency),
    mut entered: Vec<usize>,
    report: &mut Report,
) -> Result<(TriMesh, rfta_mesh::Topology, Consistency)> {
    let (mut mesh, mut topology, mut c) = checked;
    let (samples, unit) = (&*plan.samples, &plan.unit);
    let h = samples.spacing();
    for _ in 0..RECLEARS {
        if entered.is_empty() {
            break;
        }
        let mut next = mesh.clone();
        let these: Vec<u32> = entered.iter().map(|&i| i as u32).collect();
        let added = clear_spheres(
            &mut next,
            &unit.sphere_set(),
            Among::These(&these),
            PUSH_DEPTH * unit.spacing(),
        );
        // Counted before the dents, which move vertices too.
        let moved = mesh
            .vertices
            .iter()
            .zip(&next.vertices)
            .filter(|(a, b)| a != b)
            .count();
        let dents = dent_wrong_side(&mut next, samples, h, consistency::SIGN_MARGIN);
        let next_topology = rfta_mesh::Topology::of(&next);
        let (again, still) =
            consistency::measure_with(samples, &next, &next_topology, report.input.clamp)?;
        if again.sign_errors > c.sign_errors || again.entered >= c.entered {
            break;
        }
        report.repair.vertices_pushed_out += moved + added;
        report.repair.vertices_added += added;
        report.repair.dents += dents;
        report.repair.spheres_cleared_at_check += c.entered - again.entered;
        (mesh, topology, c, entered) = (next, next_topology, again, still);
    }
    Ok((mesh, topology, c))
}
