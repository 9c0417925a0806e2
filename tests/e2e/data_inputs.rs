//! The prepared inputs (`inputs/NAME/`): every ground-truth mesh loads with the topology its
//! `meta.json` records, and the library's grid sampler reproduces every reference grid.

use rfta_geom::Layout;
use rfta_mesh::{MeshSdf, Topology};

/// Reads `"key": value` numbers from the `gt_topology` object of `meta.json` (a flat scan,
/// enough for the fixed layout the data README documents).
fn meta_number(meta: &str, key: &str) -> Option<f64> {
    let section = &meta[meta.find("\"gt_topology\"")?..];
    let at = section.find(&format!("\"{key}\""))?;
    let rest = section[at..].split_once(':')?.1;
    rest.trim_start()
        .split([',', '\n', '}'])
        .next()?
        .trim()
        .parse()
        .ok()
}

#[test]
fn ground_truth_meshes_have_their_recorded_topology() {
    let Some(data) =
        rfta_testkit::data_dir_or_skip("ground_truth_meshes_have_their_recorded_topology")
    else {
        return;
    };
    for name in rfta_testkit::input_names(&data) {
        let dir = data.join("inputs").join(&name);
        let mesh = rfta_io::read_mesh(&dir.join("gt.obj")).expect("gt.obj loads");
        let meta = std::fs::read_to_string(dir.join("meta.json")).expect("meta.json");
        let t = Topology::of(&mesh);
        let expect = |k: &str| {
            meta_number(&meta, k).unwrap_or_else(|| panic!("{name}: meta.json lacks {k}"))
        };
        assert_eq!(mesh.n_vertices() as f64, expect("n_vertices"), "{name}");
        assert_eq!(mesh.n_faces() as f64, expect("n_faces"), "{name}");
        assert_eq!(t.boundary_edges as f64, expect("boundary_edges"), "{name}");
        assert_eq!(t.components as f64, expect("components"), "{name}");
        assert_eq!(t.euler_characteristic() as f64, expect("euler"), "{name}");
        assert_eq!(t.genus().map(|g| g as f64), Some(expect("genus")), "{name}");
        assert!(mesh.signed_volume() > 0.0, "{name}: faces oriented outward");
    }
}

#[test]
fn grid_sampler_reproduces_every_reference_resolution() {
    let Some(data) =
        rfta_testkit::data_dir_or_skip("grid_sampler_reproduces_every_reference_resolution")
    else {
        return;
    };
    for name in rfta_testkit::input_names(&data) {
        let dir = data.join("inputs").join(&name);
        let index =
            MeshSdf::new(&rfta_io::read_mesh(&dir.join("gt.obj")).expect("mesh")).expect("index");
        // n = 20 is covered through the CLI; here the coarser and finer grids through the library.
        for n in [10, 30] {
            let reference =
                rfta_io::read_sdf(&dir.join(format!("sdf_n{n}.npy")), None).expect("reference");
            let Layout::Grid(grid) = reference.layout else {
                panic!("{name}: reference is not a grid")
            };
            assert_eq!(grid.dims(), [n + 1; 3]);
            let ours = index.signed_distance_grid(&grid, &|| {});
            for (i, (a, b)) in ours.iter().zip(&reference.values).enumerate() {
                assert!(
                    a.signum() == b.signum() && (a - b).abs() <= 1e-9,
                    "{name} n={n} sample {i}: {a} vs {b}"
                );
            }
        }
    }
}
