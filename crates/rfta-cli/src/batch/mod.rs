//! `rfta batch`: `rfta reconstruct` over the rows of a manifest, one shard of it per task of a
//! job array (Slurm, Kubernetes Indexed Jobs; docs/batch.md).
//!
//! Each row runs as a child `rfta reconstruct` process, so that a row's timeout can stop it, a
//! row that crashes stops nothing else, and every output is the mesh `rfta reconstruct` writes.
//! Rows are recorded in the shard's status file as they finish (appended and synced), so a killed
//! shard loses only the rows it was running; a rerun skips the rows whose status says `ok` (or
//! `skipped`) and whose output exists, and runs the others again.

use std::collections::{HashMap, HashSet};
use std::fs::File;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};

use crate::reconstruct::{Checks, Preset, Tuning};
use crate::ui::{Exit, Ui, parse_bounds};

#[derive(Debug, clap::Args)]
pub(crate) struct Args {
    /// The manifest: CSV with a header and columns `input,output`, optionally `bounds` (6 numbers,
    /// quoted or separated by spaces), `clamp` and `preset` (default, paper, fast), which override
    /// the options below for their row. Paths are relative to the manifest's folder.
    #[arg(required_unless_present = "merge")]
    manifest: Option<PathBuf>,
    /// Take shard I of N (I from 0): rows I, I+N, I+2N, ... of the manifest.
    #[arg(long, value_name = "I/N", value_parser = parse_shard, default_value = "0/1")]
    shard: Shard,
    /// Rows at once; the threads (--threads, default all cores) are split between them.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
    jobs: u32,
    /// Stop a row after this many seconds (status `timeout`); the others go on.
    #[arg(long, value_name = "SECS", value_parser = parse_seconds)]
    timeout: Option<Duration>,
    /// The shard's status CSV (default: beside the manifest, MANIFEST.shard-I-of-N.status.csv).
    /// With --merge: where the merged table goes (default: merged.status.csv beside the first).
    #[arg(long, value_name = "FILE")]
    status: Option<PathBuf>,
    /// List the rows this shard would run, run nothing.
    #[arg(long)]
    dry_run: bool,
    /// Join these status files (of the shards of one manifest) into one table and print totals.
    #[arg(long, value_name = "STATUS", num_args = 1.., conflicts_with_all = ["manifest", "dry_run"])]
    merge: Vec<PathBuf>,
    /// Every row's input options, as `reconstruct`'s.
    #[command(flatten)]
    checks: Checks,
    #[command(flatten)]
    tuning: Tuning,
}

/// Shard `index` of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Shard {
    index: usize,
    count: usize,
}

impl Shard {
    /// Whether manifest row `row` (0-based, header excluded) belongs to this shard.
    fn takes(self, row: usize) -> bool {
        row % self.count == self.index
    }
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("'{s}': expected I/N, e.g. 0/4"))?;
    let parse = |t: &str| {
        t.trim()
            .parse::<usize>()
            .map_err(|_| format!("'{s}': '{t}' is not a whole number"))
    };
    let (index, count) = (parse(i)?, parse(n)?);
    if count == 0 || index >= count {
        return Err(format!(
            "'{s}': the shard index must be below the shard count (0 <= I < N)"
        ));
    }
    Ok(Shard { index, count })
}

/// A positive number of seconds that a [`Duration`] holds (up to about 5.8e11 years; 1e20 s
/// does not fit, and converting it panicked: hostile test D8).
fn parse_seconds(s: &str) -> Result<Duration, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Duration::try_from_secs_f64(v)
            .map_err(|_| format!("'{s}' seconds is longer than a timeout can be")),
        _ => Err(format!("'{s}' is not a positive number of seconds")),
    }
}

mod manifest;
mod runner;
mod status;

use manifest::*;
use runner::*;
use status::*;

pub(crate) fn run(args: Args, threads: usize, ui: &Ui) -> Result<()> {
    if !args.merge.is_empty() {
        return merge(&args.merge, args.status.as_deref());
    }
    let Some(manifest) = args.manifest.as_deref() else {
        bail!("give a manifest, or --merge STATUS...");
    };
    let (base, status_path, jobs) = shard_rows(&args, manifest)?;
    let base = base.as_path();
    if args.dry_run {
        for j in &jobs {
            crate::ui::print_line(&format!("{},{},{}", j.row, j.input, j.output))?;
        }
        return Ok(());
    }
    run_rows(&args, threads, ui, base, &status_path, &jobs)
}

/// The manifest's folder, the shard's status file and the shard's rows, once every row's files
/// are checked (whichever shard runs it: two rows writing one output, or an output that is an
/// input, the manifest or the status file, would lose data).
fn shard_rows(args: &Args, manifest: &Path) -> Result<(PathBuf, PathBuf, Vec<Job>)> {
    let base = manifest
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let all = read_manifest(manifest)?;
    let status_path = args.status.clone().unwrap_or_else(|| {
        let stem = manifest
            .file_stem()
            .map_or("manifest".into(), |s| s.to_string_lossy().into_owned());
        base.join(format!(
            "{stem}.shard-{}-of-{}.status.csv",
            args.shard.index, args.shard.count
        ))
    });
    let mut files = crate::paths::Files::new();
    files
        .read("the manifest", manifest)
        .write("the status file", &status_path);
    for j in all.iter().filter(|j| j.extra.is_ok()) {
        files
            .read_sdf(format!("row {}'s input", j.row), &base.join(&j.input))
            .write_creating_folder(format!("row {}'s output", j.row), &base.join(&j.output));
    }
    files.check()?;
    let jobs: Vec<Job> = all
        .into_iter()
        .filter(|j| args.shard.takes(j.row))
        .collect();
    Ok((base.to_path_buf(), status_path, jobs))
}

/// Runs the shard's rows not done by an earlier run, `--jobs` at once, recording each as it
/// finishes.
fn run_rows(
    args: &Args,
    threads: usize,
    ui: &Ui,
    base: &Path,
    status_path: &Path,
    jobs: &[Job],
) -> Result<()> {
    // Rows of this shard an earlier run finished are skipped (a `skipped` record appended for
    // each); nothing in the file (which other shards may share) is rewritten, and this run's
    // rows are appended as they finish.
    let mine: HashSet<(usize, &str, &str)> = jobs
        .iter()
        .map(|j| (j.row, j.input.as_str(), j.output.as_str()))
        .collect();
    let done: Vec<StatusRow> = earlier_rows(status_path, base)?
        .into_iter()
        .filter(|d| mine.contains(&(d.row, d.input.as_str(), d.output.as_str())))
        .collect();
    let mut status = StatusFile::open(status_path)?;
    // Each row skipped is recorded as such, its figures kept (the last record of a row counts).
    for d in &done {
        status.append(d)?;
    }
    let finished: HashSet<(usize, &str, &str)> = done
        .iter()
        .map(|d| (d.row, d.input.as_str(), d.output.as_str()))
        .collect();
    let todo: Vec<&Job> = jobs
        .iter()
        .filter(|j| !finished.contains(&(j.row, j.input.as_str(), j.output.as_str())))
        .collect();
    // The process's threads (--threads or RAYON_NUM_THREADS, at most the cores).
    let cores = threads;
    let n_jobs = (args.jobs as usize).min(todo.len()).max(1);
    let per_row = (cores / n_jobs).max(1);
    if n_jobs * per_row > cores {
        ui.say(format!(
            "warning: {n_jobs} rows at once on {cores} threads oversubscribes the cores"
        ));
    }
    ui.detail(format!(
        "shard {}/{}: {} rows, {} done by an earlier run; {n_jobs} at once, {per_row} thread(s) each; status in {}",
        args.shard.index,
        args.shard.count,
        jobs.len(),
        done.len(),
        status_path.display()
    ));
    let runner = Runner {
        exe: std::env::current_exe().context("cannot find the rfta executable")?,
        base: base.to_path_buf(),
        threads: per_row,
        checks: args.checks.clone(),
        tuning: args.tuning.clone(),
        timeout: args.timeout,
    };
    let bar = ui.progress(jobs.len() as u64, "batch");
    bar.inc(done.len() as u64);
    let mut counts: HashMap<Status, usize> = HashMap::new();
    counts.insert(Status::Skipped, done.len());
    let t = Instant::now();
    let write_error = runner.run_all(&todo, n_jobs, &mut status, &mut counts, &bar, ui);
    bar.finish_and_clear();
    if let Some(e) = write_error {
        return Err(e.context(format!("{}: cannot record a row", status_path.display())));
    }
    let summary = format!(
        "shard {}/{}: {} rows in {:.1} s: {}; status in {}",
        args.shard.index,
        args.shard.count,
        jobs.len(),
        t.elapsed().as_secs_f64(),
        Status::ALL
            .iter()
            .map(|s| format!("{} {}", counts.get(s).copied().unwrap_or(0), s.name()))
            .collect::<Vec<_>>()
            .join(", "),
        status_path.display()
    );
    if failures(&counts) > 0 {
        return Err(Exit::some_failed(summary).into());
    }
    ui.say(summary);
    Ok(())
}

/// Rows that failed or timed out.
fn failures(counts: &HashMap<Status, usize>) -> usize {
    Status::ALL
        .iter()
        .filter(|s| s.is_failure())
        .filter_map(|s| counts.get(s))
        .sum()
}

#[cfg(test)]
mod tests;
