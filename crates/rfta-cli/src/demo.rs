//! `rfta demo`: a built-in shape with holes, reconstructed from a grid (or asked adaptively),
//! beside marching cubes.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, bail};
use rfta::geom::{Grid, SdfSamples, TriMesh, glam::DVec3};

use crate::reconstruct::{Tuning, describe, run_pipeline, write};
use crate::ui::Ui;

/// `rfta demo`'s shape: two overlapping tori, genus 2 ([`rfta::geom::Analytic::TwoTori`]).
fn two_tori(p: DVec3) -> f64 {
    rfta::geom::Analytic::TwoTori.sdf(p)
}

#[derive(Debug, clap::Args)]
pub(crate) struct DemoArgs {
    /// Output mesh.
    #[arg(short, long, default_value = "demo.obj")]
    output: PathBuf,
    /// Grid cells per axis over [-1, 1]^3 (2D: default 32).
    #[arg(long)]
    res: Option<usize>,
    /// The 2D demo: a shape with a hole against marching squares, one SVG (default demo2d.svg).
    #[arg(long = "2d")]
    two_d: bool,
    /// Ask the shape's exact SDF where the reconstruction needs it (adaptive sampling) instead of
    /// sampling a grid.
    #[arg(long, conflicts_with_all = ["res", "two_d"])]
    adaptive: bool,
    /// With --adaptive: the most evaluations of the SDF (default 10000).
    #[arg(long, value_name = "N", requires = "adaptive")]
    budget: Option<usize>,
    #[command(flatten)]
    tuning: Tuning,
}

pub(crate) fn demo(args: DemoArgs, ui: &Ui) -> Result<()> {
    let output = if args.two_d && args.output == Path::new("demo.obj") {
        PathBuf::from("demo2d.svg")
    } else {
        args.output.clone()
    };
    crate::paths::Files::new()
        .write("the output (-o)", &output)
        .check()?;
    if args.two_d {
        crate::ui::check_output_2d(&output)?;
    } else {
        crate::ui::check_output(&output)?;
    }
    if args.adaptive {
        let budget = args.budget.unwrap_or(10_000);
        return crate::adaptive::demo(&output, budget, &args.tuning.params()?, ui);
    }
    let res = args.res.unwrap_or(if args.two_d { 32 } else { 20 });
    if res < 2 {
        bail!("--res must be at least 2");
    }
    if args.two_d {
        return crate::plane::demo(&output, res, &args.tuning.params()?, ui);
    }
    let grid = Grid::cube(res, -1.0, 1.0)?;
    let values: Vec<f64> = (0..grid.len())
        .map(|i| two_tori(grid.position(i)))
        .collect();
    let samples = SdfSamples::grid(grid, values.clone())?;
    ui.say(format!(
        "demo: two overlapping tori (genus 2) sampled on a {0}^3 grid ({1} samples)",
        res + 1,
        grid.len()
    ));
    let params = args.tuning.params()?;
    let t = Instant::now();
    let out = run_pipeline(&samples, &params, ui)?;
    describe(&out, ui, t.elapsed().as_secs_f64());
    let mc = rfta_mc::marching_cubes(&grid, &values, 0.0);
    let err = |m: &TriMesh| crate::ui::mean_and_max(m.vertices.iter().map(|&v| two_tori(v).abs()));
    let (rm, rx) = err(&out.mesh);
    let (mm, mx) = err(&mc);
    let genus = rfta_mesh::Topology::of(&out.mesh).genus();
    ui.say(format!(
        "distance of vertices to the true surface, mean / max: rfta {rm:.4} / {rx:.4}, marching cubes {mm:.4} / {mx:.4} (grid spacing {:.4}); genus {}",
        2.0 / res as f64,
        genus.map_or("n/a (several components)".into(), |g| g.to_string())
    ));
    if rx > mx {
        ui.say(format!(
            "(a vertex distance favours marching cubes' largest: its vertices sit on grid edges, where the samples pin the surface, and its faces cut across between them unmeasured; rfta's largest, {:.2} of a spacing, is where the two tori meet in a crease that its smooth surface rounds)",
            rx * res as f64 / 2.0
        ));
    }
    write(&args.output, &out.mesh, ui)
}
