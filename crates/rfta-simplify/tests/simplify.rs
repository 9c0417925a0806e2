//! The simplifier's promises, checked on analytic shapes and on random closed meshes: the
//! topology kept, the surface within the tolerance both ways at the vertices, no face turned
//! over, the judge obeyed, the face budget met, the same output every time.

use proptest::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{Grid, TriMesh, shapes};
use rfta_mesh::{MeshIndex, Topology};
use rfta_simplify::{Error, Options, Patch, simplify};

fn anything(_: &Patch<'_>) -> bool {
    true
}

/// Boundary, manifoldness, components and Euler characteristic.
fn shape_of(mesh: &TriMesh) -> (usize, usize, usize, i64) {
    let t = Topology::of(mesh);
    let chi = t.n_vertices as i64 - t.n_edges as i64 + t.n_faces as i64;
    (
        t.boundary_edges,
        t.nonmanifold_edges + t.nonmanifold_vertices + t.misoriented_edges,
        t.components,
        chi,
    )
}

/// The largest distance from `a`'s vertices to `b`.
fn one_way(a: &TriMesh, b: &TriMesh) -> f64 {
    let index = MeshIndex::new(b).expect("a mesh with faces");
    a.vertices
        .iter()
        .map(|&v| index.unsigned_distance(v))
        .fold(0.0, f64::max)
}

#[test]
fn a_ball_keeps_within_the_tolerance_of_the_sphere() {
    let ball = shapes::icosphere(1.0, 5);
    let tol = 0.005;
    let out = simplify(
        &ball,
        &Options {
            tolerance: tol,
            max_faces: None,
        },
        &anything,
    )
    .expect("simplified");
    let m = &out.mesh;
    assert!(
        m.n_faces() * 4 < ball.n_faces(),
        "{} of {}",
        m.n_faces(),
        ball.n_faces()
    );
    assert_eq!(shape_of(m), (0, 0, 1, 2));
    // The input's vertices lie on the unit sphere: the output's are within the tolerance of it.
    for v in &m.vertices {
        assert!((v.length() - 1.0).abs() <= tol + 1e-12, "{}", v.length());
    }
    assert!(one_way(&ball, m) <= tol + 1e-12);
    assert!(out.largest_deviation <= tol + 1e-12);
    // Faces face outward still: the volume is the ball's less the chords' caps.
    let v = m.signed_volume();
    assert!(v > 0.97 * 4.0 / 3.0 * std::f64::consts::PI && v < 4.0 / 3.0 * std::f64::consts::PI);
}

#[test]
fn a_torus_keeps_its_handle() {
    let torus = shapes::torus(1.0, 0.3, 96, 32);
    let out = simplify(
        &torus,
        &Options {
            tolerance: 0.01,
            max_faces: None,
        },
        &anything,
    )
    .expect("simplified");
    assert!(out.mesh.n_faces() * 2 < torus.n_faces());
    assert_eq!(shape_of(&out.mesh), (0, 0, 1, 0));
    for v in &out.mesh.vertices {
        let ring = (DVec3::new(v.x, v.y, 0.0).length() - 1.0).hypot(v.z);
        assert!((ring - 0.3).abs() <= 0.01 + 1e-9, "{ring}");
    }
}

#[test]
fn a_face_budget_is_met_without_a_tolerance() {
    let ball = shapes::icosphere(1.0, 4);
    let out = simplify(
        &ball,
        &Options {
            tolerance: f64::INFINITY,
            max_faces: Some(200),
        },
        &anything,
    )
    .expect("simplified");
    let n = out.mesh.n_faces();
    assert!((199..=200).contains(&n), "{n} faces");
    assert_eq!(shape_of(&out.mesh), (0, 0, 1, 2));
}

#[test]
fn a_judge_that_refuses_a_half_keeps_it() {
    let ball = shapes::icosphere(1.0, 4);
    let judge = |p: &Patch<'_>| p.before.iter().flatten().all(|c| c.x < -0.2);
    let out = simplify(
        &ball,
        &Options {
            tolerance: 0.05,
            max_faces: None,
        },
        &judge,
    )
    .expect("simplified");
    let kept = |v: &DVec3| out.mesh.vertices.contains(v);
    assert!(ball.vertices.iter().filter(|v| v.x >= -0.2).all(kept));
    assert!(out.mesh.n_faces() < ball.n_faces());
}

#[test]
fn a_boundary_stays_where_it_is() {
    // A flat square grid of 10 x 10 cells: every collapse inside it is free, its rim is locked.
    let n = 10;
    let vertices: Vec<DVec3> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| DVec3::new(i as f64, j as f64, 0.0)))
        .collect();
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let faces = (0..n)
        .flat_map(|j| {
            (0..n).flat_map(move |i| {
                [
                    [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                    [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
                ]
            })
        })
        .collect();
    let sheet = TriMesh { vertices, faces };
    let out = simplify(
        &sheet,
        &Options {
            tolerance: 0.1,
            max_faces: None,
        },
        &anything,
    )
    .expect("simplified");
    assert!(out.mesh.n_faces() < sheet.n_faces());
    let rim = sheet
        .vertices
        .iter()
        .filter(|v| v.x == 0.0 || v.y == 0.0 || v.x == n as f64 || v.y == n as f64);
    for v in rim {
        assert!(out.mesh.vertices.contains(v), "{v}");
    }
    assert_eq!(shape_of(&out.mesh).0, shape_of(&sheet).0);
}

#[test]
fn bad_options_and_meshes_are_refused() {
    let ball = shapes::icosphere(1.0, 1);
    for tol in [-1.0, f64::NAN] {
        let e = simplify(
            &ball,
            &Options {
                tolerance: tol,
                max_faces: None,
            },
            &anything,
        );
        assert!(matches!(e, Err(Error::Tolerance(_))));
    }
    let broken = TriMesh {
        vertices: ball.vertices.clone(),
        faces: vec![[0, 1, 99]],
    };
    let e = simplify(
        &broken,
        &Options {
            tolerance: 0.1,
            max_faces: None,
        },
        &anything,
    );
    assert!(matches!(e, Err(Error::Invalid(_))), "{e:?}");
    let other = MeshIndex::new(&shapes::icosphere(1.0, 2)).expect("indexed");
    let opts = Options {
        tolerance: 0.1,
        max_faces: None,
    };
    let e = rfta_simplify::simplify_indexed(&ball, &other, &opts, &anything);
    assert!(matches!(e, Err(Error::IndexOfAnotherMesh { .. })), "{e:?}");
}

/// A closed mesh of random blobs: marching cubes of the union of a few balls.
fn blobs(centres: &[(f64, f64, f64, f64)], res: usize) -> TriMesh {
    let grid = Grid::cube(res, -1.0, 1.0).expect("a grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| {
            let p = grid.position(i);
            centres
                .iter()
                .map(|&(x, y, z, r)| p.distance(DVec3::new(x, y, z)) - r)
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    rfta_mc::marching_cubes(&grid, &values, 0.0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn random_closed_meshes_keep_their_topology_and_stay_within_the_tolerance(
        centres in prop::collection::vec((-0.4..0.4f64, -0.4..0.4f64, -0.4..0.4f64, 0.15..0.45f64), 1..4),
        tol in 0.002..0.05f64,
    ) {
        let mesh = blobs(&centres, 24);
        prop_assume!(mesh.n_faces() > 0);
        let before = shape_of(&mesh);
        let out = simplify(&mesh, &Options { tolerance: tol, max_faces: None }, &anything)
            .expect("simplified");
        prop_assert_eq!(shape_of(&out.mesh), before);
        prop_assert!(one_way(&mesh, &out.mesh) <= tol + 1e-9);
        prop_assert!(one_way(&out.mesh, &mesh) <= tol + 1e-9);
        // Same input, same output.
        let again = simplify(&mesh, &Options { tolerance: tol, max_faces: None }, &anything)
            .expect("simplified");
        prop_assert_eq!(&again.mesh.faces, &out.mesh.faces);
        prop_assert_eq!(&again.mesh.vertices, &out.mesh.vertices);
    }
}

/// A closed polygon of `n` vertices on a circle of radius `r`, counter-clockwise.
fn circle(n: usize, r: f64, first: u32) -> (Vec<rfta_geom::glam::DVec2>, Vec<[u32; 2]>) {
    let vertices = (0..n)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            rfta_geom::glam::DVec2::new(r * t.cos(), r * t.sin())
        })
        .collect();
    let edges = (0..n as u32)
        .map(|i| [first + i, first + (i + 1) % n as u32])
        .collect();
    (vertices, edges)
}

fn polylines(parts: &[(usize, f64)]) -> rfta_geom::plane::Polylines {
    let (mut vertices, mut edges) = (Vec::new(), Vec::new());
    for &(n, r) in parts {
        let (v, e) = circle(n, r, vertices.len() as u32);
        vertices.extend(v);
        edges.extend(e);
    }
    rfta_geom::plane::Polylines { vertices, edges }
}

fn no_self_crossing(curve: &rfta_geom::plane::Polylines) -> bool {
    let seg = |e: [u32; 2]| (curve.vertices[e[0] as usize], curve.vertices[e[1] as usize]);
    let cross = |a: rfta_geom::glam::DVec2, b: rfta_geom::glam::DVec2, c, d| {
        let o = |p: rfta_geom::glam::DVec2,
                 q: rfta_geom::glam::DVec2,
                 r: rfta_geom::glam::DVec2| { (q - p).perp_dot(r - p) };
        o(a, b, c) * o(a, b, d) < 0.0 && o(c, d, a) * o(c, d, b) < 0.0
    };
    curve.edges.iter().enumerate().all(|(i, &e)| {
        curve.edges[i + 1..].iter().all(|&f| {
            let ((a, b), (c, d)) = (seg(e), seg(f));
            !cross(a, b, c, d)
        })
    })
}

#[test]
fn a_circle_polygon_keeps_its_chords_within_the_tolerance() {
    let curve = polylines(&[(720, 1.0)]);
    let tol = 0.001;
    let out = rfta_simplify::simplify_polylines(
        &curve,
        &Options {
            tolerance: tol,
            max_faces: None,
        },
        &|_: &rfta_simplify::Patch2| true,
    )
    .expect("simplified");
    let c = &out.curve;
    assert!(c.is_closed() && c.loops() == 1);
    assert!(c.edges.len() * 4 < 720, "{} edges", c.edges.len());
    assert_eq!(c.edges.len(), 720 - out.removals);
    for &[a, b] in &c.edges {
        let (p, q) = (c.vertices[a as usize], c.vertices[b as usize]);
        // The sagitta of the chord: how far the circle's arc is from it.
        let sagitta = 1.0 - (0.5 * (p + q)).length();
        assert!(sagitta <= tol + 1e-12, "{sagitta}");
    }
    assert!(out.largest_deviation <= tol + 1e-12);
}

#[test]
fn loops_stay_apart_and_keep_three_vertices() {
    // Two rings close together and a tiny one: a tolerance far beyond their gaps.
    let curve = polylines(&[(200, 1.0), (200, 0.95), (12, 0.01)]);
    let out = rfta_simplify::simplify_polylines(
        &curve,
        &Options {
            tolerance: 10.0,
            max_faces: None,
        },
        &|_: &rfta_simplify::Patch2| true,
    )
    .expect("simplified");
    let c = &out.curve;
    assert!(c.is_closed());
    assert_eq!(c.loops(), 3);
    assert!(c.edges.len() >= 9, "{}", c.edges.len());
    assert!(no_self_crossing(c));
}

#[test]
fn a_polyline_judge_keeps_what_it_refuses() {
    let curve = polylines(&[(360, 1.0)]);
    let judge = |p: &rfta_simplify::Patch2| p.before[1].x < 0.0;
    let out = rfta_simplify::simplify_polylines(
        &curve,
        &Options {
            tolerance: 0.01,
            max_faces: None,
        },
        &judge,
    )
    .expect("simplified");
    for v in curve.vertices.iter().filter(|v| v.x >= 0.0) {
        assert!(out.curve.vertices.contains(v), "{v}");
    }
    assert!(out.curve.edges.len() < 360);
}

/// The default tolerance: `0.8 / N` spacings for samples N spacings across, no more than 0.06
/// (coarse samples) and no less than 0.008 (fine ones).
#[test]
fn the_default_tolerance_follows_the_spacing_within_its_bounds() {
    let cases = [
        (1.0, 0.06),
        (10.0, 0.06),
        (20.0, 0.04),
        (50.0, 0.016),
        (100.0, 0.008),
        (128.0, 0.008),
        (1e6, 0.008),
    ];
    for (per_axis, spacings) in cases {
        let got = rfta_simplify::default_tolerance(per_axis);
        assert!((got - spacings).abs() < 1e-12, "{per_axis}: {got}");
    }
}
