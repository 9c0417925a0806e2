//! `rfta reconstruct --from-mesh MESH --budget N` and `rfta demo --adaptive`: adaptive sampling
//! ([`rfta::adaptive`]) with an SDF that can be asked, a mesh's exact signed distance or the
//! demo's analytic shape.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::{Context, Result};
use rfta::adaptive::{AdaptiveReconstruction, Budget, OracleError, Pass};
use rfta::geom::Aabb;
use rfta::geom::glam::DVec3;
use rfta::{Params, Stage};
use rfta_mesh::{MeshSdf, Topology};

use crate::reconstruct::{Args, deliver};
use crate::ui::Ui;

/// `rfta reconstruct --from-mesh MESH`: the mesh's exact signed distance (negative inside, by
/// the winding number) asked where the reconstruction needs it.
pub(crate) fn from_mesh(args: &Args, ui: &Ui) -> Result<()> {
    let Some(mesh_path) = &args.from_mesh else {
        anyhow::bail!("give an SDF file or --from-mesh");
    };
    let mut files = crate::paths::Files::new();
    files
        .read("--from-mesh", mesh_path)
        .write("the output (-o)", &args.output);
    for (role, path) in [
        ("--report", &args.report),
        ("--points", &args.points),
        ("--html", &args.html),
    ] {
        if let Some(p) = path {
            files.write(role, p);
        }
    }
    files.check()?;
    crate::ui::check_output(&args.output)?;
    let mut mesh = rfta_io::read_mesh(mesh_path)?;
    let name = mesh_path.display().to_string();
    crate::sample::as_sdf_source(&mut mesh, &name, ui);
    let sdf = MeshSdf::new(&mesh).with_context(|| format!("{name}: cannot measure distances"))?;
    let bounds = match args.bounds {
        Some(b) => Aabb::new(b.min, b.max),
        None => crate::sample::cube_around(sdf.bounds()),
    };
    // A box that misses the mesh holds none of its surface: answered as no surface (exit 3,
    // an empty mesh), saying why, before any work (hostile test E13: it was blamed on the SDF).
    if !bounds.overlaps(&sdf.bounds()) {
        let why = format!(
            "--bounds [{}, {}] does not meet the mesh, which spans [{}, {}]: the box holds none of its surface",
            fmt_point(bounds.min),
            fmt_point(bounds.max),
            fmt_point(sdf.bounds().min),
            fmt_point(sdf.bounds().max)
        );
        return crate::reconstruct::no_surface(args, &why, ui);
    }
    let mut params = args.tuning.params()?;
    params.clamp = args.checks.clamp;
    params.check = !args.checks.no_check;
    params.memory_limit = args.checks.max_memory.or_else(rfta::available_memory);
    let budget = args.budget.unwrap_or(30_000);
    rfta::check_memory(budget, &params)
        .with_context(|| format!("--budget {budget}: refused before asking {name}'s distance"))?;
    let mut oracle = |p: &[DVec3]| -> Result<Vec<f64>, OracleError> { Ok(sdf.signed_distances(p)) };
    ui.say(format!(
        "asking {name}'s signed distance at most {} times over [{}, {}]",
        budget,
        fmt_point(bounds.min),
        fmt_point(bounds.max)
    ));
    let t = Instant::now();
    let out = match run(&mut oracle, bounds, budget, &params, ui) {
        Err(e) if matches!(e.downcast_ref(), Some(rfta::Error::NoSurface { .. })) => {
            return crate::reconstruct::no_surface(args, &e, ui);
        }
        other => other.with_context(|| format!("{name}: adaptive reconstruction failed"))?,
    };
    let seconds = t.elapsed().as_secs_f64();
    summarize(&out, ui);
    let extra = serde_json::to_value(&out.report)?;
    deliver(
        args,
        &out.reconstruction,
        &out.samples,
        seconds,
        &format!("rfta reconstruct --from-mesh {name} --budget {}", budget),
        Some(("adaptive", extra)),
        ui,
    )
}

/// `rfta demo --adaptive`: the demo's two tori asked at most `budget` times.
pub(crate) fn demo(output: &Path, budget: usize, params: &Params, ui: &Ui) -> Result<()> {
    let shape = rfta::geom::Analytic::TwoTori;
    let mut oracle = |p: &[DVec3]| -> Result<Vec<f64>, OracleError> {
        Ok(p.iter().map(|&q| shape.sdf(q)).collect())
    };
    ui.say(format!(
        "demo: two overlapping tori (genus 2), their exact SDF asked at most {budget} times where the reconstruction needs it"
    ));
    let t = Instant::now();
    let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    let out = run(&mut oracle, bounds, budget, params, ui)?;
    crate::reconstruct::describe(&out.reconstruction, ui, t.elapsed().as_secs_f64());
    summarize(&out, ui);
    let mesh = &out.reconstruction.mesh;
    let (mean, max) = crate::ui::mean_and_max(mesh.vertices.iter().map(|&v| shape.sdf(v).abs()));
    let genus = Topology::of(mesh).genus();
    ui.say(format!(
        "distance of vertices to the true surface, mean / max: {mean:.5} / {max:.5}; genus {}",
        genus.map_or("n/a (several components)".into(), |g| g.to_string())
    ));
    crate::reconstruct::write(output, mesh, ui)
}

/// The run with a progress line per pass.
fn run(
    oracle: &mut rfta::adaptive::Oracle<'_>,
    bounds: Aabb,
    budget: usize,
    params: &Params,
    ui: &Ui,
) -> Result<AdaptiveReconstruction> {
    let bar = ui.progress(budget as u64, "samples");
    let b = bar.clone();
    let mut on_pass = |pass: &Pass| {
        b.set_position(pass.samples as u64);
        b.set_message(format!(
            "largest error {:.2e}, refined {}",
            pass.largest_error, pass.refined
        ));
    };
    let out = rfta::adaptive::reconstruct_adaptive(
        oracle,
        bounds,
        Budget::evaluations(budget),
        params,
        &mut |_: Stage| {},
        &mut on_pass,
        &AtomicBool::new(false),
    );
    bar.finish_and_clear();
    Ok(out?)
}

fn summarize(out: &AdaptiveReconstruction, ui: &Ui) {
    let r = &out.report;
    for (i, p) in r.passes.iter().enumerate() {
        ui.detail(format!(
            "  pass {}: {} samples, {} cells probed, {} refined, largest error {:.3e}, {:.2} s rfta, {:.2} s SDF",
            i + 1,
            p.samples,
            p.probes,
            p.refined,
            p.largest_error,
            p.rfta_seconds,
            p.oracle_seconds
        ));
    }
    ui.say(format!(
        "{} evaluations of the SDF in {} passes (finest spacing {}): {:.2} s in rfta, {:.2} s in the SDF",
        r.evaluations,
        r.passes.len(),
        crate::sample::num(r.finest_spacing),
        r.rfta_seconds,
        r.oracle_seconds
    ));
}

fn fmt_point(p: DVec3) -> String {
    use crate::sample::num;
    format!("{}, {}, {}", num(p.x), num(p.y), num(p.z))
}
