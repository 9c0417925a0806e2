//! Marching cubes on analytic shapes and adversarial noise.

use rfta_geom::{Grid, TriMesh, glam::DVec3, rng::Rng};
use rfta_mc::marching_cubes;
use rfta_mesh::Topology;
use rfta_testkit::Analytic;

fn sample(shape: Analytic, n_cells: usize) -> (Grid, Vec<f64>) {
    let grid = Grid::cube(n_cells, -1.0, 1.0).expect("grid");
    let values = (0..grid.len())
        .map(|i| shape.sdf(grid.position(i)))
        .collect();
    (grid, values)
}

fn assert_closed_manifold(mesh: &TriMesh, genus: i64, what: &str) {
    let t = Topology::of(mesh);
    assert!(
        t.is_watertight(),
        "{what}: {} boundary, {} non-manifold edges",
        t.boundary_edges,
        t.nonmanifold_edges
    );
    assert!(
        t.is_manifold(),
        "{what}: {} non-manifold vertices",
        t.nonmanifold_vertices
    );
    assert!(
        t.is_consistently_oriented(),
        "{what}: {} misoriented edges",
        t.misoriented_edges
    );
    assert_eq!(t.genus(), Some(genus), "{what}");
    assert!(mesh.signed_volume() > 0.0, "{what}: faces point outwards");
}

#[test]
fn analytic_shapes_are_closed_with_the_right_genus_and_close_to_the_surface() {
    let cases = [
        (Analytic::Sphere { radius: 0.7 }, 0),
        (
            Analytic::Torus {
                major: 0.6,
                minor: 0.25,
            },
            1,
        ),
        (
            Analytic::Box {
                half: DVec3::new(0.6, 0.4, 0.3),
            },
            0,
        ),
    ];
    for (shape, genus) in cases {
        for n in [16, 31, 40] {
            let (grid, values) = sample(shape, n);
            let mesh = marching_cubes(&grid, &values, 0.0);
            assert_closed_manifold(&mesh, genus, &format!("{shape:?} n={n}"));
            // Linear interpolation of an SDF along a grid edge errs by at most h^2 / (2 R_min)
            // for curvature radius R_min: 0.25 (torus tube) gives 2 h^2 with h = 2 / n; for the
            // box, edges crossing the corner region err by up to h.
            let h = 2.0 / n as f64;
            let tol = match shape {
                Analytic::Box { .. } => h,
                _ => 2.0 * h * h + 1e-12,
            };
            for v in &mesh.vertices {
                assert!(
                    shape.sdf(*v).abs() <= tol,
                    "{shape:?} n={n}: vertex {v} off by {}",
                    shape.sdf(*v)
                );
            }
        }
    }
}

#[test]
fn noise_gives_a_watertight_manifold_oriented_mesh() {
    // Random values exercise every case, ambiguous faces included; positive values on the grid's
    // boundary make every component closed.
    for seed in 0..6 {
        let grid = Grid::cube(14, -1.0, 1.0).expect("grid");
        let mut rng = Rng::new(seed);
        let values: Vec<f64> = (0..grid.len())
            .map(|i| {
                let [a, b, c] = grid.ijk(i);
                let boundary = [a, b, c].iter().any(|&x| x == 0 || x == 14);
                if boundary { 1.0 } else { rng.next_f64() - 0.5 }
            })
            .collect();
        let mesh = marching_cubes(&grid, &values, 0.0);
        let t = Topology::of(&mesh);
        assert!(!mesh.is_empty());
        assert!(
            t.is_watertight() && t.is_manifold() && t.is_consistently_oriented(),
            "seed {seed}: {t:?}"
        );
        assert!(mesh.signed_volume() > 0.0, "seed {seed}");
    }
}

#[test]
fn degenerate_grids_give_empty_meshes() {
    let flat = Grid::new([1, 5, 5], DVec3::ZERO, DVec3::ONE).expect("grid");
    assert!(marching_cubes(&flat, &[-1.0; 25], 0.0).is_empty());
    let (grid, _) = sample(Analytic::Sphere { radius: 0.5 }, 4);
    assert!(marching_cubes(&grid, &vec![1.0; grid.len()], 0.0).is_empty());
    assert!(marching_cubes(&grid, &vec![-1.0; grid.len()], 0.0).is_empty());
}

#[test]
fn same_mesh_at_any_thread_count() {
    let (grid, values) = sample(
        Analytic::Torus {
            major: 0.6,
            minor: 0.25,
        },
        37,
    );
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| marching_cubes(&grid, &values, 0.0))
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(4));
}
