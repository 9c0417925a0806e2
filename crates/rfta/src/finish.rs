//! Step 6: the final solve, the mesh back in the samples' coordinates, small islands removed, the
//! mesh checked and what the caller should know put in the report.

use std::sync::OnceLock;
use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::glam::DVec3;
use rfta_geom::kernels::solid_angle;
use rfta_geom::{Aabb, SdfSamples, TriMesh};
use rfta_sphere_tree::SphereTree;

use crate::normalize::UnitBox;
use crate::rounds::Rounds;
use crate::{Params, Reconstruction, Report, Result, Stage, check, consistency};

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
    let cloud = rounds.cloud;
    report.points_per_round.push(cloud.len());
    crate::pool::waiters_back();
    let t = Instant::now();
    let sides = unit.sides();
    let solved = crate::rounds::solve(&cloud, &sides, &params.spsr_params(Some(unit.spacing())))?;
    report.side_errors = solved.report.side_errors;
    let mut mesh = solved.mesh;
    report
        .timings
        .push(("final screened Poisson".into(), t.elapsed()));
    let n = unit.len();
    let mut owners = cloud.owners.clone();
    owners.dedup();
    report.far_spheres = unit.far_spheres(params);
    report.spheres_without_point = n.saturating_sub(owners.len() + report.far_spheres);
    mesh.map_vertices(|v| unit.to_input(v));
    // Every sphere's tree: the rounds' when they built one, else built on first use.
    let tree = OnceLock::new();
    if let Some(all) = rounds.all {
        let _ = tree.set(all);
    }
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
            judge(unit, params, &tree, main.as_ref(), &mesh, faces, bounds)
        },
    );
    mesh = kept;
    report.islands_removed = removed[Island::Small as usize];
    report.unsupported_removed = removed[Island::Unsupported as usize];
    report
        .timings
        .push(("components judged".into(), t.elapsed()));
    crate::pool::waiters_back();
    let t = Instant::now();
    // First radially out of the spheres that own points (near the surface and small, so the
    // tree prunes well), then out of every sphere up to CLEAR_BELOW owner radii, along the normal
    // where that is shorter, with faces split where they cut a sphere no vertex is in.
    let r_own = unit.owner_radius(params);
    let near: Vec<u32> = (0..n as u32)
        .filter(|&i| unit.spheres[i as usize].radius < r_own)
        .collect();
    let near = SphereTree::with_indices(&unit.spheres, &near);
    // Dents before clearing the spheres (which can then clear what a dent's faces enter) and
    // after it (for the samples a move out of a sphere left on the wrong side).
    report.dents = dent_wrong_side(&mut mesh, samples);
    let before = mesh.vertices.clone();
    push_out_of_spheres(&mut mesh, unit, &near, PUSH_DEPTH * unit.spacing());
    report.vertices_added = clear_spheres(
        &mut mesh,
        unit,
        CLEAR_BELOW * r_own,
        PUSH_DEPTH * unit.spacing(),
    );
    report.vertices_pushed_out = before
        .iter()
        .zip(&mesh.vertices)
        .filter(|(a, b)| a != b)
        .count()
        + report.vertices_added;
    report.dents += dent_wrong_side(&mut mesh, samples);
    report.timings.push(("spheres cleared".into(), t.elapsed()));
    if let Some(genus) = params.genus {
        let t = Instant::now();
        (report.components_joined, report.handles_cut) =
            to_genus(&mut mesh, genus, consistency::spacing(samples));
        report.timings.push(("topology".into(), t.elapsed()));
    }
    report.cavities = face_components(&mesh)
        .iter()
        .filter(|faces| signed_volume(&mesh, faces) < 0.0)
        .count();
    crate::pool::waiters_back();
    let t = Instant::now();
    let topology = rfta_mesh::Topology::of(&mesh);
    report.mesh = check::mesh(&mesh, &topology)?;
    report.consistency = consistency::measure_with(samples, &mesh, &topology, report.clamp)?;
    report
        .timings
        .push(("consistency check".into(), t.elapsed()));
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
    let points = TangentPoints {
        points: cloud.points.iter().map(|&p| unit.to_input(p)).collect(),
        normals: cloud.normals,
        owners: cloud.owners,
    };
    Ok(Reconstruction {
        mesh,
        points,
        report,
    })
}

/// How far apart the two sides of a cut handle move, in sample spacings.
const CUT_GAP: f64 = 0.05;

/// [`Params::genus`]: every component joined to the largest, then the shortest loops around
/// handles cut until the genus is `genus`; loops are searched below `pi` spacings first, then
/// below twice and four times that, and so on to 64 spacings, on meshes of genus up to
/// [`consistency::THIN_LOOP_MAX_GENUS`]. Returns the components joined and the handles cut.
fn to_genus(mesh: &mut TriMesh, genus: usize, h: f64) -> (usize, usize) {
    let mut joined = 0;
    for (a, b) in nearest_faces_to_largest(mesh) {
        if rfta_mesh::join(mesh, a, b) {
            joined += 1;
        }
    }
    let mut cut = 0;
    let mut bound = consistency::THIN_LOOP;
    while bound <= 64.0 {
        let Some(excess) = rfta_mesh::Topology::of(mesh)
            .genus()
            .filter(|&g| g <= consistency::THIN_LOOP_MAX_GENUS)
            .and_then(|g| usize::try_from(g).ok())
            .and_then(|g| g.checked_sub(genus))
            .filter(|&e| e > 0)
        else {
            break;
        };
        let Some(loops) = rfta_mesh::short_loops(mesh, bound * h) else {
            break;
        };
        if loops.loops.is_empty() {
            bound *= 2.0;
            continue;
        }
        // Shortest first; loops of one basis that share no vertex are cut in one pass (disjoint
        // and independent, they do not separate the surface: each takes one handle).
        let mut touched = vec![false; mesh.vertices.len()];
        let mut this_pass = 0;
        for cycle in &loops.loops {
            if this_pass == excess {
                break;
            }
            if cycle.iter().any(|&v| touched[v as usize]) {
                continue;
            }
            if rfta_mesh::cut_along(mesh, cycle, CUT_GAP * h) {
                for &v in cycle {
                    touched[v as usize] = true;
                }
                this_pass += 1;
            }
        }
        if this_pass == 0 {
            break;
        }
        cut += this_pass;
    }
    (joined, cut)
}

/// For each component but the largest (in face order), a face of it and the face of the largest
/// nearest to it: at its vertex nearest the largest, the face whose centre is nearest the
/// largest's closest point, and the face that point lies on. Faces of different components, so
/// the joins can be made one after another ([`rfta_mesh::join`] keeps the other faces' indices).
fn nearest_faces_to_largest(mesh: &TriMesh) -> Vec<(u32, u32)> {
    let parts = face_components(mesh);
    let Some(largest) = (0..parts.len()).max_by_key(|&i| (parts[i].len(), std::cmp::Reverse(i)))
    else {
        return Vec::new();
    };
    if parts.len() < 2 {
        return Vec::new();
    }
    let main = TriMesh {
        vertices: mesh.vertices.clone(),
        faces: parts[largest].iter().map(|&f| mesh.faces[f]).collect(),
    };
    let Ok(index) = rfta_mesh::MeshIndex::new(&main) else {
        return Vec::new();
    };
    let centre = |f: u32| {
        mesh.faces[f as usize]
            .iter()
            .map(|&i| mesh.vertices[i as usize])
            .sum::<DVec3>()
            / 3.0
    };
    let mut pairs = Vec::new();
    for (k, part) in parts.iter().enumerate() {
        if k == largest {
            continue;
        }
        let mut best: Option<(u32, rfta_mesh::ClosestPoint)> = None;
        for &f in part {
            for &v in &mesh.faces[f] {
                let q = index.closest_point(mesh.vertices[v as usize]);
                if best
                    .as_ref()
                    .is_none_or(|b| q.distance_squared < b.1.distance_squared)
                {
                    best = Some((v, q));
                }
            }
        }
        let Some((v, q)) = best else { continue };
        let a = part
            .iter()
            .map(|&f| f as u32)
            .filter(|&f| mesh.faces[f as usize].contains(&v))
            .min_by(|&f, &g| {
                centre(f)
                    .distance_squared(q.point)
                    .total_cmp(&centre(g).distance_squared(q.point))
            });
        if let Some(a) = a {
            pairs.push((a, parts[largest][q.face as usize] as u32));
        }
    }
    pairs
}

/// The faces of each connected component (faces sharing a vertex), components in the order of
/// their first face.
fn face_components(mesh: &TriMesh) -> Vec<Vec<usize>> {
    let mut sets = rfta_mesh::UnionFind::new(mesh.vertices.len());
    for f in &mesh.faces {
        sets.union(f[0] as usize, f[1] as usize);
        sets.union(f[0] as usize, f[2] as usize);
    }
    let mut index_of = std::collections::HashMap::new();
    let mut parts: Vec<Vec<usize>> = Vec::new();
    for (i, f) in mesh.faces.iter().enumerate() {
        let root = sets.find(f[0] as usize);
        let k = *index_of.entry(root).or_insert_with(|| {
            parts.push(Vec::new());
            parts.len() - 1
        });
        parts[k].push(i);
    }
    parts
}

/// Samples this close to the surface (in spacings) are the ones [`dent_wrong_side`] looks at.
const DENT_BELOW: f64 = 0.5;

/// How far beyond its sphere a dent's new vertex lands, in sample spacings.
const DENT_MARGIN: f64 = 0.05;

/// A sample less than [`DENT_BELOW`] spacings from the surface, with the mesh as near, on the
/// wrong side of the mesh: a face cuts its small sphere, or passes just beyond it (the faces are
/// about a quarter of a spacing across, so no vertex need lie inside, and moving the surface
/// away from the sample would leave it on the wrong side). The mesh's point nearest the sample
/// moves through the sphere to just beyond its far side, on the line from that point through the
/// sample ([`DENT_MARGIN`] past the sphere): a new vertex there ([`Splitter::split`]: the face,
/// or both faces beside the edge, split), or the vertex itself. The sample then lies in a shallow
/// dent, on its own side. Not made where a face would turn over. Samples are taken in order, so
/// the result does not depend on the thread count. Returns how many dents were made.
fn dent_wrong_side(mesh: &mut TriMesh, samples: &SdfSamples) -> usize {
    use rayon::prelude::*;
    let h = consistency::spacing(samples);
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
            if r <= consistency::SIGN_MARGIN * h || r >= reach {
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

/// Vertices inside a sphere by more than this many sample spacings move out of it: a fifth of the
/// margin at which [`crate::consistency`] counts a sphere as entered, and large enough that the
/// sphere tree prunes the many spheres the surface merely touches.
const PUSH_DEPTH: f64 = 0.02;

/// Passes of [`push_out_of_spheres`] per vertex: leaving the deepest sphere can land a vertex in
/// a neighbour, which the next pass leaves in turn.
const PUSH_PASSES: usize = 8;

/// The surface may not enter a sample sphere (Sellán et al. 2024, §3), yet the final screened
/// Poisson surface is smooth and cuts into the spheres where the shape is not (edges, corners,
/// thin parts). Each vertex inside some sphere by more than `depth` (unit box) moves radially onto
/// the boundary of the sphere it is deepest in, up to [`PUSH_PASSES`] times; the connectivity
/// stays, and the moves are taken without folding the surface ([`apply_moves`]). The targets do
/// not depend on one another, so the result does not depend on the thread count.
fn push_out_of_spheres(mesh: &mut TriMesh, unit: &UnitBox, tree: &SphereTree, depth: f64) {
    use rayon::prelude::*;
    let moved_to: Vec<Option<DVec3>> = mesh
        .vertices
        .par_iter()
        .map_init(Vec::new, |hits, &v| {
            let mut p = unit.to_unit(v);
            let mut moved = false;
            for _ in 0..PUSH_PASSES {
                tree.spheres_containing_into(p, 1, -depth, None, hits);
                let Some(&(_, j)) = hits.first() else {
                    break;
                };
                let s = unit.spheres[j as usize];
                let dir = (p - s.center).normalize_or_zero();
                if dir == DVec3::ZERO {
                    break;
                }
                p = s.center + dir * s.radius;
                moved = true;
            }
            moved.then(|| unit.to_input(p))
        })
        .collect();
    apply_moves(mesh, &Incidence::of(mesh), &moved_to);
}

/// How many times [`apply_moves`] goes over the vertices.
const MOVE_SWEEPS: usize = 8;

/// Moves each vertex towards its `moved_to` position where it has one without folding the
/// surface: in index order, each takes the largest of its whole remaining move, half, a quarter
/// or an eighth of it that turns none of its faces over (a face's normal against the one it had),
/// given where its neighbours are by then; [`MOVE_SWEEPS`] sweeps, so that a vertex held back by
/// a neighbour (at sharp features the faces can be a fiftieth of a spacing across) follows it.
/// `incident` holds the mesh's faces around each vertex. Returns the vertices that moved.
fn apply_moves(mesh: &mut TriMesh, incident: &Incidence, moved_to: &[Option<DVec3>]) -> Vec<u32> {
    let targets: Vec<(u32, DVec3)> = (0..mesh.vertices.len() as u32)
        .filter_map(|v| moved_to[v as usize].map(|t| (v, t)))
        .collect();
    if targets.is_empty() {
        return Vec::new();
    }
    let normals: Vec<DVec3> = (0..mesh.faces.len())
        .map(|f| mesh.face_normal_scaled(f))
        .collect();
    let turned = |mesh: &TriMesh, v: u32| {
        incident
            .faces(v)
            .iter()
            .any(|&f| normals[f as usize].dot(mesh.face_normal_scaled(f as usize)) <= 0.0)
    };
    let original: Vec<DVec3> = targets
        .iter()
        .map(|&(v, _)| mesh.vertices[v as usize])
        .collect();
    let mut arrived = vec![false; targets.len()];
    for _ in 0..MOVE_SWEEPS {
        for (k, &(v, target)) in targets.iter().enumerate() {
            if arrived[k] {
                continue;
            }
            let from = mesh.vertices[v as usize];
            for fraction in [1.0, 0.5, 0.25, 0.125] {
                mesh.vertices[v as usize] = from + (target - from) * fraction;
                if !turned(mesh, v) {
                    arrived[k] = fraction == 1.0;
                    break;
                }
                mesh.vertices[v as usize] = from;
            }
        }
    }
    targets
        .iter()
        .zip(&original)
        .filter(|&(&(v, _), o)| mesh.vertices[v as usize] != *o)
        .map(|(&(v, _), _)| v)
        .collect()
}

/// Rounds of [`clear_spheres`]: each finds the spheres the mesh still enters and moves the
/// vertices inside them out.
const CLEAR_ROUNDS: usize = 6;

/// [`clear_spheres`] looks at spheres smaller than this many owner radii ([`Params::owner_band`]
/// spacings on grids). A wider sphere tangent at the same point along the same normal enters a
/// bulge at most by a few hundredths of a spacing more (a bulge `w` wide enters a sphere of
/// radius `t` by about its height less `w^2 / 2t`): below the margin at which
/// [`crate::consistency`] counts an entry, where the many far spheres' queries would cost most
/// (nine in ten of the 129^3 bunny's samples).
const CLEAR_BELOW: f64 = 3.0;

/// The farthest a vertex moves in [`clear_spheres`], in sample spacings: an entry deeper than
/// this is not a smooth surface's overshoot but a wrong part, which moving vertices would tear.
const CLEAR_REACH: f64 = 0.5;

/// The faces around each vertex of a mesh.
struct Incidence {
    /// Where each vertex's faces start in `faces` (one more entry than vertices).
    start: Vec<u32>,
    faces: Vec<u32>,
}

impl Incidence {
    fn of(mesh: &TriMesh) -> Self {
        let mut start = vec![0u32; mesh.vertices.len() + 1];
        for face in &mesh.faces {
            for &v in face {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..mesh.vertices.len() {
            start[v + 1] += start[v];
        }
        let mut at = start.clone();
        let mut faces = vec![0u32; start[mesh.vertices.len()] as usize];
        for (f, face) in mesh.faces.iter().enumerate() {
            for &v in face {
                faces[at[v as usize] as usize] = f as u32;
                at[v as usize] += 1;
            }
        }
        Self { start, faces }
    }

    fn faces(&self, v: u32) -> &[u32] {
        &self.faces[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// The mesh in the unit box.
fn in_unit_box(mesh: &TriMesh, unit: &UnitBox) -> TriMesh {
    TriMesh {
        vertices: mesh.vertices.iter().map(|&v| unit.to_unit(v)).collect(),
        faces: mesh.faces.clone(),
    }
}

/// The surface may not enter a sample sphere (Sellán et al. 2024, §3), of any size: the far
/// spheres own no tangency point, so nothing but this keeps the smooth Poisson surface out of
/// them (a bulge at a corner, where many far spheres touch the same point), and the near ones are
/// cut wherever the shape is sharper than the surface (edges, corners, thin parts).
///
/// Each round finds every sphere (of `all`) the mesh enters by more than `depth` (unit box): the
/// first round every sphere, the later ones those entered before and those holding a vertex that
/// moved. Where no vertex of the cutting face lies in the sphere, a vertex is put at the face's
/// point nearest the centre ([`split_where_entered`]). Then each vertex inside entered spheres
/// moves along its normal (inward out of positive spheres, outward out of negative ones) or
/// radially away from the deepest sphere's centre, whichever leaves all of them sooner
/// ([`leave_along`]), as long as that is within [`CLEAR_REACH`] and meets no sphere of the other
/// sign; the moves are taken without folding the surface ([`apply_moves`]). At most
/// [`CLEAR_ROUNDS`] rounds. Vertices move in index order, so the result does not depend on the
/// thread count. Returns how many vertices were added.
fn clear_spheres(mesh: &mut TriMesh, unit: &UnitBox, below: f64, depth: f64) -> usize {
    use rayon::prelude::*;
    let reach = CLEAR_REACH * unit.spacing();
    let mut added = 0;
    // The spheres entered in the last round, each with the face that came nearest its centre.
    let mut last: Vec<(u32, rfta_mesh::ClosestPoint)> = Vec::new();
    // The faces around each vertex: only splits change them.
    let mut incident = Incidence::of(mesh);
    for round in 0..CLEAR_ROUNDS {
        let part = in_unit_box(mesh, unit);
        let entry = |i: u32| {
            let s = unit.spheres[i as usize];
            let lo = s.radius - depth;
            (lo > 0.0).then_some((s.center, lo))
        };
        // The first round asks every sphere, the later ones only those entered before, around
        // where they were entered: a vertex moves by at most CLEAR_REACH.
        let found: Vec<(u32, rfta_mesh::ClosestPoint)> = if round == 0 {
            let Ok(index) = rfta_mesh::MeshIndex::new(&part) else {
                break;
            };
            (0..unit.len() as u32)
                .into_par_iter()
                .filter(|&i| unit.spheres[i as usize].radius < below)
                .filter_map(|i| {
                    let (c, lo) = entry(i)?;
                    Some((i, index.closest_point_within(c, lo * lo)?))
                })
                .collect()
        } else {
            last.par_iter()
                .filter_map(|&(i, ref seed)| {
                    let (c, lo) = entry(i)?;
                    Some((i, nearest_around(&part, &incident, seed.face, c, lo)?))
                })
                .collect()
        };
        if found.is_empty() {
            break;
        }
        let splits = split_where_entered(mesh, &part, &incident, unit, &found, depth);
        added += splits;
        let part = if splits > 0 {
            incident = Incidence::of(mesh);
            in_unit_box(mesh, unit)
        } else {
            part
        };
        let entered: Vec<u32> = found.iter().map(|&(i, _)| i).collect();
        let tree = SphereTree::with_indices(&unit.spheres, &entered);
        // The vertices inside entered spheres: each sphere's cap, grown from the face nearest
        // its centre (the face's slot holds a piece of it after a split).
        let mut inside: Vec<u32> = found
            .par_iter()
            .flat_map_iter(|&(i, ref c)| {
                let s = unit.spheres[i as usize];
                let holds =
                    |v: u32| (part.vertices[v as usize] - s.center).length() < s.radius - depth;
                let mut cap: Vec<u32> = part.faces[c.face as usize]
                    .into_iter()
                    .filter(|&v| holds(v))
                    .collect();
                let mut next = 0;
                while next < cap.len() {
                    let v = cap[next];
                    next += 1;
                    for &f in incident.faces(v) {
                        for w in part.faces[f as usize] {
                            if !cap.contains(&w) && holds(w) {
                                cap.push(w);
                            }
                        }
                    }
                }
                cap
            })
            .collect();
        inside.sort_unstable();
        inside.dedup();
        let mut moved_to: Vec<Option<DVec3>> = vec![None; part.vertices.len()];
        let targets: Vec<Option<DVec3>> = inside
            .par_iter()
            .map_init(Vec::new, |hits, &v| {
                let p = part.vertices[v as usize];
                tree.spheres_containing_into(p, usize::MAX, -depth, None, hits);
                let &(_, deepest) = hits.first()?;
                let positive = unit.values[deepest as usize] > 0.0;
                let n: DVec3 = incident
                    .faces(v)
                    .iter()
                    .map(|&f| part.face_normal_scaled(f as usize))
                    .sum();
                let along = n.normalize_or_zero() * if positive { -1.0 } else { 1.0 };
                let radial = (p - unit.spheres[deepest as usize].center).normalize_or_zero();
                let start = std::mem::take(hits);
                [along, radial]
                    .into_iter()
                    .filter(|d| *d != DVec3::ZERO)
                    .filter_map(|dir| {
                        hits.clone_from(&start);
                        leave_along(unit, &tree, p, dir, positive, depth, reach, hits)
                            .map(|t| (t, dir))
                    })
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|(t, dir)| unit.to_input(p + dir * t))
            })
            .collect();
        for (&v, t) in inside.iter().zip(targets) {
            moved_to[v as usize] = t;
        }
        let moved = apply_moves(mesh, &incident, &moved_to);
        if moved.is_empty() && splits == 0 {
            break;
        }
        last = found;
    }
    added
}

/// The nearest point to `center` of the faces of `part` within `lo` of it that connect to the
/// face `seed` or its neighbours through such faces, if there are any: where a sphere was entered
/// before a round of [`clear_spheres`], the part still inside it after the round surrounds the
/// face that was nearest its centre.
fn nearest_around(
    part: &TriMesh,
    incident: &Incidence,
    seed: u32,
    center: DVec3,
    lo: f64,
) -> Option<rfta_mesh::ClosestPoint> {
    let mut queue = vec![seed];
    let mut seen = std::collections::HashSet::from([seed]);
    let mut next = 0;
    let mut best: Option<rfta_mesh::ClosestPoint> = None;
    while next < queue.len() {
        let f = queue[next];
        next += 1;
        let [a, b, c] = part.triangle(f as usize);
        let (point, barycentric) = rfta_geom::kernels::closest_point_on_triangle(center, a, b, c);
        let d2 = (point - center).length_squared();
        if d2 < lo * lo && best.as_ref().is_none_or(|b| d2 < b.distance_squared) {
            best = Some(rfta_mesh::ClosestPoint {
                point,
                distance_squared: d2,
                face: f,
                barycentric,
            });
        }
        if d2 < lo * lo || f == seed {
            for v in part.faces[f as usize] {
                for &g in incident.faces(v) {
                    if seen.insert(g) {
                        queue.push(g);
                    }
                }
            }
        }
    }
    best
}

/// Puts new vertices on a mesh's faces or edges, each face at most once (faces a split has made
/// or changed are left alone until the next [`Splitter`]), given the faces around each vertex
/// before the first split.
struct Splitter<'a> {
    incident: &'a Incidence,
    touched: Vec<bool>,
}

impl<'a> Splitter<'a> {
    fn new(incident: &'a Incidence, mesh: &TriMesh) -> Self {
        Self {
            incident,
            touched: vec![false; mesh.faces.len()],
        }
    }

    /// Adds a vertex at `at` for the point of face `f` with barycentric coordinates `b`: the
    /// face splits in three, or, within a fiftieth of its barycentric range of an edge, it and
    /// the face beside that edge split in two each. Not made (`None`) near a vertex, where a face
    /// was split already, or where a new face would turn against the face it is part of (`at`
    /// off the face). Returns the new vertex.
    fn split(&mut self, mesh: &mut TriMesh, f: usize, b: [f64; 3], at: DVec3) -> Option<u32> {
        if self.touched.get(f).is_none_or(|&t| t) {
            return None;
        }
        let face = mesh.faces[f];
        let k = mesh.vertices.len() as u32;
        let on_edge: Vec<usize> = (0..3).filter(|&j| b[j] < 0.02).collect();
        let pieces: Vec<(Option<usize>, [u32; 3])> = match on_edge.as_slice() {
            [] => vec![
                (Some(f), [face[0], face[1], k]),
                (None, [face[1], face[2], k]),
                (None, [face[2], face[0], k]),
            ],
            &[j] => {
                // The edge opposite vertex j, u -> v in this face, v -> u in the one beside it.
                let (w, u, v) = (face[j], face[(j + 1) % 3], face[(j + 2) % 3]);
                let g = self
                    .incident
                    .faces(u)
                    .iter()
                    .map(|&g| g as usize)
                    .find(|&g| g != f && mesh.faces[g].contains(&v))?;
                if self.touched[g] {
                    return None;
                }
                let x = mesh.faces[g].into_iter().find(|&x| x != u && x != v)?;
                vec![
                    (Some(f), [u, k, w]),
                    (None, [k, v, w]),
                    (Some(g), [v, k, x]),
                    (None, [k, u, x]),
                ]
            }
            _ => return None,
        };
        // Each piece against the face it is cut from: `f` (its slot and the new face after it)
        // or the one beside the edge.
        let mut from = f;
        for &(slot, t) in &pieces {
            from = slot.unwrap_or(from);
            let [a, b, c] = t.map(|x| {
                if x == k {
                    at
                } else {
                    mesh.vertices[x as usize]
                }
            });
            if (b - a).cross(c - a).dot(mesh.face_normal_scaled(from)) <= 0.0 {
                return None;
            }
        }
        mesh.vertices.push(at);
        for (slot, piece) in pieces {
            match slot {
                Some(g) => {
                    self.touched[g] = true;
                    mesh.faces[g] = piece;
                }
                None => mesh.faces.push(piece),
            }
        }
        Some(k)
    }

    /// Moves vertex `v` to `to`, unless a face around it was split already or would turn over.
    fn move_vertex(&mut self, mesh: &mut TriMesh, v: u32, to: DVec3) -> bool {
        let around = self.incident.faces(v);
        if around.iter().any(|&f| self.touched[f as usize]) {
            return false;
        }
        let normals: Vec<DVec3> = around
            .iter()
            .map(|&f| mesh.face_normal_scaled(f as usize))
            .collect();
        let from = std::mem::replace(&mut mesh.vertices[v as usize], to);
        let turned = around
            .iter()
            .zip(&normals)
            .any(|(&f, n)| mesh.face_normal_scaled(f as usize).dot(*n) <= 0.0);
        if turned {
            mesh.vertices[v as usize] = from;
            return false;
        }
        for &f in around {
            self.touched[f as usize] = true;
        }
        true
    }
}

/// Where no vertex of the nearest face lies inside an entered sphere (`found`: the sphere and the
/// mesh's nearest point to its centre, on `part`, the mesh in the unit box, whose faces around
/// each vertex `incident` holds), a vertex is put at that nearest point ([`Splitter::split`]; the
/// new faces lie in the old ones' planes). Returns how many vertices were added.
fn split_where_entered(
    mesh: &mut TriMesh,
    part: &TriMesh,
    incident: &Incidence,
    unit: &UnitBox,
    found: &[(u32, rfta_mesh::ClosestPoint)],
    depth: f64,
) -> usize {
    let mut splitter = Splitter::new(incident, mesh);
    let mut added = 0;
    for &(i, ref c) in found {
        let f = c.face as usize;
        let s = unit.spheres[i as usize];
        // A face split in this call holds a new vertex, which `part` does not have.
        let holds = |v: u32| {
            part.vertices
                .get(v as usize)
                .is_some_and(|&p| (p - s.center).length() < s.radius - depth)
        };
        if splitter.touched[f] || mesh.faces[f].iter().any(|&v| holds(v)) {
            continue;
        }
        let at = mesh.faces[f]
            .iter()
            .zip(c.barycentric)
            .map(|(&v, b)| mesh.vertices[v as usize] * b)
            .sum();
        added += usize::from(splitter.split(mesh, f, c.barycentric, at).is_some());
    }
    added
}

/// How far along `dir` from `p` the line leaves every sphere of `tree` that holds it by more
/// than `depth` (`hits` holds those at `p`), if it does within `reach` and meets only spheres of
/// the sign `positive`.
#[allow(clippy::too_many_arguments)]
fn leave_along(
    unit: &UnitBox,
    tree: &SphereTree,
    p: DVec3,
    dir: DVec3,
    positive: bool,
    depth: f64,
    reach: f64,
    hits: &mut Vec<(f64, u32)>,
) -> Option<f64> {
    let mut t = 0.0f64;
    for _ in 0..8 {
        for &(_, j) in hits.iter() {
            if (unit.values[j as usize] > 0.0) != positive {
                return None;
            }
            let s = unit.spheres[j as usize];
            let o = p - s.center;
            let b = o.dot(dir);
            let disc = b * b - (o.length_squared() - s.radius * s.radius);
            t = t.max(-b + disc.max(0.0).sqrt());
        }
        if t > reach {
            return None;
        }
        tree.spheres_containing_into(p + dir * t, usize::MAX, -depth, None, hits);
        if hits.is_empty() {
            return Some(t);
        }
    }
    None
}

/// Why a component of the mesh goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Island {
    /// Its bounding-box diagonal is below [`Params::min_island`] spacings, it encloses no sample
    /// of the sign its orientation gives its inside, and no sample's sphere that the largest
    /// component leaves a gap at reaches it: nothing witnesses it.
    Small,
    /// The samples contradict it: every vertex lies inside a sample sphere and it encloses no
    /// sample of its inside's sign; or it faces inward with no other component around it.
    Unsupported,
}

/// The divergence theorem over some faces (`TriMesh::signed_volume` of a part): negative for a
/// closed component that faces inward, a cavity.
fn signed_volume(mesh: &TriMesh, faces: &[usize]) -> f64 {
    faces
        .iter()
        .map(|&f| {
            let [a, b, c] = mesh.triangle(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Whether the component `faces` of `mesh` faces inward (negative volume) and no other component
/// encloses it: a cavity with no solid around it, which no bounded set of samples describes. With
/// few samples away from the surface, screened Poisson can close such a shell far out in its box.
fn inverted_and_unenclosed(
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
/// `bounds`); `tree` holds every sample sphere, built on first use; `main` indexes the largest
/// component in the unit box.
fn judge(
    unit: &UnitBox,
    params: &Params,
    tree: &OnceLock<SphereTree>,
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
    let tree = tree.get_or_init(|| SphereTree::new(&unit.spheres));
    let tol = params.tolerance;
    // A closed component stands for a solid (outward) or a cavity (inward): a sample inside it
    // of that sign witnesses it, however small it is. Computed at most once.
    let mut witnessed: Option<bool> = None;
    let mut encloses_witness = || {
        *witnessed.get_or_insert_with(|| {
            unit.samples_within(bounds).into_iter().any(|i| {
                let p = unit.to_input(unit.centers[i]);
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
    // A small closed component needs a witness: a sample inside it, or some sample's sphere
    // that reaches it and no farther part of the surface: a thin part between the samples,
    // which no sample lies in, is where the spheres around it touch (without it they would have
    // gaps).
    if diag < params.min_island * h
        && !encloses_witness()
        && !closes_gap(unit, tree, main, mesh, faces, &vertices)
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
const GAP_WITNESSES: usize = 3;

/// Whether the component (`faces` of `mesh`, with its `vertices`) touches the spheres of at
/// least [`GAP_WITNESSES`] unclamped samples, its nearest point to each sample within the margins
/// of [`crate::consistency`] (entered by at most [`consistency::ENTER_MARGIN`] spacings, at most
/// [`consistency::GAP_MARGIN`] beyond), while `main` (the largest component) is farther from
/// those samples than the gap margin: without the component, they would have gaps
/// ([`crate::Consistency::gaps`]).
fn closes_gap(
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
        let (c, r) = (unit.centers[i as usize], unit.values[i as usize].abs());
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

/// Removes the connected components (by shared vertices) that `unsupported` condemns (given their
/// faces; unless it condemns all), then those other than the largest remaining (by faces) that
/// `verdict` condemns, given their faces, bounding box and the largest's faces; unused vertices
/// are dropped. Returns
/// the mesh and the number removed for each [`Island`] reason (`unsupported`: unsupported).
fn remove_islands(
    mesh: &TriMesh,
    unsupported: impl Fn(&[usize]) -> bool,
    verdict: impl Fn(&[usize], Aabb, &[usize]) -> Option<Island>,
) -> (TriMesh, [usize; 2]) {
    let n = mesh.vertices.len();
    let faces_of = face_components(mesh);
    let bounds: Vec<Aabb> = faces_of
        .iter()
        .map(|faces| {
            faces
                .iter()
                .flat_map(|&f| mesh.faces[f])
                .fold(Aabb::EMPTY, |b, v| b.grow(mesh.vertices[v as usize]))
        })
        .collect();
    let mut removed = [0usize; 2];
    if faces_of.len() < 2 {
        return (mesh.clone(), removed);
    }
    let mut out: Vec<bool> = faces_of.iter().map(|f| unsupported(f)).collect();
    if out.iter().all(|&o| o) {
        out.fill(false);
    }
    let largest = (0..faces_of.len())
        .filter(|&c| !out[c])
        .max_by_key(|&c| (faces_of[c].len(), std::cmp::Reverse(c)))
        .unwrap_or(0);
    let keep: Vec<bool> = (0..faces_of.len())
        .map(|c| {
            if out[c] {
                removed[Island::Unsupported as usize] += 1;
                return false;
            }
            if c == largest {
                return true;
            }
            match verdict(&faces_of[c], bounds[c], &faces_of[largest]) {
                Some(why) => {
                    removed[why as usize] += 1;
                    false
                }
                None => true,
            }
        })
        .collect();
    if keep.iter().all(|&k| k) {
        return (mesh.clone(), removed);
    }
    let mut remap = vec![u32::MAX; n];
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut kept = vec![false; mesh.faces.len()];
    for (c, faces) in faces_of.iter().enumerate() {
        for &f in faces {
            kept[f] = keep[c];
        }
    }
    for (f, &k) in mesh.faces.iter().zip(&kept) {
        if !k {
            continue;
        }
        let g = f.map(|v| {
            if remap[v as usize] == u32::MAX {
                remap[v as usize] = vertices.len() as u32;
                vertices.push(mesh.vertices[v as usize]);
            }
            remap[v as usize]
        });
        faces.push(g);
    }
    (TriMesh { vertices, faces }, removed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    /// Eight samples 0.2 apart, about a spacing beyond the unit sphere, with its exact distances:
    /// they set the spacing of the dent tests.
    fn far_samples() -> (Vec<DVec3>, Vec<f64>) {
        let positions: Vec<DVec3> = (0..8)
            .map(|k| {
                let bit = |j: u32| f64::from((k >> j) & 1) * 0.2;
                DVec3::new(bit(0), bit(1), 2.0 + bit(2))
            })
            .collect();
        let values = positions.iter().map(|p| p.length() - 1.0).collect();
        (positions, values)
    }

    /// The exact distance to the sphere of radius 0.5 on the 21^3 grid over [-1, 1]^3.
    fn ball_grid() -> SdfSamples {
        let grid = rfta_geom::Grid::cube(20, -1.0, 1.0).expect("grid");
        let values = (0..grid.len())
            .map(|i| grid.position(i).length() - 0.5)
            .collect();
        SdfSamples::grid(grid, values).expect("samples")
    }

    fn winding(mesh: &TriMesh, p: DVec3) -> f64 {
        rfta_mesh::MeshIndex::new(mesh)
            .expect("mesh")
            .winding_number(p)
    }

    #[test]
    fn a_dent_puts_a_sample_whose_small_sphere_a_face_cuts_on_its_side() {
        let mut mesh = shapes::icosphere(1.0, 2);
        let [a, b, c] = mesh.triangle(0);
        let n = (b - a).cross(c - a).normalize();
        let centroid = (a + b + c) / 3.0;
        // Eight far samples (0.2 apart) set the spacing; the ninth lies 0.003 inside face 0 and
        // says "outside, 0.01 from the surface": its sphere is cut by the face, no vertex in it.
        let (mut positions, mut values) = far_samples();
        let wrong = centroid - 0.003 * n;
        positions.push(wrong);
        values.push(0.01);
        // A sample on its side, equally close, changes nothing.
        let right = (a + 2.0 * b + 3.0 * c) / 6.0 + 0.003 * n;
        positions.push(right);
        values.push(0.01);
        let samples = SdfSamples::scattered(positions, values).expect("samples");
        assert!(winding(&mesh, wrong) > 0.5, "inside before");
        let faces = mesh.faces.len();
        assert_eq!(dent_wrong_side(&mut mesh, &samples), 1);
        assert_eq!(mesh.faces.len(), faces + 2);
        assert!(winding(&mesh, wrong) < 0.5, "outside after");
        assert!(winding(&mesh, right) < 0.5);
        let topology = rfta_mesh::Topology::of(&mesh);
        assert!(topology.is_watertight() && topology.is_consistently_oriented());
        // Its sphere is clear of the dent's apex.
        let apex = mesh.vertices[mesh.vertices.len() - 1];
        assert!(apex.distance(wrong) > 0.01);
    }

    /// The same where the mesh's point nearest the sample is on an edge (both faces beside it
    /// split, 2 faces more each) or a vertex (the vertex moves, no face is added); the sample
    /// ends on its side and the mesh stays closed.
    #[test]
    fn a_dent_at_an_edge_or_a_vertex_puts_the_sample_on_its_side() {
        for at_vertex in [false, true] {
            let mut mesh = shapes::icosphere(1.0, 2);
            let [a, b, _] = mesh.triangle(0);
            let on = if at_vertex { a } else { (a + b) / 2.0 };
            // Inside the sphere, 0.003 under the surface point, says "outside, 0.01 away".
            let wrong = on * (1.0 - 0.003 / on.length());
            let (mut positions, mut values) = far_samples();
            positions.push(wrong);
            values.push(0.01);
            let samples = SdfSamples::scattered(positions, values).expect("samples");
            assert!(winding(&mesh, wrong) > 0.5, "inside before");
            let (faces, vertices) = (mesh.faces.len(), mesh.vertices.len());
            assert_eq!(
                dent_wrong_side(&mut mesh, &samples),
                1,
                "vertex {at_vertex}"
            );
            let more = if at_vertex { (0, 0) } else { (2, 1) };
            assert_eq!(
                (mesh.faces.len(), mesh.vertices.len()),
                (faces + more.0, vertices + more.1)
            );
            assert!(
                winding(&mesh, wrong) < 0.5,
                "outside after (vertex {at_vertex})"
            );
            let topology = rfta_mesh::Topology::of(&mesh);
            assert!(topology.is_watertight() && topology.is_consistently_oriented());
        }
    }

    fn union(parts: &[TriMesh]) -> TriMesh {
        let mut out = TriMesh::default();
        for m in parts {
            out.append(m);
        }
        out
    }

    fn ball(c: DVec3, r: f64) -> TriMesh {
        let mut m = shapes::icosphere(r, 2);
        m.map_vertices(|v| v + c);
        m
    }

    /// A surface sunk 0.05 into the ball of radius 0.5 (grid spacing 0.1) enters the inside
    /// samples' spheres; pushed out, no vertex is deeper than the push depth in any of them (brute
    /// force), and a surface on the true sphere does not move.
    #[test]
    fn pushed_vertices_leave_every_sphere_and_others_stay() {
        let unit = UnitBox::new(&ball_grid(), None, None);
        let all: Vec<u32> = (0..unit.len() as u32).collect();
        let tree = SphereTree::with_indices(&unit.spheres, &all);
        let depth = PUSH_DEPTH * unit.spacing();
        let deepest = |mesh: &TriMesh| {
            mesh.vertices
                .iter()
                .flat_map(|&v| {
                    let p = unit.to_unit(v);
                    unit.spheres
                        .iter()
                        .map(move |s| s.radius - (p - s.center).length())
                })
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let mut sunk = shapes::icosphere(0.45, 3);
        assert!(deepest(&sunk) > 0.02, "the test surface must enter spheres");
        let before = sunk.clone();
        push_out_of_spheres(&mut sunk, &unit, &tree, depth);
        let moved = before
            .vertices
            .iter()
            .zip(&sunk.vertices)
            .filter(|(a, b)| a != b);
        assert_eq!(moved.count(), sunk.vertices.len());
        assert!(deepest(&sunk) <= depth + 1e-12, "{}", deepest(&sunk));
        // Out of the spheres is back near the true surface (within the grid's resolution).
        for v in &sunk.vertices {
            assert!((v.length() - 0.5).abs() < 0.03, "{}", v.length());
        }
        let mut exact = shapes::icosphere(0.5, 3);
        let before = exact.clone();
        push_out_of_spheres(&mut exact, &unit, &tree, depth);
        assert_eq!(exact, before);
    }

    /// The deepest entry of any face of `mesh` (samples' coordinates) into the spheres of `unit`,
    /// in sample spacings, by brute force.
    fn deepest_entry(unit: &UnitBox, mesh: &TriMesh) -> f64 {
        let part = in_unit_box(mesh, unit);
        unit.spheres
            .iter()
            .map(|s| {
                let d = (0..part.faces.len())
                    .map(|f| {
                        let [a, b, c] = part.triangle(f);
                        let (q, _) =
                            rfta_geom::kernels::closest_point_on_triangle(s.center, a, b, c);
                        (q - s.center).length()
                    })
                    .fold(f64::INFINITY, f64::min);
                (s.radius - d) / unit.spacing()
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// A coarse surface around the ball of radius 0.5 (grid spacing 0.1), a quarter spacing too
    /// large, enters the outside samples' spheres, the far ones too, and its faces (1.6 spacings
    /// across) cut small spheres with no vertex inside. Cleared, no face enters any sphere by more
    /// than the margin at which the consistency check counts an entry (brute force over every
    /// sphere and face), vertices were added where faces cut, and the mesh is still closed and
    /// oriented with the same Euler characteristic.
    #[test]
    fn cleared_spheres_are_left_by_faces_too() {
        let unit = UnitBox::new(&ball_grid(), None, None);
        let mut mesh = shapes::icosphere(0.525, 2);
        assert!(
            deepest_entry(&unit, &mesh) > 0.2,
            "{}",
            deepest_entry(&unit, &mesh)
        );
        let depth = PUSH_DEPTH * unit.spacing();
        let added = clear_spheres(&mut mesh, &unit, f64::INFINITY, depth);
        assert!(added > 0);
        let entry = deepest_entry(&unit, &mesh);
        assert!(entry < consistency::ENTER_MARGIN, "{entry}");
        let topology = rfta_mesh::Topology::of(&mesh);
        assert!(topology.is_watertight() && topology.is_manifold());
        assert!(topology.is_consistently_oriented());
        let euler = mesh.vertices.len() as i64 - (3 * mesh.faces.len() / 2) as i64
            + mesh.faces.len() as i64;
        assert_eq!(euler, 2);
        // Out of the spheres is on the true surface (within the grid's resolution).
        for v in &mesh.vertices {
            assert!((v.length() - 0.5).abs() < 0.04, "{}", v.length());
        }
    }

    #[test]
    fn components_go_by_the_verdict_and_the_largest_always_stays() {
        let main = ball(DVec3::ZERO, 1.0);
        let small = ball(DVec3::new(3.0, 0.0, 0.0), 0.01);
        let doomed = ball(DVec3::new(0.0, 3.0, 0.0), 0.3);
        let free = ball(DVec3::new(0.0, 0.0, 3.0), 0.3);
        let mesh = union(&[main.clone(), small, doomed, free.clone()]);
        let verdict = |_: &[usize], b: Aabb, _: &[usize]| {
            if (b.max - b.min).length() < 0.1 {
                Some(Island::Small)
            } else if b.contains(DVec3::new(0.0, 3.0, 0.0)) {
                Some(Island::Unsupported)
            } else {
                None
            }
        };
        let (kept, removed) = remove_islands(&mesh, |_| false, verdict);
        assert_eq!(removed, [1, 1]);
        let expect = union(&[main, free]);
        assert_eq!(kept.faces.len(), expect.faces.len());
        assert_eq!(kept.vertices.len(), expect.vertices.len());
        // What is left is the first and the last ball: near the origin or near (0, 0, 3).
        assert!(
            kept.vertices
                .iter()
                .all(|v| v.length() < 1.01 || (*v - DVec3::new(0.0, 0.0, 3.0)).length() < 0.31)
        );
        // The largest component is never judged; an empty mesh is returned as it is.
        let tiny = ball(DVec3::ZERO, 0.01);
        let (all, removed) = remove_islands(&tiny, |_| false, |_, _, _| Some(Island::Small));
        assert!(all == tiny && removed == [0, 0]);
        let (empty, removed) = remove_islands(
            &TriMesh::default(),
            |_| false,
            |_, _, _| Some(Island::Small),
        );
        assert!(empty.faces.is_empty() && removed == [0, 0]);
    }

    /// An inward-facing component goes, even the largest, unless another encloses it (a cavity);
    /// nothing goes when every component would.
    #[test]
    fn an_inverted_shell_goes_and_a_cavity_stays() {
        let inner = ball(DVec3::ZERO, 0.5);
        let mut shell = ball(DVec3::ZERO, 3.0);
        shell.flip();
        let mesh = union(&[inner.clone(), shell.clone()]);
        let (kept, removed) = remove_islands(
            &mesh,
            |faces| inverted_and_unenclosed(&mesh, faces, &OnceLock::new()),
            |_, _, _| None,
        );
        assert_eq!(removed, [0, 1]);
        assert_eq!(kept.faces.len(), inner.faces.len());
        assert!(kept.vertices.iter().all(|v| v.length() < 0.51));
        // Inside a solid ball of radius 4, the inverted shell is a cavity and stays.
        let outer = ball(DVec3::ZERO, 4.0);
        let hollow = union(&[outer, shell, inner]);
        let (kept, removed) = remove_islands(
            &hollow,
            |faces| inverted_and_unenclosed(&hollow, faces, &OnceLock::new()),
            |_, _, _| None,
        );
        assert_eq!(removed, [0, 0]);
        assert_eq!(kept.faces.len(), hollow.faces.len());
    }

    /// The verdict on a small closed component, against grids whose samples describe it or not:
    /// kept when a sample inside says so, removed when the samples say empty space (or solid).
    #[test]
    fn a_small_component_stays_only_where_the_samples_enclose_it() {
        use rfta_geom::{Grid, SdfSamples};
        let grid = Grid::cube(20, -1.0, 1.0).expect("grid");
        let samples = |f: &dyn Fn(DVec3) -> f64| {
            let values = (0..grid.len()).map(|i| f(grid.position(i))).collect();
            SdfSamples::grid(grid, values).expect("samples")
        };
        let ball_sdf = |p: DVec3| p.length() - 0.5;
        let (solid_c, cavity_c) = (DVec3::new(0.8, 0.0, 0.0), DVec3::new(0.2, 0.0, 0.0));
        let with_solid = samples(&|p| ball_sdf(p).min((p - solid_c).length() - 0.05));
        let with_cavity = samples(&|p| ball_sdf(p).max(0.05 - (p - cavity_c).length()));
        let plain = samples(&ball_sdf);
        // A small outward ball (a solid), and a small inward one (a cavity), 1.7 spacings across.
        let solid = ball(solid_c, 0.05);
        let mut cavity = ball(cavity_c, 0.05);
        cavity.flip();
        let params = Params::default();
        // The largest component: the ball of radius 0.5, in the unit box.
        let judge_on = |s: &SdfSamples, m: &TriMesh| {
            let unit = UnitBox::new(s, None, None);
            let mut main = ball(DVec3::ZERO, 0.5);
            main.map_vertices(|v| unit.to_unit(v));
            let main = rfta_mesh::MeshIndex::new(&main).expect("index");
            let faces: Vec<usize> = (0..m.faces.len()).collect();
            let bounds = Aabb::from_points(&m.vertices);
            judge(
                &unit,
                &params,
                &OnceLock::new(),
                Some(&main),
                m,
                &faces,
                bounds,
            )
        };
        assert_eq!(judge_on(&with_solid, &solid), None);
        // Without the small parts, the samples around them are large: inside their spheres.
        assert_eq!(judge_on(&plain, &solid), Some(Island::Unsupported));
        assert_eq!(judge_on(&with_cavity, &cavity), None);
        assert_eq!(judge_on(&plain, &cavity), Some(Island::Unsupported));
        // A cavity (or solid) a fifth the size of the sample's sphere, around the sample: inside
        // that sphere, but the sample says it is there, so it stays (the clearing widens it); the
        // same cavity beside the sample, around none, goes.
        let mut small_cavity = ball(cavity_c, 0.01);
        small_cavity.flip();
        assert_eq!(judge_on(&with_cavity, &small_cavity), None);
        assert_eq!(judge_on(&with_solid, &ball(solid_c, 0.01)), None);
        let mut beside = ball(cavity_c + DVec3::new(0.03, 0.0, 0.0), 0.01);
        beside.flip();
        assert_eq!(judge_on(&with_cavity, &beside), Some(Island::Unsupported));
        // Size alone removes nothing: a ball a fifth of a spacing across, exactly where a
        // negative sample says there is one, stays; a ball as small that straddles the big ball's
        // surface around no sample goes.
        let tiny = samples(&|p| ball_sdf(p).min((p - solid_c).length() - 0.01));
        assert_eq!(judge_on(&tiny, &ball(solid_c, 0.01)), None);
        assert_eq!(
            judge_on(&tiny, &ball(DVec3::new(0.5, 0.05, 0.05), 0.01)),
            Some(Island::Small)
        );
        // A thin part between the samples, no sample inside it (the nearest is 0.087 from its
        // centre): the samples around it touch it and are far from the big ball, so it stays.
        // A ball as large where the samples see nothing but the big ball is inside their spheres.
        let thin_c = DVec3::new(0.75, 0.05, 0.05);
        let thin = samples(&|p| ball_sdf(p).min((p - thin_c).length() - 0.03));
        assert_eq!(judge_on(&thin, &ball(thin_c, 0.03)), None);
        assert_eq!(
            judge_on(&plain, &ball(thin_c, 0.03)),
            Some(Island::Unsupported)
        );
        // Half a spacing off the thin part, the samples' spheres reach it no more.
        assert_eq!(
            judge_on(&thin, &ball(thin_c + DVec3::new(0.0, -0.3, 0.0), 0.03)),
            Some(Island::Unsupported)
        );
    }
}
