//! Terminal output: verbosity, progress bars, argument parsers shared by subcommands.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};
use rfta_geom::glam::DVec3;
use rfta_io::GridBounds;

/// How much to print.
pub(crate) struct Ui {
    quiet: bool,
    verbose: bool,
}

impl Ui {
    pub(crate) fn new(quiet: bool, verbose: bool) -> Self {
        Self { quiet, verbose }
    }

    /// A summary line (suppressed by `-q`).
    pub(crate) fn say(&self, msg: impl AsRef<str>) {
        if !self.quiet {
            note(msg.as_ref());
        }
    }

    /// A detail line (only with `-v`).
    pub(crate) fn detail(&self, msg: impl AsRef<str>) {
        if self.verbose {
            note(msg.as_ref());
        }
    }

    /// Whether `-v` was given.
    pub(crate) fn is_verbose(&self) -> bool {
        self.verbose
    }

    /// A progress bar over `len` steps (hidden with `-q` or when stderr is not a terminal).
    pub(crate) fn progress(&self, len: u64, what: &str) -> ProgressBar {
        if self.quiet {
            return ProgressBar::hidden();
        }
        let bar = ProgressBar::new(len);
        let style = ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        bar.set_message(what.to_string());
        bar.enable_steady_tick(Duration::from_millis(200));
        bar
    }
}

/// An outcome that ends the tool with its own exit status and a line of its own, rather than
/// status 1 and "error: ...".
#[derive(Debug)]
pub(crate) struct Exit {
    /// The exit status.
    pub(crate) code: u8,
    /// The line printed, whole.
    pub(crate) line: String,
}

impl Exit {
    /// The input describes no surface (an empty mesh was written): status 3.
    pub(crate) fn no_surface(why: String) -> Self {
        Self {
            code: 3,
            line: format!("no surface: {why}"),
        }
    }

    /// A batch tried every row and some failed or timed out: status 4.
    pub(crate) fn some_failed(summary: String) -> Self {
        Self {
            code: 4,
            line: format!("error: {summary}"),
        }
    }
}

impl std::fmt::Display for Exit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.line)
    }
}

impl std::error::Error for Exit {}

/// Parses `xmin,ymin,zmin,xmax,ymax,zmax` (or `lo,hi` for a cube).
pub(crate) fn parse_bounds(s: &str) -> Result<GridBounds, String> {
    let v: Result<Vec<f64>, _> = s.split(',').map(|t| t.trim().parse::<f64>()).collect();
    let v = v.map_err(|_| format!("'{s}' is not a list of numbers"))?;
    let (min, max) = match v.as_slice() {
        [lo, hi] => (DVec3::splat(*lo), DVec3::splat(*hi)),
        [a, b, c, d, e, f] => (DVec3::new(*a, *b, *c), DVec3::new(*d, *e, *f)),
        _ => return Err(format!("expected 2 or 6 numbers, found {}", v.len())),
    };
    if !(min.is_finite() && max.is_finite()) {
        return Err("bounds must be finite".into());
    }
    if min.cmpge(max).any() {
        return Err(format!(
            "bounds are inverted or of zero size: min {min} must be below max {max} on every axis"
        ));
    }
    Ok(GridBounds { min, max })
}

/// "N vertices, M faces, watertight" (or what keeps it from being): the check every written mesh
/// gets before the tool reports it.
pub(crate) fn mesh_summary(mesh: &rfta_geom::TriMesh) -> String {
    let t = rfta_mesh::Topology::of(mesh);
    let shape = if mesh.is_empty() {
        "empty".to_string()
    } else if t.is_watertight() && t.degenerate_faces == 0 {
        "watertight".to_string()
    } else {
        format!(
            "NOT watertight: {} boundary, {} non-manifold edges, {} degenerate faces",
            t.boundary_edges, t.nonmanifold_edges, t.degenerate_faces
        )
    };
    format!(
        "{} vertices, {} faces, {shape}",
        mesh.n_vertices(),
        mesh.n_faces()
    )
}

/// A line on stdout (results, not messages); a closed pipe is an error `main` ends quietly on.
pub(crate) fn print_line(msg: &str) -> std::io::Result<()> {
    use std::io::Write;
    writeln!(std::io::stdout().lock(), "{msg}")
}

/// A line on stderr; a closed stderr (`rfta ... 2>&1 | head -1`) is not worth a panic.
pub(crate) fn note(msg: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{msg}");
}

/// Parses a byte size: a number with an optional K, M, G or T suffix (powers of 1024).
pub(crate) fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, mult) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let m: u64 = match c.to_ascii_uppercase() {
                'K' => 1 << 10,
                'M' => 1 << 20,
                'G' => 1 << 30,
                'T' => 1 << 40,
                'B' => 1,
                _ => return Err(format!("'{s}': unknown unit '{c}' (use K, M, G or T)")),
            };
            (&t[..i], m)
        }
        _ => (t, 1),
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a size such as 8G or 512M"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("'{s}' must be a positive size"));
    }
    Ok((v * mult as f64) as u64)
}

/// Refuses a mesh output format that cannot be written, before the work rather than after it
/// (where the file may go: [`crate::paths::Files`]).
pub(crate) fn check_output(path: &std::path::Path) -> anyhow::Result<()> {
    if rfta_io::MeshFormat::from_path(path)? == rfta_io::MeshFormat::Off {
        anyhow::bail!(
            "{}: OFF is read-only; write .obj, .ply, .stl or .glb",
            path.display()
        );
    }
    Ok(())
}

/// As [`check_output`], for polylines (.obj, .svg, .csv).
pub(crate) fn check_output_2d(path: &std::path::Path) -> anyhow::Result<()> {
    if !matches!(
        rfta_io::extension_of(path).as_deref(),
        Some("obj" | "svg" | "csv")
    ) {
        anyhow::bail!(
            "{}: 2D input gives polylines; write .obj, .svg or .csv",
            path.display()
        );
    }
    Ok(())
}

/// A finite number above zero (an option's value; NaN, infinities, zero and negatives refused
/// where they are parsed rather than taken to mean something).
pub(crate) fn parse_positive(s: &str) -> Result<f64, String> {
    parse_finite(s, false)
}

/// A finite number at or above zero, as [`parse_positive`].
pub(crate) fn parse_non_negative(s: &str) -> Result<f64, String> {
    parse_finite(s, true)
}

fn parse_finite(s: &str, zero: bool) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (v > 0.0 || (zero && v == 0.0)) => Ok(v),
        _ => Err(format!(
            "'{s}' is not a finite number {} 0",
            if zero { "at or above" } else { "above" }
        )),
    }
}

/// A `--report` file: one JSON object, written atomically.
pub(crate) fn write_json(path: &std::path::Path, json: &serde_json::Value) -> anyhow::Result<()> {
    rfta_io::write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, json)?;
        writeln!(w)
    })?;
    Ok(())
}

/// Mean and largest of the demos' vertex errors (0 for none).
pub(crate) fn mean_and_max(errors: impl Iterator<Item = f64>) -> (f64, f64) {
    let (sum, max, n) = errors.fold((0.0, 0.0f64, 0usize), |(s, m, n), d| {
        (s + d, m.max(d), n + 1)
    });
    (sum / n.max(1) as f64, max)
}
