//! `rfta batch`: shards run as concurrent processes, a killed shard resumed, a timeout, and the
//! job-array recipes of docs/batch.md checked by their shard arithmetic.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use common::{command, rfta, s, stderr, temp};
use rfta_geom::Grid;
use rfta_geom::glam::DVec3;

/// A torus (radii 0.5 and `tube`) sampled on an `(n+1)^3` grid over [-1, 1]^3.
fn torus_grid(path: &Path, n: usize, tube: f64) {
    let grid = Grid::cube(n, -1.0, 1.0).expect("grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| {
            let p: DVec3 = grid.position(i);
            let ring = (p.x * p.x + p.y * p.y).sqrt() - 0.5;
            (ring * ring + p.z * p.z).sqrt() - tube
        })
        .collect();
    rfta_io::write_sdf_grid(path, &grid, &values).expect("write grid");
}

/// A grid whose every value is positive and large: no surface.
fn empty_grid(path: &Path) {
    let grid = Grid::cube(6, -1.0, 1.0).expect("grid");
    rfta_io::write_sdf_grid(path, &grid, &vec![3.0; grid.len()]).expect("write grid");
}

/// The rows of a status CSV as `row -> (status, output)`, each row's last record (a rerun
/// appends after the rows it redoes or skips); panics on a row seen twice unless `reruns`.
fn status_rows(path: &Path) -> BTreeMap<usize, (String, String)> {
    records(path, false)
}

fn records(path: &Path, reruns: bool) -> BTreeMap<usize, (String, String)> {
    let text = std::fs::read_to_string(path).expect("status file");
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).expect("column");
    let (row, out, status) = (col("row"), col("output"), col("status"));
    let mut rows = BTreeMap::new();
    for l in lines {
        // The rows checked here have no quoted fields before the status column.
        let f: Vec<&str> = l.split(',').collect();
        let r: usize = f[row].parse().expect("row number");
        let prev = rows.insert(r, (f[status].to_string(), f[out].to_string()));
        assert!(
            reruns || prev.is_none(),
            "{}: row {r} recorded twice",
            path.display()
        );
    }
    rows
}

/// `rfta reconstruct` of `input` as one would run it by hand, for comparison.
fn reference(input: &Path, output: &Path) -> Vec<u8> {
    let o = rfta(&["-q", "reconstruct", s(input), "-o", s(output)]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::read(output).expect("reference mesh")
}

/// Three shards of a manifest with a corrupt row and a no-surface row, run at the same time as
/// separate processes: every good row's mesh is byte for byte `rfta reconstruct`'s, every row is
/// recorded once by the shard that owns it, and the merged table has each row once with the
/// right status.
#[test]
fn three_concurrent_shards_do_every_row_once() {
    let dir = temp("shards");
    let mut manifest = String::from("input,output\n");
    let mut good = Vec::new();
    for (i, tube) in [0.2, 0.25, 0.3, 0.22, 0.28, 0.18].iter().enumerate() {
        let name = format!("t{i}.npy");
        torus_grid(&dir.join(&name), 10, *tube);
        manifest += &format!("{name},out/t{i}.ply\n");
        good.push(i);
    }
    std::fs::write(dir.join("corrupt.npy"), b"\x93NUMPY garbage").expect("write");
    manifest += "corrupt.npy,out/corrupt.ply\n";
    empty_grid(&dir.join("empty.npy"));
    manifest += "empty.npy,out/empty.ply\n";
    std::fs::write(dir.join("m.csv"), manifest).expect("manifest");

    let children: Vec<_> = (0..3)
        .map(|i| {
            command()
                .args(["-q", "--threads", "1", "batch"])
                .arg(dir.join("m.csv"))
                .args(["--shard", &format!("{i}/3")])
                .stderr(Stdio::piped())
                .spawn()
                .expect("start a shard")
        })
        .collect();
    let codes: Vec<Option<i32>> = children
        .into_iter()
        .map(|c| c.wait_with_output().expect("shard").status.code())
        .collect();
    // Rows 0..8: shard 0 has 0, 3, 6 (the corrupt row), shard 1 has 1, 4, 7 (no surface: not a
    // failure), shard 2 has 2, 5.
    assert_eq!(codes, [Some(4), Some(0), Some(0)]);

    let mut all = BTreeMap::new();
    for i in 0..3 {
        let rows = status_rows(&dir.join(format!("m.shard-{i}-of-3.status.csv")));
        for (&r, v) in &rows {
            assert_eq!(r % 3, i, "row {r} in shard {i}'s status");
            assert!(all.insert(r, v.clone()).is_none(), "row {r} done twice");
        }
    }
    assert_eq!(
        all.keys().copied().collect::<Vec<_>>(),
        (0..8).collect::<Vec<_>>()
    );
    for &i in &good {
        assert_eq!(all[&i].0, "ok", "row {i}");
        let ours = std::fs::read(dir.join(format!("out/t{i}.ply"))).expect("batch output");
        let by_hand = reference(
            &dir.join(format!("t{i}.npy")),
            &dir.join(format!("ref{i}.ply")),
        );
        assert!(
            ours == by_hand,
            "row {i}: batch and reconstruct meshes differ"
        );
    }
    assert_eq!(all[&6].0, "failed");
    assert_eq!(all[&7].0, "no_surface");
    assert!(!dir.join("out/corrupt.ply").exists());

    let merged = dir.join("merged.csv");
    let shards: Vec<PathBuf> = (0..3)
        .map(|i| dir.join(format!("m.shard-{i}-of-3.status.csv")))
        .collect();
    let mut args = vec!["batch", "--status", s(&merged), "--merge"];
    args.extend(shards.iter().map(|p| s(p)));
    let o = rfta(&args);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("| ok | 6 |"), "{table}");
    assert!(table.contains("| failed | 1 |"), "{table}");
    assert!(table.contains("| no_surface | 1 |"), "{table}");
    assert!(table.contains("| all | 8 |"), "{table}");
    assert_eq!(status_rows(&merged), all);
}

/// A shard killed while it works, run again, finishes the rest: the rows recorded before the kill
/// are skipped (their outputs kept), the others done, each recorded once, every mesh as
/// `rfta reconstruct` writes it.
#[test]
fn a_killed_shard_resumes() {
    let dir = temp("resume");
    let mut manifest = String::from("input,output\n");
    let rows = 5;
    for i in 0..rows {
        torus_grid(&dir.join(format!("t{i}.npy")), 16, 0.2 + 0.02 * i as f64);
        manifest += &format!("t{i}.npy,out/t{i}.ply\n");
    }
    let m = dir.join("m.csv");
    std::fs::write(&m, manifest).expect("manifest");
    let status = dir.join("m.shard-0-of-1.status.csv");

    let mut child = command()
        .args(["-q", "--threads", "1", "batch"])
        .arg(&m)
        .stderr(Stdio::null())
        .spawn()
        .expect("start");
    // Kill it once the first row is recorded.
    let t = Instant::now();
    while std::fs::read_to_string(&status).map_or(0, |t| t.lines().count()) < 2 {
        assert!(t.elapsed() < Duration::from_secs(120), "no row finished");
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let _ = child.kill();
    let _ = child.wait();
    let before = status_rows(&status);
    assert!(
        !before.is_empty() && before.len() < rows,
        "the kill should land mid-batch: {before:?}"
    );

    let o = rfta(&["-q", "--threads", "1", "batch", s(&m)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let after = records(&status, true);
    assert_eq!(after.len(), rows);
    for (r, (st, _)) in &after {
        let expected = if before.contains_key(r) {
            "skipped"
        } else {
            "ok"
        };
        assert_eq!(st, expected, "row {r}");
        let ours = std::fs::read(dir.join(format!("out/t{r}.ply"))).expect("output");
        let by_hand = reference(
            &dir.join(format!("t{r}.npy")),
            &dir.join(format!("ref{r}.ply")),
        );
        assert!(ours == by_hand, "row {r}: mesh differs from reconstruct's");
    }
    // No temporary file of an interrupted write is left beside the outputs.
    let leftovers: Vec<_> = std::fs::read_dir(dir.join("out"))
        .expect("out")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.len() <= 1, "{leftovers:?}");
}

/// A row slower than --timeout ends as `timeout`, the batch goes on to the next row and exits
/// with the failure status.
#[test]
fn the_timeout_stops_a_slow_row() {
    let dir = temp("timeout");
    // The paper's setting (20 rounds, 30 points per sphere) on a 41^3 grid takes tens of seconds.
    torus_grid(&dir.join("slow.npy"), 40, 0.2);
    torus_grid(&dir.join("fast.npy"), 5, 0.3);
    std::fs::write(
        dir.join("m.csv"),
        "input,output,preset\nslow.npy,slow.ply,paper\nfast.npy,fast.ply,fast\n",
    )
    .expect("manifest");
    let t = Instant::now();
    let o = rfta(&["-q", "batch", s(&dir.join("m.csv")), "--timeout", "3"]);
    let took = t.elapsed();
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(took < Duration::from_secs(60), "took {took:?}");
    let rows = status_rows(&dir.join("m.shard-0-of-1.status.csv"));
    assert_eq!(rows[&0].0, "timeout");
    assert_eq!(rows[&1].0, "ok");
    assert!(!dir.join("slow.ply").exists());
    assert!(dir.join("fast.ply").exists());
}

/// The Slurm and Kubernetes recipes of docs/batch.md: every task's `--shard` argument, formed as
/// the scheduler sets the variables, takes its rows, and the tasks together take every row once.
#[test]
fn the_job_array_recipes_cover_the_manifest() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/batch.md"))
            .expect("docs/batch.md");
    let dir = temp("recipes");
    let rows = 23;
    let mut manifest = String::from("input,output\n");
    for i in 0..rows {
        manifest += &format!("in{i}.npy,out{i}.ply\n");
    }
    let m = dir.join("m.csv");
    std::fs::write(&m, manifest).expect("manifest");

    // Slurm: `#SBATCH --array=0-K` gives tasks 0..=K with SLURM_ARRAY_TASK_COUNT = K + 1.
    let array = doc
        .lines()
        .find_map(|l| l.trim().strip_prefix("#SBATCH --array=0-"))
        .expect("an #SBATCH --array=0-K line");
    let last: usize = array
        .split(|c: char| !c.is_ascii_digit())
        .next()
        .and_then(|d| d.parse().ok())
        .expect("the array's last index");
    assert!(doc.contains("--shard \"$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT\""));
    let slurm: Vec<String> = (0..=last).map(|id| format!("{id}/{}", last + 1)).collect();

    // Kubernetes: `completions: K` with `completionMode: Indexed` gives JOB_COMPLETION_INDEX 0..K.
    let completions: usize = doc
        .lines()
        .find_map(|l| l.trim().strip_prefix("completions:"))
        .and_then(|v| v.trim().parse().ok())
        .expect("a completions: K line");
    assert!(doc.contains("completionMode: Indexed"));
    let shard_arg = format!("\"$(JOB_COMPLETION_INDEX)/{completions}\"");
    assert!(doc.contains(&shard_arg), "expected --shard {shard_arg}");
    let k8s: Vec<String> = (0..completions)
        .map(|id| format!("{id}/{completions}"))
        .collect();

    for (name, shards) in [("slurm", slurm), ("kubernetes", k8s)] {
        let mut seen = vec![0; rows];
        for shard in &shards {
            let o = rfta(&["batch", s(&m), "--shard", shard, "--dry-run"]);
            assert!(o.status.success(), "{name} {shard}: {}", stderr(&o));
            for line in String::from_utf8_lossy(&o.stdout).lines() {
                let row: usize = line
                    .split(',')
                    .next()
                    .and_then(|r| r.parse().ok())
                    .expect("row");
                seen[row] += 1;
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "{name}: rows taken {seen:?}");
    }
}
