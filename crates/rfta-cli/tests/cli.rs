//! The `rfta` binary, end to end.

mod common;

use common::{json, rfta, s, stderr, temp};
use rfta_io::read_sdf;

/// `rfta sample gt.obj --res 20` reproduces the reference grid (libigl's exact distance and
/// winding-number sign) to 1e-9 absolute, sign included, for every prepared input.
#[test]
fn sample_matches_reference_grids() {
    let Some(data) = rfta_testkit::data_dir_or_skip("sample_matches_reference_grids") else {
        return;
    };
    let names = rfta_testkit::input_names(&data);
    assert!(
        names.len() >= 8,
        "expected the 8 prepared inputs, found {names:?}"
    );
    let dir = temp("reference");
    for name in names {
        let input = data.join("inputs").join(&name);
        let out = dir.join(format!("{name}.npy"));
        let o = rfta(&[
            "-q",
            "sample",
            s(&input.join("gt.obj")),
            "--res",
            "20",
            "-o",
            s(&out),
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let ours = read_sdf(&out, None).expect("our grid");
        let reference = read_sdf(&input.join("sdf_n20.npy"), None).expect("reference grid");
        assert_eq!(ours.layout, reference.layout, "{name}: grid layout");
        let mut worst: f64 = 0.0;
        for (i, (a, b)) in ours.values.iter().zip(&reference.values).enumerate() {
            assert_eq!(
                a.signum(),
                b.signum(),
                "{name}: sign differs at sample {i}: {a} vs {b}"
            );
            worst = worst.max((a - b).abs());
        }
        assert!(worst <= 1e-9, "{name}: max deviation {worst}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn builtin_example_and_info() {
    let dir = temp("builtin");
    let npy = dir.join("torus.npy");
    let obj = dir.join("torus.obj");
    let o = rfta(&[
        "sample",
        "--shape",
        "torus",
        "--res",
        "12",
        "-o",
        s(&npy),
        "--save-mesh",
        s(&obj),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info = rfta(&["info", s(&obj)]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(
        text.contains("genus       1") && text.contains("watertight  yes"),
        "{text}"
    );
    let info = rfta(&["info", s(&npy)]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(
        text.contains("[13, 13, 13] points") && text.contains("valid       yes"),
        "{text}"
    );
    // Values agree with the analytic torus up to the tessellation's sagitta (256 x 128 segments):
    // at most 0.85 * (1 - cos(pi/256)) + 0.25 * (1 - cos(pi/128)) = 1.39e-4 (outer ring radius 0.85).
    let raw = read_sdf(&npy, None).expect("grid");
    let torus = rfta_testkit::Analytic::Torus {
        major: 0.6,
        minor: 0.25,
    };
    let grid = match raw.layout {
        rfta_geom::Layout::Grid(g) => g,
        other => panic!("expected a grid, got {other:?}"),
    };
    for (i, v) in raw.values.iter().enumerate() {
        let exact = torus.sdf(grid.position(i));
        assert!((v - exact).abs() < 1.4e-4, "sample {i}: {v} vs {exact}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn errors_are_one_clear_line_with_nonzero_status() {
    let dir = temp("errors");
    let bad = dir.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nf 1 2 3\n").expect("write");
    let cases: Vec<(Vec<String>, i32, &str)> = vec![
        (
            vec!["info".into(), s(&dir.join("missing.npy")).into()],
            1,
            "missing.npy: No such file",
        ),
        (
            vec![
                "sample".into(),
                s(&bad).into(),
                "--res".into(),
                "4".into(),
                "-o".into(),
                "x.npy".into(),
            ],
            1,
            "bad.obj: face 0 refers to vertex 1",
        ),
        (
            vec![
                "sample".into(),
                "--shape".into(),
                "box".into(),
                "--res".into(),
                "0".into(),
                "-o".into(),
                "x.npy".into(),
            ],
            1,
            "--res must be at least 1",
        ),
        (
            vec![
                "sample".into(),
                "--shape".into(),
                "box".into(),
                "--res".into(),
                "4".into(),
                "-o".into(),
                s(&dir.join("x.vtk")).into(),
            ],
            1,
            "x.vtk: unsupported file type",
        ),
        (
            vec![
                "sample".into(),
                "--shape".into(),
                "box".into(),
                "--res".into(),
                "4".into(),
                "--bounds".into(),
                "1,0".into(),
                "-o".into(),
                "x.npy".into(),
            ],
            2,
            "inverted",
        ),
    ];
    for (args, code, needle) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = rfta(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
        assert!(
            err.contains(needle),
            "{args:?}: '{err}' should contain '{needle}'"
        );
        if code == 1 {
            assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn sample_is_byte_identical_at_any_thread_count() {
    let dir = temp("threads");
    let out = |t: &str| {
        let path = dir.join(format!("t{t}.npy"));
        let o = rfta(&[
            "-q",
            "--threads",
            t,
            "sample",
            "--shape",
            "torus",
            "--res",
            "16",
            "-o",
            s(&path),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read(&path).expect("grid written")
    };
    let one = out("1");
    assert_eq!(one, out("2"));
    assert_eq!(one, out("3"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn psr_reconstructs_an_oriented_cloud_and_refuses_bad_ones() {
    let dir = temp("psr");
    // 3,000 points of the unit sphere (Fibonacci spiral) in the xyz + normals text format.
    let n = 3000;
    let mut text = String::new();
    for i in 0..n {
        let z = 1.0 - 2.0 * (f64::from(i) + 0.5) / f64::from(n);
        let r = (1.0 - z * z).sqrt();
        let phi = f64::from(i) * 2.399_963_229_728_653;
        let (x, y) = (r * phi.cos(), r * phi.sin());
        text += &format!("{x} {y} {z} {x} {y} {z}\n");
    }
    let cloud = dir.join("sphere.xyz");
    std::fs::write(&cloud, text).expect("write cloud");
    let out = dir.join("sphere.ply");
    let o = rfta(&[
        "psr",
        s(&cloud),
        "-o",
        s(&out),
        "--depth",
        "6",
        "--screen",
        "10",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mesh = rfta_io::read_mesh(&out).expect("mesh");
    let topo = rfta_mesh::Topology::of(&mesh);
    assert!(
        topo.is_watertight() && topo.is_manifold() && topo.components == 1,
        "{topo:?}"
    );
    let v = mesh.signed_volume();
    assert!((v - 4.18879).abs() < 0.05, "volume {v}");
    // Two points: a clear error, non-zero status, no output file.
    let two = dir.join("two.xyz");
    std::fs::write(&two, "0 0 0 0 0 1\n1 0 0 0 0 1\n").expect("write");
    let bad_out = dir.join("two.ply");
    let o = rfta(&["psr", s(&two), "-o", s(&bad_out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("at least 3"), "{}", stderr(&o));
    assert!(!bad_out.exists());
    // A zero normal is named with its index.
    let zero = dir.join("zero.xyz");
    std::fs::write(&zero, "0 0 0 0 0 1\n1 0 0 0 0 0\n0 1 0 0 0 1\n").expect("write");
    let o = rfta(&["psr", s(&zero), "-o", s(&bad_out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("normal"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn demo_reconstructs_the_genus_two_shape_better_than_marching_cubes() {
    let dir = temp("demo");
    let out = dir.join("demo.ply");
    let o = rfta(&["demo", "-o", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("marching cubes") && err.contains("watertight"),
        "{err}"
    );
    let mesh = rfta_io::read_mesh(&out).expect("mesh");
    let topo = rfta_mesh::Topology::of(&mesh);
    assert!(topo.is_watertight() && topo.is_manifold(), "{topo:?}");
    assert!(mesh.signed_volume() > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// 2D input is detected from the file: `reconstruct` and `mc` write polylines (`v x y 0`,
/// `l a b`), SVG and CSV; `demo --2d` writes one SVG with both curves.
#[test]
fn two_dimensional_input_gives_polylines() {
    let dir = temp("plane");
    let input = dir.join("disc.npy");
    // A disc of radius 0.5 on a 21 x 21 grid over [-1, 1]^2, S[i, j] at (x_i, y_j).
    let n = 21;
    let values: Vec<f64> = (0..n * n)
        .map(|k| {
            let (x, y) = (-1.0 + 0.1 * (k / n) as f64, -1.0 + 0.1 * (k % n) as f64);
            (x * x + y * y).sqrt() - 0.5
        })
        .collect();
    rfta_io::write_atomic(&input, |w| rfta_io::write_npy_f64(w, &[n, n], &values))
        .expect("write npy");
    for (cmd, out) in [("reconstruct", "curve.obj"), ("mc", "ms.obj")] {
        let out = dir.join(out);
        let o = rfta(&[cmd, s(&input), "-o", s(&out)]);
        assert!(o.status.success(), "{cmd}: {}", stderr(&o));
        let text = std::fs::read_to_string(&out).expect("written");
        let curve = rfta_io::read_polylines(&out).expect("polylines");
        assert_eq!(curve.loops(), 1, "{cmd}");
        assert!(curve.is_closed(), "{cmd}");
        assert!(text.lines().any(|l| l.starts_with("l ")));
        for v in text.lines().filter(|l| l.starts_with("v ")) {
            let f: Vec<f64> = v[2..]
                .split(' ')
                .map(|t| t.parse().expect("number"))
                .collect();
            assert_eq!(f.len(), 3);
            assert_eq!(f[2], 0.0);
            assert!(
                ((f[0] * f[0] + f[1] * f[1]).sqrt() - 0.5).abs() < 0.01,
                "{cmd}: {v}"
            );
        }
    }
    // The report `rfta batch` reads, and the points.
    let (report, points) = (dir.join("r.json"), dir.join("p.ply"));
    let o = rfta(&[
        "reconstruct",
        s(&input),
        "-o",
        s(&dir.join("again.obj")),
        "--report",
        s(&report),
        "--points",
        s(&points),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json = json(&report);
    assert_eq!(json["components"], 1);
    assert_eq!(json["watertight"], true);
    assert_eq!(json["samples"], 441);
    let cloud = rfta_io::read_oriented_points(&points).expect("points");
    assert!(cloud.len() > 10);
    for p in cloud.positions() {
        assert_eq!(p.z, 0.0);
        assert!((p.truncate().length() - 0.5).abs() < 0.01);
    }
    for ext in ["svg", "csv"] {
        let out = dir.join(format!("curve.{ext}"));
        let o = rfta(&["reconstruct", s(&input), "-o", s(&out)]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = std::fs::read_to_string(&out).expect("written");
        assert!(text.starts_with(if ext == "svg" { "<svg" } else { "x0,y0,x1,y1" }));
    }
    // `info` knows both.
    let o = rfta(&["info", s(&input)]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        text.contains("2D SDF samples") && text.contains("21 x 21"),
        "{text}"
    );
    let o = rfta(&["info", s(&dir.join("curve.obj"))]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(text.contains("1 (closed, inside on the left)"), "{text}");
    // A mesh extension is refused for 2D input, before any work.
    let o = rfta(&["reconstruct", s(&input), "-o", s(&dir.join("x.ply"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("write .obj, .svg or .csv"),
        "{}",
        stderr(&o)
    );
    let demo = dir.join("demo.svg");
    let o = rfta(&["demo", "--2d", "-o", s(&demo)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(&demo).expect("svg");
    assert_eq!(svg.matches("<path").count(), 2, "both curves drawn");
    assert!(stderr(&o).contains("marching squares"));
}

/// Every command that writes a mesh or a curve writes none with a vertex that no face or edge
/// uses: 3D reconstruct in each mesh format and with a genus, marching cubes, psr, demo, the
/// sampled shape's mesh, batch; 2D reconstruct (over coarse grids where loops get removed) and
/// marching squares.
#[test]
fn no_output_has_an_unreferenced_vertex() {
    let dir = temp("unreferenced");
    let npy = dir.join("torus.npy");
    let shape = dir.join("shape.obj");
    let o = rfta(&[
        "-q",
        "sample",
        "--shape",
        "torus",
        "--res",
        "14",
        "-o",
        s(&npy),
        "--save-mesh",
        s(&shape),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let points = dir.join("points.ply");
    let mut meshes = vec![shape];
    for (i, args) in [
        vec!["reconstruct", s(&npy), "--points", s(&points)],
        vec!["reconstruct", s(&npy), "--genus", "1"],
        vec!["mc", s(&npy)],
        vec!["demo"],
    ]
    .iter()
    .enumerate()
    {
        for ext in ["obj", "ply", "stl", "glb"] {
            let out = dir.join(format!("out{i}.{ext}"));
            let mut args = args.clone();
            args.extend(["-o", s(&out)]);
            let o = rfta(&args);
            assert!(o.status.success(), "{args:?}: {}", stderr(&o));
            meshes.push(out);
        }
    }
    let psr = dir.join("psr.obj");
    let o = rfta(&["psr", s(&points), "-o", s(&psr), "--preset", "rfta"]);
    assert!(o.status.success(), "{}", stderr(&o));
    meshes.push(psr);
    let manifest = dir.join("manifest.csv");
    let batch_out = dir.join("batch.obj");
    std::fs::write(
        &manifest,
        format!("input,output\n{},{}\n", s(&npy), s(&batch_out)),
    )
    .expect("manifest");
    let o = rfta(&["-q", "batch", s(&manifest)]);
    assert!(o.status.success(), "{}", stderr(&o));
    meshes.push(batch_out);
    for path in &meshes {
        let mesh = rfta_io::read_mesh(path).expect("mesh");
        assert!(!mesh.is_empty(), "{}", path.display());
        assert_eq!(mesh.unreferenced_vertices(), 0, "{}", path.display());
    }
    // 2D: a ring 0.24 wide around the circle of radius 0.5 on coarse grids with gpytoolbox's three rounds, where screened Poisson
    // leaves small loops that the island rule removes.
    let mut removed = 0;
    for n in 6..=14usize {
        let k = n + 1;
        let values: Vec<f64> = (0..k * k)
            .map(|i| {
                let step = 2.0 / n as f64;
                let (x, y) = (-1.0 + step * (i / k) as f64, -1.0 + step * (i % k) as f64);
                (x.hypot(y) - 0.5).abs() - 0.12
            })
            .collect();
        let input = dir.join(format!("ring{n}.npy"));
        rfta_io::write_atomic(&input, |w| rfta_io::write_npy_f64(w, &[k, k], &values))
            .expect("write npy");
        let (curve, ms, report) = (dir.join("c.obj"), dir.join("ms.obj"), dir.join("r.json"));
        let o = rfta(&[
            "reconstruct",
            s(&input),
            "-o",
            s(&curve),
            "--iters",
            "3",
            "--report",
            s(&report),
        ]);
        assert!(o.status.success(), "n = {n}: {}", stderr(&o));
        let o = rfta(&["mc", s(&input), "-o", s(&ms)]);
        assert!(o.status.success(), "n = {n}: {}", stderr(&o));
        for path in [&curve, &ms] {
            let lines = rfta_io::read_polylines(path).expect("polylines");
            assert_eq!(
                lines.unreferenced_vertices(),
                0,
                "n = {n}: {}",
                path.display()
            );
        }
        let json = json(&report);
        removed += json["islands_removed"].as_u64().expect("islands_removed");
    }
    assert!(
        removed > 0,
        "no loop was removed: the 2D sweep tests nothing"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--initial raster` reaches the pipeline: on a grid the default takes the empty space from the
/// samples' gradients (no raster: resolution 0 in the report), the paper's rasterizes it.
#[test]
fn initial_points_from_the_gradients_or_the_raster() {
    let dir = temp("initial");
    let npy = dir.join("t.npy");
    let o = rfta(&["sample", "--shape", "torus", "--res", "12", "-o", s(&npy)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let resolution = |extra: &[&str]| {
        let (mesh, report) = (dir.join("m.ply"), dir.join("r.json"));
        let mut args = vec![
            "-q",
            "reconstruct",
            s(&npy),
            "-o",
            s(&mesh),
            "--report",
            s(&report),
        ];
        args.extend_from_slice(extra);
        let o = rfta(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let r = json(&report);
        r["raster_resolution"].as_u64().expect("a figure")
    };
    assert_eq!(resolution(&[]), 0);
    assert_eq!(resolution(&["--initial", "gradient"]), 0);
    assert!(resolution(&["--initial", "raster"]) >= 64);
    let _ = std::fs::remove_dir_all(&dir);
}
