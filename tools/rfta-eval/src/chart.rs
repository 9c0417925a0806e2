//! Charts as SVG: Table 2's Chamfer against N, and the line charts of the scenarios.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use crate::report::{Reference, Row, mean, reference_method};

/// Mean Chamfer against N per method (solid) and reference (dashed), log scale.
pub(crate) fn write_svg(
    path: &Path,
    rows: &[Row],
    reference: &Reference,
    res: &[usize],
    methods: &[String],
) -> Result<()> {
    // (label, dashed, points)
    type Series = (String, bool, Vec<(usize, f64)>);
    let mut series: Vec<Series> = Vec::new();
    for m in methods {
        let ours: Vec<(usize, f64)> = res
            .iter()
            .filter_map(|&n| {
                mean(
                    rows.iter()
                        .filter(|r| r.n == n && &r.method == m)
                        .map(|r| r.chamfer),
                )
                .map(|(v, _)| (n, v))
            })
            .collect();
        let theirs: Vec<(usize, f64)> = res
            .iter()
            .filter_map(|&n| {
                mean(
                    rows.iter()
                        .filter(|r| r.n == n && &r.method == m)
                        .filter_map(|r| {
                            reference
                                .get(&(r.shape.clone(), n, reference_method(m)))
                                .map(|v| v.chamfer)
                        }),
                )
                .map(|(v, _)| (n, v))
            })
            .collect();
        series.push((m.clone(), false, ours));
        let label = format!("reference {}", reference_method(m));
        if !series.iter().any(|s| s.0 == label) {
            series.push((label, true, theirs));
        }
    }
    let series: Vec<Line> = series
        .into_iter()
        .map(|(l, d, pts)| (l, d, pts.into_iter().map(|(n, v)| (n as f64, v)).collect()))
        .collect();
    let ticks: Vec<(f64, String)> = res.iter().map(|&n| (n as f64, n.to_string())).collect();
    line_chart(
        path,
        "Mean Chamfer vs N (log scale)",
        "N (grid cells per axis)",
        &ticks,
        &series,
        2,
    )
}

/// One line of a chart: label, dashed, `(x, y)` points.
pub(crate) type Line = (String, bool, Vec<(f64, f64)>);

/// A line chart on a log y axis, written as SVG: `series` are `(label, dashed, (x, y) points)`,
/// `ticks` the x positions to label, `per_color` consecutive series that share a colour.
pub(crate) fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    ticks: &[(f64, String)],
    series: &[Line],
    per_color: usize,
) -> Result<()> {
    let (w, h, left, right, top, bottom) = (640.0, 400.0, 70.0, 170.0, 30.0, 50.0);
    let all: Vec<f64> = series
        .iter()
        .flat_map(|s| s.2.iter().map(|p| p.1))
        .filter(|v| *v > 0.0)
        .collect();
    let (lo, hi) = all
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v.log10()), b.max(v.log10()))
        });
    let (lo, hi) = if lo.is_finite() {
        (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
    } else {
        (-3.0, 0.0)
    };
    let (nlo, nhi) = ticks
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t.0), b.max(t.0))
        });
    let x = |n: f64| {
        left + (w - left - right)
            * if nhi > nlo {
                (n - nlo) / (nhi - nlo)
            } else {
                0.5
            }
    };
    let y = |v: f64| top + (h - top - bottom) * (hi - v.log10()) / (hi - lo);
    let colors = [
        "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
    ];
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    writeln!(
        s,
        "<text x=\"{}\" y=\"18\" text-anchor=\"middle\">{title}</text>",
        (left + w - right) / 2.0
    )?;
    for e in (lo as i64)..=(hi as i64) {
        let yy = y(10f64.powi(e as i32));
        writeln!(
            s,
            "<line x1=\"{left}\" x2=\"{}\" y1=\"{yy}\" y2=\"{yy}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\">1e{e}</text>",
            w - right,
            left - 6.0,
            yy + 4.0
        )?;
    }
    for (t, label) in ticks {
        writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{label}</text>",
            x(*t),
            h - bottom + 18.0
        )?;
    }
    writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{x_label}</text>",
        (left + w - right) / 2.0,
        h - 10.0
    )?;
    for (i, (label, dashed, pts)) in series.iter().enumerate() {
        let color = colors[(i / per_color.max(1)) % colors.len()];
        let dash = if *dashed {
            " stroke-dasharray=\"6 4\""
        } else {
            ""
        };
        let path: Vec<String> = pts
            .iter()
            .map(|(n, v)| format!("{:.1},{:.1}", x(*n), y(*v)))
            .collect();
        if !path.is_empty() {
            writeln!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"2\"{dash}/>",
                path.join(" ")
            )?;
        }
        let ly = top + 20.0 * i as f64;
        writeln!(
            s,
            "<line x1=\"{}\" x2=\"{}\" y1=\"{ly}\" y2=\"{ly}\" stroke=\"{color}\" stroke-width=\"2\"{dash}/><text x=\"{}\" y=\"{}\">{label}</text>",
            w - right + 10.0,
            w - right + 35.0,
            w - right + 40.0,
            ly + 4.0
        )?;
    }
    s.push_str("</svg>\n");
    rfta_io::write_atomic(path, |wr| wr.write_all(s.as_bytes()))?;
    Ok(())
}
