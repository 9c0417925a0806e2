//! `cargo xtask eval --adaptive`: prototype.

use std::time::Instant;

use anyhow::{Context, Result};
use rfta_geom::Aabb;
use rfta_geom::glam::DVec3;
use rfta_mesh::MeshIndex;
use rfta_metrics::MeshSummary;

use super::Shape;

pub(crate) fn run(shapes: &[Shape], budgets: &[usize], samples: usize) -> Result<()> {
    for shape in shapes {
        let gt_index = MeshIndex::new(&shape.gt).context("gt")?;
        let gt_summary = MeshSummary::of(&shape.gt);
        for &b in budgets {
            let t = Instant::now();
            let mut oracle = |p: &[DVec3]| -> std::result::Result<Vec<f64>, rfta::adaptive::OracleError> {
                Ok(gt_index.signed_distances(p))
            };
            let out = rfta::adaptive::reconstruct_adaptive(
                &mut oracle,
                Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
                rfta::adaptive::Budget::evaluations(b),
                &rfta::Params { spsr_depth: std::env::var("HACK_DEPTH").ok().and_then(|d| d.parse().ok()), ..rfta::Params::default() },
                &mut |_| {},
                &mut |_| {},
                &std::sync::atomic::AtomicBool::new(false),
            );
            let secs = t.elapsed().as_secs_f64();
            match out {
                Ok(out) => {
                    let mesh = &out.reconstruction.mesh;
                    let index = MeshIndex::new(mesh)?;
                    let ch = rfta_metrics::chamfer_indexed((&shape.gt, &gt_index), (mesh, &index), samples, 1);
                    let s = MeshSummary::of(mesh);
                    let c = &out.reconstruction.report.consistency;
                    println!(
                        "{} b={} evals={} chamfer={:.6} genus={:?}/{:?} comps={} cav={} wrong={} entered={} thin={} secs={:.2} rfta={:.2} oracle={:.2} passes={}",
                        shape.name, b, out.report.evaluations, ch, s.genus, gt_summary.genus, s.components, s.cavities,
                        c.sign_errors, c.entered, c.thin_loops.len(), secs, out.report.rfta_seconds, out.report.oracle_seconds,
                        out.report.passes.iter().map(|p| format!("[{} p{} r{} e{:.4} u{}]", p.samples, p.probes, p.refined, p.largest_error, p.undecided)).collect::<Vec<_>>().join("")
                    );
                    if std::env::var("RFTA_TIMINGS").is_ok() {
                        println!("{:?}", out.reconstruction.report.timings);
                    }
                }
                Err(e) => println!("{} b={} error {e}", shape.name, b),
            }
        }
    }
    Ok(())
}
