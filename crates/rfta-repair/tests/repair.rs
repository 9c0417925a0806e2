//! Mesh repair on meshes and samples with known answers, without the pipeline.

use rfta_geom::glam::DVec3;
use rfta_geom::{SdfSamples, Sphere, TriMesh, shapes};
use rfta_mesh::Incidence;
use rfta_mesh::Topology;
use rfta_repair::edit::Splitter;
use rfta_repair::{
    Among, Frame, Island, Spheres, apply_moves, clear_spheres, cut_sub_cell_handles,
    dent_wrong_side, face_components, remove_islands, signed_volume, to_genus,
};

/// The spacing of the dent tests' samples, and the pipeline's margin of a reliable side.
const H: f64 = 0.2;
const SIGN_MARGIN: f64 = 0.01;

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
    assert_eq!(dent_wrong_side(&mut mesh, &samples, H, SIGN_MARGIN), 1);
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
            dent_wrong_side(&mut mesh, &samples, H, SIGN_MARGIN),
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

/// A ball of radius 1 entering an outside sample's sphere (radius 0.3, 0.2 deep) and an inside
/// one's (a sphere of radius 0.2 centred 0.1 outside the surface, 0.1 deep): cleared, no vertex
/// is inside either by more than the depth allowed, the mesh is closed, oriented, of the same
/// Euler characteristic, and vertices far from both have not moved.
#[test]
fn cleared_spheres_hold_no_vertex_and_the_rest_stays() {
    let mut mesh = shapes::icosphere(1.0, 3);
    let before = mesh.clone();
    let spheres = [
        Sphere::new(DVec3::new(1.1, 0.0, 0.0), 0.3),
        Sphere::new(DVec3::new(0.0, 0.0, -1.1), 0.2),
    ];
    let values = [0.3, -0.2];
    let set = Spheres {
        spheres: &spheres,
        values: &values,
        frame: Frame::IDENTITY,
        spacing: 1.0,
    };
    let depth = 0.001;
    clear_spheres(&mut mesh, &set, Among::SmallerThan(f64::INFINITY), depth);
    for s in &spheres {
        for v in &mesh.vertices {
            assert!(v.distance(s.center) >= s.radius - depth - 1e-9, "{v}");
        }
    }
    let (t0, t1) = (Topology::of(&before), Topology::of(&mesh));
    assert!(t1.is_watertight() && t1.is_consistently_oriented());
    assert_eq!(t0.euler_characteristic(), t1.euler_characteristic());
    for (a, b) in before.vertices.iter().zip(&mesh.vertices) {
        if spheres
            .iter()
            .all(|s| a.distance(s.center) > s.radius + 0.5)
        {
            assert_eq!(a, b);
        }
    }
}

/// Only the spheres asked for: of the same two spheres, asking for the inside sample's (and for
/// one past the set, which is ignored) clears it and leaves the outside sample's entered as deep
/// as before.
#[test]
fn clearing_these_spheres_leaves_the_others() {
    let mut mesh = shapes::icosphere(1.0, 3);
    let spheres = [
        Sphere::new(DVec3::new(1.1, 0.0, 0.0), 0.3),
        Sphere::new(DVec3::new(0.0, 0.0, -1.1), 0.2),
    ];
    let set = Spheres {
        spheres: &spheres,
        values: &[0.3, -0.2],
        frame: Frame::IDENTITY,
        spacing: 1.0,
    };
    let deepest = |mesh: &TriMesh, s: &Sphere| {
        mesh.vertices
            .iter()
            .map(|v| s.radius - v.distance(s.center))
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let before = deepest(&mesh, &spheres[0]);
    assert!(before > 0.15, "{before}");
    let depth = 0.001;
    clear_spheres(&mut mesh, &set, Among::These(&[1, 7]), depth);
    assert!(deepest(&mesh, &spheres[1]) <= depth + 1e-9);
    assert_eq!(deepest(&mesh, &spheres[0]), before);
}

/// A frame that is not the identity: the same spheres and mesh scaled by 4 and moved give the
/// same mesh, scaled and moved (up to rounding; the sphere off every symmetry of the mesh, so
/// that no two faces tie for nearest).
#[test]
fn clearing_in_a_frame_is_clearing_in_the_mesh_coordinates() {
    let spheres = [Sphere::new(DVec3::new(1.02, 0.17, -0.09), 0.3)];
    let set = Spheres {
        spheres: &spheres,
        values: &[0.3],
        frame: Frame::IDENTITY,
        spacing: 1.0,
    };
    let mut unit = shapes::icosphere(1.0, 3);
    clear_spheres(&mut unit, &set, Among::SmallerThan(f64::INFINITY), 0.001);
    let frame = Frame {
        origin: DVec3::new(0.5, -2.0, 8.0),
        scale: 4.0,
    };
    let mut moved = shapes::icosphere(1.0, 3);
    moved.map_vertices(|v| frame.to_mesh(v));
    clear_spheres(
        &mut moved,
        &Spheres { frame, ..set },
        Among::SmallerThan(f64::INFINITY),
        0.001,
    );
    assert_eq!(unit.vertices.len(), moved.vertices.len());
    assert!(unit.vertices.len() > shapes::icosphere(1.0, 3).vertices.len());
    for (a, b) in unit.vertices.iter().zip(&moved.vertices) {
        let d = (frame.to_mesh(*a) - *b).length();
        assert!(d < 1e-12, "{d}");
    }
}

/// Two balls and a small inward shell: the verdict removes the small ball, the unsupported rule
/// the shell; the largest always stays, and no vertex is left that no face uses.
#[test]
fn components_go_by_their_verdicts() {
    let mut mesh = shapes::icosphere(1.0, 2);
    let mut small = shapes::icosphere(0.1, 1);
    small.map_vertices(|v| v + DVec3::new(3.0, 0.0, 0.0));
    let mut shell = shapes::icosphere(0.2, 1);
    shell.flip();
    shell.map_vertices(|v| v + DVec3::new(-3.0, 0.0, 0.0));
    mesh.append(&small);
    mesh.append(&shell);
    assert_eq!(face_components(&mesh).len(), 3);
    let (kept, removed) = remove_islands(
        &mesh,
        |faces| signed_volume(&mesh, faces) < 0.0,
        |_, bounds, _| (bounds.max.x > 2.0).then_some(Island::Small),
    );
    assert_eq!(removed, [1, 1]);
    assert_eq!(face_components(&kept).len(), 1);
    assert_eq!(kept.unreferenced_vertices(), 0);
    assert!((kept.signed_volume() - shapes::icosphere(1.0, 2).signed_volume()).abs() < 1e-12);
    // Condemning every component condemns none.
    let (all, removed) = remove_islands(&mesh, |_| true, |_, _, _| None);
    assert_eq!((all.faces.len(), removed), (mesh.faces.len(), [0, 0]));
}

/// A torus told genus 0: its one handle is cut (both sides capped), one surface of genus 0.
#[test]
fn a_torus_told_genus_zero_loses_its_handle() {
    let mut mesh = shapes::torus(0.6, 0.1, 48, 12);
    assert_eq!(Topology::of(&mesh).genus(), Some(1));
    // Loops from pi spacings of 0.1 up: the tube's (0.63 around) is found at once.
    assert_eq!(
        to_genus(&mut mesh, 0, 0.1, std::f64::consts::PI, 256),
        (0, 1)
    );
    let t = Topology::of(&mesh);
    assert_eq!((t.genus(), t.components), (Some(0), 1));
    assert!(t.is_watertight());
}

/// Two tori 3 apart: one with a tube of radius 0.01, whose 12-gon meridian is
/// `24 * 0.01 * sin(pi / 12) = 0.0621` around, and one with a tube ten times as thick (0.621).
fn thin_and_thick_tori() -> TriMesh {
    let mut mesh = shapes::torus(0.6, 0.01, 48, 12);
    let thick = shapes::torus(0.6, 0.1, 48, 12);
    let base = mesh.vertices.len() as u32;
    mesh.vertices.extend(
        thick
            .vertices
            .iter()
            .map(|&v| v + DVec3::new(3.0, 0.0, 0.0)),
    );
    mesh.faces
        .extend(thick.faces.iter().map(|f| f.map(|i| i + base)));
    mesh
}

/// A handle whose loop is shorter than the given cells is cut; one longer is kept, as is every
/// handle when the cells are small enough.
#[test]
fn handles_narrower_than_the_cells_are_cut_and_no_other() {
    let mut mesh = thin_and_thick_tori();
    assert_eq!(Topology::of(&mesh).genus(), Some(2));
    // Two cells of 0.02: 0.04, shorter than either tube's loop.
    assert_eq!(cut_sub_cell_handles(&mut mesh, 0.02, 2.0, 0.001, 256), 0);
    assert_eq!(Topology::of(&mesh).genus(), Some(2));
    // Two cells of 0.05: 0.1, longer than the thin tube's 0.0621 only.
    assert_eq!(cut_sub_cell_handles(&mut mesh, 0.05, 2.0, 0.001, 256), 1);
    let t = Topology::of(&mesh);
    assert_eq!((t.genus(), t.components), (Some(1), 2));
    assert!(t.is_watertight());
    // The thick torus is untouched: its vertices are where they were.
    let thick = thin_and_thick_tori();
    let moved = thick
        .vertices
        .iter()
        .zip(&mesh.vertices)
        .filter(|(a, _)| a.x > 2.0)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(moved, 0);
    // Above the genus bound nothing is searched.
    let mut mesh = thin_and_thick_tori();
    assert_eq!(cut_sub_cell_handles(&mut mesh, 0.05, 2.0, 0.001, 1), 0);
}

/// A split puts one vertex in a face (three faces for one, the area kept); a move that would turn
/// a face over is taken only as far as it does not.
#[test]
fn edits_keep_the_surface() {
    let mut mesh = shapes::octahedron(1.0);
    let (area, faces) = (mesh.area(), mesh.faces.len());
    let incident = Incidence::of(&mesh);
    let mut splitter = Splitter::new(&incident, &mesh);
    let [a, b, c] = mesh.triangle(0);
    let k = splitter
        .split(&mut mesh, 0, [1.0 / 3.0; 3], (a + b + c) / 3.0)
        .expect("a split");
    assert_eq!((k as usize, mesh.faces.len()), (6, faces + 2));
    assert!((mesh.area() - area).abs() < 1e-12);
    // The same face again: left alone.
    assert!(splitter.split(&mut mesh, 0, [1.0 / 3.0; 3], a).is_none());
    // Vertex 0 of an octahedron (at +x) asked through the opposite vertex: not taken whole.
    let mut octa = shapes::octahedron(1.0);
    let target = -2.0 * octa.vertices[0];
    let mut to = vec![None; octa.vertices.len()];
    to[0] = Some(target);
    let incident = Incidence::of(&octa);
    apply_moves(&mut octa, &incident, &to);
    assert_ne!(octa.vertices[0], target);
    assert!(Topology::of(&octa).is_consistently_oriented());
    let normals_ok = (0..octa.faces.len()).all(|f| {
        let n0 = shapes::octahedron(1.0).face_normal_scaled(f);
        n0.dot(octa.face_normal_scaled(f)) > 0.0
    });
    assert!(normals_ok);
}

/// An axis-aligned box from `lo` to `hi`, outward, or inward (a cavity's wall) when `inward`.
fn boxed(lo: DVec3, hi: DVec3, inward: bool) -> TriMesh {
    let mut mesh = shapes::cuboid((hi - lo) / 2.0);
    mesh.map_vertices(|p| p + (lo + hi) / 2.0);
    if inward {
        for f in &mut mesh.faces {
            f.swap(1, 2);
        }
    }
    mesh
}

/// A grid of 10^3 points 0.1 apart from 0.05 to 0.95, each a sphere of radius 0.01 with the value
/// `value(p)` (frame = the mesh's coordinates).
fn grid_samples(value: impl Fn(DVec3) -> f64) -> (rfta_geom::Grid, Vec<Sphere>, Vec<f64>) {
    let grid =
        rfta_geom::Grid::new([10, 10, 10], DVec3::splat(0.05), DVec3::splat(0.1)).expect("grid");
    let centres: Vec<DVec3> = (0..grid.len()).map(|i| grid.position(i)).collect();
    let spheres = centres.iter().map(|&c| Sphere::new(c, 0.01)).collect();
    let values = centres.iter().map(|&c| value(c)).collect();
    (grid, spheres, values)
}

/// A solid box from 0.2 to `outer_x` along x (0.8 along y and z) with a cavity from 0.32 to 0.66
/// along x (0.68 along y and z): the samples are outside beyond the box and in the cavity, inside
/// in the walls.
fn hollow_box(outer_x: f64) -> (TriMesh, impl Fn(DVec3) -> f64) {
    let outer_hi = DVec3::new(outer_x, 0.8, 0.8);
    let (cav_lo, cav_hi) = (DVec3::splat(0.32), DVec3::new(0.66, 0.68, 0.68));
    let mut mesh = boxed(DVec3::splat(0.2), outer_hi, false);
    mesh.append(&boxed(cav_lo, cav_hi, true));
    let inside = move |p: DVec3, lo: DVec3, hi: DVec3| p.cmpgt(lo).all() && p.cmplt(hi).all();
    let value = move |p: DVec3| {
        if !inside(p, DVec3::splat(0.2), outer_hi) || inside(p, cav_lo, cav_hi) {
            0.05
        } else {
            -0.05
        }
    };
    (mesh, value)
}

/// A wall thinner than a spacing, with no sample in it, between outside samples in the cavity and
/// outside samples beyond the box: the cavity opens there, on the 4 x 4 grid edges that cross it,
/// with points in the gaps between their spheres; a wall with inside samples in it all round (a
/// hollow box) keeps its void; a mesh without a cavity has nothing to open.
#[test]
fn a_cavity_opens_through_a_wall_the_samples_leave_open_and_a_void_stays() {
    // The +x wall runs from 0.66 to 0.70, between the grid's x = 0.65 and 0.75.
    let (mesh, value) = hollow_box(0.70);
    let (grid, spheres, values) = grid_samples(value);
    let set = Spheres {
        spheres: &spheres,
        values: &values,
        frame: Frame::IDENTITY,
        spacing: 0.1,
    };
    let open = rfta_repair::cavity_openings(&mesh, &set, &grid);
    assert_eq!((open.cavities, open.sealed), (1, 0));
    assert_eq!(open.edges.len(), 16, "{:?}", open.edges);
    for &[i, j] in &open.edges {
        let (a, b) = (grid.position(i), grid.position(j));
        assert!(
            (a.x - 0.65).abs() < 1e-9 && (b.x - 0.75).abs() < 1e-9,
            "{a} {b}"
        );
        assert_eq!((a.y, a.z), (b.y, b.z));
    }
    // Three points along each gap: at a quarter, half and three quarters of the way.
    assert_eq!(open.points.len(), 16 * 3);
    // Spread over the gap between the spheres: x from 0.66 to 0.74.
    assert!(
        open.points.iter().all(|p| p.x > 0.66 && p.x < 0.74),
        "{:?}",
        open.points
    );

    // The same cavity with a wall 0.24 thick on that side, holding inside samples: a void.
    let (mesh, value) = hollow_box(0.90);
    let (grid, spheres, values) = grid_samples(value);
    let set = Spheres {
        spheres: &spheres,
        values: &values,
        ..set
    };
    let void = rfta_repair::cavity_openings(&mesh, &set, &grid);
    assert_eq!((void.cavities, void.sealed), (1, 1));
    assert!(void.edges.is_empty() && void.points.is_empty());

    let solid = boxed(DVec3::splat(0.2), DVec3::splat(0.8), false);
    let none = rfta_repair::cavity_openings(&solid, &set, &grid);
    assert_eq!(none, rfta_repair::Openings::default());
}
