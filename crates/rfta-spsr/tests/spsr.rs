//! Screened Poisson on analytic clouds: topology, accuracy against the exact surface,
//! determinism across thread counts, and errors on bad input.
#![allow(clippy::print_stderr)]

use rfta_geom::{OrientedPoints, glam::DVec3};
use rfta_mesh::Topology;
use rfta_spsr::{Boundary, Error, SidePoint, SpsrParams, reconstruct, reconstruct_with_sides};
use rfta_testkit::Analytic;

const R: f64 = 0.6;
const RT: f64 = 0.25;

type Cloud = (Vec<DVec3>, Vec<DVec3>, Analytic);

fn sphere(n: usize, seed: u64) -> Cloud {
    let s = Analytic::Sphere { radius: 1.0 };
    let (p, nn) = s.oriented_samples(n, seed);
    (p, nn, s)
}

/// Torus R = 0.6, r = 0.25 around z.
fn torus(n: usize, seed: u64) -> Cloud {
    let s = Analytic::Torus {
        major: R,
        minor: RT,
    };
    let (p, nn) = s.oriented_samples(n, seed);
    (p, nn, s)
}

/// Box [-0.5, 0.5] x [-0.4, 0.4] x [-0.3, 0.3] (sharp edges).
fn cuboid(n: usize, seed: u64) -> Cloud {
    let s = Analytic::Box {
        half: DVec3::new(0.5, 0.4, 0.3),
    };
    let (p, nn) = s.oriented_samples(n, seed);
    (p, nn, s)
}

struct Outcome {
    mean: f64,
    max: f64,
    topology: Topology,
    volume: f64,
}

fn run(cloud: Cloud, params: &SpsrParams) -> Outcome {
    let (p, n, shape) = cloud;
    let dist = |q: DVec3| shape.sdf(q).abs();
    let points = OrientedPoints::new(p, n, None).expect("valid cloud");
    let out = reconstruct(&points, params).expect("reconstruction");
    assert_eq!(out.report.broken_leaves, 0);
    // The finest cell: the cube (box_scale times the points' longest side) over 2^depth.
    let b = points.bounds();
    let cell = params.box_scale * (b.max - b.min).max_element() / f64::from(1u32 << params.depth);
    assert!(
        (out.report.finest_cell - cell).abs() < 1e-12 * cell,
        "finest cell {} against {cell}",
        out.report.finest_cell
    );
    let d: Vec<f64> = out.mesh.vertices.iter().map(|&v| dist(v)).collect();
    eprintln!(
        "{} points: mean {:.3e} max {:.3e}",
        points.len(),
        d.iter().sum::<f64>() / d.len() as f64,
        d.iter().copied().fold(0.0, f64::max)
    );
    Outcome {
        mean: d.iter().sum::<f64>() / d.len() as f64,
        max: d.iter().copied().fold(0.0, f64::max),
        topology: Topology::of(&out.mesh),
        volume: out.mesh.signed_volume(),
    }
}

fn check_closed(o: &Outcome, genus: i64, what: &str) {
    let t = &o.topology;
    assert!(
        t.is_watertight(),
        "{what}: {} boundary edges",
        t.boundary_edges
    );
    assert!(t.is_manifold(), "{what}: not manifold: {t:?}");
    assert!(
        t.is_consistently_oriented(),
        "{what}: {} misoriented edges",
        t.misoriented_edges
    );
    assert_eq!(t.components, 1, "{what}");
    assert_eq!(t.genus(), Some(genus), "{what}");
    assert!(o.volume > 0.0, "{what}: triangles face inward");
}

fn depth8() -> SpsrParams {
    SpsrParams {
        depth: 8,
        screening: 10.0,
        ..SpsrParams::default()
    }
}

// Bars: the issue asks for a mean vertex error below 0.5% of the shape's size (sphere: 2,
// torus: 1.7). Our own, tighter bars come from PoissonRecon 18.75 at the same setting on the
// same kind of cloud (degree 1, depth 8, alpha 10: sphere 100k mean 9.3e-5 / max 2.1e-3, torus
// 100k 1.06e-4 / 7.6e-4 on a torus R = 1, r = 0.35, not directly comparable): the sphere is held
// to the anchor's quality gate, the rest to 2x (mean) and 3x (max).

#[test]
fn sphere_10k_and_100k_depth_8() {
    let o = run(sphere(10_000, 1), &depth8());
    check_closed(&o, 0, "sphere 10k");
    assert!(
        o.mean < 7e-4, // well inside 0.5% of the size (1e-2)
        "sphere 10k mean {}",
        o.mean
    );
    assert!(o.max < 6e-3, "sphere 10k max {}", o.max);
    let o = run(sphere(100_000, 2), &depth8());
    check_closed(&o, 0, "sphere 100k");
    // The same setting and cloud size as PoissonRecon's 9.3e-5 / 2.1e-3: the quality gate of
    // notes/spsr-anchor.md §6 (mean within 1.1x, max within 1.5x). Measured 8.7e-5 / 8.5e-4.
    assert!(o.mean < 1.1 * 9.3e-5, "sphere 100k mean {}", o.mean);
    assert!(o.max < 1.5 * 2.1e-3, "sphere 100k max {}", o.max);
    let exact = 4.0 / 3.0 * std::f64::consts::PI;
    assert!(
        (o.volume - exact).abs() < 1e-3 * exact,
        "volume {}",
        o.volume
    );
}

#[test]
fn torus_10k_and_100k_depth_8() {
    let o = run(torus(10_000, 3), &depth8());
    check_closed(&o, 1, "torus 10k");
    assert!(
        o.mean < 7e-4, // well inside 0.5% of the size (8.5e-3)
        "torus 10k mean {}",
        o.mean
    );
    let o = run(torus(100_000, 4), &depth8());
    check_closed(&o, 1, "torus 100k");
    assert!(o.mean < 2.0 * 1.06e-4, "torus 100k mean {}", o.mean);
    assert!(o.max < 3.0 * 7.6e-4, "torus 100k max {}", o.max);
}

#[test]
fn box_with_sharp_edges_10k_and_100k_depth_8() {
    // Screened Poisson rounds sharp corners off by a few cells of the depth the samples support
    // (about depth 7 for 10k points here, cell 1.1 / 128 = 8.6e-3; depth 8 for 100k, 4.3e-3), so
    // the max sits at the corners, at most 1.5 such cells (ratio measured 1.2), and the mean is a
    // quarter of a cell at most (measured 0.18 at 10k).
    for (n, seed, cell) in [(10_000, 5, 1.1 / 128.0), (100_000, 6, 1.1 / 256.0)] {
        let o = run(cuboid(n, seed), &depth8());
        // With screening 10 the solution can hold a closed bubble of a few vertices against a
        // sharp edge (seen at 10k: 5 vertices on the x = 0.5, z = 0.3 edge; it is in the solved
        // function, not the extraction: more Gauss-Seidel sweeps keep it, screening 4 removes
        // it). Allow one, and require every component to be a sphere.
        let t = &o.topology;
        assert!(
            t.is_watertight() && t.is_manifold() && t.is_consistently_oriented(),
            "{t:?}"
        );
        assert!(t.components <= 2, "box {n}: {} components", t.components);
        assert_eq!(
            t.euler_characteristic(),
            2 * t.components as i64,
            "box {n}: {t:?}"
        );
        assert!(o.volume > 0.0);
        assert!(
            o.mean < 0.005 * 1.0 && o.mean < 0.25 * cell,
            "box {n} mean {}",
            o.mean
        );
        assert!(o.max < 1.5 * cell, "box {n} max {}", o.max);
        let exact = 1.0 * 0.8 * 0.6;
        assert!(
            (o.volume - exact).abs() < 0.01 * exact,
            "box volume {}",
            o.volume
        );
    }
}

#[test]
fn same_mesh_at_one_and_two_threads() {
    let (p, n, _) = torus(20_000, 9);
    let points = OrientedPoints::new(p, n, None).expect("cloud");
    let one = on(1, || reconstruct(&points, &depth8())).expect("1 thread");
    let two = on(2, || reconstruct(&points, &depth8())).expect("2 threads");
    assert_eq!(one.mesh.faces, two.mesh.faces);
    assert_eq!(one.mesh.vertices, two.mesh.vertices);
    let again = on(2, || reconstruct(&points, &depth8())).expect("again");
    assert_eq!(again.mesh.vertices, two.mesh.vertices);
}

/// A workspace's second solve starts from the first: with one sweep per depth it lands nearer the
/// converged solution (40 sweeps, cold) than one cold sweep does, in volume and in iso-value; and a
/// workspace's sequence of solves is the same at any thread count.
#[test]
fn rfta_setting_and_dirichlet_give_closed_meshes() {
    let o = run(sphere(10_000, 11), &SpsrParams::rfta_reference());
    check_closed(&o, 0, "rfta setting");
    // PoissonRecon in this setting: mean 3.2e-4, max 7.5e-3 (sphere 10k).
    assert!(o.mean < 2.0 * 3.2e-4, "mean {}", o.mean);
    let o = run(
        torus(10_000, 12),
        &SpsrParams {
            boundary: Boundary::Dirichlet,
            ..depth8()
        },
    );
    check_closed(&o, 1, "dirichlet");
    assert!(o.mean < 1e-3, "dirichlet mean {}", o.mean);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    let n = vec![DVec3::Z; 3];
    // NaN positions and zero normals are refused when the cloud is built.
    let mut bad = p.clone();
    bad[1].y = f64::NAN;
    assert!(OrientedPoints::new(bad, n.clone(), None).is_err());
    assert!(OrientedPoints::new(p.clone(), vec![DVec3::Z, DVec3::ZERO, DVec3::Z], None).is_err());
    // Too few points.
    let two = OrientedPoints::new(p[..2].to_vec(), n[..2].to_vec(), None).expect("cloud");
    let e = reconstruct(&two, &SpsrParams::default()).expect_err("two points");
    assert!(matches!(e, Error::TooFewPoints { found: 2 }), "{e}");
    assert!(e.to_string().contains("at least 3"), "{e}");
    // All points identical.
    let same = OrientedPoints::new(vec![DVec3::ONE; 50], vec![DVec3::X; 50], None).expect("cloud");
    let e = reconstruct(&same, &SpsrParams::default()).expect_err("identical");
    assert!(e.to_string().contains("identical"), "{e}");
    // Parameters out of range.
    let (p, n, _) = sphere(100, 1);
    let ok = OrientedPoints::new(p, n, None).expect("cloud");
    for params in [
        SpsrParams {
            depth: 0,
            ..SpsrParams::default()
        },
        SpsrParams {
            depth: 17,
            ..SpsrParams::default()
        },
        SpsrParams {
            screening: f64::NAN,
            ..SpsrParams::default()
        },
        SpsrParams {
            box_scale: 0.5,
            ..SpsrParams::default()
        },
        SpsrParams {
            samples_per_node: 0.0,
            ..SpsrParams::default()
        },
    ] {
        let e = reconstruct(&ok, &params).expect_err("bad params");
        assert!(matches!(e, Error::InvalidParams(_)), "{e}");
    }
    // Three collinear points: a degenerate but valid call must not panic.
    let line = OrientedPoints::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0],
        vec![DVec3::Y; 3],
        None,
    )
    .expect("cloud");
    let _ = reconstruct(
        &line,
        &SpsrParams {
            depth: 5,
            ..SpsrParams::default()
        },
    );
}

/// Two unit-diameter spheres 0.04 apart, sampled densely: at depth 5 (finest cell 0.07) the smooth
/// solution bridges the gap. A side point at the gap's centre, said to be outside, opens it: the
/// plain mesh has the centre inside (winding number near 1), the constrained one outside, and
/// the report shows the point was wrong after the first solve and right after the last.
#[test]
fn side_points_open_a_bridged_gap() {
    let gap = 0.04;
    let (mut p, mut n) = (Vec::new(), Vec::new());
    for cx in [-(0.5 + gap / 2.0), 0.5 + gap / 2.0] {
        let (sp, sn, _) = sphere(4_000, 3);
        p.extend(sp.iter().map(|q| DVec3::new(cx, 0.0, 0.0) + 0.5 * *q));
        n.extend(sn);
    }
    let cloud = OrientedPoints::new(p, n, None).expect("cloud");
    let params = SpsrParams {
        depth: 5,
        ..SpsrParams::default()
    };
    let centre_inside = |mesh: &rfta_geom::TriMesh| {
        let index = rfta_mesh::MeshIndex::new(mesh).expect("index");
        index.winding_number(DVec3::ZERO) > 0.5
    };
    let plain = reconstruct(&cloud, &params).expect("plain");
    assert!(
        centre_inside(&plain.mesh),
        "the plain solve should bridge the gap"
    );
    assert!(plain.report.side_errors.is_empty());
    let sides = [SidePoint {
        position: DVec3::ZERO,
        inside: false,
    }];
    let fixed = reconstruct_with_sides(&cloud, &sides, &params).expect("with sides");
    assert!(
        !centre_inside(&fixed.mesh),
        "{:?}",
        fixed.report.side_errors
    );
    assert_eq!(fixed.report.side_errors.first(), Some(&1));
    assert_eq!(fixed.report.side_errors.last(), Some(&0));
    assert!(Topology::of(&fixed.mesh).is_watertight());
    // A side point the plain solve already gets right changes nothing.
    let right = [SidePoint {
        position: DVec3::new(0.5 + gap / 2.0, 0.0, 0.0),
        inside: true,
    }];
    let same = reconstruct_with_sides(&cloud, &right, &params).expect("right side");
    assert_eq!(same.report.side_errors, vec![0]);
    assert_eq!(same.mesh.vertices, plain.mesh.vertices);
}

/// A side point inside a solid ball, 0.11 under its surface, said to be outside: at depth 7 its
/// cell is a coarse leaf beside the fine cells along the surface, so a constraint on the depths
/// whose cells hold it would be undone by the finer hats that reach it (measured: still wrong
/// after all four re-solves, 0.10 and 0.12 under the surface too). The re-solves refine the octree
/// around it and open a cavity there: the point ends outside the mesh, the report says it was
/// wrong after the first solve and right after the last, and the mesh is closed.
#[test]
fn a_side_point_beside_the_fine_cells_opens_a_cavity() {
    let (p, n, _) = sphere(6_000, 4);
    let cloud = OrientedPoints::new(p, n, None).expect("cloud");
    let params = SpsrParams {
        depth: 7,
        ..SpsrParams::default()
    };
    let inside = |mesh: &rfta_geom::TriMesh, q: DVec3| {
        rfta_mesh::MeshIndex::new(mesh)
            .expect("index")
            .winding_number(q)
            > 0.5
    };
    let centre = 0.89 * DVec3::new(0.6, 0.48, 0.64);
    let plain = reconstruct(&cloud, &params).expect("plain");
    assert!(inside(&plain.mesh, centre));
    let sides = [SidePoint {
        position: centre,
        inside: false,
    }];
    let carved = reconstruct_with_sides(&cloud, &sides, &params).expect("with sides");
    let errors = &carved.report.side_errors;
    assert_eq!(errors.first(), Some(&1), "{errors:?}");
    assert_eq!(errors.last(), Some(&0), "{errors:?}");
    assert!(!inside(&carved.mesh, centre), "{errors:?}");
    // The ball is still there around the cavity.
    assert!(inside(&carved.mesh, DVec3::ZERO));
    assert!(inside(&carved.mesh, -centre));
    assert!(Topology::of(&carved.mesh).is_watertight());
}

/// Flat cells taken whole (`flat_tolerance`): the torus's mesh stays closed with its genus and
/// loses most of its faces; its vertices are the full extraction's on the same edges (all but
/// the centres of fans, at most one per cell), every vertex and face centre of either mesh lies
/// within twice the tolerance (the slab's width) of the other, and the mesh is the same on one
/// and two threads.
#[test]
fn flat_cells_taken_whole_keep_the_surface_within_the_tolerance() {
    let (p, n, _) = torus(40_000, 21);
    let points = OrientedPoints::new(p, n, None).expect("cloud");
    let full = reconstruct(&points, &depth8()).expect("full").mesh;
    // A tenth of the finest cell (1.1 * 1.7 / 256 = 7.3e-3).
    let tolerance = 7e-4;
    let params = SpsrParams {
        flat_tolerance: Some(tolerance),
        ..depth8()
    };
    let merged = on(2, || reconstruct(&points, &params)).expect("merged");
    assert_eq!(merged.report.broken_leaves, 0);
    let merged = merged.mesh;
    let o = Outcome {
        mean: 0.0,
        max: 0.0,
        topology: Topology::of(&merged),
        volume: merged.signed_volume(),
    };
    check_closed(&o, 1, "merged torus");
    eprintln!("faces {} -> {}", full.faces.len(), merged.faces.len());
    assert!(
        2 * merged.faces.len() < full.faces.len(),
        "{} faces against {}",
        merged.faces.len(),
        full.faces.len()
    );
    let bits = |v: &DVec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let on_full: std::collections::HashSet<[u64; 3]> = full.vertices.iter().map(bits).collect();
    let shared = merged
        .vertices
        .iter()
        .filter(|v| on_full.contains(&bits(v)))
        .count();
    assert!(
        shared * 100 >= merged.vertices.len() * 98,
        "{shared} of {} vertices on the full mesh's",
        merged.vertices.len()
    );
    for (from, to, what) in [
        (&merged, &full, "merged to full"),
        (&full, &merged, "full to merged"),
    ] {
        let index = rfta_mesh::MeshIndex::new(to).expect("index");
        let centroids = from
            .faces
            .iter()
            .map(|f| f.iter().map(|&i| from.vertices[i as usize]).sum::<DVec3>() / 3.0);
        let worst = from
            .vertices
            .iter()
            .copied()
            .chain(centroids)
            .map(|q| index.closest_point(q).distance_squared.sqrt())
            .fold(0.0, f64::max);
        assert!(
            worst <= 2.0 * tolerance,
            "{what}: {worst} against {tolerance}"
        );
    }
    let one = on(1, || reconstruct(&points, &params))
        .expect("1 thread")
        .mesh;
    assert_eq!(one.faces, merged.faces);
    assert_eq!(one.vertices, merged.vertices);
}

/// Runs `f` on a rayon pool of `threads` workers.
fn on<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

/// A side point said to be inside, between the unit sphere and the cube's face (the cube is 1.1
/// times the points' box): the re-solves that pull the surface out to it reach the face, where
/// the mesh would come out open, so the result is the first solve's surface, the plain mesh,
/// with the first pass's side error alone in the report. At depth 5 the octree is kept through
/// the re-solves; at depth 7 the point's cell is a coarse one, the octree is rebuilt around it,
/// and the first surface comes from the octree before.
#[test]
fn a_re_solve_that_reaches_the_cube_falls_back_to_the_first_surface() {
    let (p, n, _) = sphere(6_000, 4);
    let cloud = OrientedPoints::new(p, n, None).expect("cloud");
    for (depth, z, refined) in [(5, 1.08, false), (7, 1.09, true)] {
        let params = SpsrParams {
            depth,
            ..SpsrParams::default()
        };
        let plain = reconstruct(&cloud, &params).expect("plain");
        let sides = [SidePoint {
            position: DVec3::new(0.0, 0.0, z),
            inside: true,
        }];
        let r = reconstruct_with_sides(&cloud, &sides, &params).expect("with sides");
        assert_eq!(r.report.side_errors, vec![1], "depth {depth}");
        assert_eq!(r.mesh.vertices, plain.mesh.vertices, "depth {depth}");
        assert_eq!(r.mesh.faces, plain.mesh.faces, "depth {depth}");
        assert_eq!(r.report.iso_value, plain.report.iso_value, "depth {depth}");
        assert_eq!(
            r.report.nodes_per_depth != plain.report.nodes_per_depth,
            refined,
            "depth {depth}: {:?} against {:?}",
            r.report.nodes_per_depth,
            plain.report.nodes_per_depth
        );
    }
}
