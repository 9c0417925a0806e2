//! Mesh queries against brute force and analytic shapes.

use proptest::prelude::*;
use rfta_geom::{TriMesh, glam::DVec3, kernels, rng::Rng, shapes};
use rfta_mesh::{MeshIndex, Shell, Topology, sample_surface};

fn brute_closest(mesh: &TriMesh, p: DVec3) -> f64 {
    (0..mesh.n_faces())
        .map(|f| {
            let [a, b, c] = mesh.triangle(f);
            p.distance_squared(kernels::closest_point_on_triangle(p, a, b, c).0)
        })
        .fold(f64::INFINITY, f64::min)
}

fn random_points(n: usize, seed: u64, half: f64) -> Vec<DVec3> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 * half
                - DVec3::splat(half)
        })
        .collect()
}

/// A deliberately irregular mesh: a torus with jittered vertices plus a separate icosphere.
fn test_mesh() -> TriMesh {
    let mut t = shapes::torus(0.6, 0.25, 40, 20);
    let mut rng = Rng::new(3);
    for v in &mut t.vertices {
        *v += DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 0.01;
    }
    let mut s = shapes::icosphere(0.2, 2);
    s.map_vertices(|v| v + DVec3::new(0.0, 0.0, 0.6));
    let offset = t.vertices.len() as u32;
    t.vertices.extend(s.vertices);
    t.faces
        .extend(s.faces.iter().map(|f| f.map(|i| i + offset)));
    t
}

#[test]
fn closest_point_equals_brute_force() {
    let mesh = test_mesh();
    let index = MeshIndex::new(&mesh).expect("valid mesh");
    for p in random_points(2000, 11, 1.2) {
        let cp = index.closest_point(p);
        let brute = brute_closest(&mesh, p);
        assert!(
            (cp.distance_squared - brute).abs() <= 1e-15 * brute.max(1e-300),
            "{p}: {} vs {brute}",
            cp.distance_squared
        );
        // The reported face and barycentrics reproduce the point.
        let [a, b, c] = mesh.triangle(cp.face as usize);
        let w = cp.barycentric;
        assert!((w[0] * a + w[1] * b + w[2] * c).distance(cp.point) < 1e-12);
    }
}

#[test]
fn fast_winding_number_agrees_with_exact_sum() {
    let mesh = test_mesh();
    let index = MeshIndex::new(&mesh).expect("valid mesh");
    let mut worst: f64 = 0.0;
    for p in random_points(3000, 5, 1.2) {
        let fast = index.winding_number(p);
        let exact = index.winding_number_exact(p);
        worst = worst.max((fast - exact).abs());
        // Closed meshes: the exact value is an integer away from the surface, and the sign test
        // (w > 1/2) must agree wherever the point is not on the surface.
        if index.unsigned_distance(p) > 1e-9 {
            assert_eq!(fast > 0.5, exact > 0.5, "{p}: fast {fast}, exact {exact}");
        }
    }
    // The truncated far field (second-order error, falling as beta^-3) at beta = 2 on this coarse,
    // jittered mesh: measured deviations are a few hundredths; the documented bound is 0.05.
    assert!(worst < 0.05, "worst deviation {worst}");
}

#[test]
fn signed_distance_of_a_sphere_matches_the_analytic_one() {
    // Inscribed polyhedron: distances agree with |p| - 1 up to the sagitta of the tessellation.
    let mesh = shapes::icosphere(1.0, 5);
    let index = MeshIndex::new(&mesh).expect("valid mesh");
    // Edge length ~0.0375, so the sagitta is below 2e-4.
    for p in random_points(500, 9, 1.5) {
        let d = index.signed_distance(p);
        assert!((d - (p.length() - 1.0)).abs() < 3e-4, "{p}: {d}");
    }
}

#[test]
fn surface_samples_are_on_the_mesh_area_weighted_and_seeded() {
    let mesh = shapes::cuboid(DVec3::new(1.0, 0.5, 0.25));
    let index = MeshIndex::new(&mesh).expect("valid mesh");
    let samples = sample_surface(&mesh, 20_000, 1);
    assert_eq!(samples, sample_surface(&mesh, 20_000, 1));
    assert_ne!(samples[0], sample_surface(&mesh, 1, 2)[0]);
    assert!(
        samples
            .iter()
            .all(|s| index.unsigned_distance(s.point) < 1e-12)
    );
    // Side lengths 2 x 1 x 0.5: the two faces normal to x have area 2 * (1 * 0.5) = 1 of the
    // total 2 * (0.5 + 1 + 2) = 7.
    let on_x = samples
        .iter()
        .filter(|s| (s.point.x.abs() - 1.0).abs() < 1e-12)
        .count() as f64;
    let frac = on_x / samples.len() as f64;
    // Binomial standard deviation ~0.0025: allow 5 sigma.
    assert!((frac - 1.0 / 7.0).abs() < 0.0125, "fraction {frac}");
}

#[test]
fn topology_of_known_shapes() {
    let sphere = Topology::of(&shapes::icosphere(1.0, 2));
    assert!(sphere.is_watertight() && sphere.is_manifold() && sphere.is_consistently_oriented());
    assert_eq!(
        (
            sphere.euler_characteristic(),
            sphere.genus(),
            sphere.components
        ),
        (2, Some(0), 1)
    );
    let torus = Topology::of(&shapes::torus(0.6, 0.25, 12, 8));
    assert_eq!((torus.genus(), torus.components), (Some(1), 1));
    let both = Topology::of(&test_mesh());
    assert_eq!((both.genus(), both.components), (Some(1), 2));
    // Removing a face opens a boundary of three edges; genus is then undefined.
    let mut open = shapes::icosphere(1.0, 1);
    open.faces.pop();
    let t = Topology::of(&open);
    assert_eq!(
        (t.boundary_edges, t.is_watertight(), t.genus()),
        (3, false, None)
    );
    // Flipping one face breaks consistent orientation on its three edges.
    let mut flipped = shapes::icosphere(1.0, 1);
    flipped.faces[0].swap(1, 2);
    assert_eq!(Topology::of(&flipped).misoriented_edges, 3);
    // Two tetrahedra sharing one vertex: a bow-tie vertex, still edge-manifold.
    let tet = |o: DVec3| vec![o, o + DVec3::X, o + DVec3::Y, o + DVec3::Z];
    let mut v = tet(DVec3::ZERO);
    v.extend(tet(DVec3::ZERO).iter().skip(1).map(|p| -*p));
    let faces = vec![
        [0, 2, 1],
        [0, 1, 3],
        [0, 3, 2],
        [1, 2, 3],
        [0, 5, 4],
        [0, 4, 6],
        [0, 6, 5],
        [4, 5, 6],
    ];
    let bowtie = Topology::of(&TriMesh::new(v, faces).expect("valid"));
    assert_eq!(
        (
            bowtie.nonmanifold_edges,
            bowtie.nonmanifold_vertices,
            bowtie.components
        ),
        (0, 1, 1)
    );
    assert!(bowtie.is_watertight() && !bowtie.is_manifold());
}

#[test]
fn empty_and_invalid_meshes_are_errors() {
    assert_eq!(
        MeshIndex::new(&TriMesh::default()).err(),
        Some(rfta_mesh::Error::EmptyMesh)
    );
    let bad = TriMesh {
        vertices: vec![DVec3::ZERO; 3],
        faces: vec![[0, 1, 3]],
    };
    assert!(matches!(
        MeshIndex::new(&bad),
        Err(rfta_mesh::Error::Geom(_))
    ));
    // A single triangle (the tree is one leaf) works.
    let one = TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).expect("valid");
    let index = MeshIndex::new(&one).expect("one triangle");
    assert!((index.unsigned_distance(DVec3::new(0.2, 0.2, 1.0)) - 1.0).abs() < 1e-15);
}

/// `n` triangles with corners uniform in the unit cube, and their index.
fn random_soup(rng: &mut Rng, n: usize) -> (TriMesh, MeshIndex) {
    let vertices: Vec<DVec3> = (0..3 * n)
        .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()))
        .collect();
    let faces = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let mesh = TriMesh::new(vertices, faces).expect("valid");
    let index = MeshIndex::new(&mesh).expect("non-empty");
    (mesh, index)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn closest_point_on_random_soups(seed in 0u64..10_000, n in 1usize..60) {
        let mut rng = Rng::new(seed);
        let (mesh, index) = random_soup(&mut rng, n);
        let mut r = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        for _ in 0..20 {
            let p = r() * 3.0 - DVec3::ONE;
            let brute = brute_closest(&mesh, p);
            prop_assert!((index.closest_point(p).distance_squared - brute).abs() <= 1e-15 * brute.max(1e-300));
        }
    }

    /// The shell query against the brute-force nearest distance `d`: closer than `lo` with the
    /// exact nearest point, within `[lo, hi]`, or beyond `hi`; the shells are drawn wholly beyond
    /// `d`, around it and wholly short of it in turn (inner radii below zero and outer radii
    /// below zero among them), so that every answer occurs.
    #[test]
    fn shell_equals_brute_force_on_random_soups(seed in 0u64..10_000, n in 1usize..60) {
        let mut rng = Rng::new(seed);
        let (mesh, index) = random_soup(&mut rng, n);
        let mut r = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        let mut seen = [0; 3];
        for i in 0..30 {
            let p = r() * 3.0 - DVec3::ONE;
            let d = brute_closest(&mesh, p).sqrt();
            let t = r() * 0.3;
            let (lo, hi) = match i % 3 {
                0 => (d + 1e-3 + t.x, d + 1e-3 + t.x + t.y),
                1 => (d - 1e-3 - t.x, d + 1e-3 + t.y),
                _ => (d - 1e-3 - t.x - t.y, d - 1e-3 - t.x),
            };
            match index.shell(p, lo, hi) {
                Shell::Closer(c) => {
                    seen[0] += 1;
                    prop_assert!(d < lo);
                    prop_assert!((c.distance_squared - d * d).abs() <= 1e-15 * (d * d).max(1e-300));
                }
                Shell::Within => {
                    seen[1] += 1;
                    prop_assert!(lo <= d && d <= hi, "{lo} {d} {hi}");
                }
                Shell::Beyond => {
                    seen[2] += 1;
                    prop_assert!(d > hi);
                }
            }
        }
        prop_assert_eq!(seen, [10, 10, 10]);
    }

    #[test]
    fn segment_queries_equal_brute_force_on_random_soups(seed in 0u64..10_000, n in 1usize..60) {
        let mut rng = Rng::new(seed);
        let (mesh, index) = random_soup(&mut rng, n);
        let mut r = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        // Every crossing, face by face, in order along the segment (ties by face).
        let brute = |a: DVec3, b: DVec3| {
            let v = &mesh.vertices;
            let mut hits: Vec<(f64, u32)> = mesh.faces.iter().enumerate().filter_map(|(f, &[i, j, k])| {
                kernels::segment_triangle(a, b, v[i as usize], v[j as usize], v[k as usize]).map(|t| (t, f as u32))
            }).collect();
            hits.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            hits
        };
        for i in 0..40 {
            let a = r() * 3.0 - DVec3::ONE;
            // Some segments run along an axis, where the box test divides by zero.
            let b = if i % 4 == 0 { a + DVec3::X * (r().x - 0.5) * 2.0 } else { r() * 3.0 - DVec3::ONE };
            let all = brute(a, b);
            prop_assert_eq!(index.segment_hits(a, b), !all.is_empty());
            prop_assert_eq!(index.segment_crossings(a, b), all);
        }
        // Hits too: a segment through each triangle's centroid along its normal crosses it.
        for f in 0..mesh.faces.len() {
            let [a, b, c] = mesh.triangle(f);
            let n = (b - a).cross(c - a).normalize_or_zero();
            prop_assume!(n != DVec3::ZERO);
            let m = (a + b + c) / 3.0;
            prop_assert!(index.segment_hits(m - 0.1 * n, m + 0.1 * n));
        }
    }
}

#[test]
fn winding_number_near_one_half_is_refined_on_open_meshes() {
    // A sphere with its top cap removed: near the opening the exact value passes through 1/2.
    let mut mesh = shapes::icosphere(1.0, 3);
    let keep: Vec<[u32; 3]> = mesh
        .faces
        .iter()
        .copied()
        .filter(|f| f.iter().all(|&i| mesh.vertices[i as usize].z < 0.6))
        .collect();
    mesh.faces = keep;
    let index = MeshIndex::new(&mesh).expect("valid mesh");
    let mut n_ambiguous = 0;
    for p in random_points(3000, 17, 1.2) {
        let (fast, exact) = (index.winding_number(p), index.winding_number_exact(p));
        if (exact - 0.5).abs() < 0.05 {
            n_ambiguous += 1;
            // Refined at beta = 8: 64 times below the coarse bound of 0.05.
            assert!(
                (fast - exact).abs() < 1e-3,
                "{p}: fast {fast}, exact {exact}"
            );
        }
    }
    assert!(
        n_ambiguous > 10,
        "the test must exercise the refinement ({n_ambiguous} points)"
    );
}

#[test]
fn segments_through_a_sphere_hit_it_and_segments_beside_or_inside_do_not() {
    let index = MeshIndex::new(&shapes::icosphere(1.0, 3)).expect("non-empty");
    // Through the centre, from outside to outside: two crossings.
    assert!(index.segment_hits(DVec3::new(-2.0, 0.1, 0.2), DVec3::new(2.0, 0.1, 0.2)));
    // From the centre out: one crossing.
    assert!(index.segment_hits(DVec3::ZERO, DVec3::new(0.3, 1.5, 0.2)));
    // Wholly inside, wholly outside and beside.
    assert!(!index.segment_hits(DVec3::new(-0.5, 0.0, 0.0), DVec3::new(0.5, 0.1, 0.0)));
    assert!(!index.segment_hits(DVec3::new(1.5, 1.5, 0.0), DVec3::new(1.5, -1.5, 0.0)));
    assert!(!index.segment_hits(DVec3::new(2.0, 0.0, 0.0), DVec3::new(1.2, 0.0, 0.0)));
}

/// A mesh large enough for its tree's halves to be built side by side, several levels deep
/// (144,000 faces of a jittered torus and a sphere inside its hole): closest points, shells and
/// the sign of the winding number against brute force, and the same answers as the tree built
/// on one thread.
#[test]
fn an_index_built_in_parallel_answers_as_brute_force() {
    let mut mesh = shapes::torus(0.6, 0.25, 400, 180);
    let mut rng = Rng::new(9);
    for v in &mut mesh.vertices {
        *v += DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 0.002;
    }
    mesh.append(&shapes::icosphere(0.2, 3));
    assert!(mesh.n_faces() > 32 * 4096);
    let index = MeshIndex::new(&mesh).expect("valid mesh");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(|| MeshIndex::new(&mesh).expect("valid mesh"));
    for p in random_points(200, 17, 1.0) {
        let brute = brute_closest(&mesh, p);
        let cp = index.closest_point(p);
        assert!(
            (cp.distance_squared - brute).abs() <= 1e-15 * brute.max(1e-300),
            "{p}"
        );
        assert_eq!(one.closest_point(p), cp, "{p}");
        let d = brute.sqrt();
        assert_eq!(index.shell(p, d - 1e-3, d + 1e-3), Shell::Within, "{p}");
        assert!(
            matches!(index.shell(p, d + 1e-3, d + 2e-3), Shell::Closer(_)),
            "{p}"
        );
        assert_eq!(index.shell(p, d - 2e-3, d - 1e-3), Shell::Beyond, "{p}");
        if d > 1e-3 {
            assert_eq!(
                index.winding_number(p) > 0.5,
                index.winding_number_exact(p) > 0.5,
                "{p}"
            );
        }
    }
}
