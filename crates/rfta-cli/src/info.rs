//! `rfta info`: describe a mesh, SDF samples or oriented points.

use std::io::Write;
use std::path::Path;

use anyhow::{Result, bail};
use rfta_geom::{Layout, SignBalance, TriMesh};
use rfta_io::{GridBounds, RawSdf};
use rfta_mesh::Topology;

use crate::sample::fmt_vec;
use crate::ui::Ui;

/// `println!` that returns an error instead of panicking when stdout is closed (`rfta info | head`).
macro_rules! out {
    ($($arg:tt)*) => {
        writeln!(std::io::stdout().lock(), $($arg)*)?
    };
}

/// 2D samples: count, grid or scattered, bounds, signs and value range.
fn describe_2d(path: &Path, s: &rfta_geom::plane::SdfSamples2) -> Result<()> {
    out!("{}: 2D SDF samples", path.display());
    match s.as_grid() {
        Some(g) => {
            let [nx, ny] = g.dims();
            out!("  grid        {nx} x {ny} ({} samples)", s.len());
            out!("  spacing     {} {}", g.spacing().x, g.spacing().y);
        }
        None => out!("  scattered   {} samples", s.len()),
    }
    let (lo, hi) = s.bounds();
    out!("  bounds      ({}, {}) .. ({}, {})", lo.x, lo.y, hi.x, hi.y);
    let v = s.values();
    let negative = v.iter().filter(|&&x| x < 0.0).count();
    let (min, max) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    out!(
        "  values      {min} .. {max}; {negative} negative (inside), {} zero or positive",
        v.len() - negative
    );
    Ok(())
}

/// Polylines: counts, loops, closed or not, length, bounds.
fn describe_polylines(path: &Path, c: &rfta_geom::plane::Polylines) -> Result<()> {
    out!("{}: polylines", path.display());
    out!("  vertices    {}", c.vertices.len());
    out!("  edges       {}", c.edges.len());
    let mut degree = vec![0u32; c.vertices.len()];
    for &[a, b] in &c.edges {
        degree[a as usize] += 1;
        degree[b as usize] += 1;
    }
    let shape = if c.is_closed() {
        "closed, inside on the left"
    } else if degree.iter().all(|&d| d == 0 || d == 2) {
        "closed, edges not consistently directed"
    } else {
        "open"
    };
    out!("  loops       {} ({shape})", c.loops());
    out!("  length      {}", c.length());
    let (lo, hi) = c.vertices.iter().fold(
        (
            rfta_geom::glam::DVec2::splat(f64::INFINITY),
            rfta_geom::glam::DVec2::splat(f64::NEG_INFINITY),
        ),
        |(a, b), &v| (a.min(v), b.max(v)),
    );
    out!("  bounds      ({}, {}) .. ({}, {})", lo.x, lo.y, hi.x, hi.y);
    Ok(())
}

pub(crate) fn run(
    path: &Path,
    bounds: Option<GridBounds>,
    grid: Option<&str>,
    _ui: &Ui,
) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if matches!(ext.as_str(), "npy" | "exr" | "csv" | "xyz" | "txt" | "png")
        && rfta_io::is_sdf_2d(path)?
    {
        let b = bounds.map(|b| (b.min.truncate(), b.max.truncate()));
        return describe_2d(path, &rfta_io::read_sdf_2d(path, b)?);
    }
    match ext.as_str() {
        "obj" => {
            let mesh = rfta_io::read_mesh(path)?;
            if mesh.is_empty() {
                let lines = rfta_io::read_polylines(path)?;
                if !lines.is_empty() {
                    return describe_polylines(path, &lines);
                }
            }
            describe_mesh(path, &mesh)
        }
        "off" | "stl" | "glb" => describe_mesh(path, &rfta_io::read_mesh(path)?),
        "npy" | "exr" | "csv" | "xyz" | "txt" => {
            describe_sdf(path, rfta_io::read_sdf(path, bounds)?)
        }
        "vdb" => describe_sdf(path, rfta_io::read_vdb(path, grid, bounds)?),
        "ply" => {
            // A PLY holds a mesh (faces), SDF samples (a scalar) or oriented points (normals).
            let mesh = rfta_io::read_mesh(path);
            if let Ok(m) = &mesh
                && !m.is_empty()
            {
                return describe_mesh(path, m);
            }
            if let Ok(raw) = rfta_io::read_sdf(path, bounds) {
                return describe_sdf(path, raw);
            }
            let pts = match (rfta_io::read_oriented_points(path), mesh) {
                (Ok(pts), _) => pts,
                // An empty mesh (rfta writes one when there is no surface).
                (Err(_), Ok(m)) => return describe_mesh(path, &m),
                (Err(e), Err(_)) => return Err(e.into()),
            };
            out!("{}: oriented points", path.display());
            out!("  points      {}", pts.len());
            let b = pts.bounds();
            out!("  bounds      {} .. {}", fmt_vec(b.min), fmt_vec(b.max));
            Ok(())
        }
        _ => bail!(
            "{}: unknown file type (expected a mesh or SDF samples)",
            path.display()
        ),
    }
}

fn describe_mesh(path: &Path, mesh: &TriMesh) -> Result<()> {
    let t = Topology::of(mesh);
    let b = mesh.bounds();
    let yes = |x: bool| if x { "yes" } else { "no" };
    out!("{}: triangle mesh", path.display());
    out!(
        "  vertices    {} ({} used)",
        mesh.n_vertices(),
        t.n_vertices
    );
    out!("  faces       {}", mesh.n_faces());
    out!("  edges       {}", t.n_edges);
    out!("  bounds      {} .. {}", fmt_vec(b.min), fmt_vec(b.max));
    out!("  area        {:.6}", mesh.area());
    out!("  volume      {:.6}", mesh.signed_volume());
    out!(
        "  watertight  {} ({} boundary edges, {} non-manifold edges)",
        yes(t.is_watertight()),
        t.boundary_edges,
        t.nonmanifold_edges
    );
    out!(
        "  manifold    {} ({} non-manifold vertices)",
        yes(t.is_manifold()),
        t.nonmanifold_vertices
    );
    out!(
        "  oriented    {} ({} misoriented edges)",
        yes(t.is_consistently_oriented()),
        t.misoriented_edges
    );
    out!("  components  {}", t.components);
    out!("  euler       {}", t.euler_characteristic());
    match t.genus() {
        Some(g) => out!("  genus       {g}"),
        None => out!("  genus       undefined (not a closed manifold)"),
    }
    if t.degenerate_faces > 0 {
        out!("  degenerate  {} faces repeat a vertex", t.degenerate_faces);
    }
    Ok(())
}

fn describe_sdf(path: &Path, raw: RawSdf) -> Result<()> {
    let raw_clamp = raw.clamp;
    out!("{}: SDF samples ({})", path.display(), raw.description);
    out!("  samples     {}", raw.values.len());
    match &raw.layout {
        Layout::Grid(g) => {
            let b = g.bounds();
            out!(
                "  grid        {:?} points, spacing {}",
                g.dims(),
                fmt_vec(g.spacing())
            );
            out!(
                "  bounds      {} .. {} (from {})",
                fmt_vec(b.min),
                fmt_vec(b.max),
                raw.bounds_source
            );
        }
        Layout::Scattered(p) => {
            let b = rfta_geom::Aabb::from_points(p);
            out!("  bounds      {} .. {}", fmt_vec(b.min), fmt_vec(b.max));
        }
    }
    let finite = raw.values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    out!("  values      {lo:.6} .. {hi:.6}");
    let s = SignBalance::of(&raw.values);
    out!(
        "  signs       {} inside (< 0), {} zero, {} outside (> 0), {} not finite",
        s.negative,
        s.zero,
        s.positive,
        s.non_finite
    );
    match raw.validate(path) {
        Ok(samples) => {
            out!("  valid       yes");
            // What `rfta reconstruct` will make of the values (docs/hardening.md).
            let c = rfta::check::inspect(&samples);
            let worst = c.worst.map_or(String::new(), |(i, j, r)| {
                format!(", worst ratio {r:.3} (samples {i} and {j})")
            });
            out!(
                "  distance    {} of {} samples overlap the nearest sample of the other sign ({:.1}%), {} by more than {}x{worst}{}",
                c.inconsistent,
                c.checked,
                100.0 * c.inconsistent_fraction(),
                c.severe,
                c.severe_ratio(),
                if c.beyond_extent.is_empty() {
                    String::new()
                } else {
                    format!(
                        "; {} values exceed the samples' extent",
                        c.beyond_extent.len()
                    )
                }
            );
            let (rim_negative, rim_all) = c.rim;
            out!(
                "  sign        {rim_negative} of the {rim_all} samples around the set negative{}",
                if c.looks_inside_positive() {
                    ": looks inside-positive (reconstruct refuses it; negate the values)"
                } else {
                    ""
                }
            );
            match (raw_clamp, c.clamp) {
                (Some(v), _) => out!("  clamped     at {v} (the file's background value)"),
                (None, Some((v, n))) => out!("  clamped     at {v} ({n} plateau samples)"),
                (None, None) => out!("  clamped     no"),
            }
        }
        Err(e) => out!("  valid       no: {e}"),
    }
    Ok(())
}
