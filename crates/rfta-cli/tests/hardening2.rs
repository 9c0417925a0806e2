//! The defects E1-E18 of the second hostile test (docs/hardening.md, "Round two"), each as a
//! regression test through the binary with inputs the test makes (the OpenVDB reader's own,
//! E1, E2 and E9, are in rfta-io's tests): what was replaced, aborted, lost or taken silently is
//! now written where it belongs, refused before the work, or answered as documented.

mod common;

use std::path::{Path, PathBuf};

use common::{command, rfta, s, stderr, temp, torus_mesh};
use rfta_geom::Grid;

/// A sphere of radius 0.5 on a 13^3 grid over [-1, 1]^3, in `dir`.
fn sphere_grid(dir: &Path) -> PathBuf {
    let path = dir.join("sph.npy");
    let o = rfta(&[
        "-q",
        "sample",
        "--shape",
        "sphere",
        "--res",
        "12",
        "-o",
        s(&path),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    path
}

/// A disk of radius 0.5 on a 17^2 grid over [-1, 1]^2 as `NAME.npy` in `dir`, its values
/// times `sign`.
fn disk_grid(dir: &Path, name: &str, sign: f64) -> PathBuf {
    let grid = rfta::geom::plane::Grid2::from_bounds(
        [17, 17],
        rfta::geom::glam::DVec2::splat(-1.0),
        rfta::geom::glam::DVec2::splat(1.0),
    )
    .expect("grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| sign * (grid.position(i).length() - 0.5))
        .collect();
    let path = dir.join(format!("{name}.npy"));
    let mut bytes = Vec::new();
    rfta_io::write_npy_f64(&mut bytes, &[17, 17], &values).expect("npy");
    std::fs::write(&path, bytes).expect("npy");
    path
}

/// `rfta reconstruct GRID -o OUT` with one fine-tuning round and `extra`.
fn reconstruct(grid: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["reconstruct", s(grid), "-o", s(out), "--rounds", "1"];
    args.extend_from_slice(extra);
    rfta(&args)
}

#[cfg(unix)]
fn kind(path: &Path) -> std::fs::FileType {
    std::fs::symlink_metadata(path).expect("exists").file_type()
}

/// E3: outputs through a link land in the file it names (the link stays); a FIFO and a
/// descriptor of the process (what /dev/stdout leads to) get the bytes as streams and stay what
/// they are; a socket is refused before the work.
#[cfg(target_os = "linux")]
#[test]
fn e3_links_fifos_and_descriptors_are_written_through_not_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let dir = temp("e3");
    let grid = sphere_grid(&dir);
    let out = dir.join("m.obj");
    // A link to a file elsewhere.
    std::fs::create_dir_all(dir.join("real")).expect("dir");
    std::fs::write(dir.join("real/page.html"), "old").expect("target");
    let link = dir.join("linked.html");
    std::os::unix::fs::symlink("real/page.html", &link).expect("link");
    let o = reconstruct(&grid, &out, &["--html", s(&link)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(kind(&link).is_symlink());
    let page = std::fs::read_to_string(dir.join("real/page.html")).expect("page");
    assert!(page.starts_with("<!DOCTYPE html>"), "{}", &page[..40]);
    // A FIFO, read as it is written.
    let fifo = dir.join("fifo.json");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo")
            .success()
    );
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).expect("read fifo"))
    };
    let o = reconstruct(&grid, &out, &["--report", s(&fifo)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&reader.join().expect("reader")).expect("JSON through the FIFO");
    assert!(report["samples"].as_u64() == Some(13 * 13 * 13), "{report}");
    assert!(kind(&fifo).is_fifo());
    // The process's own stdout, through a link to /proc/self/fd/1 as /dev/stdout is.
    let to_stdout = dir.join("to_stdout.json");
    std::os::unix::fs::symlink("/proc/self/fd/1", &to_stdout).expect("link");
    let o = reconstruct(&grid, &out, &["-q", "--report", s(&to_stdout)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    assert!(report["samples"].as_u64().is_some(), "{report}");
    assert!(kind(&to_stdout).is_symlink());
    // A socket: refused, before -o is written.
    let sock = dir.join("s.json");
    let _listener = std::os::unix::net::UnixListener::bind(&sock).expect("bind");
    let fresh = dir.join("fresh.obj");
    let o = reconstruct(&grid, &fresh, &["--report", s(&sock)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("socket"), "{}", stderr(&o));
    assert!(kind(&sock).is_socket() && !fresh.exists());
    let _ = std::fs::remove_dir_all(dir);
}

/// E4: RAYON_NUM_THREADS beyond the cores is capped as --threads is, with a warning, where
/// starting that many threads would fail (a small address space).
#[cfg(target_os = "linux")]
#[test]
fn e4_rayon_num_threads_is_capped_like_threads() {
    let dir = temp("e4");
    let grid = sphere_grid(&dir);
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 2000000; exec '{}' reconstruct '{}' -o '{}' --rounds 1",
            env!("CARGO_BIN_EXE_rfta"),
            s(&grid),
            s(&dir.join("m.obj"))
        ))
        .env("RAYON_NUM_THREADS", "100000")
        .output()
        .expect("run");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("RAYON_NUM_THREADS 100000 is more than the"),
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// E5: the shards of one job array may share a status file: every row's record is kept.
#[test]
fn e5_shards_sharing_a_status_file_keep_every_record() {
    let dir = temp("e5");
    sphere_grid(&dir);
    let mut manifest = String::from("input,output,preset\n");
    for k in 0..6 {
        manifest += &format!("sph.npy,o/{k}.obj,fast\n");
    }
    std::fs::write(dir.join("m.csv"), manifest).expect("manifest");
    let status = dir.join("st.csv");
    let shard = |i: &str| {
        command()
            .args(["-q", "--threads", "1", "batch"])
            .arg(dir.join("m.csv"))
            .args(["--shard", i, "--status"])
            .arg(&status)
            .spawn()
            .expect("shard")
    };
    let (mut a, mut b) = (shard("0/2"), shard("1/2"));
    assert!(a.wait().expect("a").success() && b.wait().expect("b").success());
    let text = std::fs::read_to_string(&status).expect("status");
    let mut rows: Vec<&str> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap_or(""))
        .collect();
    rows.sort_unstable();
    assert_eq!(rows, ["0", "1", "2", "3", "4", "5"], "{text}");
    assert_eq!(text.lines().filter(|l| l.starts_with("row,")).count(), 1);
    // A rerun of one shard skips its rows and keeps the other's records.
    let o = rfta(&[
        "-q",
        "batch",
        s(&dir.join("m.csv")),
        "--shard",
        "0/2",
        "--status",
        s(&status),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let again = std::fs::read_to_string(&status).expect("status");
    assert!(
        again.starts_with(&text),
        "the records before are kept as they were"
    );
    let added: Vec<&str> = again[text.len()..].lines().collect();
    assert_eq!(added.len(), 3, "{again}");
    assert!(added.iter().all(|l| l.contains(",skipped,")), "{again}");
    let _ = std::fs::remove_dir_all(dir);
}

/// E6: an output named where the input's sidecar would be is refused, sidecar there or not.
#[test]
fn e6_the_place_of_the_inputs_sidecar_is_reserved() {
    let dir = temp("e6");
    let grid = sphere_grid(&dir);
    // `sample` wrote sph.json; without it, the place is reserved all the same.
    std::fs::remove_file(dir.join("sph.json")).expect("sidecar");
    let o = reconstruct(
        &grid,
        &dir.join("m.obj"),
        &["--report", s(&dir.join("sph.json"))],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("sidecar"), "{}", stderr(&o));
    assert!(!dir.join("sph.json").exists() && !dir.join("m.obj").exists());
    let _ = std::fs::remove_dir_all(dir);
}

/// E7: a mesh at 1e-300 and at 1e155 (inside out, as a mesh may come) is sampled to the same
/// values, in its units, as at the unit.
#[test]
fn e7_meshes_of_any_scale_are_sampled_alike() {
    let dir = temp("e7");
    let mut grids: Vec<Vec<f64>> = Vec::new();
    for scale in [1.0, 1e-300, 1e155] {
        // The unit cube scaled, its faces turned inward: `sample` must see that at any scale.
        let mut mesh = rfta_geom::shapes::cuboid(rfta_geom::glam::DVec3::splat(0.5));
        mesh.vertices.iter_mut().for_each(|v| *v *= scale);
        mesh.flip();
        let path = dir.join(format!("cube{scale:e}.obj"));
        rfta_io::write_mesh(&path, &mesh).expect("mesh");
        let out = dir.join(format!("g{scale:e}.npy"));
        let b = format!("--bounds={},{}", -scale, scale);
        let o = rfta(&["sample", s(&path), "--res", "8", &b, "-o", s(&out)]);
        assert!(o.status.success(), "{scale:e}: {}", stderr(&o));
        let raw = rfta_io::read_sdf(&out, None).expect("grid");
        assert!(raw.values.iter().all(|v| v.is_finite()));
        grids.push(raw.values.iter().map(|&v| v / scale).collect());
    }
    // The same values in the mesh's units, to rounding, and a surface in the grid.
    for g in &grids[1..] {
        assert!(g.iter().zip(&grids[0]).all(|(a, b)| (a - b).abs() < 1e-9));
    }
    assert!(grids[0].iter().any(|&v| v < 0.0) && grids[0].iter().any(|&v| v > 0.0));
    let _ = std::fs::remove_dir_all(dir);
}

/// E8: samples of one sign whose spheres cover their box describe no surface (exit 3, an
/// empty mesh), not a mesh outside the box.
#[test]
fn e8_one_signed_samples_covering_their_box_are_no_surface() {
    let dir = temp("e8");
    let grid = Grid::cube(12, -1.0, 1.0).expect("grid");
    let ramp: Vec<f64> = (0..grid.len())
        .map(|i| 0.6 + 0.3 * grid.position(i).x)
        .collect();
    let path = dir.join("ramp.npy");
    rfta_io::write_sdf_grid(&path, &grid, &ramp).expect("ramp");
    let out = dir.join("ramp.obj");
    let o = reconstruct(&path, &out, &[]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let mesh = rfta_io::read_mesh(&out);
    assert!(mesh.is_err() || mesh.is_ok_and(|m| m.is_empty()));
    let _ = std::fs::remove_dir_all(dir);
}

/// E10: `--html` on 2D input writes a page with the drawing.
#[test]
fn e10_html_for_2d_input_writes_a_page() {
    let dir = temp("e10");
    let path = disk_grid(&dir, "disk", 1.0);
    let page = dir.join("disk.html");
    let o = reconstruct(&path, &dir.join("disk.svg"), &["--html", s(&page)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&page).expect("page");
    assert!(text.contains("<svg") && text.contains("loops"), "{text}");
    let _ = std::fs::remove_dir_all(dir);
}

/// E11, E12: a 240-byte output name is written; an output whose folder takes no file is
/// refused before the work, and nothing is written.
#[test]
fn e11_e12_long_names_are_written_and_unwritable_folders_refused_first() {
    let dir = temp("e11");
    let grid = sphere_grid(&dir);
    let long = dir.join(format!("{}.obj", "n".repeat(236)));
    let o = reconstruct(&grid, &long, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(long.is_file());
    #[cfg(target_os = "linux")]
    {
        let out = dir.join("first.obj");
        let o = reconstruct(&grid, &out, &["--html", "/proc/rfta-test-page.html"]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains("--html"), "{}", stderr(&o));
        assert!(!out.exists(), "-o was written before the refusal");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// E13, E15: adaptive bounds that miss the mesh are no surface, said as such; a budget
/// beyond memory is refused before the first evaluation.
#[test]
fn e13_e15_adaptive_bounds_and_budgets_are_judged_before_the_work() {
    let dir = temp("e13");
    let mesh = dir.join("cube.obj");
    rfta_io::write_mesh(
        &mesh,
        &rfta_geom::shapes::cuboid(rfta_geom::glam::DVec3::splat(0.5)),
    )
    .expect("mesh");
    let out = dir.join("m.obj");
    let o = rfta(&[
        "reconstruct",
        "--from-mesh",
        s(&mesh),
        "--budget",
        "600",
        "--bounds=2,3",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("does not meet the mesh"),
        "{}",
        stderr(&o)
    );
    let o = rfta(&[
        "reconstruct",
        "--from-mesh",
        s(&mesh),
        "--budget",
        "100000000000",
        "-o",
        s(&dir.join("big.obj")),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("refused before asking"),
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// E14: a merge refuses a record it cannot read, naming its line, instead of dropping it.
#[test]
fn e14_merge_refuses_records_it_cannot_read() {
    let dir = temp("e14");
    let status = dir.join("st.csv");
    std::fs::write(
        &status,
        "row,input,output,status,seconds,message,samples,vertices,faces,components,watertight,sign_errors,entered,gaps\n\
         0,a.npy,a.obj,ok,1.0,,,,,,,,,\n\
         1,b.npy,b.obj,failed,,boom,,,,,,,,\n",
    )
    .expect("status");
    let o = rfta(&[
        "batch",
        "--merge",
        s(&status),
        "--status",
        s(&dir.join("all.csv")),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("line 3"), "{}", stderr(&o));
    assert!(!dir.join("all.csv").exists());
    let _ = std::fs::remove_dir_all(dir);
}

/// E16: an adaptive run in a box that is not a cube keeps no piece beyond the box it sampled.
#[test]
fn e16_no_piece_beyond_the_box_an_adaptive_run_sampled() {
    let dir = temp("e16");
    let mesh = torus_mesh(&dir);
    let out = dir.join("m.obj");
    let b = [-0.9, -0.9, -0.4, 1.0, 0.9, 0.35];
    let bounds = format!("--bounds={}", b.map(|v| v.to_string()).join(","));
    let o = rfta(&[
        "reconstruct",
        "--from-mesh",
        s(&mesh),
        "--budget",
        "3000",
        &bounds,
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = rfta_io::read_mesh(&out).expect("mesh");
    let topo = rfta_mesh::Topology::of(&m);
    assert_eq!(topo.components, 1, "{}", stderr(&o));
    let spacing = 0.1;
    for v in &m.vertices {
        for a in 0..3 {
            assert!(
                v[a] > b[a] - spacing && v[a] < b[a + 3] + spacing,
                "vertex {v} beyond the box"
            );
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// E17: a mesh beyond [-1, 1]^3 is sampled in a cube around it, said aloud, not cut.
#[test]
fn e17_a_mesh_beyond_the_default_box_is_sampled_whole() {
    let dir = temp("e17");
    let mut big = rfta_geom::shapes::icosphere(4.0, 3);
    for v in &mut big.vertices {
        *v += rfta_geom::glam::DVec3::new(3.0, 0.0, 0.0);
    }
    let mesh = dir.join("big.obj");
    rfta_io::write_mesh(&mesh, &big).expect("mesh");
    let out = dir.join("g.npy");
    let o = rfta(&["sample", s(&mesh), "--res", "10", "-o", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("beyond the default box"),
        "{}",
        stderr(&o)
    );
    let raw = rfta_io::read_sdf(&out, None).expect("grid");
    let rfta_geom::Layout::Grid(g) = raw.layout else {
        panic!("a grid")
    };
    // The whole sphere (x from -1 to 7) in the box, positive all around its rim.
    assert!(g.origin().x < -1.0 && g.position(g.len() - 1).x > 7.0);
    let inside = raw.values.iter().filter(|&&v| v < 0.0).count();
    assert!(inside > 0 && inside < raw.values.len() / 2);
    let _ = std::fs::remove_dir_all(dir);
}

/// E18: an inside-positive field is refused with the reason and the way out, and `info` says
/// it; the field as it was is not; the same in 2D.
#[test]
fn e18_an_inside_positive_field_is_refused_with_the_reason() {
    let dir = temp("e18");
    let grid = sphere_grid(&dir);
    let raw = rfta_io::read_sdf(&grid, None).expect("grid");
    let rfta_geom::Layout::Grid(g) = raw.layout else {
        panic!("a grid")
    };
    let flipped: Vec<f64> = raw.values.iter().map(|v| -v).collect();
    let path = dir.join("flipped.npy");
    rfta_io::write_sdf_grid(&path, &g, &flipped).expect("flipped");
    let o = reconstruct(&path, &dir.join("f.obj"), &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("inside-positive") && err.contains("--no-check"),
        "{err}"
    );
    assert!(!dir.join("f.obj").exists());
    // `info` says so too, and not of the field as it was.
    let said = |p: &Path| String::from_utf8_lossy(&rfta(&["info", s(p)]).stdout).into_owned();
    assert!(
        said(&path).contains("looks inside-positive"),
        "{}",
        said(&path)
    );
    assert!(
        !said(&grid).contains("looks inside-positive"),
        "{}",
        said(&grid)
    );
    // The same rule in 2D: a disk's field negated is refused, the disk's reconstructs.
    let disk = disk_grid(&dir, "disk", 1.0);
    let flipped = disk_grid(&dir, "flipped2d", -1.0);
    let o = reconstruct(&flipped, &dir.join("f.svg"), &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("inside-positive"), "{}", stderr(&o));
    let o = reconstruct(&disk, &dir.join("d.svg"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(dir);
}
