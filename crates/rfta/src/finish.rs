//! Step 6: the final solve, the mesh back in the samples' coordinates, small islands removed, the
//! mesh checked and what the caller should know put in the report.

use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;

use crate::normalize::UnitBox;
use crate::rounds::Rounds;
use crate::{Params, Reconstruction, Report, Result, Stage, check};

/// The last solve on the final points, and the [`Reconstruction`] in the input's coordinates.
pub(crate) fn finish(
    unit: &UnitBox,
    params: &Params,
    rounds: Rounds,
    mut report: Report,
    progress: &mut (dyn FnMut(Stage) + Send),
) -> Result<Reconstruction> {
    progress(Stage::Final);
    let cloud = rounds.cloud;
    report.points_per_round.push(cloud.len());
    let t = Instant::now();
    let mut mesh = crate::rounds::solve(&cloud, &rounds.spsr)?;
    report
        .timings
        .push(("final screened Poisson".into(), t.elapsed()));
    let n = unit.len();
    let mut owners = cloud.owners.clone();
    owners.dedup();
    report.spheres_without_point = n - owners.len();
    mesh.map_vertices(|v| unit.to_input(v));
    if params.min_island > 0.0 {
        let (kept, removed) = remove_islands(&mesh, params.min_island * unit.input_spacing);
        mesh = kept;
        report.islands_removed = removed;
    }
    report.mesh = check::mesh(&mesh)?;
    // A few spheres covered by their neighbours are normal (the reference has them too); a
    // twentieth of them means clamped, zero or inconsistent values and a less certain surface.
    if report.spheres_without_point * 20 > n {
        report.warnings.push(format!(
            "{} of {n} spheres ended without a tangency point (clamped, zero-valued, or covered by other spheres)",
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

/// Removes connected components (by shared vertices) whose bounding-box diagonal is below
/// `min_diagonal`, unless that would remove everything; unused vertices are dropped.
fn remove_islands(mesh: &TriMesh, min_diagonal: f64) -> (TriMesh, usize) {
    let n = mesh.vertices.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for f in &mesh.faces {
        let a = root(&mut parent, f[0]);
        for &v in &f[1..] {
            let b = root(&mut parent, v);
            if a != b {
                parent[b as usize] = a;
            }
        }
    }
    let mut lo = vec![DVec3::splat(f64::INFINITY); n];
    let mut hi = vec![DVec3::splat(f64::NEG_INFINITY); n];
    for f in &mesh.faces {
        let r = root(&mut parent, f[0]) as usize;
        for &v in f {
            lo[r] = lo[r].min(mesh.vertices[v as usize]);
            hi[r] = hi[r].max(mesh.vertices[v as usize]);
        }
    }
    let mut roots: Vec<u32> = mesh.faces.iter().map(|f| root(&mut parent, f[0])).collect();
    let keep_root = |r: u32| (hi[r as usize] - lo[r as usize]).length() >= min_diagonal;
    if !roots.iter().any(|&r| keep_root(r)) {
        return (mesh.clone(), 0);
    }
    let mut removed_roots: Vec<u32> = roots.iter().copied().filter(|&r| !keep_root(r)).collect();
    removed_roots.sort_unstable();
    removed_roots.dedup();
    if removed_roots.is_empty() {
        return (mesh.clone(), 0);
    }
    let mut remap = vec![u32::MAX; n];
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for (f, r) in mesh.faces.iter().zip(roots.iter_mut()) {
        if !keep_root(*r) {
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
    (TriMesh { vertices, faces }, removed_roots.len())
}
