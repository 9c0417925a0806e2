//! Step 6: the final solve, the mesh back in the samples' coordinates, small islands removed, the
//! mesh checked and what the caller should know put in the report.

use std::sync::OnceLock;
use std::time::Instant;

use rfta_feasible::TangentPoints;
use rfta_geom::kernels::solid_angle;
use rfta_geom::{Aabb, TriMesh};
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
    let mut mesh = crate::rounds::solve(&cloud, &params.spsr_params(Some(unit.spacing())))?;
    report
        .timings
        .push(("final screened Poisson".into(), t.elapsed()));
    let n = unit.len();
    let mut owners = cloud.owners.clone();
    owners.dedup();
    report.far_spheres = unit.far_spheres(params);
    report.spheres_without_point = n.saturating_sub(owners.len() + report.far_spheres);
    mesh.map_vertices(|v| unit.to_input(v));
    let tree = OnceLock::new();
    let (kept, removed) = remove_islands(&mesh, |faces, bounds| {
        judge(unit, params, &tree, &mesh, faces, bounds)
    });
    mesh = kept;
    report.islands_removed = removed[Island::Small as usize];
    report.unsupported_removed = removed[Island::Unsupported as usize];
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

/// Why a component of the mesh goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Island {
    /// Its bounding-box diagonal is below [`Params::min_island`] spacings.
    Small,
    /// The samples contradict it: every vertex lies inside a sample sphere, or it is at most
    /// [`UNSUPPORTED_BELOW`] spacings across and encloses no sample of the sign its orientation
    /// gives its inside.
    Unsupported,
}

/// Components at most this many sample spacings across must enclose a sample to stay.
const UNSUPPORTED_BELOW: f64 = 2.0;

/// The verdict on one component (`faces` of `mesh`, in the samples' coordinates, within
/// `bounds`); `tree` holds every sample sphere, built on first use.
fn judge(
    unit: &UnitBox,
    params: &Params,
    tree: &OnceLock<SphereTree>,
    mesh: &TriMesh,
    faces: &[usize],
    bounds: Aabb,
) -> Option<Island> {
    use rayon::prelude::*;
    let h = unit.input_spacing;
    let diag = (bounds.max - bounds.min).length();
    if diag < params.min_island * h {
        return Some(Island::Small);
    }
    // The surface may not enter a sample sphere: a component inside them is not there.
    let mut vertices: Vec<u32> = faces.iter().flat_map(|&f| mesh.faces[f]).collect();
    vertices.sort_unstable();
    vertices.dedup();
    let tree = tree.get_or_init(|| SphereTree::new(&unit.spheres));
    let tol = params.tolerance;
    if vertices
        .par_iter()
        .all(|&v| tree.inside_any(unit.to_unit(mesh.vertices[v as usize]), -tol, None))
    {
        return Some(Island::Unsupported);
    }
    // A small closed component stands for a solid (outward) or a cavity (inward): some sample
    // inside it must say so.
    if diag < UNSUPPORTED_BELOW * h {
        let supported = (0..unit.len()).any(|i| {
            let p = unit.to_input(unit.centers[i]);
            if !bounds.contains(p) {
                return false;
            }
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
        });
        if !supported {
            return Some(Island::Unsupported);
        }
    }
    None
}

/// Removes the connected components (by shared vertices) other than the largest (by faces) that
/// `verdict` condemns, given their faces and bounding box; unused vertices are dropped. Returns
/// the mesh and the number removed for each [`Island`] reason.
fn remove_islands(
    mesh: &TriMesh,
    verdict: impl Fn(&[usize], Aabb) -> Option<Island>,
) -> (TriMesh, [usize; 2]) {
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
    let roots: Vec<u32> = mesh.faces.iter().map(|f| root(&mut parent, f[0])).collect();
    // Faces and bounds per component, components in order of their first face.
    let mut component_of = vec![u32::MAX; n];
    let mut faces_of: Vec<Vec<usize>> = Vec::new();
    let mut bounds: Vec<Aabb> = Vec::new();
    for (f, &r) in roots.iter().enumerate() {
        if component_of[r as usize] == u32::MAX {
            component_of[r as usize] = faces_of.len() as u32;
            faces_of.push(Vec::new());
            bounds.push(Aabb::EMPTY);
        }
        let c = component_of[r as usize] as usize;
        faces_of[c].push(f);
        for &v in &mesh.faces[f] {
            bounds[c] = bounds[c].grow(mesh.vertices[v as usize]);
        }
    }
    let mut removed = [0usize; 2];
    if faces_of.len() < 2 {
        return (mesh.clone(), removed);
    }
    let largest = (0..faces_of.len())
        .max_by_key(|&c| (faces_of[c].len(), std::cmp::Reverse(c)))
        .unwrap_or(0);
    let keep: Vec<bool> = (0..faces_of.len())
        .map(|c| {
            if c == largest {
                return true;
            }
            match verdict(&faces_of[c], bounds[c]) {
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
    for (f, &r) in mesh.faces.iter().zip(&roots) {
        if !keep[component_of[r as usize] as usize] {
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
    use rfta_geom::glam::DVec3;
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
    fn components_go_by_the_verdict_and_the_largest_always_stays() {
        let main = ball(DVec3::ZERO, 1.0);
        let small = ball(DVec3::new(3.0, 0.0, 0.0), 0.01);
        let doomed = ball(DVec3::new(0.0, 3.0, 0.0), 0.3);
        let free = ball(DVec3::new(0.0, 0.0, 3.0), 0.3);
        let mesh = union(&[main.clone(), small, doomed, free.clone()]);
        let verdict = |_: &[usize], b: Aabb| {
            if (b.max - b.min).length() < 0.1 {
                Some(Island::Small)
            } else if b.contains(DVec3::new(0.0, 3.0, 0.0)) {
                Some(Island::Unsupported)
            } else {
                None
            }
        };
        let (kept, removed) = remove_islands(&mesh, verdict);
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
        let (all, removed) = remove_islands(&tiny, |_, _| Some(Island::Small));
        assert!(all == tiny && removed == [0, 0]);
        let (empty, removed) = remove_islands(&TriMesh::default(), |_, _| Some(Island::Small));
        assert!(empty.faces.is_empty() && removed == [0, 0]);
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
        let judge_on = |s: &SdfSamples, m: &TriMesh| {
            let unit = UnitBox::new(s, None);
            let faces: Vec<usize> = (0..m.faces.len()).collect();
            let bounds = Aabb::from_points(&m.vertices);
            judge(&unit, &params, &OnceLock::new(), m, &faces, bounds)
        };
        assert_eq!(judge_on(&with_solid, &solid), None);
        assert_eq!(judge_on(&plain, &solid), Some(Island::Unsupported));
        assert_eq!(judge_on(&with_cavity, &cavity), None);
        assert_eq!(judge_on(&plain, &cavity), Some(Island::Unsupported));
        // Below half a spacing across: small, whatever the samples say.
        assert_eq!(
            judge_on(&with_solid, &ball(solid_c, 0.01)),
            Some(Island::Small)
        );
    }
}
