//! `rfta reconstruct` from an SDF file, and what every reconstruction delivers: the mesh, the
//! report, the page, the summary.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta::geom::{SdfSamples, TriMesh};
use rfta::{Params, Stage};

use crate::ui::{Exit, Ui, parse_bounds};

/// Parameter presets.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub(crate) enum Preset {
    /// The paper's defaults: 10 fine-tuning rounds (3 on grids of more than 80 cells along their
    /// longest side), 3 points per sphere.
    Default,
    /// The setting of the paper's Table 2: 20 rounds, 30 points per sphere.
    Paper,
    /// gpytoolbox's defaults: 3 rounds, 3 points per sphere.
    Fast,
}

/// GPU use for the rasterization.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub(crate) enum Gpu {
    /// The GPU when one is found (this build falls back to the CPU, with a log line, otherwise).
    Auto,
    /// Ask for the GPU (same fallback).
    On,
    /// CPU only.
    Off,
}

#[derive(Debug, clap::Args)]
pub(crate) struct Args {
    /// SDF samples: a grid (.npy, .exr), an OpenVDB level set (.vdb: its background is the
    /// clamp) or scattered samples (.ply with an sdf property, .csv/.xyz rows x y z s).
    /// 2D samples are detected: .npy of shape (nx, ny) or (n, 3), .csv rows x y s, 16-bit .png, .exr images.
    #[arg(required_unless_present = "from_mesh")]
    pub(crate) input: Option<PathBuf>,
    /// Instead of an SDF file, ask a mesh's exact signed distance where the reconstruction needs
    /// it (adaptive sampling, at most --budget evaluations; for evaluation and demos).
    #[arg(long, value_name = "MESH", conflicts_with_all = ["input", "grid"])]
    pub(crate) from_mesh: Option<PathBuf>,
    /// With --from-mesh: the most evaluations of the SDF (default 30000).
    #[arg(long, value_name = "N", requires = "from_mesh")]
    pub(crate) budget: Option<usize>,
    /// Output mesh (.obj .ply .stl .glb); for 2D input, polylines (.obj .svg .csv).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Grid bounds for an .npy grid, overriding its sidecar (as for `sample`); with --from-mesh,
    /// the box sampled (default: the cube around the mesh's box, its longest side grown by a tenth at each end).
    #[arg(long, value_name = "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX", value_parser = parse_bounds)]
    pub(crate) bounds: Option<rfta_io::GridBounds>,
    /// The level set of a .vdb file to reconstruct, by name (default: the first level set).
    #[arg(long, value_name = "NAME")]
    grid: Option<String>,
    #[command(flatten)]
    pub(crate) checks: Checks,
    /// Also write the final tangency points with their normals (PLY), e.g. for `rfta psr`.
    #[arg(long, value_name = "PLY")]
    pub(crate) points: Option<PathBuf>,
    /// Also write the report's key figures as JSON (counts, agreement with the samples, seconds).
    #[arg(long, value_name = "JSON")]
    pub(crate) report: Option<PathBuf>,
    /// Also write the mesh as one HTML page that opens without a network (an interactive 3D
    /// view with the samples on the wrong side, the spheres entered, thin handles, cavities and
    /// islands marked, marching cubes' mesh of the same grid to compare, the report's figures).
    #[arg(long, value_name = "HTML")]
    pub(crate) html: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) tuning: Tuning,
}

/// How the input is taken: shared by `reconstruct` and `batch`.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct Checks {
    /// The SDF was clamped at this magnitude (samples at or beyond it get no tangency point).
    /// Without it a clamp is detected from flat plateaus of the values (see --no-check).
    #[arg(long, value_parser = crate::ui::parse_positive)]
    pub(crate) clamp: Option<f64>,
    /// Do not inspect the values: reconstruct even from samples that are not a signed distance
    /// (occupancy, random, rescaled values; a value beyond the samples' extent), and detect no
    /// clamp.
    #[arg(long)]
    pub(crate) no_check: bool,
    /// Refuse inputs whose estimated peak memory exceeds this (e.g. 8G, 512M; default: the
    /// memory available now).
    #[arg(long, value_name = "SIZE", value_parser = crate::ui::parse_size)]
    pub(crate) max_memory: Option<u64>,
}

impl Checks {
    /// These options as `reconstruct` arguments (what `batch` passes to each row), with `clamp`
    /// in place of `--clamp` where given.
    pub(crate) fn to_args(&self, clamp: Option<f64>) -> Vec<String> {
        let mut a = Vec::new();
        if let Some(c) = clamp.or(self.clamp) {
            a.extend(["--clamp".into(), c.to_string()]);
        }
        if self.no_check {
            a.push("--no-check".into());
        }
        if let Some(m) = self.max_memory {
            a.extend(["--max-memory".into(), format!("{m}B")]);
        }
        a
    }
}

/// Options shared by `reconstruct` and `demo`. The fields after `gpu` are named as
/// [`rfta::Params`]' serde form names its settings (the Python package's keywords), and reach
/// it through that form ([`Tuning::params`], [`Tuning::to_args`]): an option is added here with
/// a field of the same name and nothing else.
#[derive(Debug, Clone, clap::Args, serde::Serialize)]
pub(crate) struct Tuning {
    /// Starting parameters; the options below override them.
    #[arg(long, value_enum, default_value_t = Preset::Default)]
    #[serde(skip)]
    preset: Preset,
    /// Rasterize on the GPU.
    #[arg(long, value_enum, default_value_t = Gpu::Off)]
    #[serde(skip)]
    gpu: Gpu,
    /// Fine-tuning rounds (k_max; the preset's: 10, 3 on grids of more than 80 cells along
    /// their longest side, where three hold ten's accuracy).
    #[arg(long, visible_alias = "iters")]
    #[serde(skip_serializing_if = "Option::is_none")]
    rounds: Option<usize>,
    /// Maximum tangency points per sphere (n_max).
    #[arg(long, visible_alias = "max-points")]
    #[serde(skip_serializing_if = "Option::is_none")]
    max_points_per_sphere: Option<usize>,
    /// Seed of every random choice.
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    seed: Option<u64>,
    /// Closed islands smaller than this many sample spacings across stay only where a sample
    /// witnesses them, inside them or touching them where the rest of the mesh leaves a gap (0
    /// keeps all; default: the library's `Params::min_island`).
    #[arg(long, value_parser = crate::ui::parse_non_negative)]
    #[serde(skip_serializing_if = "Option::is_none")]
    min_island: Option<f64>,
    /// The shape's genus, when known: the output becomes one surface of at most this genus (other
    /// components joined to the largest by a tube, the thinnest handles beyond it cut).
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    genus: Option<usize>,
    /// Keep the cavities the surface seals around outside samples where the grid leaves them
    /// open (a gap or a hole closed; in 2D, holes of the curve); by default they are opened.
    /// Voids walled in by inside samples are kept either way.
    #[arg(long)]
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    keep_cavities: bool,
    /// Keep the handles less than about a spacing across that no sample confirms, and the pieces
    /// less than a spacing across that no sample lies in; by default, on a grid, such a handle is
    /// cut along its loop (a bar through empty space cut, a tunnel filled) unless a sample of its
    /// side lies next to it, and such a piece removed. Scattered samples: kept.
    #[arg(long)]
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    keep_thin_handles: bool,
    /// Spheres farther than this many sample spacings from the surface own no tangency point
    /// (they stay constraints): a grid's spacing, or each scattered sample's own (the distance to
    /// its fourth nearest sample); 0 gives every sphere points, as the reference.
    #[arg(long, value_name = "SPACINGS", value_parser = crate::ui::parse_non_negative)]
    #[serde(skip_serializing_if = "Option::is_none")]
    owner_band: Option<f64>,
    /// Cells per axis of the empty-space rasterization (default: the paper's 64 ceil(n^(1/3) / 16)).
    #[arg(long, visible_alias = "raster-res", value_name = "CELLS", value_parser = clap::value_parser!(u32).range(8..=1024))]
    #[serde(skip_serializing_if = "Option::is_none")]
    raster_resolution: Option<u32>,
    /// Octree depth of the screened Poisson solves (default: matched to the sample spacing,
    /// 4 finest cells per spacing; the reference always uses 10).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16))]
    #[serde(skip_serializing_if = "Option::is_none")]
    depth: Option<u32>,
    /// Where the initial tangency points come from on a grid: the closest surface points the
    /// samples' gradients point to (the default), or the paper's rasterized empty space.
    /// Scattered samples are always rasterized.
    #[arg(long, value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    initial: Option<Initial>,
    /// How the samples are read: as distances (the paper's spheres), as a level set whose zero
    /// set is the surface (grids: trained networks, any field that is not a distance), as bounds
    /// on the distance (grids: CSG trees, smooth blends: spheres as empty space, points on the
    /// zero set), or, by default, as a level set when a grid's values fall short of their zero
    /// set and as bounds when other spheres cover some of theirs (the report's field figures say
    /// how far they reach and how many are covered).
    #[arg(long, value_enum)]
    #[serde(skip_serializing_if = "Option::is_none")]
    field: Option<FieldArg>,
    /// Write the repaired mesh unsimplified. By default its edges are collapsed while the
    /// surface stays within --simplify-tolerance of it, no sample changes side, no sphere is
    /// entered past the consistency check's margin and the topology stays the same.
    #[arg(long = "no-simplify", action = clap::ArgAction::SetFalse)]
    #[serde(skip_serializing_if = "Clone::clone")]
    simplify: bool,
    /// How far the simplified surface may lie from the unsimplified one, in sample spacings
    /// (default 0.8 / N for samples N spacings across, within 0.008 to 0.06: 0.06 at N = 10,
    /// 0.016 at N = 50, 0.008 from N = 100; with --faces, 1 unless given).
    #[arg(long, visible_alias = "tolerance", value_name = "SPACINGS", value_parser = crate::ui::parse_non_negative)]
    #[serde(skip_serializing_if = "Option::is_none")]
    simplify_tolerance: Option<f64>,
    /// Simplify to at most this many faces, as far as the samples, the topology and the
    /// tolerance allow.
    #[arg(long, value_name = "N")]
    #[serde(skip_serializing_if = "Option::is_none")]
    faces: Option<usize>,
}

/// `--field`: `rfta::Field` by its serde names.
#[derive(Debug, Clone, Copy, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub(crate) enum FieldArg {
    /// Distances when they behave like them, else a level set or bounds.
    Auto,
    /// The paper's spheres.
    Distance,
    /// The field's zero set (grids).
    LevelSet,
    /// Bounds on the distance: spheres as empty space, points on the zero set (grids).
    Bound,
}

/// `--initial`: `rfta::InitialPoints` by its serde names.
#[derive(Debug, Clone, Copy, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum Initial {
    /// From the samples' gradients (grids).
    Gradient,
    /// The paper's rasterized empty space.
    Raster,
}

/// The command-line name of a preset.
pub(crate) fn preset_name(p: Preset) -> String {
    clap::ValueEnum::to_possible_value(&p).map_or_else(String::new, |v| v.get_name().to_string())
}

impl Tuning {
    /// The options given, by [`rfta::Params`]' serde names.
    fn options(&self) -> serde_json::Map<String, serde_json::Value> {
        match serde_json::to_value(self) {
            Ok(serde_json::Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        }
    }

    /// These options as `reconstruct` arguments (what `batch` passes to each row), with `preset`
    /// in place of `--preset` where given.
    pub(crate) fn to_args(&self, preset: Option<Preset>) -> Vec<String> {
        let gpu = clap::ValueEnum::to_possible_value(&self.gpu)
            .map_or_else(String::new, |v| v.get_name().to_string());
        let mut a = vec![
            "--preset".to_string(),
            preset_name(preset.unwrap_or(self.preset)),
            "--gpu".to_string(),
            gpu,
        ];
        for (name, value) in self.options() {
            let flag = name.replace('_', "-");
            match value {
                // A flag (serialized only when given): `--keep-cavities`, `--no-simplify`.
                serde_json::Value::Bool(true) => a.push(format!("--{flag}")),
                serde_json::Value::Bool(false) => a.push(format!("--no-{flag}")),
                serde_json::Value::String(s) => a.extend([format!("--{flag}"), s]),
                v => a.extend([format!("--{flag}"), v.to_string()]),
            }
        }
        a
    }

    /// The preset, then the options given.
    pub(crate) fn params(&self) -> Result<Params> {
        // Every variant's name is one of rfta::PRESETS (tested below).
        let mut p = Params::preset(&preset_name(self.preset)).unwrap_or_default();
        p.gpu = !matches!(self.gpu, Gpu::Off);
        Ok(p.with_options(self.options())?)
    }
}

/// Reconstruct with a progress bar over the stages.
pub(crate) fn run_pipeline(
    samples: &SdfSamples,
    params: &Params,
    ui: &Ui,
) -> Result<rfta::Reconstruction> {
    // The initial points and the final solve, and the rounds once the first says how many the
    // run takes (they depend on the samples: `Params::rounds_for`).
    let bar = ui.progress(2, "rfta");
    let b = bar.clone();
    let mut label = String::from("initial");
    let mut progress = move |stage: Stage| match stage {
        Stage::Initial => {
            label = "initial".into();
            b.set_message(label.clone());
        }
        Stage::FineTune { round, of } => {
            b.set_length(of as u64 + 2);
            label = format!("round {round}/{of}");
            b.set_message(label.clone());
            b.inc(1);
        }
        Stage::Final => {
            label = "final".into();
            b.set_message(label.clone());
            b.inc(1);
        }
        Stage::Progress { done, of } => {
            b.set_message(format!("{label} {}%", 100 * done / of.max(1)));
        }
        _ => {}
    };
    let out = rfta::reconstruct_with_progress(samples, params, &mut progress);
    bar.finish_and_clear();
    Ok(out?)
}

pub(crate) fn describe(out: &rfta::Reconstruction, ui: &Ui, seconds: f64) {
    let r = &out.report;
    ui.detail(format!(
        "{} samples ({} negative), raster {}^3, {} empty-space points, {} feasible initial points ({} kept from the pass before); screened Poisson depth {} ({} in the rounds); points per round {:?}; {} spheres without a point, {} far spheres (constraints only)",
        r.input.samples, r.initial.negative, r.initial.raster_resolution, r.initial.empty_space_points, r.initial.feasible_initial, r.initial.seeded, r.rounds.spsr_depth, r.rounds.round_spsr_depth, r.rounds.points_per_round, r.final_solve.spheres_without_point, r.final_solve.far_spheres
    ));
    for (stage, t) in &r.timings {
        ui.detail(format!("  {stage}: {:.3} s", t.as_secs_f64()));
    }
    for change in r.changes() {
        ui.detail(change);
    }
    for answer in r.answers() {
        ui.say(answer);
    }
    ui.detail(r.agreement());
    if let Some(field) = r.field_quality() {
        ui.detail(field);
    }
    if let Some(why) = &r.rounds.stopped_early {
        ui.say(format!("warning: fine-tuning stopped early ({why})"));
    }
    for w in &r.warnings {
        ui.say(format!("warning: {w}"));
    }
    ui.say(format!(
        "{} vertices, {} faces, {} component(s), genus {}, {}, {} samples on the wrong side, {} spheres entered, in {seconds:.2} s",
        out.mesh.n_vertices(),
        out.mesh.n_faces(),
        r.mesh.components,
        r.mesh
            .genus
            .map_or_else(|| "undefined".to_string(), |g| g.to_string()),
        if r.mesh.watertight {
            "watertight"
        } else {
            "NOT watertight"
        },
        r.consistency.sign_errors,
        r.consistency.entered,
    ));
}

pub(crate) fn run(args: Args, ui: &Ui) -> Result<()> {
    let Some(input) = args.input.clone() else {
        bail!("an SDF file (or --from-mesh) is needed");
    };
    if args.budget.is_some() {
        bail!("--budget is the most evaluations of --from-mesh's SDF; an SDF file has its samples");
    }
    let mut files = crate::paths::Files::new();
    files
        .read_sdf("the input", &input)
        .write("the output (-o)", &args.output);
    if let Some(p) = &args.report {
        files.write("--report", p);
    }
    if let Some(p) = &args.points {
        files.write("--points", p);
    }
    if let Some(p) = &args.html {
        files.write("--html", p);
    }
    files.check()?;
    if rfta_io::is_sdf_2d(&input)? {
        crate::ui::check_output_2d(&args.output)?;
        let mut params = args.tuning.params()?;
        params.clamp = args.checks.clamp;
        params.check = !args.checks.no_check;
        let extras = crate::plane::Extras {
            report: args.report.as_deref(),
            points: args.points.as_deref(),
            html: args.html.as_deref(),
        };
        return crate::plane::reconstruct(&input, &args.output, args.bounds, &params, extras, ui);
    }
    crate::ui::check_output(&args.output)?;
    if let Some(p) = &args.points {
        crate::ui::check_output(p)?;
    }
    let mut params = args.tuning.params()?;
    params.clamp = args.checks.clamp;
    params.check = !args.checks.no_check;
    params.memory_limit = args.checks.max_memory.or_else(rfta::available_memory);
    // Refuse an oversized grid from its header, before reading the data.
    if let Some(n) = rfta_io::peek_sdf_len(&input, args.grid.as_deref())? {
        rfta::check_memory(n, &params).with_context(|| {
            format!(
                "{}: refused before reading (the limit is {})",
                input.display(),
                if args.checks.max_memory.is_some() {
                    "--max-memory"
                } else {
                    "the memory available now"
                }
            )
        })?;
    }
    let raw = match &args.grid {
        Some(name) => rfta_io::read_vdb(&input, Some(name), args.bounds)?,
        None => rfta_io::read_sdf(&input, args.bounds)?,
    };
    // An OpenVDB level set says where it is clamped: its background value.
    if params.clamp.is_none()
        && let Some(c) = raw.clamp
    {
        ui.say(format!("clamped at {c} (the level set's background value)"));
        params.clamp = Some(c);
    }
    let samples = match raw.validate(&input) {
        Ok(s) => s,
        Err(rfta_io::Error::Geom {
            source: source @ rfta::geom::Error::NoSignChange { .. },
            ..
        }) => return no_surface(&args, &source, ui),
        Err(e) => return Err(e.into()),
    };
    let t = Instant::now();
    let out = match run_pipeline(&samples, &params, ui) {
        Err(e) if matches!(e.downcast_ref(), Some(rfta::Error::NoSurface { .. })) => {
            return no_surface(&args, &e, ui);
        }
        Err(e) if matches!(e.downcast_ref(), Some(rfta::Error::NotADistance(_))) => {
            return Err(e.context(format!(
                "{}: reconstruction refused (--no-check turns the check off)",
                input.display()
            )));
        }
        other => other.with_context(|| format!("{}: reconstruction failed", input.display()))?,
    };
    let seconds = t.elapsed().as_secs_f64();
    let title = format!("rfta reconstruct {}", input.display());
    deliver(&args, &out, &samples, seconds, &title, None, ui)
}

/// What `reconstruct` does with a reconstruction: describe it, write the mesh and what the
/// options ask for beside it (`extra` joins the report's JSON: an adaptive run's own report).
pub(crate) fn deliver(
    args: &Args,
    out: &rfta::Reconstruction,
    samples: &SdfSamples,
    seconds: f64,
    title: &str,
    extra: Option<(&str, serde_json::Value)>,
    ui: &Ui,
) -> Result<()> {
    describe(out, ui, seconds);
    write(&args.output, &out.mesh, ui)?;
    if let Some(path) = &args.report {
        write_report(path, out, seconds, extra)?;
    }
    if let Some(path) = &args.html {
        let scene = crate::view::scene(
            title,
            &out.mesh,
            Some(samples),
            out.report.input.clamp,
            rfta_view::report_figures(&out.report),
        )?;
        crate::view::write(path, &scene)?;
        ui.say(format!("wrote {}", path.display()));
    }
    if let Some(path) = &args.points {
        let p = &out.points;
        let cloud = rfta::geom::OrientedPoints::new(p.points.clone(), p.normals.clone(), None)
            .context("the tangency points")?;
        rfta_io::write_oriented_points_ply(path, &cloud)?;
        ui.say(format!(
            "wrote {} tangency points to {}",
            cloud.len(),
            path.display()
        ));
    }
    Ok(())
}

/// The report as one JSON object: [`rfta::Report`]'s serde form, and the mesh's size and the
/// command's seconds.
fn write_report(
    path: &Path,
    out: &rfta::Reconstruction,
    seconds: f64,
    extra: Option<(&str, serde_json::Value)>,
) -> Result<()> {
    let mut json = serde_json::to_value(&out.report)?;
    if let Some((key, value)) = extra {
        json[key] = value;
    }
    json["vertices"] = out.mesh.n_vertices().into();
    json["faces"] = out.mesh.n_faces().into();
    json["seconds"] = seconds.into();
    crate::ui::write_json(path, &json)
}

/// The input describes no surface: an empty mesh is written, and the reason returned as
/// [`Exit::no_surface`] (exit status 3).
pub(crate) fn no_surface(args: &Args, why: &dyn std::fmt::Display, ui: &Ui) -> Result<()> {
    write(&args.output, &TriMesh::default(), ui)?;
    Err(Exit::no_surface(format!(
        "{}: {why}; wrote an empty mesh to {}",
        args.input
            .as_deref()
            .or(args.from_mesh.as_deref())
            .unwrap_or(Path::new("the input"))
            .display(),
        args.output.display()
    ))
    .into())
}

pub(crate) fn write(path: &Path, mesh: &TriMesh, ui: &Ui) -> Result<()> {
    // `write_mesh` refuses non-finite vertices and writes nothing.
    rfta_io::write_mesh(path, mesh)?;
    ui.say(format!("wrote {}", path.display()));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--preset`'s values are the library's presets, every one of them.
    #[test]
    fn the_presets_are_the_librarys() {
        let ours: Vec<String> = <Preset as clap::ValueEnum>::value_variants()
            .iter()
            .map(|&p| preset_name(p))
            .collect();
        assert_eq!(ours, rfta::PRESETS);
        for name in &ours {
            assert!(Params::preset(name).is_some(), "{name}");
        }
        assert_eq!(
            Params::preset("fast").map(|p| p.rounds),
            Some(Params::fast().rounds)
        );
    }

    /// `--field`'s values are the library's readings by their serde names, every one of them.
    #[test]
    fn the_field_values_are_the_librarys() {
        let fields: Vec<rfta::Field> = <FieldArg as clap::ValueEnum>::value_variants()
            .iter()
            .map(|f| {
                let name = serde_json::to_value(f).expect("a name");
                serde_json::from_value(name).expect("a library reading")
            })
            .collect();
        use rfta::Field::{Auto, Bound, Distance, LevelSet};
        assert_eq!(fields, [Auto, Distance, LevelSet, Bound]);
    }
}
