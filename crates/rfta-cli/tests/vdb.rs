//! OpenVDB level sets in: a `.vdb` written by OpenVDB reconstructs to the same mesh as the
//! equivalent clamped grid (the dense grid OpenVDB itself makes of it, as an `.npy` with a
//! sidecar, and `--clamp` at its background), in `reconstruct` and `batch`.

mod common;

use std::path::{Path, PathBuf};

use common::{json, rfta, s, stderr, temp};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../rfta-io/tests/data/vdb")
        .join(name)
}

/// `box.npy` with a sidecar from OpenVDB's origin and voxel size, in `dir`; and the background.
fn clamped_twin(dir: &Path) -> (PathBuf, f64) {
    let twin = json(&data("box.twin.json"));
    let npy = dir.join("box.npy");
    std::fs::copy(data("box.npy"), &npy).expect("test data");
    let side = serde_json::json!({"origin": twin["origin"], "spacing": twin["spacing"]});
    std::fs::write(dir.join("box.json"), side.to_string()).expect("test data");
    (npy, twin["background"].as_f64().expect("test data"))
}

#[test]
fn a_level_set_reconstructs_as_its_clamped_dense_grid() {
    let dir = temp("same");
    let (npy, background) = clamped_twin(&dir);
    let from_npy = dir.join("npy.ply");
    let o = rfta(&[
        "reconstruct",
        s(&npy),
        "-o",
        s(&from_npy),
        "--clamp",
        &background.to_string(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for file in ["box.vdb", "box-zip.vdb"] {
        let from_vdb = dir.join(format!("{file}.ply"));
        let o = rfta(&["reconstruct", s(&data(file)), "-o", s(&from_vdb)]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("the level set's background value"),
            "{}",
            stderr(&o)
        );
        let (a, b) = (
            std::fs::read(&from_npy).expect("test data"),
            std::fs::read(&from_vdb).expect("test data"),
        );
        assert!(a.len() > 1000 && a == b, "{file}: the meshes differ");
    }
    // And it is the box make.py gave OpenVDB, (-0.3, -0.3, 0.05) .. (0.5, 0.2, 0.5), within a
    // voxel (0.05): no axis swapped, no translation lost.
    let mesh = rfta_io::read_mesh(&from_npy).expect("test data");
    let b = mesh.bounds();
    let want = ([-0.3, -0.3, 0.05], [0.5, 0.2, 0.5]);
    for a in 0..3 {
        assert!((b.min[a] - want.0[a]).abs() < 0.05, "min {}", b.min);
        assert!((b.max[a] - want.1[a]).abs() < 0.05, "max {}", b.max);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_grid_is_chosen_by_name_and_a_wrong_one_is_named() {
    let dir = temp("named");
    let out = dir.join("ball.obj");
    let o = rfta(&[
        "reconstruct",
        s(&data("three.vdb")),
        "--grid",
        "ball",
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = rfta(&[
        "reconstruct",
        s(&data("three.vdb")),
        "--grid",
        "density",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("grid \"density\": it is a fog volume"),
        "{}",
        stderr(&o)
    );
    let o = rfta(&["info", s(&data("three.vdb"))]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("OpenVDB level set \"ball\""), "{text}");
    assert!(text.contains("(the file's background value)"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn batch_rows_read_level_sets() {
    let dir = temp("batch");
    let manifest = dir.join("m.csv");
    std::fs::write(
        &manifest,
        format!(
            "input,output\n{},{}\n",
            s(&data("box-half.vdb")),
            s(&dir.join("half.ply"))
        ),
    )
    .expect("test data");
    let o = rfta(&["batch", s(&manifest)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.join("half.ply").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
