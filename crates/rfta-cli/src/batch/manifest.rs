//! The manifest: which rows to run, each row's input and output and its optional columns.

use super::*;

/// What a manifest row's optional columns add.
#[derive(Debug, Default)]
pub(super) struct RowArgs {
    /// `--bounds`.
    pub(super) args: Vec<String>,
    /// The row's clamp, in place of `--clamp`.
    pub(super) clamp: Option<f64>,
    /// The row's preset, in place of `--preset`.
    pub(super) preset: Option<Preset>,
}

/// A manifest row: what to run, or why it cannot run.
#[derive(Debug)]
pub(super) struct Job {
    pub(super) row: usize,
    pub(super) input: String,
    pub(super) output: String,
    /// `reconstruct` arguments from the row's own columns, or the reason the row is bad.
    pub(super) extra: std::result::Result<RowArgs, String>,
}

/// The manifest's rows. A row that cannot run (a missing path, a bad bound, clamp or preset)
/// is kept with the reason, so that it ends as `failed` with the rest going on.
pub(super) fn read_manifest(path: &Path) -> Result<Vec<Job>> {
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
pub(super) fn row_args(
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
