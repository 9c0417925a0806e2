//! Running one row: a child `rfta reconstruct` process, its timeout, its outputs.

use super::*;

/// Runs rows as child processes.
pub(super) struct Runner {
    pub(super) exe: PathBuf,
    pub(super) base: PathBuf,
    /// Threads per row.
    pub(super) threads: usize,
    pub(super) checks: Checks,
    pub(super) tuning: Tuning,
    pub(super) timeout: Option<Duration>,
}

impl Runner {
    /// Runs `todo`, `n_jobs` rows at once, each recorded in `status` and counted as it
    /// finishes; the first error writing `status`, which stops handing out rows (a shard that
    /// cannot record them would redo them).
    pub(super) fn run_all(
        &self,
        todo: &[&Job],
        n_jobs: usize,
        status: &mut StatusFile,
        counts: &mut HashMap<Status, usize>,
        bar: &indicatif::ProgressBar,
        ui: &Ui,
    ) -> Option<anyhow::Error> {
        let next = AtomicUsize::new(0);
        let (send, receive) = mpsc::channel::<StatusRow>();
        let mut write_error: Option<anyhow::Error> = None;
        std::thread::scope(|scope| {
            for _ in 0..n_jobs {
                let send = send.clone();
                let next = &next;
                scope.spawn(move || {
                    while let Some(job) = todo.get(next.fetch_add(1, Ordering::Relaxed)) {
                        if send.send(self.run(job)).is_err() {
                            break;
                        }
                    }
                });
            }
            drop(send);
            for row in receive {
                *counts.entry(row.status).or_default() += 1;
                let line = row.line();
                if bar.is_hidden() {
                    ui.say(&line);
                } else if row.status != Status::Ok || ui.is_verbose() {
                    bar.println(&line);
                }
                if let Err(e) = status.append(&row) {
                    next.store(todo.len(), Ordering::Relaxed);
                    write_error.get_or_insert(e);
                }
                bar.set_message(format!("{} failed", failures(counts)));
                bar.inc(1);
            }
        });
        write_error
    }

    /// Runs one row.
    pub(super) fn run(&self, job: &Job) -> StatusRow {
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

    pub(super) fn spawn(&self, job: &Job, extra: &RowArgs) -> (Status, String, Vec<String>) {
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

pub(super) enum Ended {
    Code(i32),
    Signal(String),
    TimedOut(Duration),
}

/// Waits for `child`, killing it after `timeout`.
pub(super) fn wait(child: &mut Child, timeout: Option<Duration>) -> Ended {
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
