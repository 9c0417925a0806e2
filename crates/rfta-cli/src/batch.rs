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

/// How a row ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Status {
    Ok,
    NoSurface,
    Failed,
    Timeout,
    Skipped,
}

impl Status {
    const ALL: [Status; 5] = [
        Status::Ok,
        Status::NoSurface,
        Status::Failed,
        Status::Timeout,
        Status::Skipped,
    ];

    fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::NoSurface => "no_surface",
            Status::Failed => "failed",
            Status::Timeout => "timeout",
            Status::Skipped => "skipped",
        }
    }

    fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|x| x.name() == s)
    }

    /// A status that fails the batch.
    fn is_failure(self) -> bool {
        matches!(self, Status::Failed | Status::Timeout)
    }
}

/// The report figures a status row carries (from `reconstruct --report`: [`rfta::Report`]'s
/// serde names, and the mesh's `vertices` and `faces`).
const FIGURES: [&str; 8] = [
    "samples",
    "vertices",
    "faces",
    "components",
    "watertight",
    "sign_errors",
    "entered",
    "gaps",
];

/// The columns of a status file.
fn header() -> Vec<String> {
    ["row", "input", "output", "status", "seconds", "message"]
        .into_iter()
        .chain(FIGURES)
        .map(String::from)
        .collect()
}

/// One row of a status file.
#[derive(Debug, Clone)]
struct StatusRow {
    /// The manifest row (0-based, header excluded).
    row: usize,
    /// As the manifest says (relative to its folder).
    input: String,
    output: String,
    status: Status,
    seconds: f64,
    message: String,
    /// [`FIGURES`], empty where unknown.
    figures: Vec<String>,
}

impl StatusRow {
    fn fields(&self) -> Vec<String> {
        [
            self.row.to_string(),
            self.input.clone(),
            self.output.clone(),
            self.status.name().to_string(),
            format!("{:.3}", self.seconds),
            self.message.clone(),
        ]
        .into_iter()
        .chain(self.figures.iter().cloned())
        .collect()
    }

    /// The record on `row` of a status `table`, as written (fields untrimmed, empty ones kept).
    fn parse(table: &rfta_io::table::Table, row: &rfta_io::table::Row) -> Option<Self> {
        let get = |name: &str| table.column(name).and_then(|i| row.fields.get(i)).cloned();
        Some(Self {
            row: get("row")?.parse().ok()?,
            input: get("input")?,
            output: get("output")?,
            status: Status::parse(&get("status")?)?,
            seconds: get("seconds")?.parse().ok()?,
            message: get("message").unwrap_or_default(),
            figures: FIGURES.iter().map(|f| get(f).unwrap_or_default()).collect(),
        })
    }
}

/// What a manifest row's optional columns add.
#[derive(Debug, Default)]
struct RowArgs {
    /// `--bounds`.
    args: Vec<String>,
    /// The row's clamp, in place of `--clamp`.
    clamp: Option<f64>,
    /// The row's preset, in place of `--preset`.
    preset: Option<Preset>,
}

/// A manifest row: what to run, or why it cannot run.
#[derive(Debug)]
struct Job {
    row: usize,
    input: String,
    output: String,
    /// `reconstruct` arguments from the row's own columns, or the reason the row is bad.
    extra: std::result::Result<RowArgs, String>,
}

pub(crate) fn run(args: Args, threads: Option<usize>, ui: &Ui) -> Result<()> {
    if !args.merge.is_empty() {
        return merge(&args.merge, args.status.as_deref());
    }
    let Some(manifest) = args.manifest.as_deref() else {
        bail!("give a manifest, or --merge STATUS...");
    };
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
    // Every row of the manifest, whichever shard runs it: two rows writing one output, or an
    // output that is an input, the manifest or the status file, would lose data.
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
    if args.dry_run {
        for j in &jobs {
            crate::ui::print_line(&format!("{},{},{}", j.row, j.input, j.output))?;
        }
        return Ok(());
    }
    // Rows an earlier run of this shard finished: kept (as `skipped`), the file rewritten with
    // them only, then this run's rows appended as they finish.
    let done = earlier_rows(&status_path, base)?;
    let mut status = StatusFile::create(&status_path, &done)?;
    let finished: HashSet<(usize, &str, &str)> = done
        .iter()
        .map(|d| (d.row, d.input.as_str(), d.output.as_str()))
        .collect();
    let todo: Vec<&Job> = jobs
        .iter()
        .filter(|j| !finished.contains(&(j.row, j.input.as_str(), j.output.as_str())))
        .collect();
    let cores = threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
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
    let next = AtomicUsize::new(0);
    let (send, receive) = mpsc::channel::<StatusRow>();
    let mut write_error: Option<anyhow::Error> = None;
    std::thread::scope(|scope| {
        for _ in 0..n_jobs {
            let send = send.clone();
            let (todo, next, runner) = (&todo, &next, &runner);
            scope.spawn(move || {
                while let Some(job) = todo.get(next.fetch_add(1, Ordering::Relaxed)) {
                    if send.send(runner.run(job)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(send);
        for row in receive {
            *counts.entry(row.status).or_default() += 1;
            let line = format!(
                "{} {} -> {}: {}{}",
                row.status.name(),
                row.input,
                row.output,
                if row.message.is_empty() {
                    format!("{:.2} s", row.seconds)
                } else {
                    row.message.clone()
                },
                if row.status == Status::Ok {
                    String::new()
                } else {
                    format!(" ({:.2} s)", row.seconds)
                }
            );
            if bar.is_hidden() {
                ui.say(&line);
            } else if row.status != Status::Ok || ui.is_verbose() {
                bar.println(&line);
            }
            if let Err(e) = status.append(&row) {
                // Stop handing out rows: a shard that cannot record them would redo them.
                next.store(todo.len(), Ordering::Relaxed);
                write_error.get_or_insert(e);
            }
            bar.set_message(format!("{} failed", failures(&counts)));
            bar.inc(1);
        }
    });
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

/// Runs rows as child processes.
struct Runner {
    exe: PathBuf,
    base: PathBuf,
    /// Threads per row.
    threads: usize,
    checks: Checks,
    tuning: Tuning,
    timeout: Option<Duration>,
}

impl Runner {
    fn run(&self, job: &Job) -> StatusRow {
        let t = Instant::now();
        let (status, message, figures) = match &job.extra {
            Err(why) => (Status::Failed, why.clone(), Vec::new()),
            Ok(extra) => self.spawn(job, extra),
        };
        StatusRow {
            row: job.row,
            input: job.input.clone(),
            output: job.output.clone(),
            status,
            seconds: t.elapsed().as_secs_f64(),
            message,
            figures: if figures.is_empty() {
                vec![String::new(); FIGURES.len()]
            } else {
                figures
            },
        }
    }

    fn spawn(&self, job: &Job, extra: &RowArgs) -> (Status, String, Vec<String>) {
        let output = self.base.join(&job.output);
        if let Some(dir) = output.parent()
            && let Err(e) = std::fs::create_dir_all(dir)
        {
            return (
                Status::Failed,
                format!("cannot create {}: {e}", dir.display()),
                Vec::new(),
            );
        }
        let report = std::env::temp_dir().join(format!(
            "rfta-batch-{}-{}.json",
            std::process::id(),
            job.row
        ));
        let _ = std::fs::remove_file(&report);
        let mut command = Command::new(&self.exe);
        command
            .arg("reconstruct")
            .arg(self.base.join(&job.input))
            .arg("-o")
            .arg(&output)
            .arg("--report")
            .arg(&report)
            .args(["-q", "--threads", &self.threads.to_string()])
            .args(self.checks.to_args(extra.clamp))
            .args(self.tuning.to_args(extra.preset))
            .args(&extra.args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        let mut child = match command.spawn() {
            Ok(c) => c,
            Err(e) => {
                return (
                    Status::Failed,
                    format!("cannot start {}: {e}", self.exe.display()),
                    Vec::new(),
                );
            }
        };
        // Drained on the side: a child blocked on a full pipe would look like a timeout.
        let stderr = child.stderr.take().map(|mut pipe| {
            std::thread::spawn(move || {
                let mut text = String::new();
                let _ = pipe.read_to_string(&mut text);
                text
            })
        });
        let ended = wait(&mut child, self.timeout);
        let text = stderr
            .and_then(|h| h.join().ok())
            .unwrap_or_default()
            .trim()
            .to_string();
        // The error line (`main` prints its chain on one line; clap's usage errors have more
        // lines after it), else the last line.
        let last = text
            .lines()
            .rfind(|l| l.starts_with("error:") || l.starts_with("no surface:"))
            .or_else(|| text.lines().last())
            .unwrap_or("")
            .to_string();
        let result = match ended {
            Ended::TimedOut(after) => {
                // A killed writer may leave its temporary files (never the outputs).
                for written in [&output, &report] {
                    rfta_io::remove_temp_files(written, child.id());
                }
                (
                    Status::Timeout,
                    format!("stopped after {:.1} s", after.as_secs_f64()),
                    Vec::new(),
                )
            }
            Ended::Code(0) => (Status::Ok, String::new(), figures(&report)),
            Ended::Code(3) => (
                Status::NoSurface,
                last.strip_prefix("no surface: ")
                    .unwrap_or(&last)
                    .to_string(),
                Vec::new(),
            ),
            Ended::Code(c) => (
                Status::Failed,
                if last.is_empty() {
                    format!("exit status {c}")
                } else {
                    last.strip_prefix("error: ").unwrap_or(&last).to_string()
                },
                Vec::new(),
            ),
            Ended::Signal(why) => (Status::Failed, why, Vec::new()),
        };
        let _ = std::fs::remove_file(&report);
        result
    }
}

enum Ended {
    Code(i32),
    Signal(String),
    TimedOut(Duration),
}

/// Waits for `child`, killing it after `timeout`.
fn wait(child: &mut Child, timeout: Option<Duration>) -> Ended {
    let t = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => {
                return match status.code() {
                    Some(c) => Ended::Code(c),
                    None => Ended::Signal(format!("the process ended abnormally ({status})")),
                };
            }
            Ok(None) => {}
            Err(e) => return Ended::Signal(format!("cannot wait for the process: {e}")),
        }
        if let Some(limit) = timeout
            && t.elapsed() >= limit
        {
            let _ = child.kill();
            let _ = child.wait();
            return Ended::TimedOut(t.elapsed());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The status row's figures from a `reconstruct --report` file (empty where it is unreadable).
fn figures(report: &Path) -> Vec<String> {
    let json: Option<serde_json::Value> = std::fs::read(report)
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok());
    FIGURES
        .iter()
        .map(|f| {
            json.as_ref()
                .and_then(|j| j.get(f))
                .map(|v| v.to_string())
                .unwrap_or_default()
        })
        .collect()
}

/// The manifest's rows. A row that cannot run (a missing path, a bad bound, clamp or preset)
/// is kept with the reason, so that it ends as `failed` with the rest going on.
fn read_manifest(path: &Path) -> Result<Vec<Job>> {
    let table = rfta_io::table::read_table(path)?;
    for needed in ["input", "output"] {
        if table.column(needed).is_none() {
            bail!(
                "{}: the header has no '{needed}' column (found: {})",
                path.display(),
                table.columns.join(",")
            );
        }
    }
    Ok(table
        .rows
        .iter()
        .enumerate()
        .map(|(row, r)| {
            // Blank lines still count as rows, so shards stay stable when they are filled in.
            if r.is_blank() {
                return Job {
                    row,
                    input: String::new(),
                    output: String::new(),
                    extra: Err("empty row".into()),
                };
            }
            let get = |name: &str| table.get(r, name).map(str::to_string);
            let (input, output) = (get("input"), get("output"));
            let extra = match (&input, &output) {
                (Some(_), Some(_)) => row_args(get("bounds"), get("clamp"), get("preset")),
                _ => Err("the row needs both an input and an output".into()),
            };
            Job {
                row,
                input: input.unwrap_or_default(),
                output: output.unwrap_or_default(),
                extra,
            }
        })
        .collect())
}

/// `reconstruct` arguments from a row's optional columns.
fn row_args(
    bounds: Option<String>,
    clamp: Option<String>,
    preset: Option<String>,
) -> std::result::Result<RowArgs, String> {
    let mut a = Vec::new();
    if let Some(b) = bounds {
        let joined = b
            .split([',', ' ', ';'])
            .filter(|t| !t.is_empty())
            .collect::<Vec<_>>();
        let joined = joined.join(",");
        parse_bounds(&joined).map_err(|e| format!("bounds: {e}"))?;
        a.push(format!("--bounds={joined}"));
    }
    let clamp = clamp
        .map(|c| match c.parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
            _ => Err(format!("clamp: '{c}' is not a positive number")),
        })
        .transpose()?;
    let preset = preset
        .map(|p| {
            <Preset as clap::ValueEnum>::from_str(&p, true)
                .map_err(|_| format!("preset: '{p}' is not one of {}", rfta::PRESETS.join(", ")))
        })
        .transpose()?;
    Ok(RowArgs {
        args: a,
        clamp,
        preset,
    })
}

/// The rows of a status file (none if it does not exist).
fn read_status(path: &Path) -> Result<Vec<StatusRow>> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let table = rfta_io::table::read_table(path)?;
    if !["row", "input", "output", "status"]
        .iter()
        .all(|c| table.column(c).is_some())
    {
        bail!(
            "{}: not an rfta batch status file (header: {})",
            path.display(),
            table.columns.join(",")
        );
    }
    // Rows are appended whole, line break last: a line cut short by a kill (no line break, or
    // too few fields) is no record, and its row runs again.
    Ok(table
        .rows
        .iter()
        .filter(|r| r.complete && r.fields.len() == table.columns.len())
        .filter_map(|r| StatusRow::parse(&table, r))
        .collect())
}

/// The rows of an earlier run that need not run again: the last word on each row is `ok` or
/// `skipped` and its output exists. Returned as `skipped`.
fn earlier_rows(path: &Path, base: &Path) -> Result<Vec<StatusRow>> {
    Ok(last_by_row(read_status(path)?)
        .into_iter()
        .filter(|r| matches!(r.status, Status::Ok | Status::Skipped))
        .filter(|r| base.join(&r.output).is_file())
        .map(|mut r| {
            if r.status == Status::Ok {
                r.status = Status::Skipped;
                r.message = format!("done by an earlier run in {:.2} s", r.seconds);
            }
            r
        })
        .collect())
}

/// The last record of each row (a rerun appends after the row it redoes), in manifest order.
fn last_by_row(rows: Vec<StatusRow>) -> Vec<StatusRow> {
    let mut last: HashMap<usize, StatusRow> = HashMap::new();
    for r in rows {
        last.insert(r.row, r);
    }
    let mut rows: Vec<StatusRow> = last.into_values().collect();
    rows.sort_by_key(|r| r.row);
    rows
}

/// A status file written a row at a time.
struct StatusFile {
    file: File,
}

impl StatusFile {
    /// Starts `path` afresh (atomically) with `rows`, then opens it for appending.
    fn create(path: &Path, rows: &[StatusRow]) -> Result<Self> {
        rfta_io::write_atomic(path, |w| {
            writeln!(w, "{}", rfta_io::table::join_csv(&header()))?;
            for r in rows {
                writeln!(w, "{}", rfta_io::table::join_csv(&r.fields()))?;
            }
            Ok(())
        })?;
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .with_context(|| format!("{}: cannot open for appending", path.display()))?;
        Ok(Self { file })
    }

    fn append(&mut self, row: &StatusRow) -> Result<()> {
        writeln!(self.file, "{}", rfta_io::table::join_csv(&row.fields()))?;
        self.file.sync_data()?;
        Ok(())
    }
}

/// `--merge`: the rows of every status file, in manifest order, with totals.
fn merge(paths: &[PathBuf], out: Option<&Path>) -> Result<()> {
    let mut all: Vec<StatusRow> = Vec::new();
    for p in paths {
        if !p.is_file() {
            bail!("{}: no such status file", p.display());
        }
        all.extend(read_status(p)?);
    }
    let rows = last_by_row(all);
    let out = out.map_or_else(
        || {
            paths[0]
                .parent()
                .unwrap_or(Path::new("."))
                .join("merged.status.csv")
        },
        Path::to_path_buf,
    );
    let mut files = crate::paths::Files::new();
    for (k, p) in paths.iter().enumerate() {
        files.read(format!("status file {}", k + 1), p);
    }
    files.write("the merged table (--status)", &out).check()?;
    rfta_io::write_atomic(&out, |w| {
        writeln!(w, "{}", rfta_io::table::join_csv(&header()))?;
        for r in &rows {
            writeln!(w, "{}", rfta_io::table::join_csv(&r.fields()))?;
        }
        Ok(())
    })?;
    let mut table = String::from("| status | rows | seconds |\n|---|---|---|\n");
    for s in Status::ALL {
        let these: Vec<&StatusRow> = rows.iter().filter(|r| r.status == s).collect();
        if !these.is_empty() {
            table += &format!(
                "| {} | {} | {:.1} |\n",
                s.name(),
                these.len(),
                these.iter().map(|r| r.seconds).sum::<f64>()
            );
        }
    }
    table += &format!(
        "| all | {} | {:.1} |\n",
        rows.len(),
        rows.iter().map(|r| r.seconds).sum::<f64>()
    );
    crate::ui::print_line(&format!(
        "{} rows from {} status file(s), merged into {}\n\n{table}",
        rows.len(),
        paths.len(),
        out.display()
    ))?;
    if rows.iter().any(|r| r.status.is_failure()) {
        return Err(Exit::some_failed(format!(
            "{} row(s) failed or timed out",
            rows.iter().filter(|r| r.status.is_failure()).count()
        ))
        .into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_row_once() {
        for count in 1..7 {
            for row in 0..50 {
                let owners = (0..count)
                    .filter(|&index| Shard { index, count }.takes(row))
                    .count();
                assert_eq!(owners, 1, "row {row} of {count} shards");
            }
        }
        assert!(parse_shard("3/3").is_err());
        assert!(parse_shard("1/0").is_err());
        assert_eq!(parse_shard("2/5"), Ok(Shard { index: 2, count: 5 }));
    }

    /// A row's clamp and preset replace the command line's, never repeat them (clap refuses an
    /// option given twice).
    #[test]
    fn a_rows_clamp_and_preset_replace_the_command_lines() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let cli = Cli::try_parse_from(["rfta", "m.csv", "--clamp", "0.5", "--preset", "paper"])
            .expect("options");
        let row = row_args(None, Some("0.25".into()), Some("fast".into())).expect("row");
        let mut args = cli.args.checks.to_args(row.clamp);
        args.extend(cli.args.tuning.to_args(row.preset));
        let count = |flag: &str| args.iter().filter(|a| *a == flag).count();
        assert_eq!((count("--clamp"), count("--preset")), (1, 1));
        assert!(args.windows(2).any(|w| w == ["--clamp", "0.25"]));
        assert!(args.windows(2).any(|w| w == ["--preset", "fast"]));
        // Without row values, the command line's.
        let args = cli.args.checks.to_args(None);
        assert!(args.windows(2).any(|w| w == ["--clamp", "0.5"]));
    }

    /// Every `reconstruct` option of `Checks` and `Tuning` reaches the rows: set them all on
    /// the command line and `to_args` gives each back (an option added to either and forgotten in
    /// its `to_args` fails here).
    #[test]
    fn every_reconstruct_option_reaches_the_rows() {
        use clap::{Args as _, Parser};
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let cli = Cli::try_parse_from([
            "rfta",
            "m.csv",
            "--clamp",
            "0.5",
            "--no-check",
            "--max-memory",
            "2G",
            "--preset",
            "paper",
            "--iters",
            "4",
            "--max-points",
            "5",
            "--seed",
            "9",
            "--gpu",
            "on",
            "--min-island",
            "0.25",
            "--owner-band",
            "2",
            "--raster-res",
            "64",
            "--depth",
            "7",
            "--genus",
            "0",
        ])
        .expect("options");
        let mut given: Vec<String> = cli.args.checks.to_args(None);
        given.extend(cli.args.tuning.to_args(None));
        let flags: std::collections::BTreeSet<String> = given
            .iter()
            .filter_map(|a| a.strip_prefix("--"))
            .map(String::from)
            .collect();
        let declared = Tuning::augment_args(Checks::augment_args(clap::Command::new("t")));
        let all: std::collections::BTreeSet<String> = declared
            .get_arguments()
            .filter_map(|a| a.get_long().map(String::from))
            .collect();
        assert_eq!(flags, all);
        // And the values are the ones given.
        for pair in [
            ["--rounds", "4"],
            ["--preset", "paper"],
            ["--max-memory", "2147483648B"],
        ] {
            assert!(given.windows(2).any(|w| w == pair), "{pair:?} in {given:?}");
        }
        // Read back, they make the same parameters.
        let again = Cli::try_parse_from(
            ["rfta".to_string(), "m.csv".into()]
                .into_iter()
                .chain(given),
        )
        .expect("options");
        let params = |c: &Cli| c.args.tuning.params().expect("valid");
        assert_eq!(params(&again), params(&cli));
        assert_eq!(params(&cli).rounds, 4);
        assert_eq!(params(&cli).spsr_depth, Some(7));
    }

    /// The status columns are figures of the report `reconstruct --report` writes (its
    /// [`rfta::Report`] and the mesh's size), by the same names.
    #[test]
    fn the_status_figures_are_report_figures() {
        let report = serde_json::to_value(rfta::Report::default()).expect("serializes");
        for f in FIGURES {
            assert!(
                report.get(f).is_some() || ["vertices", "faces"].contains(&f),
                "{f} is no figure of the report"
            );
        }
    }

    #[test]
    fn bad_row_columns_are_reasons_not_errors() {
        assert!(row_args(Some("0 0 0 1 1".into()), None, None).is_err());
        assert!(row_args(None, Some("-1".into()), None).is_err());
        assert!(row_args(None, None, Some("fastest".into())).is_err());
        let row = row_args(Some("-1 -1 -1 1 1 1".into()), None, Some("Fast".into()));
        let row = row.expect("a good row");
        assert_eq!(row.args, ["--bounds=-1,-1,-1,1,1,1"]);
        assert!(matches!(row.preset, Some(Preset::Fast)));
    }
}
