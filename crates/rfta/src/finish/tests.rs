//! The final step's repair on the pipeline's unit box, and its verdicts on components, on meshes
//! and samples with known answers.

use rfta_geom::glam::DVec3;
use rfta_geom::{Aabb, shapes};

use rfta_repair::{Among, Island, clear_spheres, push_out_of_spheres, remove_islands};

use super::islands::*;
use super::reach::Reach;
use super::*;
use crate::Params;

/// The exact distance to the sphere of radius 0.5 on the 21^3 grid over [-1, 1]^3.
fn ball_grid() -> SdfSamples {
    let grid = rfta_geom::Grid::cube(20, -1.0, 1.0).expect("grid");
    let values = (0..grid.len())
        .map(|i| grid.position(i).length() - 0.5)
        .collect();
    SdfSamples::grid(grid, values).expect("samples")
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
    let tree = SphereTree::with_indices(&unit, &all);
    let depth = PUSH_DEPTH * unit.spacing();
    let deepest = |mesh: &TriMesh| {
        mesh.vertices
            .iter()
            .flat_map(|&v| {
                let p = unit.to_unit(v);
                unit.spheres()
                    .map(move |s| s.radius - (p - s.center).length())
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let mut sunk = shapes::icosphere(0.45, 3);
    assert!(deepest(&sunk) > 0.02, "the test surface must enter spheres");
    let before = sunk.clone();
    push_out_of_spheres(&mut sunk, &unit.sphere_set(), &tree, depth);
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
    push_out_of_spheres(&mut exact, &unit.sphere_set(), &tree, depth);
    assert_eq!(exact, before);
}

/// The deepest entry of any face of `mesh` (samples' coordinates) into the spheres of `unit`,
/// in sample spacings, by brute force.
fn deepest_entry(unit: &UnitBox, mesh: &TriMesh) -> f64 {
    let frame = unit.frame();
    let part = TriMesh {
        vertices: mesh.vertices.iter().map(|&v| frame.to_frame(v)).collect(),
        faces: mesh.faces.clone(),
    };
    unit.spheres()
        .map(|s| {
            let d = (0..part.faces.len())
                .map(|f| {
                    let [a, b, c] = part.triangle(f);
                    let (q, _) = rfta_geom::kernels::closest_point_on_triangle(s.center, a, b, c);
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
    let added = clear_spheres(
        &mut mesh,
        &unit.sphere_set(),
        Among::SmallerThan(f64::INFINITY),
        depth,
    );
    assert!(added > 0);
    let entry = deepest_entry(&unit, &mesh);
    assert!(entry < consistency::ENTER_MARGIN, "{entry}");
    let topology = rfta_mesh::Topology::of(&mesh);
    assert!(topology.is_watertight() && topology.is_manifold());
    assert!(topology.is_consistently_oriented());
    let euler =
        mesh.vertices.len() as i64 - (3 * mesh.faces.len() / 2) as i64 + mesh.faces.len() as i64;
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
            &Reach::new(&unit),
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
    // The same wall facing inward, a bubble no sample lies in, goes, though the same spheres
    // touch it: a cavity needs a sample inside.
    let mut bubble = ball(thin_c, 0.03);
    bubble.flip();
    assert_eq!(judge_on(&thin, &bubble), Some(Island::Small));
    assert_eq!(
        judge_on(&plain, &ball(thin_c, 0.03)),
        Some(Island::Unsupported)
    );
    // A thinner part, less than a spacing across (its box's diagonal 0.07), between the
    // samples: below what they resolve, it goes, unless thin parts are kept.
    let thinner = samples(&|p| ball_sdf(p).min((p - thin_c).length() - 0.02));
    assert_eq!(judge_on(&thinner, &ball(thin_c, 0.02)), Some(Island::Small));
    let keep = Params {
        keep_thin_handles: true,
        ..Params::default()
    };
    let unit = UnitBox::new(&thinner, None, None);
    let mut main = ball(DVec3::ZERO, 0.5);
    main.map_vertices(|v| unit.to_unit(v));
    let main = rfta_mesh::MeshIndex::new(&main).expect("index");
    let piece = ball(thin_c, 0.02);
    let faces: Vec<usize> = (0..piece.faces.len()).collect();
    let bounds = Aabb::from_points(&piece.vertices);
    assert_eq!(
        judge(
            &unit,
            &keep,
            &Reach::new(&unit),
            Some(&main),
            &piece,
            &faces,
            bounds
        ),
        None
    );
    // Half a spacing off the thin part, the samples' spheres reach it no more.
    assert_eq!(
        judge_on(&thin, &ball(thin_c + DVec3::new(0.0, -0.3, 0.0), 0.03)),
        Some(Island::Unsupported)
    );
}

/// A guide pass's ending ([`crate::Ending::Guide`]) on the ball: one closed piece within a
/// tenth of a spacing (0.1) of the sphere on average, from the final solve alone: no repair, no
/// verdict, and no time in the steps after the components. Its points (the rounds' last, in the
/// samples' coordinates) lie on their owners' spheres, and a run seeded with them on the same
/// samples keeps every one.
#[test]
fn a_guide_pass_ends_at_the_solve_with_the_components_removed() {
    let samples = ball_grid();
    let params = Params {
        rounds: Some(2),
        ..Params::default()
    };
    // The stages of an adaptive guide pass.
    let run = |seeds: Option<&TangentPoints>| {
        crate::plan::with_plan(&samples, &params, |plan, mut journal| {
            let (cloud, initial) =
                crate::initial::initial_points(&plan, seeds, &mut journal, &mut |_| {})?;
            let (cloud, _) =
                crate::rounds::fine_tune(&plan, cloud, &mut journal, &mut |_| {}, &|| Ok(()))?;
            let mesh = guide(&plan, &cloud, &mut journal, &mut |_| {})?;
            let points = plan.unit.points_to_input(cloud);
            Ok((mesh, points, initial, journal.timings))
        })
        .expect("guide")
    };
    let (mesh, points, _, timings) = run(None);
    let out = crate::Reconstruction {
        mesh,
        points,
        report: Report::default(),
    };
    let topology = rfta_mesh::Topology::of(&out.mesh);
    assert!(topology.is_watertight());
    assert_eq!(rfta_mesh::face_components(&out.mesh).len(), 1);
    let mean = out
        .mesh
        .vertices
        .iter()
        .map(|v| (v.length() - 0.5).abs())
        .sum::<f64>()
        / out.mesh.vertices.len() as f64;
    assert!(mean < 0.01, "{mean}");
    assert!(out.points.len() > 100, "{}", out.points.len());
    let positions = samples.positions();
    for (p, &o) in out.points.points.iter().zip(&out.points.owners) {
        let o = o as usize;
        let off = (*p - positions[o]).length() - samples.values()[o].abs();
        assert!(off.abs() < 1e-9, "{off}");
    }
    let (_, _, seeded, _) = run(Some(&out.points));
    assert_eq!(seeded.seeded, out.points.len());
    let steps: Vec<Step> = timings.iter().map(|&(s, _)| s).collect();
    assert!(steps.contains(&Step::FinalSolve), "{steps:?}");
    assert!(steps.contains(&Step::Components), "{steps:?}");
    for step in [Step::SpheresCleared, Step::Consistency] {
        assert!(!steps.contains(&step), "{step:?} in {steps:?}");
    }
}

/// A surface a third of a spacing too large around the ball of radius 0.5 (grid spacing 0.1)
/// enters the outside samples' spheres, the far ones wider than the repair's clearing looks at
/// (`CLEAR_BELOW` owner radii) too. The verdict's check finds them and clears them: the mesh it
/// returns enters none by the check's margin, the counts it reports are the check of that mesh,
/// and the repair's counts grew by what moved and by every sphere found entered.
#[test]
fn the_verdict_clears_the_spheres_it_finds_entered_of_any_size() {
    let samples = ball_grid();
    let mut journal = Journal::default();
    let plan = Plan::new(&samples, &Params::default(), &mut journal).expect("plan");
    let mesh = shapes::icosphere(0.53, 3);
    let marked = consistency::marked(&samples, &mesh, None).expect("marked");
    let wide = CLEAR_BELOW * plan.owner_radius;
    assert!(marked.entered.iter().any(|&i| plan.unit.radius(i) > wide));
    let found = consistency::measure(&samples, &mesh, None)
        .expect("measure")
        .entered;
    let mut report = Report::default();
    let (mesh, checked, c) = measure(&plan, mesh, &mut report, &mut journal).expect("verdict");
    assert_eq!((c.entered, c.sign_errors), (0, 0), "{c:?}");
    assert_eq!(
        c,
        consistency::measure(&samples, &mesh, None).expect("measure")
    );
    assert!(checked.watertight && checked.genus == Some(0));
    assert!(report.repair.vertices_pushed_out > 0);
    assert_eq!(report.repair.spheres_cleared_at_check, found);
}
