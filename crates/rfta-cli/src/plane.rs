//! The 2D commands: `rfta reconstruct` and `rfta mc` on 2D input (detected from the file), and
//! `rfta demo --2d`.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rfta::Params;
use rfta::geom::glam::DVec2;
use rfta::geom::plane::{Grid2, Polylines, SdfSamples2};

use crate::ui::{Exit, Ui};

/// The 2D samples of `input`, with `--bounds` (x and y of it) for grids without a sidecar.
fn read(input: &Path, bounds: Option<rfta_io::GridBounds>) -> Result<SdfSamples2> {
    let b = bounds.map(|b| (b.min.truncate(), b.max.truncate()));
    Ok(rfta_io::read_sdf_2d(input, b)?)
}

fn summary(curve: &Polylines) -> String {
    format!(
        "{} vertices, {} edges, {} loop{}{}",
        curve.vertices.len(),
        curve.edges.len(),
        curve.loops(),
        if curve.loops() == 1 { "" } else { "s" },
        if curve.is_closed() {
            ", closed"
        } else {
            ", NOT closed"
        }
    )
}

/// What `reconstruct` writes besides the curve.
pub(crate) struct Extras<'a> {
    /// `--report`: the key figures as JSON (the names `rfta batch` reads: `samples`,
    /// `vertices`, `faces` = edges, `components` = loops, `watertight` = closed).
    pub(crate) report: Option<&'a Path>,
    /// `--points`: the tangency points and normals, as PLY with `z = 0`.
    pub(crate) points: Option<&'a Path>,
    /// `--html`: one page with the curve drawn over the samples (and marching squares beside it
    /// on a grid), and the report's figures.
    pub(crate) html: Option<&'a Path>,
}

/// `rfta reconstruct` on 2D samples: polylines to `output` (.obj, .svg, .csv).
pub(crate) fn reconstruct(
    input: &Path,
    output: &Path,
    bounds: Option<rfta_io::GridBounds>,
    params: &Params,
    extras: Extras<'_>,
    ui: &Ui,
) -> Result<()> {
    let samples = match read(input, bounds) {
        Err(e)
            if matches!(
                e.downcast_ref(),
                Some(rfta_io::Error::Geom {
                    source: rfta::geom::Error::NoSignChange { .. },
                    ..
                })
            ) =>
        {
            rfta_io::write_polylines(output, &Polylines::default())?;
            return Err(Exit::no_surface(format!(
                "{e}; wrote an empty curve to {}",
                output.display()
            ))
            .into());
        }
        other => other?,
    };
    ui.detail(format!(
        "read {} 2D samples from {}{}",
        samples.len(),
        input.display(),
        samples
            .as_grid()
            .map(|g| format!(" (grid {} x {})", g.dims()[0], g.dims()[1]))
            .unwrap_or_default()
    ));
    let t = Instant::now();
    let out = match rfta::plane::reconstruct(&samples, params) {
        Err(e @ rfta::Error::NoSurface { .. }) => {
            rfta_io::write_polylines(output, &Polylines::default())?;
            return Err(Exit::no_surface(format!(
                "{}: {e}; wrote an empty curve to {}",
                input.display(),
                output.display()
            ))
            .into());
        }
        other => other.with_context(|| format!("{}: reconstruction failed", input.display()))?,
    };
    let r = &out.report;
    describe(&out, t.elapsed().as_secs_f64(), ui);
    rfta_io::write_polylines(output, &out.curve)?;
    ui.say(format!("wrote {}", output.display()));
    if let Some(path) = extras.report {
        // The report's own figures, and the curve's under the names the 3D report gives a mesh.
        let mut json = serde_json::to_value(r)?;
        json["dimension"] = 2.into();
        json["vertices"] = out.curve.vertices.len().into();
        json["faces"] = out.curve.edges.len().into();
        json["components"] = out.curve.loops().into();
        json["watertight"] = out.curve.is_closed().into();
        crate::ui::write_json(path, &json)?;
    }
    if let Some(path) = extras.html {
        write_page(path, input, &samples, &out, ui)?;
    }
    if let Some(path) = extras.points {
        let (p, n): (Vec<_>, Vec<_>) = out
            .points
            .iter()
            .map(|(p, n)| (p.extend(0.0), n.extend(0.0)))
            .unzip();
        let cloud = rfta::geom::OrientedPoints::new(p, n, None).context("the tangency points")?;
        rfta_io::write_oriented_points_ply(path, &cloud)?;
        ui.say(format!(
            "wrote {} tangency points to {}",
            cloud.len(),
            path.display()
        ));
    }
    Ok(())
}

/// What a 2D reconstruction did, as the command line says it.
fn describe(out: &rfta::plane::Reconstruction2, seconds: f64, ui: &Ui) {
    let r = &out.report;
    ui.say(format!(
        "reconstructed in {seconds:.2} s: {} tangency points on {} circles, {} rounds, quadtree depth {}; {}",
        r.points,
        r.circles_with_points,
        r.rounds,
        r.depth,
        summary(&out.curve)
    ));
    if r.holes_opened > 0 {
        ui.say(format!(
            "opened {} hole(s) the curve closed around outside samples, through a wall thinner than a spacing that no inside sample shows (--keep-cavities keeps them)",
            r.holes_opened
        ));
    }
    if r.edges_unsimplified > out.curve.edges.len() {
        ui.detail(format!(
            "simplified {} edges to {}, at most {:.3} sample spacings from the curve before, every sample's side and circle kept (--no-simplify keeps them all)",
            r.edges_unsimplified,
            out.curve.edges.len(),
            r.simplify_deviation
        ));
    }
}

/// `--html` for 2D input: the samples (blue inside), rfta's curve in red and, on a grid,
/// marching squares dashed in blue, as an inline SVG, with the report's figures below it.
fn write_page(
    path: &Path,
    input: &Path,
    samples: &SdfSamples2,
    out: &rfta::plane::Reconstruction2,
    ui: &Ui,
) -> Result<()> {
    let positions = samples.positions();
    let ms = samples
        .as_grid()
        .map(|g| rfta_mc::marching_squares(g, samples.values(), 0.0));
    let mut curves = vec![&out.curve];
    curves.extend(ms.as_ref());
    let mut svg = rfta_io::Svg::around(&curves, positions).samples(positions, samples.values());
    if let Some(ms) = &ms {
        svg = svg.curve(ms, "#1f618d", "6 4");
    }
    let svg = svg.curve(&out.curve, "#c0392b", "").finish();
    let escape = |t: &str| {
        t.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut rows = format!(
        "<tr><td>loops</td><td>{}</td></tr><tr><td>vertices</td><td>{}</td></tr><tr><td>closed</td><td>{}</td></tr>",
        out.curve.loops(),
        out.curve.vertices.len(),
        out.curve.is_closed()
    );
    if let Some(ms) = &ms {
        rows += &format!(
            "<tr><td>marching squares loops</td><td>{}</td></tr>",
            ms.loops()
        );
    }
    if let serde_json::Value::Object(m) = serde_json::to_value(&out.report)? {
        for (k, v) in m {
            rows += &format!(
                "<tr><td>{}</td><td>{}</td></tr>",
                escape(&k.replace('_', " ")),
                escape(&v.to_string())
            );
        }
    }
    let title = escape(&format!("rfta reconstruct {}", input.display()));
    let page = format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{title}</title>\
         <style>body{{font-family:sans-serif;margin:1em}}td{{padding:0 1em 0 0}}</style></head>\
         <body><h1>{title}</h1><p>Red: Reach for the Arcs; dashed blue: marching squares of the \
         same grid; dots: the samples (blue inside).</p>\n{svg}<table>{rows}</table></body></html>\n"
    );
    rfta_io::write_atomic(path, |w| w.write_all(page.as_bytes()))?;
    ui.say(format!("wrote {}", path.display()));
    Ok(())
}

/// `rfta mc` on a 2D grid: marching squares.
pub(crate) fn marching_squares(
    input: &Path,
    output: &Path,
    bounds: Option<rfta_io::GridBounds>,
    iso: f64,
    ui: &Ui,
) -> Result<()> {
    let samples = read(input, bounds)?;
    let Some(grid) = samples.as_grid() else {
        bail!(
            "{}: marching squares needs a grid, not scattered samples",
            input.display()
        );
    };
    let curve = rfta_mc::marching_squares(grid, samples.values(), iso);
    if curve.is_empty() {
        bail!(
            "{}: the values never cross {iso}, so there is no curve",
            input.display()
        );
    }
    rfta_io::write_polylines(output, &curve)?;
    ui.say(format!("wrote {} ({})", output.display(), summary(&curve)));
    Ok(())
}

/// The demo shape: a rounded square with an off-centre round hole and a notch. Each part's
/// distance is exact; the max of the square's and the negated hole's and notch's is exact outside
/// and a lower bound on the distance elsewhere, so the circles never cross the curve.
fn demo_shape(p: DVec2) -> f64 {
    let rounded_square = {
        let q = p.abs() - DVec2::splat(0.55);
        q.max(DVec2::ZERO).length() + q.x.max(q.y).min(0.0) - 0.15
    };
    let hole = (p - DVec2::new(0.2, 0.15)).length() - 0.28;
    let notch = (p - DVec2::new(-0.75, -0.35)).length() - 0.3;
    rounded_square.max(-hole).max(-notch)
}

/// `rfta demo --2d`: the demo shape on a grid, reconstructed and contoured, drawn in one SVG.
pub(crate) fn demo(output: &Path, res: usize, params: &Params, ui: &Ui) -> Result<()> {
    let grid = Grid2::from_bounds([res + 1, res + 1], DVec2::splat(-1.0), DVec2::splat(1.0))?;
    let values: Vec<f64> = (0..grid.len())
        .map(|i| demo_shape(grid.position(i)))
        .collect();
    let samples = SdfSamples2::grid(grid, values.clone())?;
    ui.say(format!(
        "demo --2d: a rounded square with a hole and a notch, sampled on a {0} x {0} grid",
        res + 1
    ));
    let t = Instant::now();
    let out = rfta::plane::reconstruct(&samples, params)?;
    let seconds = t.elapsed().as_secs_f64();
    let ms = rfta_mc::marching_squares(&grid, &values, 0.0);
    let err =
        |c: &Polylines| crate::ui::mean_and_max(c.vertices.iter().map(|&v| demo_shape(v).abs()));
    let (rm, rx) = err(&out.curve);
    let (mm, mx) = err(&ms);
    let line = format!(
        "distance of vertices to the true curve, mean / max: rfta {rm:.4} / {rx:.4} ({} loops, {seconds:.2} s), marching squares {mm:.4} / {mx:.4} ({} loops); grid spacing {:.4}",
        out.curve.loops(),
        ms.loops(),
        2.0 / res as f64
    );
    ui.say(&line);
    let positions: Vec<DVec2> = (0..grid.len()).map(|i| grid.position(i)).collect();
    let svg = rfta_io::Svg::around(&[&out.curve, &ms], &positions)
        .samples(&positions, &values)
        .curve(&ms, "#1f618d", "6 4")
        .curve(&out.curve, "#c0392b", "")
        .caption(&format!(
            "red: Reach for the Arcs (mean error {rm:.4}); dashed blue: marching squares (mean error {mm:.4}); dots: samples (blue inside)"
        ));
    match rfta_io::extension_of(output).as_deref() {
        Some("svg") => rfta_io::write_svg(output, svg)?,
        _ => {
            rfta_io::write_polylines(output, &out.curve)?;
            let drawing = output.with_extension("svg");
            rfta_io::write_svg(&drawing, svg)?;
            ui.say(format!("wrote {}", drawing.display()));
        }
    }
    ui.say(format!("wrote {}", output.display()));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_demo_shape_is_a_lower_bound_on_the_distance_with_one_hole() {
        // Inside the hole's centre: outside the shape; in the square's corner region: outside.
        assert!(demo_shape(DVec2::new(0.2, 0.15)) > 0.0);
        assert!(demo_shape(DVec2::new(-0.3, 0.4)) < 0.0);
        assert!(demo_shape(DVec2::splat(0.95)) > 0.0);
        // 1-Lipschitz on a few pairs (a lower bound of a distance is).
        for k in 0..100 {
            let t = k as f64 * 0.37;
            let (a, b) = (
                DVec2::new(t.sin(), t.cos()) * 0.9,
                DVec2::new(t.cos(), (2.0 * t).sin()) * 0.9,
            );
            assert!((demo_shape(a) - demo_shape(b)).abs() <= (a - b).length() + 1e-12);
        }
    }
}
