//! `cargo xtask slurm`: docs/batch.md's Slurm job-array script, unchanged, on a real one-node
//! Slurm cluster started on this machine (Debian's `slurm-wlm` and `munge`; root).
//!
//! 1. munged (when none answers), slurmctld and slurmd start with a configuration of their own
//!    under `<out>/cluster` (one node, 8 CPUs and 16 GB declared, so that the script's 8 tasks of
//!    4 CPUs and 8 GB are accepted; `OverSubscribe`).
//! 2. A manifest of the dev grids (`../shared/data/inputs/*/sdf_n10.npy`) and one corrupt grid;
//!    `sbatch --wait` of the script taken from docs/batch.md; `rfta batch --merge` of the shards.
//!    Every good row's output must equal, byte for byte, what `rfta reconstruct` writes for it;
//!    the corrupt row must be `failed`, and the merge exit with 4.
//! 3. The same script on the N = 30 grids: one array task is cancelled (`scancel JOB_0`) while it
//!    runs a row; the job is submitted again and must finish every row, each output equal to
//!    `rfta reconstruct`'s, the cancelled shard's finished rows kept as `skipped`.
//!
//! Skipped with a message where the Slurm or munge programs are missing, except under CI.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};

/// The programs the test needs.
const PROGRAMS: [&str; 6] = [
    "slurmctld",
    "slurmd",
    "munged",
    "sbatch",
    "squeue",
    "scancel",
];

pub(crate) fn run(root: &Path, args: &[String]) -> Result<()> {
    let missing: Vec<&str> = PROGRAMS
        .into_iter()
        .filter(|p| which(p).is_none())
        .collect();
    if !missing.is_empty() {
        if std::env::var_os("CI").is_some() {
            bail!(
                "Slurm is not installed ({} missing): apt-get install slurm-wlm munge",
                missing.join(", ")
            );
        }
        crate::skipped(format!(
            "the Slurm test: {} not installed",
            missing.join(", ")
        ));
        return Ok(());
    }
    let target = crate::target_dir(root);
    let out = match args {
        [flag, dir] if flag == "--out" => PathBuf::from(dir),
        [] => target.join("slurm"),
        _ => bail!("usage: cargo xtask slurm [--out DIR]"),
    };
    let rfta = target.join("debug").join("rfta");
    if !rfta.is_file() {
        bail!("{} not built: cargo build -p rfta-cli", rfta.display());
    }
    let inputs = rfta_testkit::data_dir()
        .context("../shared/data not found")?
        .join("inputs");
    let script = job_script(root)?;
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out)?;
    let cluster = Cluster::start(&out.join("cluster"))?;
    let started = Instant::now();
    let result = (|| {
        let run = Run {
            cluster: &cluster,
            inputs: &inputs,
            rfta: &rfta,
            script: &script,
        };
        run.first(&out.join("grids"))?;
        run.cancelled(&out.join("cancel"))
    })();
    drop(cluster);
    result?;
    println!(
        "slurm: both runs passed in {:.0} s",
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

fn which(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .chain(["/usr/sbin".into(), "/sbin".into()])
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

/// The `sh` block under "## Slurm job array" in docs/batch.md, as it is.
fn job_script(root: &Path) -> Result<String> {
    let doc = std::fs::read_to_string(root.join("docs/batch.md"))?;
    let section = doc
        .split("## Slurm job array")
        .nth(1)
        .context("docs/batch.md has no Slurm job array section")?;
    let block = section
        .split("```sh\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .context("the Slurm section has no sh block")?;
    Ok(block.to_string())
}

/// A one-node cluster; stopped when dropped.
struct Cluster {
    conf: PathBuf,
    daemons: Vec<Child>,
}

impl Cluster {
    fn start(dir: &Path) -> Result<Self> {
        for sub in ["state", "spool", "log"] {
            std::fs::create_dir_all(dir.join(sub))?;
        }
        let host = String::from_utf8(Command::new("hostname").arg("-s").output()?.stdout)?
            .trim()
            .to_string();
        let d = dir.display();
        let conf = dir.join("slurm.conf");
        std::fs::write(
            &conf,
            format!(
                "ClusterName=rfta\nSlurmctldHost={host}\nSlurmUser=root\nSlurmdUser=root\n\
                 AuthType=auth/munge\nStateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\n\
                 SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\n\
                 SlurmctldLogFile={d}/log/slurmctld.log\nSlurmdLogFile={d}/log/slurmd.log\n\
                 ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
                 SchedulerType=sched/backfill\nSelectType=select/cons_tres\n\
                 SelectTypeParameters=CR_Core\nReturnToService=2\n\
                 SlurmdParameters=config_overrides\nMpiDefault=none\n\
                 JobAcctGatherType=jobacct_gather/none\n\
                 AccountingStorageType=accounting_storage/none\n\
                 NodeName={host} CPUs=8 RealMemory=16000 State=UNKNOWN\n\
                 PartitionName=main Nodes={host} Default=YES MaxTime=INFINITE State=UP \
                 OverSubscribe=YES\n"
            ),
        )?;
        let mut cluster = Self {
            conf,
            daemons: Vec::new(),
        };
        cluster.munge()?;
        for daemon in ["slurmctld", "slurmd"] {
            let log = std::fs::File::create(dir.join(format!("log/{daemon}.out")))?;
            let child = Command::new(which(daemon).context(daemon)?)
                .args(["-D", "-f"])
                .arg(&cluster.conf)
                .env("SLURM_CONF", &cluster.conf)
                .stdout(log.try_clone()?)
                .stderr(log)
                .spawn()
                .with_context(|| format!("cannot start {daemon}"))?;
            cluster.daemons.push(child);
            std::thread::sleep(Duration::from_secs(2));
        }
        // Ready when the node is idle.
        let t = Instant::now();
        loop {
            let o = cluster.command("sinfo").args(["-h", "-o", "%t"]).output()?;
            if String::from_utf8_lossy(&o.stdout).contains("idle") {
                return Ok(cluster);
            }
            if t.elapsed() > Duration::from_secs(60) {
                bail!(
                    "the Slurm node did not come up in 60 s; logs in {}",
                    dir.join("log").display()
                );
            }
            std::thread::sleep(Duration::from_millis(500));
        }
    }

    /// munged, with a key of its own, unless one answers already.
    fn munge(&mut self) -> Result<()> {
        let answers = || {
            Command::new("sh")
                .args(["-c", "munge -n | unmunge"])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        };
        if answers() {
            return Ok(());
        }
        let key = Path::new("/etc/munge/munge.key");
        if !key.is_file() {
            let status = Command::new("sh")
                .args([
                    "-c",
                    "mkdir -p /etc/munge && dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null && chmod 400 /etc/munge/munge.key",
                ])
                .status()?;
            if !status.success() {
                bail!("cannot write a munge key");
            }
        }
        for d in ["/run/munge", "/var/log/munge", "/var/lib/munge"] {
            std::fs::create_dir_all(d)?;
        }
        let status = Command::new(which("munged").context("munged")?)
            .arg("--force")
            .status()?;
        if !status.success() || !answers() {
            bail!("munged did not start");
        }
        Ok(())
    }

    /// A Slurm client command against this cluster.
    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// Submits `script` from `dir` with `rfta` on the PATH; returns the job id.
    fn submit(&self, dir: &Path, script: &Path, rfta: &Path, wait: bool) -> Result<String> {
        let path = format!(
            "{}:{}",
            rfta.parent()
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            std::env::var("PATH").unwrap_or_default()
        );
        let mut c = self.command("sbatch");
        c.arg("--parsable")
            .arg(format!("--chdir={}", dir.display()))
            .arg(format!("--output={}/slurm-%A_%a.out", dir.display()));
        if wait {
            c.arg("--wait");
        }
        let o = c.arg(script).env("PATH", path).output()?;
        let id = String::from_utf8_lossy(&o.stdout).trim().to_string();
        if id.is_empty() {
            bail!("sbatch: {}", String::from_utf8_lossy(&o.stderr));
        }
        Ok(id.split(';').next().unwrap_or_default().to_string())
    }

    /// Waits until no task of job `id` is pending or running.
    fn wait(&self, id: &str, limit: Duration) -> Result<()> {
        let t = Instant::now();
        while t.elapsed() < limit {
            let o = self
                .command("squeue")
                .args(["-h", "-j", id, "-o", "%i"])
                .output()?;
            if String::from_utf8_lossy(&o.stdout).trim().is_empty() {
                return Ok(());
            }
            std::thread::sleep(Duration::from_millis(500));
        }
        bail!("job {id} still running after {} s", limit.as_secs())
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for child in self.daemons.iter_mut().rev() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// `shapes/` with one grid per dev shape at resolution `n` (copied) and, with `corrupt`, one
/// that is not an `.npy`; the manifest lists them in name order. Returns the manifest's rows
/// (input, output).
fn shapes(dir: &Path, inputs: &Path, n: usize, corrupt: bool) -> Result<Vec<(String, String)>> {
    let shapes = dir.join("shapes");
    std::fs::create_dir_all(&shapes)?;
    let mut names: Vec<String> = std::fs::read_dir(inputs)?
        .filter_map(|e| e.ok())
        .filter(|e| e.path().join(format!("sdf_n{n}.npy")).is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut rows = Vec::new();
    for name in &names {
        std::fs::copy(
            inputs.join(name).join(format!("sdf_n{n}.npy")),
            shapes.join(format!("{name}.npy")),
        )?;
        rows.push((format!("{name}.npy"), format!("meshes/{name}.ply")));
    }
    if corrupt {
        std::fs::write(shapes.join("corrupt.npy"), b"\x93NUMPY this is not a grid")?;
        rows.push(("corrupt.npy".into(), "meshes/corrupt.ply".into()));
    }
    let mut manifest = String::from("input,output\n");
    for (i, o) in &rows {
        manifest.push_str(&format!("{i},{o}\n"));
    }
    std::fs::write(shapes.join("manifest.csv"), manifest)?;
    Ok(rows)
}

/// Every good row's output equals `rfta reconstruct`'s of its input.
fn same_as_reconstruct(dir: &Path, rfta: &Path, rows: &[(String, String)]) -> Result<()> {
    let shapes = dir.join("shapes");
    let reference = dir.join("reference");
    std::fs::create_dir_all(&reference)?;
    for (input, output) in rows.iter().filter(|(i, _)| i != "corrupt.npy") {
        let expect = reference.join(input.replace(".npy", ".ply"));
        let status = Command::new(rfta)
            .args(["-q", "reconstruct"])
            .arg(shapes.join(input))
            .arg("-o")
            .arg(&expect)
            .status()?;
        if !status.success() {
            bail!("rfta reconstruct {input} failed");
        }
        let got = std::fs::read(shapes.join(output))
            .with_context(|| format!("row {input}: no output {output}"))?;
        if got != std::fs::read(&expect)? {
            bail!("row {input}: the batch's {output} differs from rfta reconstruct's");
        }
    }
    Ok(())
}

/// The merged status table of the shards in `dir/shapes`: (input, status) per row, and the
/// merge's exit code.
fn merged(dir: &Path, rfta: &Path) -> Result<(Vec<(String, String)>, i32)> {
    let shapes = dir.join("shapes");
    let mut shards: Vec<PathBuf> = std::fs::read_dir(&shapes)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.to_string_lossy().ends_with(".status.csv"))
        .collect();
    shards.sort();
    let table = dir.join("merged.csv");
    let o = Command::new(rfta)
        .args(["-q", "batch", "--merge"])
        .args(&shards)
        .arg("--status")
        .arg(&table)
        .output()?;
    let text = std::fs::read_to_string(&table).context("the merged table")?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let (i, s) = (
        col("input").context("input")?,
        col("status").context("status")?,
    );
    let rows = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f.get(i).copied().unwrap_or_default().to_string(),
                f.get(s).copied().unwrap_or_default().to_string(),
            )
        })
        .collect();
    Ok((rows, o.status.code().unwrap_or(-1)))
}

/// What both runs use: the cluster, the dev grids, the binary, the job script.
struct Run<'a> {
    cluster: &'a Cluster,
    inputs: &'a Path,
    rfta: &'a Path,
    script: &'a str,
}

impl Run<'_> {
    /// `dir` with the grids of resolution `n` (and a corrupt one) under `shapes/`, their manifest
    /// and the job script; the manifest's rows and the script's path.
    fn prepare(
        &self,
        dir: &Path,
        n: usize,
        corrupt: bool,
    ) -> Result<(Vec<(String, String)>, PathBuf)> {
        let rows = shapes(dir, self.inputs, n, corrupt)?;
        let file = dir.join("rfta-array.sh");
        std::fs::write(&file, self.script)?;
        Ok((rows, file))
    }

    fn first(&self, dir: &Path) -> Result<()> {
        let (cluster, rfta) = (self.cluster, self.rfta);
        let (rows, file) = self.prepare(dir, 10, true)?;
        let t = Instant::now();
        let id = cluster.submit(dir, &file, rfta, true)?;
        cluster.wait(&id, Duration::from_secs(600))?;
        let (table, code) = merged(dir, rfta)?;
        println!(
            "slurm: job {id}, {} rows over 8 array tasks, {:.0} s",
            rows.len(),
            t.elapsed().as_secs_f64()
        );
        if table.len() != rows.len() {
            bail!(
                "the merged table has {} rows, the manifest {}",
                table.len(),
                rows.len()
            );
        }
        for (input, status) in &table {
            let expect = if input == "corrupt.npy" {
                "failed"
            } else {
                "ok"
            };
            if status != expect {
                bail!("row {input}: {status}, expected {expect}");
            }
        }
        if code != 4 {
            bail!("the merge exited with {code}, expected 4 (a failed row)");
        }
        same_as_reconstruct(dir, rfta, &rows)
    }

    fn cancelled(&self, dir: &Path) -> Result<()> {
        let (cluster, rfta) = (self.cluster, self.rfta);
        let (rows, file) = self.prepare(dir, 30, false)?;
        let id = cluster.submit(dir, &file, rfta, false)?;
        // Task 0 is cancelled once its shard has a status file (it runs its row).
        let status = dir.join("shapes/manifest.shard-0-of-8.status.csv");
        let t = Instant::now();
        while !status.exists() {
            if t.elapsed() > Duration::from_secs(120) {
                bail!("task 0 of job {id} did not start in 120 s");
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let o = cluster.command("scancel").arg(format!("{id}_0")).output()?;
        if !o.status.success() {
            bail!("scancel: {}", String::from_utf8_lossy(&o.stderr));
        }
        cluster.wait(&id, Duration::from_secs(600))?;
        let (before, _) = merged(dir, rfta)?;
        let unfinished = rows.len() - before.iter().filter(|(_, s)| s == "ok").count();
        if unfinished == 0 {
            bail!("the cancelled task finished its row anyway: nothing left to resume");
        }
        let again = cluster.submit(dir, &file, rfta, true)?;
        cluster.wait(&again, Duration::from_secs(600))?;
        let (table, code) = merged(dir, rfta)?;
        println!(
            "slurm: job {id} with task 0 cancelled ({unfinished} row(s) left), job {again} resumed"
        );
        if table.len() != rows.len() || table.iter().any(|(_, s)| s != "ok" && s != "skipped") {
            bail!("after the resubmission: {table:?}");
        }
        if code != 0 {
            bail!("the merge exited with {code}");
        }
        same_as_reconstruct(dir, rfta, &rows)
    }
}
