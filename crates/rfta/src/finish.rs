//! Step 6: the final solve, the mesh back in the samples' coordinates, small islands removed, the
//! mesh checked and what the caller should know put in the report.

use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;
use rfta_sphere_tree::SphereTree;

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
    report.far_spheres = unit.far_spheres(params);
    report.spheres_without_point = n.saturating_sub(owners.len() + report.far_spheres);
    mesh.map_vertices(|v| unit.to_input(v));
    // Components that lie entirely inside sample spheres contradict the samples (the surface may
    // not enter a sphere): removed with the small ones. The tree is built only if needed.
    let all = std::sync::OnceLock::new();
    let tol = params.tolerance;
    let enclosed = |v: DVec3| {
        all.get_or_init(|| SphereTree::new(&unit.spheres))
            .inside_any(unit.to_unit(v), -tol, None)
    };
    let (kept, small, inside) =
        remove_islands(&mesh, params.min_island * unit.input_spacing, enclosed);
    mesh = kept;
    report.islands_removed = small;
    report.enclosed_removed = inside;
    report.mesh = check::mesh(&mesh)?;
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

/// Removes connected components (by shared vertices) whose bounding-box diagonal is below
/// `min_diagonal`, and those whose every vertex `enclosed` says lies inside a sample sphere,
/// unless that would remove everything; unused vertices are dropped. Returns the mesh and the
/// numbers of small and of enclosed components removed.
fn remove_islands(
    mesh: &TriMesh,
    min_diagonal: f64,
    enclosed: impl Fn(DVec3) -> bool + Sync,
) -> (TriMesh, usize, usize) {
    use rayon::prelude::*;
    if mesh.faces.is_empty() {
        return (mesh.clone(), 0, 0);
    }
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
    let roots: Vec<u32> = mesh.faces.iter().map(|f| root(&mut parent, f[0])).collect();
    let used: Vec<u32> = {
        let mut u: Vec<u32> = mesh.faces.iter().flatten().copied().collect();
        u.sort_unstable();
        u.dedup();
        u
    };
    // A component is outside every sphere somewhere unless all its vertices are enclosed. The
    // largest component (by faces) is the surface the samples describe: not tested.
    let mut faces_of = vec![0usize; n];
    for &r in &roots {
        faces_of[r as usize] += 1;
    }
    let largest = (0..n)
        .max_by_key(|&r| (faces_of[r], std::cmp::Reverse(r)))
        .unwrap_or(0);
    let mut seen_outside = vec![false; n];
    seen_outside[largest] = true;
    let tested: Vec<(u32, u32)> = used
        .iter()
        .map(|&v| (v, root(&mut parent, v)))
        .filter(|&(_, r)| r as usize != largest)
        .collect();
    let outside: Vec<bool> = tested
        .par_iter()
        .map(|&(v, _)| !enclosed(mesh.vertices[v as usize]))
        .collect();
    for (&(_, r), &o) in tested.iter().zip(&outside) {
        if o {
            seen_outside[r as usize] = true;
        }
    }
    let small = |r: u32| (hi[r as usize] - lo[r as usize]).length() < min_diagonal;
    let keep_root = |r: u32| !small(r) && seen_outside[r as usize];
    if !roots.iter().any(|&r| keep_root(r)) {
        return (mesh.clone(), 0, 0);
    }
    let mut removed_roots: Vec<u32> = roots.iter().copied().filter(|&r| !keep_root(r)).collect();
    removed_roots.sort_unstable();
    removed_roots.dedup();
    if removed_roots.is_empty() {
        return (mesh.clone(), 0, 0);
    }
    let removed_small = removed_roots.iter().filter(|&&r| small(r)).count();
    let mut remap = vec![u32::MAX; n];
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for (f, &r) in mesh.faces.iter().zip(&roots) {
        if !keep_root(r) {
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
    (
        TriMesh { vertices, faces },
        removed_small,
        removed_roots.len() - removed_small,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    fn union(parts: &[TriMesh]) -> TriMesh {
        let mut out = TriMesh::default();
        for m in parts {
            let base = out.vertices.len() as u32;
            out.vertices.extend(&m.vertices);
            out.faces
                .extend(m.faces.iter().map(|f| f.map(|v| v + base)));
        }
        out
    }

    fn ball(c: DVec3, r: f64) -> TriMesh {
        let mut m = shapes::icosphere(r, 2);
        m.map_vertices(|v| v + c);
        m
    }

    #[test]
    fn islands_go_by_size_and_by_lying_inside_sample_spheres() {
        let main = ball(DVec3::ZERO, 1.0);
        let small = ball(DVec3::new(3.0, 0.0, 0.0), 0.01);
        let enclosed = ball(DVec3::new(0.0, 3.0, 0.0), 0.3);
        let free = ball(DVec3::new(0.0, 0.0, 3.0), 0.3);
        let mesh = union(&[main.clone(), small, enclosed, free.clone()]);
        // A sample sphere of radius 0.5 around (0, 3, 0) holds the third ball entirely.
        let inside = |v: DVec3| (v - DVec3::new(0.0, 3.0, 0.0)).length() < 0.5;
        let (kept, n_small, n_inside) = remove_islands(&mesh, 0.1, inside);
        assert_eq!((n_small, n_inside), (1, 1));
        let expect = union(&[main, free]);
        assert_eq!(kept.faces.len(), expect.faces.len());
        assert_eq!(kept.vertices.len(), expect.vertices.len());
        // The largest component is never tested, and nothing is removed when all would go.
        let (all, _, _) = remove_islands(&ball(DVec3::ZERO, 0.01), 0.1, |_| true);
        assert_eq!(all.faces.len(), ball(DVec3::ZERO, 0.01).faces.len());
        let (empty, a, b) = remove_islands(&TriMesh::default(), 0.1, |_| true);
        assert!(empty.faces.is_empty() && a == 0 && b == 0);
    }
}
