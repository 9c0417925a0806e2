//! Status files: one row per manifest row run, its status, time, message and report figures;
//! read back by a rerun (rows done are skipped) and merged across shards.

use super::*;

/// How a row ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(super) enum Status {
    Ok,
    NoSurface,
    Failed,
    Timeout,
    Skipped,
}

impl Status {
    pub(super) const ALL: [Status; 5] = [
        Status::Ok,
        Status::NoSurface,
        Status::Failed,
        Status::Timeout,
        Status::Skipped,
    ];

    pub(super) fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::NoSurface => "no_surface",
            Status::Failed => "failed",
            Status::Timeout => "timeout",
            Status::Skipped => "skipped",
        }
    }

    pub(super) fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|x| x.name() == s)
    }

    /// A status that fails the batch.
    pub(super) fn is_failure(self) -> bool {
        matches!(self, Status::Failed | Status::Timeout)
    }
}

/// The report figures a status row carries (from `reconstruct --report`: [`rfta::Report`]'s
/// serde names, and the mesh's `vertices` and `faces`).
pub(super) const FIGURES: [&str; 8] = [
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
pub(super) fn header() -> Vec<String> {
    ["row", "input", "output", "status", "seconds", "message"]
        .into_iter()
        .chain(FIGURES)
        .map(String::from)
        .collect()
}

/// One row of a status file.
#[derive(Debug, Clone)]
pub(super) struct StatusRow {
    /// The manifest row (0-based, header excluded).
    pub(super) row: usize,
    /// As the manifest says (relative to its folder).
    pub(super) input: String,
    pub(super) output: String,
    pub(super) status: Status,
    pub(super) seconds: f64,
    pub(super) message: String,
    /// [`FIGURES`], empty where unknown.
    pub(super) figures: Vec<String>,
}

impl StatusRow {
    /// The row as the progress output shows it.
    pub(super) fn line(&self) -> String {
        format!(
            "{} {} -> {}: {}{}",
            self.status.name(),
            self.input,
            self.output,
            if self.message.is_empty() {
                format!("{:.2} s", self.seconds)
            } else {
                self.message.clone()
            },
            if self.status == Status::Ok {
                String::new()
            } else {
                format!(" ({:.2} s)", self.seconds)
            }
        )
    }

    pub(super) fn fields(&self) -> Vec<String> {
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

    /// The record on `row` of a status `table`, as written (fields untrimmed, empty ones kept),
    /// or why it is none.
    pub(super) fn parse(
        table: &rfta_io::table::Table,
        row: &rfta_io::table::Row,
    ) -> std::result::Result<Self, String> {
        if row.fields.len() != table.columns.len() {
            return Err(format!(
                "{} fields where the header has {}",
                row.fields.len(),
                table.columns.len()
            ));
        }
        let get = |name: &str| {
            table
                .column(name)
                .and_then(|i| row.fields.get(i))
                .cloned()
                .unwrap_or_default()
        };
        let number = get("row");
        let status = get("status");
        let seconds = get("seconds");
        Ok(Self {
            row: number
                .parse()
                .map_err(|_| format!("the row {number:?} is not a row number"))?,
            input: get("input"),
            output: get("output"),
            status: Status::parse(&status).ok_or_else(|| {
                format!(
                    "the status {status:?} is none of {}",
                    Status::ALL.map(Status::name).join(", ")
                )
            })?,
            seconds: seconds
                .parse()
                .map_err(|_| format!("the seconds {seconds:?} are not a number"))?,
            message: get("message"),
            figures: FIGURES.iter().map(|f| get(f)).collect(),
        })
    }
}

/// The status row's figures from a `reconstruct --report` file (empty where it is unreadable).
pub(super) fn figures(report: &Path) -> Vec<String> {
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

/// The rows of a status file (none if it does not exist, or holds no whole line yet: a shard
/// that has just created it writes its header under the lock next). It is read under a shared
/// lock, so no shard's append is half there. A last line without its line break was cut short
/// by a kill: no record (its row runs again). Any other line that is not a record rfta writes
/// is an error naming it: a record dropped silently would hide its row (hostile test E14: a
/// failed row vanished from a merge that exited 0).
pub(super) fn read_status(path: &Path) -> Result<Vec<StatusRow>> {
    let handle = match File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("{}: cannot open", path.display())),
    };
    // As `StatusFile::locked_append`: a file system without locks is read unlocked.
    let locked = match handle.lock_shared() {
        Ok(()) => true,
        Err(e) if e.kind() == std::io::ErrorKind::Unsupported => false,
        Err(e) => return Err(e.into()),
    };
    let read = (|| -> Result<Option<rfta_io::table::Table>> {
        if complete_length(&handle)? == 0 {
            return Ok(None);
        }
        Ok(Some(rfta_io::table::read_table(path)?))
    })();
    if locked {
        handle.unlock()?;
    }
    let Some(table) = read? else {
        return Ok(Vec::new());
    };
    if !["row", "input", "output", "status", "seconds"]
        .iter()
        .all(|c| table.column(c).is_some())
    {
        bail!(
            "{}: not an rfta batch status file (header: {})",
            path.display(),
            table.columns.join(",")
        );
    }
    let mut rows = Vec::new();
    for r in &table.rows {
        if !r.complete || r.is_blank() {
            continue;
        }
        match StatusRow::parse(&table, r) {
            Ok(record) => rows.push(record),
            Err(why) => bail!(
                "{}: line {}: not a status record ({why}): {}",
                path.display(),
                r.line,
                r.fields.join(",")
            ),
        }
    }
    Ok(rows)
}

/// The length of `file` up to the end of its last line break (its whole length when it ends
/// with one): what a killed writer left of its last record lies beyond.
fn complete_length(file: &File) -> std::io::Result<u64> {
    let mut end = file.metadata()?.len();
    let mut chunk = [0u8; 4096];
    while end > 0 {
        let start = end.saturating_sub(chunk.len() as u64);
        let part = &mut chunk[..(end - start) as usize];
        #[cfg(unix)]
        std::os::unix::fs::FileExt::read_exact_at(file, part, start)?;
        #[cfg(not(unix))]
        part.fill(b'\n');
        if let Some(i) = part.iter().rposition(|&b| b == b'\n') {
            return Ok(start + i as u64 + 1);
        }
        end = start;
    }
    Ok(0)
}

/// The rows of an earlier run that need not run again: the last word on each row is `ok` or
/// `skipped` and its output exists. Returned as `skipped`.
pub(super) fn earlier_rows(path: &Path, base: &Path) -> Result<Vec<StatusRow>> {
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
pub(super) fn last_by_row(rows: Vec<StatusRow>) -> Vec<StatusRow> {
    let mut last: HashMap<usize, StatusRow> = HashMap::new();
    for r in rows {
        last.insert(r.row, r);
    }
    let mut rows: Vec<StatusRow> = last.into_values().collect();
    rows.sort_by_key(|r| r.row);
    rows
}

/// A status file written a row at a time, which the shards of a job array may share: each
/// record is appended whole under an exclusive lock of the file, after the header when the
/// file is new, and after cutting off what a killed writer left of a last record (hostile test
/// E5: shards that each rewrote a shared file at their start lost each other's records).
pub(super) struct StatusFile {
    pub(super) file: File,
}

impl StatusFile {
    /// Opens `path` for appending, creating it with its header if it is missing or empty; the
    /// records there stay (a rerun's records follow them, and the last record of a row counts).
    pub(super) fn open(path: &Path) -> Result<Self> {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .append(true)
            .create(true)
            .open(path)
            .with_context(|| format!("{}: cannot open for appending", path.display()))?;
        let mut status = Self { file };
        status.locked_append(None)?;
        Ok(status)
    }

    /// Under the lock: a last line left without its line break (a writer killed mid-record)
    /// cut off, the header if the file is then empty, then `row` if given, synced.
    fn locked_append(&mut self, row: Option<&StatusRow>) -> Result<()> {
        // A file system without locks (some network mounts) gets the appends unlocked: safe
        // for one writer, the default of one status file per shard.
        let locked = match self.file.lock() {
            Ok(()) => true,
            Err(e) if e.kind() == std::io::ErrorKind::Unsupported => false,
            Err(e) => return Err(e.into()),
        };
        let result = (|| -> Result<()> {
            let len = complete_length(&self.file)?;
            if len < self.file.metadata()?.len() {
                self.file.set_len(len)?;
            }
            let mut text = String::new();
            if len == 0 {
                text += &rfta_io::table::join_csv(&header());
                text.push('\n');
            }
            if let Some(row) = row {
                text += &rfta_io::table::join_csv(&row.fields());
                text.push('\n');
            }
            if !text.is_empty() {
                self.file.write_all(text.as_bytes())?;
                self.file.sync_data()?;
            }
            Ok(())
        })();
        let unlocked = if locked { self.file.unlock() } else { Ok(()) };
        result?;
        unlocked?;
        Ok(())
    }

    pub(super) fn append(&mut self, row: &StatusRow) -> Result<()> {
        self.locked_append(Some(row))
    }
}

/// `--merge`: the rows of every status file, in manifest order, with totals.
pub(super) fn merge(paths: &[PathBuf], out: Option<&Path>) -> Result<()> {
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
