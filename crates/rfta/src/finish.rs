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
    let t = Instant::now();
    // The spheres that own points: near the surface and small, so the tree prunes well. The far
    // ones are large and tangent to the same surface, which no bound can rule out cheaply; a
    // smooth surface that enters one of them usually enters the near spheres between it and the
    // surface as well.
    let r_own = unit.owner_radius(params);
    let near: Vec<u32> = (0..n as u32)
        .filter(|&i| unit.spheres[i as usize].radius < r_own)
        .collect();
    let near = SphereTree::with_indices(&unit.spheres, &near);
    report.vertices_pushed_out =
        push_out_of_spheres(&mut mesh, unit, &near, PUSH_DEPTH * unit.spacing());
    report.dents = dent_wrong_side(&mut mesh, samples);
    report.timings.push(("spheres cleared".into(), t.elapsed()));
    let t = Instant::now();
    let topology = rfta_mesh::Topology::of(&mesh);
    report.mesh = check::mesh(&mesh, &topology)?;
    report.consistency = consistency::measure_with(samples, &mesh, &topology, report.clamp)?;
    report
        .timings
        .push(("consistency check".into(), t.elapsed()));
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

/// Samples this close to the surface (in spacings) are the ones [`dent_wrong_side`] looks at.
const DENT_BELOW: f64 = 0.5;

/// How far beyond its sphere a dent's new vertex lands, in sample spacings.
const DENT_MARGIN: f64 = 0.05;

/// A small sphere (the sample less than [`DENT_BELOW`] spacings from the surface) that a face
/// cuts with the sample on the wrong side of the mesh: no vertex need lie inside it (the faces
/// are about a quarter of a spacing across), so [`push_out_of_spheres`] cannot clear it, and
/// moving the surface away from the sample would leave it on the wrong side. The face is split
/// at its point nearest the sample, and the new vertex moves through the sphere to just beyond
/// its far side (along the face normal, [`DENT_MARGIN`] past it): the sample then lies in a
/// shallow dent, on its own side. A split whose new faces would turn over, or of a face nearer
/// an edge than a fiftieth of its barycentric range, is not made; a face split once is left to
/// the next sample. Samples are taken in order, so the result does not depend on the thread
/// count. Returns how many dents were made.
fn dent_wrong_side(mesh: &mut TriMesh, samples: &SdfSamples) -> usize {
    use rayon::prelude::*;
    let h = consistency::spacing(samples);
    let Ok(index) = rfta_mesh::MeshIndex::new(mesh) else {
        return 0;
    };
    let values = samples.values();
    let wrong: Vec<(usize, u32)> = (0..values.len())
        .into_par_iter()
        .filter_map(|i| {
            let (p, s) = (samples.position(i), values[i]);
            let r = s.abs();
            if r <= consistency::SIGN_MARGIN * h || r >= DENT_BELOW * h {
                return None;
            }
            let c = index.closest_point_within(p, r * r)?;
            let inside = index.winding_number(p) > 0.5;
            (inside != (s < 0.0) && c.barycentric.iter().all(|&b| b > 0.02)).then_some((i, c.face))
        })
        .collect();
    let mut touched = vec![false; mesh.faces.len()];
    let mut dents = 0;
    for (i, f) in wrong {
        let f = f as usize;
        if touched[f] {
            continue;
        }
        touched[f] = true;
        let (p, s) = (samples.position(i), values[i]);
        let n = mesh.face_normal_scaled(f).normalize_or_zero();
        if n == DVec3::ZERO {
            continue;
        }
        // Outside (s > 0): the surface passes behind the sample, against the outward normal.
        let apex = p - s.signum() * (s.abs() + DENT_MARGIN * h) * n;
        let [a, b, c] = mesh.faces[f];
        let k = mesh.vertices.len() as u32;
        let split = [[a, b, k], [b, c, k], [c, a, k]];
        let turned = split.iter().any(|&[u, v, _]| {
            let [u, v] = [u, v].map(|x| mesh.vertices[x as usize]);
            (v - u).cross(apex - u).dot(n) <= 0.0
        });
        if turned {
            continue;
        }
        mesh.vertices.push(apex);
        mesh.faces[f] = split[0];
        mesh.faces.extend_from_slice(&split[1..]);
        dents += 1;
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
/// stays, and a move that would turn a face over is undone. Each vertex moves on its own, so the
/// result does not depend on the thread count. Returns how many vertices moved.
fn push_out_of_spheres(mesh: &mut TriMesh, unit: &UnitBox, tree: &SphereTree, depth: f64) -> usize {
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
    // Moving a vertex must not fold the surface: where a face turns over (its normal against the
    // one it had), its moved vertices go back, until no face is turned.
    let original = mesh.vertices.clone();
    let normals: Vec<DVec3> = (0..mesh.faces.len())
        .map(|f| mesh.face_normal_scaled(f))
        .collect();
    let mut moved: Vec<bool> = moved_to.iter().map(Option::is_some).collect();
    for (v, m) in mesh.vertices.iter_mut().zip(&moved_to) {
        if let Some(p) = m {
            *v = *p;
        }
    }
    loop {
        let turned: Vec<usize> = (0..mesh.faces.len())
            .filter(|&f| {
                mesh.faces[f].iter().any(|&v| moved[v as usize])
                    && normals[f].dot(mesh.face_normal_scaled(f)) <= 0.0
            })
            .collect();
        if turned.is_empty() {
            break;
        }
        for f in turned {
            for v in mesh.faces[f] {
                let v = v as usize;
                if moved[v] {
                    moved[v] = false;
                    mesh.vertices[v] = original[v];
                }
            }
        }
    }
    moved.iter().filter(|&&m| m).count()
}

/// Why a component of the mesh goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Island {
    /// Its bounding-box diagonal is below [`Params::min_island`] spacings, it encloses no sample
    /// of the sign its orientation gives its inside, and no sample's sphere that the largest
    /// component leaves a gap at reaches it: nothing witnesses it.
    Small,
    /// The samples contradict it: every vertex lies inside a sample sphere; or it faces inward
    /// with no other component around it.
    Unsupported,
}

/// Whether the component `faces` of `mesh` faces inward (negative volume) and no other component
/// encloses it: a cavity with no solid around it, which no bounded set of samples describes. With
/// few samples away from the surface, screened Poisson can close such a shell far out in its box.
fn inverted_and_unenclosed(
    mesh: &TriMesh,
    faces: &[usize],
    whole: &OnceLock<Option<rfta_mesh::MeshIndex>>,
) -> bool {
    // The divergence theorem over the component's faces (`TriMesh::signed_volume` of a part).
    let volume: f64 = faces
        .iter()
        .map(|&f| {
            let [a, b, c] = mesh.triangle(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    if volume >= 0.0 {
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
    if vertices
        .par_iter()
        .all(|&v| tree.inside_any(unit.to_unit(mesh.vertices[v as usize]), -tol, None))
    {
        return Some(Island::Unsupported);
    }
    // A small closed component stands for a solid (outward) or a cavity (inward): some sample
    // inside it must say so, however small it is, or some sample's sphere must reach it and no
    // farther part of the surface: a thin part between the samples, which no sample lies in,
    // is where the spheres around it touch (without it they would have gaps).
    if diag < params.min_island * h {
        let inside = unit.samples_within(bounds).into_iter().any(|i| {
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
        });
        // The cheap witness first: a few samples in the box.
        if !inside && !closes_gap(unit, tree, main, mesh, faces, &vertices) {
            return Some(Island::Small);
        }
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
    use rfta_geom::shapes;

    #[test]
    fn a_dent_puts_a_sample_whose_small_sphere_a_face_cuts_on_its_side() {
        let mut mesh = shapes::icosphere(1.0, 2);
        let [a, b, c] = mesh.triangle(0);
        let n = (b - a).cross(c - a).normalize();
        let centroid = (a + b + c) / 3.0;
        // Eight far samples (0.2 apart) set the spacing; the ninth lies 0.003 inside face 0 and
        // says "outside, 0.01 from the surface": its sphere is cut by the face, no vertex in it.
        let mut positions: Vec<DVec3> = (0..8)
            .map(|k| {
                let bit = |j: u32| f64::from((k >> j) & 1) * 0.2;
                DVec3::new(bit(0), bit(1), 2.0 + bit(2))
            })
            .collect();
        let mut values: Vec<f64> = positions.iter().map(|p| p.length() - 1.0).collect();
        let wrong = centroid - 0.003 * n;
        positions.push(wrong);
        values.push(0.01);
        // A sample on its side, equally close, changes nothing.
        let right = (a + 2.0 * b + 3.0 * c) / 6.0 + 0.003 * n;
        positions.push(right);
        values.push(0.01);
        let samples = SdfSamples::scattered(positions, values).expect("samples");
        let winding = |m: &TriMesh, p: DVec3| {
            rfta_mesh::MeshIndex::new(m)
                .expect("mesh")
                .winding_number(p)
        };
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
        let grid = rfta_geom::Grid::cube(20, -1.0, 1.0).expect("grid");
        let values = (0..grid.len())
            .map(|i| grid.position(i).length() - 0.5)
            .collect();
        let samples = SdfSamples::grid(grid, values).expect("samples");
        let unit = UnitBox::new(&samples, None, None);
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
        let moved = push_out_of_spheres(&mut sunk, &unit, &tree, depth);
        assert_eq!(moved, sunk.vertices.len());
        assert!(deepest(&sunk) <= depth + 1e-12, "{}", deepest(&sunk));
        // Out of the spheres is back near the true surface (within the grid's resolution).
        for v in &sunk.vertices {
            assert!((v.length() - 0.5).abs() < 0.03, "{}", v.length());
        }
        let mut exact = shapes::icosphere(0.5, 3);
        let before = exact.clone();
        assert_eq!(push_out_of_spheres(&mut exact, &unit, &tree, depth), 0);
        assert_eq!(exact, before);
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
