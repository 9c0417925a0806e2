//! The `rfta` command-line tool.
//!
//! Exit status: 0 on success, 1 when the work failed (the message says which file and why),
//! 2 for invalid command-line usage, 3 when `reconstruct`'s input describes no surface (every
//! value of one sign): an empty mesh is written and the reason printed; 4 when `batch` tried
//! every row and some failed or timed out. Output goes through
//! `writeln!` (`ui::note`, `info`'s `out!`), so a closed pipe ends the tool quietly instead of
//! panicking.

mod adaptive;
mod batch;
mod demo;
mod info;
mod paths;
mod plane;
mod psr;
mod reconstruct;
mod sample;
mod ui;
mod view;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Reach for the Arcs: meshes from signed distance samples.
#[derive(Debug, Parser)]
#[command(name = "rfta", version, about, long_about = None)]
struct Cli {
    /// Print nothing but errors (no progress bars, no summaries).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// Print timings and details.
    #[arg(short, long, global = true)]
    verbose: bool,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Sample the exact signed distance of a mesh (negative inside) on a regular grid.
    Sample(sample::Args),
    /// Marching cubes: the iso-surface of an SDF grid (the baseline rfta is compared against);
    /// marching squares on a 2D grid (polylines out: .obj .svg .csv).
    Mc {
        /// The SDF grid (.npy or .exr; 2D: .npy of shape (nx, ny), .png).
        input: PathBuf,
        /// Output mesh (.obj .ply .stl .glb).
        #[arg(short, long)]
        output: PathBuf,
        /// Grid bounds, overriding the sidecar (as for `sample`).
        #[arg(long, value_name = "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX", value_parser = ui::parse_bounds)]
        bounds: Option<rfta_io::GridBounds>,
        /// Iso value.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        iso: f64,
    },
    /// Reach for the Arcs: a mesh from signed distance samples.
    Reconstruct(reconstruct::Args),
    /// Reconstruct a built-in genus-2 shape from a 21^3 grid and compare with marching cubes
    /// (`--2d`: a 2D shape with a hole against marching squares, drawn as SVG).
    Demo(demo::DemoArgs),
    /// Screened Poisson surface reconstruction of oriented points (PoissonRecon's algorithm).
    Psr(psr::Args),
    /// Reconstruct every row of a manifest (or one shard of it), for job arrays: status CSV,
    /// resume, timeouts (docs/batch.md).
    Batch(batch::Args),
    /// A mesh as one HTML page that opens without a network: an interactive 3D view, with the
    /// samples on the wrong side, the spheres entered, thin handles, cavities and islands marked
    /// (`--sdf`), and marching cubes' mesh of the same grid to compare.
    View(view::Args),
    /// Describe a mesh or SDF file: counts, bounds, sign balance, watertightness, genus.
    Info {
        /// The file (.obj .off .ply .stl .glb meshes; .npy .exr .vdb .ply .csv .xyz SDF samples).
        file: PathBuf,
        /// Grid bounds for an .npy grid, overriding its sidecar (as for `sample`).
        #[arg(long, value_name = "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX", value_parser = ui::parse_bounds)]
        bounds: Option<rfta_io::GridBounds>,
        /// The level set of a .vdb file to describe, by name (default: the first level set).
        #[arg(long, value_name = "NAME")]
        grid: Option<String>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let ui = ui::Ui::new(cli.quiet, cli.verbose);
    // No input is read past a quarter of the memory this process may use (a link to /dev/zero,
    // a huge file): the rest is for decoding it and for the work.
    if let Some(bytes) = rfta::available_memory() {
        rfta_io::set_read_limit(bytes / 4);
    }
    // One cap for --threads and RAYON_NUM_THREADS: the cores here (threads beyond them only
    // cost; results never depend on the count).
    let threads = match rfta::start_global_pool(cli.threads) {
        Ok(pool) => {
            if let Some((n, from)) = pool.capped {
                ui.say(format!(
                    "warning: {from} {n} is more than the {} cores here; using {}",
                    pool.threads, pool.threads
                ));
            }
            pool.threads
        }
        Err(e) => {
            ui::note(&format!("error: {e}"));
            return ExitCode::from(1);
        }
    };
    let result = match cli.command {
        Command::Sample(args) => sample::run(args, &ui),
        Command::Psr(args) => psr::run(args, &ui),
        Command::Reconstruct(args) if args.input.is_none() => adaptive::from_mesh(&args, &ui),
        Command::Reconstruct(args) => reconstruct::run(args, &ui),
        Command::Demo(args) => demo::demo(args, &ui),
        Command::Batch(args) => batch::run(args, threads, &ui),
        Command::View(args) => view::run(args, &ui),
        Command::Info { file, bounds, grid } => info::run(&file, bounds, grid.as_deref(), &ui),
        Command::Mc {
            input,
            output,
            bounds,
            iso,
        } => mc(&input, &output, bounds, iso, &ui),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<ui::Exit>() => {
            ui::note(&e.to_string());
            e.downcast_ref::<ui::Exit>()
                .map_or(ExitCode::from(1), |x| ExitCode::from(x.code))
        }
        // The reader of our output went away (`rfta info x | head`): nothing left to say.
        Err(e)
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            ExitCode::SUCCESS
        }
        Err(e) => {
            // One line: the context chain joined, outermost first, without repeating a cause
            // that an outer message already quotes.
            let mut msg = String::new();
            for cause in e.chain().map(|c| c.to_string()) {
                if !msg.contains(&cause) {
                    msg += if msg.is_empty() { "" } else { ": " };
                    msg += &cause;
                }
            }
            ui::note(&format!("error: {msg}"));
            ExitCode::from(1)
        }
    }
}

fn mc(
    input: &std::path::Path,
    output: &std::path::Path,
    bounds: Option<rfta_io::GridBounds>,
    iso: f64,
    ui: &ui::Ui,
) -> anyhow::Result<()> {
    paths::Files::new()
        .read_sdf("the input", input)
        .write("the output (-o)", output)
        .check()?;
    if rfta_io::is_sdf_2d(input)? {
        ui::check_output_2d(output)?;
        return plane::marching_squares(input, output, bounds, iso, ui);
    }
    ui::check_output(output)?;
    let samples = rfta_io::read_sdf(input, bounds)?.validate(input)?;
    let Some(grid) = samples.as_grid() else {
        anyhow::bail!(
            "{}: marching cubes needs a grid, not scattered samples",
            input.display()
        );
    };
    let t = std::time::Instant::now();
    let mesh = rfta_mc::marching_cubes(grid, samples.values(), iso);
    ui.detail(format!(
        "marching cubes in {:.3} s",
        t.elapsed().as_secs_f64()
    ));
    if mesh.is_empty() {
        anyhow::bail!(
            "{}: the values never cross {iso}, so there is no surface",
            input.display()
        );
    }
    rfta_io::write_mesh(output, &mesh)?;
    ui.say(format!(
        "wrote {} ({})",
        output.display(),
        ui::mesh_summary(&mesh)
    ));
    Ok(())
}
