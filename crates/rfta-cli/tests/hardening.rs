//! The defects D1-D13 of a hostile test of the CLI (docs/hardening.md), each as a regression
//! test whose inputs the test makes: what was lost, overwritten, panicked or taken silently is now
//! refused with a clear message or handled right, and every input is byte-for-byte as it was.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{rfta, s, stderr, temp};
use rfta_geom::Grid;
use rfta_geom::glam::DVec3;

/// A torus (radii 0.5 and 0.2) on an `(n+1)^3` grid over `[-scale, scale]^3`, values scaled alike.
fn torus_grid(path: &Path, n: usize, scale: f64) {
    let grid = Grid::cube(n, -scale, scale).expect("grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| {
            let p: DVec3 = grid.position(i) / scale;
            let ring = p.truncate().length() - 0.5;
            scale * ((ring * ring + p.z * p.z).sqrt() - 0.2)
        })
        .collect();
    rfta_io::write_sdf_grid(path, &grid, &values).expect("write grid");
}

/// The bytes of every file in `dir`, to compare before and after.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(dir)
        .expect("dir")
        .flatten()
        .filter(|e| e.path().is_file())
        .map(|e| (e.path(), std::fs::read(e.path()).expect("read")))
        .collect();
    files.sort();
    files
}

/// Runs `args`, expects exit status `code` with `message` in the error, and every file of `dir`
/// exactly as it was (nothing overwritten, nothing added).
fn refused(dir: &Path, args: &[&str], code: i32, message: &str) {
    let before = snapshot(dir);
    let o = rfta(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
    assert!(err.contains(message), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert!(snapshot(dir) == before, "{args:?} changed the folder");
}

#[test]
fn d1_two_batch_rows_writing_one_output_are_refused_before_any_row_runs() {
    let dir = temp("d1");
    torus_grid(&dir.join("a.npy"), 8, 1.0);
    torus_grid(&dir.join("b.npy"), 10, 1.0);
    let manifest = dir.join("m.csv");
    let m = s(&manifest);
    for rows in [
        "input,output\na.npy,o/same.obj\nb.npy,o/same.obj\n",
        "input,output\na.npy,o/x.obj\nb.npy,o/../o/x.obj\n",
    ] {
        std::fs::write(&manifest, rows).expect("manifest");
        refused(&dir, &["batch", m], 1, "are the same file");
        // Another shard's rows count too.
        refused(
            &dir,
            &["batch", m, "--shard", "1/2"],
            1,
            "are the same file",
        );
    }
    assert!(!dir.join("o").exists());
    // An output that is the manifest, the status file or another row's input.
    for (rows, status) in [
        ("input,output\na.npy,m.csv\n", None),
        ("input,output\na.npy,st.csv\n", Some("st.csv")),
        ("input,output\na.npy,x.obj\nb.npy,a.npy\n", None),
        ("input,output\na.npy,x.obj\nb.npy,a.json\n", None),
    ] {
        std::fs::write(&manifest, rows).expect("manifest");
        let st = dir.join(status.unwrap_or("unused.csv"));
        let mut args = vec!["batch", m];
        if status.is_some() {
            args.extend(["--status", s(&st)]);
        }
        refused(&dir, &args, 1, "are the same file");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d2_an_output_that_is_an_input_or_another_output_is_refused() {
    let dir = temp("d2");
    let grid = dir.join("g.npy");
    torus_grid(&grid, 8, 1.0);
    let side = dir.join("g.json");
    // Scattered samples (PLY), oriented points, 2D rows.
    let ply = dir.join("scat.ply");
    let mut text = String::from(
        "ply\nformat ascii 1.0\nelement vertex 400\nproperty double x\nproperty double y\nproperty double z\nproperty double sdf\nend_header\n",
    );
    for i in 0..400 {
        let p = DVec3::new(
            ((i * 37) % 101) as f64 / 50.0 - 1.0,
            ((i * 53) % 97) as f64 / 48.0 - 1.0,
            ((i * 71) % 89) as f64 / 44.0 - 1.0,
        );
        text += &format!("{} {} {} {}\n", p.x, p.y, p.z, p.length() - 0.5);
    }
    std::fs::write(&ply, text).expect("ply");
    let xyz = dir.join("pts.xyz");
    std::fs::write(
        &xyz,
        "0 0 1 0 0 1\n1 0 0 1 0 0\n0 1 0 0 1 0\n0 0 -1 0 0 -1\n",
    )
    .expect("xyz");
    let csv = dir.join("c.csv");
    std::fs::write(&csv, "0,0,-0.5\n1,0,0.5\n0,1,0.5\n-1,0,0.5\n0,-1,0.5\n").expect("csv");
    let out = dir.join("m.obj");
    let (g, o) = (s(&grid), s(&out));
    let same = "are the same file";
    for args in [
        vec!["reconstruct", s(&ply), "-o", s(&ply)],
        vec!["psr", s(&xyz), "-o", s(&xyz)],
        vec!["reconstruct", s(&csv), "-o", s(&csv)],
        vec!["mc", g, "-o", g],
        vec!["reconstruct", g, "-o", o, "--report", g],
        vec!["reconstruct", g, "-o", o, "--report", s(&side)],
        vec!["reconstruct", g, "-o", o, "--report", o],
        vec!["reconstruct", g, "-o", o, "--points", o],
        vec![
            "reconstruct",
            g,
            "-o",
            s(&dir.join("./m.obj")),
            "--report",
            o,
        ],
        vec![
            "sample",
            "--shape",
            "torus",
            "--res",
            "8",
            "-o",
            s(&dir.join("t.npy")),
            "--save-mesh",
            s(&dir.join("t.json")),
        ],
    ] {
        refused(&dir, &args, 1, same);
    }
    // A link to the input is the input.
    #[cfg(unix)]
    {
        let link = dir.join("link.obj");
        std::os::unix::fs::symlink(&ply, &link).expect("link");
        refused(&dir, &["reconstruct", s(&ply), "-o", s(&link)], 1, same);
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d3_coordinates_of_any_size_give_a_mesh_and_no_panic() {
    let dir = temp("d3");
    for (scale, name) in [
        (1e155, "big.npy"),
        (1e-200, "small.npy"),
        (1e300, "huge.npy"),
    ] {
        let input = dir.join(name);
        torus_grid(&input, 12, scale);
        let out = dir.join(format!("{name}.obj"));
        let o = rfta(&["reconstruct", s(&input), "-o", s(&out)]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let mesh = rfta_io::read_mesh(&out).expect("mesh");
        let topo = rfta_mesh::Topology::of(&mesh);
        assert!(
            topo.is_watertight() && topo.components == 1,
            "{name}: {topo:?}"
        );
        let o = rfta(&["info", s(&input)]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(text.contains("valid       yes"), "{name}: {text}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d4_a_stale_sidecar_beside_an_exr_is_refused() {
    let dir = temp("d4");
    let (npy, exr) = (dir.join("x.npy"), dir.join("x.exr"));
    let o = rfta(&[
        "-q",
        "sample",
        "--shape",
        "sphere",
        "--res",
        "10",
        "--bounds=-2,2",
        "-o",
        s(&npy),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = rfta(&[
        "-q",
        "sample",
        "--shape",
        "sphere",
        "--res",
        "10",
        "-o",
        s(&exr),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    refused(
        &dir,
        &["reconstruct", s(&exr), "-o", s(&dir.join("x.obj"))],
        1,
        "disagrees with",
    );
    // The sidecar that agrees is fine.
    std::fs::remove_file(dir.join("x.json")).expect("remove");
    let o = rfta(&["reconstruct", s(&exr), "-o", s(&dir.join("x.obj"))]);
    assert!(o.status.success(), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d5_an_inside_out_mesh_is_sampled_with_inside_negative() {
    let dir = temp("d5");
    // An octahedron of radius 0.8 with every face turned inward.
    let mut mesh = rfta_geom::shapes::octahedron(0.8);
    mesh.flip();
    assert!(mesh.signed_volume() < 0.0);
    let obj = dir.join("inverted.obj");
    rfta_io::write_mesh(&obj, &mesh).expect("mesh");
    let out = dir.join("inv.npy");
    let o = rfta(&["sample", s(&obj), "--res", "12", "-o", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("inside out"), "{}", stderr(&o));
    let raw = rfta_io::read_sdf(&out, None).expect("grid");
    // The centre is 0.8 / sqrt(3) inside every face.
    let centre = raw.values[raw.values.len() / 2];
    assert!((centre + 0.8 / 3f64.sqrt()).abs() < 1e-9, "{centre}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d6_a_grid_with_one_sample_along_an_axis_is_refused() {
    let dir = temp("d6");
    let slice = dir.join("slice.npy");
    let values: Vec<f64> = (0..169).map(|i| f64::from(i % 13) / 6.0 - 1.2).collect();
    rfta_io::write_atomic(&slice, |w| rfta_io::write_npy_f64(w, &[1, 13, 13], &values))
        .expect("npy");
    let message = "a 3D grid needs at least 2 points along every axis";
    refused(
        &dir,
        &["reconstruct", s(&slice), "-o", s(&dir.join("s.obj"))],
        1,
        message,
    );
    refused(
        &dir,
        &["mc", s(&slice), "-o", s(&dir.join("s.obj"))],
        1,
        message,
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d7_headers_that_disagree_with_their_bodies_are_refused() {
    let dir = temp("d7");
    let head = |format: &str, n: usize| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\nproperty double sdf\nend_header\n"
        )
    };
    let mut rows = String::new();
    for i in 0..50 {
        let t = f64::from(i) * 0.37;
        let p = DVec3::new(t.cos(), t.sin(), (t * 0.3).sin()) * 0.9;
        rows += &format!("{} {} {} {}\n", p.x, p.y, p.z, p.length() - 0.5);
    }
    for (name, text, message) in [
        (
            "bin.ply",
            head("binary_little_endian", 50) + &rows,
            "the body is ASCII text",
        ),
        (
            "less.ply",
            head("ascii", 40) + &rows,
            "more records than the header",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("ply");
        refused(
            &dir,
            &["reconstruct", s(&path), "-o", s(&dir.join("o.obj"))],
            1,
            message,
        );
        refused(&dir, &["info", s(&path)], 1, message);
    }
    let off = dir.join("t.off");
    std::fs::write(
        &off,
        "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
    )
    .expect("off");
    refused(
        &dir,
        &["info", s(&off)],
        1,
        "more data than the header's counts",
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d8_a_timeout_beyond_what_a_duration_holds_is_a_usage_error() {
    let dir = temp("d8");
    let manifest = dir.join("m.csv");
    std::fs::write(&manifest, "input,output\n").expect("manifest");
    for t in ["1e20", "inf", "nan", "-1", "0"] {
        let arg = format!("--timeout={t}");
        refused(&dir, &["batch", s(&manifest), &arg], 2, "--timeout");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d10_a_process_under_a_small_address_space_refuses_before_reading() {
    let dir = temp("d10");
    let grid = dir.join("g.npy");
    torus_grid(&grid, 64, 1.0);
    // ulimit -v: an allocation past it aborted (status 134); now it is the memory limit.
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 300000 && exec {} reconstruct {} -o {}",
            env!("CARGO_BIN_EXE_rfta"),
            s(&grid),
            s(&dir.join("g.obj"))
        ))
        .output()
        .expect("sh");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("refused before reading"),
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d11_manifests_and_status_files_as_spreadsheets_and_kills_leave_them() {
    let dir = temp("d11");
    torus_grid(&dir.join("a.npy"), 8, 1.0);
    let manifest = dir.join("m.csv");
    // A byte order mark and trailing blank lines: one row, which runs.
    std::fs::write(&manifest, "\u{feff}input,output\na.npy,a.obj\n\n\n").expect("manifest");
    let o = rfta(&["batch", s(&manifest)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("1 rows") && stderr(&o).contains("1 ok"),
        "{}",
        stderr(&o)
    );
    // A line cut inside its figures is no record: the row runs again.
    let status = dir.join("m.shard-0-of-1.status.csv");
    let text = std::fs::read_to_string(&status).expect("status");
    let cut = &text[..text.trim_end().len() - 3];
    std::fs::write(&status, cut).expect("cut");
    let o = rfta(&["batch", s(&manifest)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("1 ok, 0 no_surface, 0 failed, 0 timeout, 0 skipped"),
        "{}",
        stderr(&o)
    );
    // A column named twice.
    std::fs::write(&manifest, "input,output,output\na.npy,a.obj,b.obj\n").expect("manifest");
    refused(
        &dir,
        &["batch", s(&manifest)],
        1,
        "names the column 'output' twice",
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d12_threads_beyond_the_cores_are_capped_with_a_warning() {
    let dir = temp("d12");
    let grid = dir.join("g.npy");
    torus_grid(&grid, 10, 1.0);
    for n in ["10000", "4294967296"] {
        let t = std::time::Instant::now();
        let o = rfta(&[
            "--threads",
            n,
            "reconstruct",
            s(&grid),
            "-o",
            s(&dir.join("g.obj")),
        ]);
        assert!(o.status.success(), "{n}: {}", stderr(&o));
        assert!(stderr(&o).contains("more than the"), "{n}: {}", stderr(&o));
        // Starting 10,000 threads took 42 s; the whole run takes about a second.
        assert!(t.elapsed().as_secs() < 30, "{n}: {:?}", t.elapsed());
    }
    // The library refuses a pool that size, before starting it.
    let too_many = rfta::Params {
        threads: Some(1 << 32),
        ..rfta::Params::default()
    };
    let raw = rfta_io::read_sdf(&grid, None).expect("grid");
    let samples = raw.validate(&grid).expect("samples");
    assert!(matches!(
        rfta::reconstruct(&samples, &too_many),
        Err(rfta::Error::InvalidParams(_))
    ));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn d13_bad_option_values_headers_and_outputs_are_refused_before_the_work() {
    let dir = temp("d13");
    let grid = dir.join("g.npy");
    torus_grid(&grid, 8, 1.0);
    let out = dir.join("g.obj");
    let (g, o) = (s(&grid), s(&out));
    for (option, value) in [
        ("--owner-band", "nan"),
        ("--owner-band", "-1"),
        ("--clamp", "0"),
        ("--clamp", "inf"),
        ("--min-island", "nan"),
    ] {
        let arg = format!("{option}={value}");
        refused(&dir, &["reconstruct", g, "-o", o, &arg], 2, option);
    }
    // An output that is a folder, a report into a missing folder: refused at once.
    std::fs::create_dir(dir.join("folder")).expect("folder");
    refused(
        &dir,
        &["reconstruct", g, "-o", s(&dir.join("folder"))],
        1,
        "is a folder",
    );
    let missing = dir.join("missing/r.json");
    refused(
        &dir,
        &["reconstruct", g, "-o", o, "--report", s(&missing)],
        1,
        "does not exist",
    );
    // A headerless CSV that starts with a byte order mark keeps its first row.
    let csv = dir.join("bom.csv");
    let mut text = String::from("\u{feff}");
    for i in 0..30 {
        let t = f64::from(i) * 0.7;
        let p = DVec3::new(t.cos(), t.sin(), (t * 0.5).cos()) * 0.8;
        text += &format!("{},{},{},{}\n", p.x, p.y, p.z, p.length() - 0.5);
    }
    std::fs::write(&csv, text).expect("csv");
    let info = rfta(&["info", s(&csv)]);
    let text = String::from_utf8_lossy(&info.stdout).into_owned();
    assert!(text.contains("samples     30"), "{text}{}", stderr(&info));
    // An .npy header that names its shape twice.
    let npy = dir.join("dup.npy");
    let dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2, 2), 'shape': (8,), }";
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    let pad = (64 - (10 + dict.len() + 1) % 64) % 64;
    let header = format!("{dict}{}\n", " ".repeat(pad));
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in [-0.5f64, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(&npy, bytes).expect("npy");
    refused(&dir, &["info", s(&npy)], 1, "names 'shape' twice");
    let _ = std::fs::remove_dir_all(dir);
}
