//! The evaluation's outputs: results.csv, report.md (Table 2's layout), chamfer.svg.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

/// One (shape, resolution, method) result.
#[derive(Debug, Clone)]
pub(crate) struct Row {
    pub(crate) shape: String,
    pub(crate) n: usize,
    pub(crate) method: String,
    pub(crate) seconds: f64,
    /// CPU seconds of this process (all threads) while the method ran.
    pub(crate) cpu_seconds: f64,
    pub(crate) chamfer: f64,
    pub(crate) hausdorff: f64,
    pub(crate) e_sdf: f64,
    pub(crate) watertight: bool,
    pub(crate) genus: Option<i64>,
    pub(crate) gt_genus: Option<i64>,
    pub(crate) components: usize,
    /// The mesh's faces.
    pub(crate) faces: usize,
    /// Components facing inward (`rfta_mesh::cavities`), and the ground truth's.
    pub(crate) cavities: usize,
    pub(crate) gt_cavities: usize,
    /// Agreement with every input sample (`rfta::consistency`); `None` when the method failed.
    pub(crate) consistency: Option<rfta::Consistency>,
    pub(crate) status: String,
}

/// Reference metrics by (shape, n, our method name).
pub(crate) type Reference = HashMap<(String, usize, String), RefRow>;

/// One reference result.
pub(crate) struct RefRow {
    pub(crate) chamfer: f64,
    hausdorff: f64,
    e_sdf: f64,
    cpu: f64,
    /// The ground truth's genus and one component; `None` where the file has no topology.
    right_topology: Option<bool>,
}

/// Reads `reference/gpytoolbox.csv` if present (methods `mc`, `rfta`, `rfta_paper`, `dcsdd`).
pub(crate) fn read_reference(path: &Path) -> Reference {
    let mut map = Reference::new();
    let Ok(text) = std::fs::read_to_string(path) else {
        return map;
    };
    let mut lines = text.lines();
    let Some(header) = lines.next() else {
        return map;
    };
    let cols: Vec<&str> = header.split(',').collect();
    let col = |n: &str| cols.iter().position(|c| *c == n);
    let (Some(m), Some(nn), Some(me), Some(ch), Some(ha), Some(es), Some(cpu), Some(st)) = (
        col("mesh"),
        col("n"),
        col("method"),
        col("chamfer"),
        col("hausdorff"),
        col("sdf_energy"),
        col("cpu_seconds"),
        col("status"),
    ) else {
        return map;
    };
    let (genus, gt_genus, components) = (col("genus"), col("gt_genus"), col("components"));
    for l in lines {
        let r: Vec<&str> = l.split(',').collect();
        if r.len() < cols.len() || r[st] != "ok" {
            continue;
        }
        let num = |i: usize| r[i].parse::<f64>().unwrap_or(f64::NAN);
        let method = r[me].replace('_', "-");
        let right_topology = match (genus, gt_genus, components) {
            (Some(g), Some(t), Some(c)) => Some(num(g) == num(t) && num(c) == 1.0),
            _ => None,
        };
        if let Ok(n) = r[nn].parse() {
            map.insert(
                (r[m].to_string(), n, method),
                RefRow {
                    chamfer: num(ch),
                    hausdorff: num(ha),
                    e_sdf: num(es),
                    cpu: num(cpu),
                    right_topology,
                },
            );
        }
    }
    map
}

/// The reference rows a method is compared with: gpytoolbox has no run of the default preset,
/// so `rfta-default` is shown next to gpytoolbox's defaults (`rfta`), the comparison the speed
/// goal is stated in.
pub(crate) fn reference_method(m: &str) -> String {
    match m {
        "rfta-default" | "rfta-genus" => "rfta".into(),
        other => other.into(),
    }
}

pub(crate) fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut s = String::from(
        "shape,n,method,seconds,cpu_seconds,chamfer,hausdorff,e_sdf,watertight,genus,gt_genus,components,faces,cavities,gt_cavities,sign_errors,entered,gaps,deepest_entry,thin_loops,status\n",
    );
    for r in rows {
        let g = |v: Option<i64>| v.map(|g| g.to_string()).unwrap_or_default();
        let c =
            |f: fn(&rfta::Consistency) -> String| r.consistency.as_ref().map(f).unwrap_or_default();
        writeln!(
            s,
            "{},{},{},{:.6},{:.3},{:.6},{:.6},{:.6},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.shape,
            r.n,
            r.method,
            r.seconds,
            r.cpu_seconds,
            r.chamfer,
            r.hausdorff,
            r.e_sdf,
            r.watertight,
            g(r.genus),
            g(r.gt_genus),
            r.components,
            r.faces,
            r.cavities,
            r.gt_cavities,
            c(|c| c.sign_errors.to_string()),
            c(|c| c.entered.to_string()),
            c(|c| c.gaps.to_string()),
            c(|c| format!("{:.3}", c.deepest_entry)),
            c(|c| c.thin_loops.len().to_string()),
            r.status.replace(',', ";")
        )?;
    }
    rfta_io::write_atomic(path, |w| w.write_all(s.as_bytes()))?;
    Ok(())
}

pub(crate) fn mean(values: impl Iterator<Item = f64>) -> Option<(f64, usize)> {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    (!v.is_empty()).then(|| (v.iter().sum::<f64>() / v.len() as f64, v.len()))
}

fn fmt(m: Option<(f64, usize)>, total: usize) -> String {
    match m {
        Some((v, k)) if k == total => format!("{v:.5}"),
        Some((v, k)) => format!("{v:.5} ({k}/{total})"),
        None => "n/a".into(),
    }
}

/// A UTC calendar date from the system clock (days-from-civil inverse, Hinnant's algorithm).
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    format!("{:04}-{m:02}-{d:02}", yoe + era * 400 + i64::from(m <= 2))
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!("{cpu}, {cores} threads")
}

pub(crate) fn write_markdown(
    path: &Path,
    rows: &[Row],
    reference: &Reference,
    res: &[usize],
    methods: &[String],
    samples: usize,
) -> Result<()> {
    let mut s = String::new();
    writeln!(s, "# rfta evaluation\n")?;
    writeln!(
        s,
        "Date: {}. Machine: {}. Chamfer with {samples} samples per side.",
        today(),
        machine()
    )?;
    writeln!(
        s,
        "Metrics as the paper defines them (`rfta-metrics`); reference columns are the shared data's results (libigl marching cubes, gpytoolbox `reach_for_the_arcs`, and gpytoolbox's `dual_contouring_of_signed_distance_data`, the authors' newer method, as `dcsdd`) on the same inputs.\n"
    )?;
    type Subset = (&'static str, fn(&Row) -> bool);
    let subsets: [Subset; 3] = [
        ("all shapes", |_| true),
        ("genus 0", |r| r.gt_genus == Some(0)),
        ("genus > 0", |r| r.gt_genus.is_some_and(|g| g > 0)),
    ];
    for (metric, pick, ref_pick) in [
        (
            "Chamfer",
            (|r: &Row| r.chamfer) as fn(&Row) -> f64,
            (|v: &RefRow| v.chamfer) as fn(&RefRow) -> f64,
        ),
        ("Hausdorff", |r: &Row| r.hausdorff, |v: &RefRow| v.hausdorff),
        ("E_SDF", |r: &Row| r.e_sdf, |v: &RefRow| v.e_sdf),
    ] {
        writeln!(s, "## Mean {metric}\n")?;
        for (subset, keep) in subsets {
            writeln!(s, "{subset}:\n")?;
            let mut head = String::from("| N |");
            let mut rule = String::from("|---|");
            for m in methods {
                write!(head, " {m} | reference {} |", reference_method(m))?;
                rule.push_str("---|---|");
            }
            // The authors' newer method, from the shared reference results only.
            head.push_str(" reference dcsdd |");
            rule.push_str("---|");
            writeln!(s, "{head}\n{rule}")?;
            for &n in res {
                let mut line = format!("| {n} |");
                for m in methods {
                    let sel: Vec<&Row> = rows
                        .iter()
                        .filter(|r| r.n == n && &r.method == m && keep(r))
                        .collect();
                    let ours = mean(sel.iter().map(|r| pick(r)));
                    let theirs = mean(sel.iter().filter_map(|r| {
                        reference
                            .get(&(r.shape.clone(), n, reference_method(m)))
                            .map(ref_pick)
                    }));
                    write!(
                        line,
                        " {} | {} |",
                        fmt(ours, sel.len()),
                        fmt(theirs, sel.len())
                    )?;
                }
                let mut shapes: Vec<&str> = rows
                    .iter()
                    .filter(|r| r.n == n && keep(r))
                    .map(|r| r.shape.as_str())
                    .collect();
                shapes.sort_unstable();
                shapes.dedup();
                let dcsdd = mean(shapes.iter().filter_map(|shape| {
                    reference
                        .get(&(shape.to_string(), n, "dcsdd".to_string()))
                        .map(ref_pick)
                }));
                write!(line, " {} |", fmt(dcsdd, shapes.len()))?;
                writeln!(s, "{line}")?;
            }
            writeln!(s)?;
        }
    }
    write_consistency(&mut s, rows, reference, res, methods)?;
    writeln!(s, "## Time\n")?;
    writeln!(
        s,
        "Mean wall and CPU seconds per shape (reference: CPU seconds on a shared 2-core machine).\n"
    )?;
    writeln!(
        s,
        "| N | method | seconds | CPU seconds | reference CPU seconds | reference CPU / ours | ratio to mc |\n|---|---|---|---|---|---|---|"
    )?;
    for &n in res {
        let mc = mean(
            rows.iter()
                .filter(|r| r.n == n && r.method == "mc" && r.status == "ok")
                .map(|r| r.seconds),
        );
        for m in methods {
            let sel: Vec<&Row> = rows
                .iter()
                .filter(|r| r.n == n && &r.method == m && r.status == "ok")
                .collect();
            let t = mean(sel.iter().map(|r| r.seconds));
            let cpu = mean(sel.iter().map(|r| r.cpu_seconds));
            let rt = mean(
                rows.iter()
                    .filter(|r| r.n == n && &r.method == m)
                    .filter_map(|r| {
                        reference
                            .get(&(r.shape.clone(), n, reference_method(m)))
                            .map(|v| v.cpu)
                    }),
            );
            let ratio = match (t, mc) {
                (Some((a, _)), Some((b, _))) if b > 0.0 => format!("{:.1}", a / b),
                _ => "n/a".into(),
            };
            let speedup = match (cpu, rt) {
                (Some((a, _)), Some((b, _))) if a > 0.0 => format!("{:.1}", b / a),
                _ => "n/a".into(),
            };
            writeln!(
                s,
                "| {n} | {m} | {} | {} | {} | {speedup} | {ratio} |",
                fmt(t, sel.len().max(1)),
                fmt(cpu, sel.len().max(1)),
                fmt(rt, 1).split(' ').next().unwrap_or("n/a")
            )?;
        }
    }
    write_faces(&mut s, rows, methods, res)?;
    writeln!(s, "\n## Per shape\n")?;
    writeln!(
        s,
        "| shape | N | method | seconds | Chamfer | reference | Hausdorff | E_SDF | watertight | genus (GT) | components | faces | cavities (GT) | wrong side / entered / thin loops | status |"
    )?;
    writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )?;
    for r in rows {
        let refc = reference
            .get(&(r.shape.clone(), r.n, reference_method(&r.method)))
            .map(|v| format!("{:.5}", v.chamfer))
            .unwrap_or_else(|| "n/a".into());
        let g = r.genus.map(|g| g.to_string()).unwrap_or_else(|| "-".into());
        let gt = r
            .gt_genus
            .map(|g| g.to_string())
            .unwrap_or_else(|| "-".into());
        writeln!(
            s,
            "| {} | {} | {} | {:.3} | {:.5} | {refc} | {:.5} | {:.4} | {} | {g} ({gt}) | {} | {} | {} ({}) | {} | {} |",
            r.shape,
            r.n,
            r.method,
            r.seconds,
            r.chamfer,
            r.hausdorff,
            r.e_sdf,
            r.watertight,
            r.components,
            r.faces,
            r.cavities,
            r.gt_cavities,
            r.consistency
                .as_ref()
                .map(|c| format!("{} / {} / {}", c.sign_errors, c.entered, c.thin_loops.len()))
                .unwrap_or_else(|| "-".into()),
            r.status
        )?;
    }
    writeln!(
        s,
        "\n`contact_sheet.png` (labelled in `contact_sheet.html`): one row per shape, the ground truth first, then each method's output by resolution, every face coloured by its distance to the ground truth."
    )?;
    rfta_io::write_atomic(path, |w| w.write_all(s.as_bytes()))?;
    Ok(())
}

/// Agreement with the samples and with the ground truth's topology, per N and method.
/// The median faces per shape of each method at each N, beside marching cubes'.
fn write_faces(s: &mut String, rows: &[Row], methods: &[String], res: &[usize]) -> Result<()> {
    writeln!(s, "\n## Faces\n")?;
    writeln!(
        s,
        "Median faces per shape, and that median over marching cubes' on the same grids.\n"
    )?;
    writeln!(
        s,
        "| N | method | median faces | ratio to mc |\n|---|---|---|---|"
    )?;
    let median = |n: usize, m: &str| {
        let mut f: Vec<usize> = rows
            .iter()
            .filter(|r| r.n == n && r.method == m && r.status == "ok")
            .map(|r| r.faces)
            .collect();
        f.sort_unstable();
        match f.len() {
            0 => None,
            k if k % 2 == 1 => Some(f[k / 2] as f64),
            k => Some(0.5 * (f[k / 2 - 1] + f[k / 2]) as f64),
        }
    };
    for &n in res {
        let mc = median(n, "mc");
        for m in methods {
            let Some(faces) = median(n, m) else { continue };
            let ratio = mc
                .filter(|&b| b > 0.0)
                .map_or_else(|| "n/a".into(), |b| format!("{:.2}", faces / b));
            writeln!(s, "| {n} | {m} | {faces:.0} | {ratio} |")?;
        }
    }
    Ok(())
}

fn write_consistency(
    s: &mut String,
    rows: &[Row],
    reference: &Reference,
    res: &[usize],
    methods: &[String],
) -> Result<()> {
    writeln!(s, "## Agreement with the samples and the topology\n")?;
    let margins = rfta::Margins::default();
    writeln!(
        s,
        "Per N and method, over the shapes that produced a mesh (`rfta::consistency`, h = grid spacing): samples with |s| > {} h on the wrong side of the mesh by winding number, and samples whose sphere the mesh enters by more than {} h (total, and the shapes with any); the worst shape's share of entered samples; independent loops around handles shorter than {:.2} h, thin handles the samples can neither confirm nor rule out (total, and the shapes with any); cavities the ground truth lacks (inward-facing components beyond its own; total, and the shapes with any); the shapes whose output has the ground truth's genus and one component. The reference rows give the last column for the shared data's results on the same shapes (the other columns were not measured for them).\n",
        margins.sign, margins.enter, margins.thin_loop
    )?;
    writeln!(
        s,
        "| N | method | shapes | wrong side (shapes) | entered (shapes) | worst entered % | thin loops (shapes) | extra cavities (shapes) | right genus, one component |\n|---|---|---|---|---|---|---|---|---|"
    )?;
    for &n in res {
        for m in methods {
            let sel: Vec<&Row> = rows.iter().filter(|r| r.n == n && &r.method == m).collect();
            let done: Vec<(&Row, &rfta::Consistency)> = sel
                .iter()
                .filter_map(|r| r.consistency.as_ref().map(|c| (*r, c)))
                .collect();
            let wrong: usize = done.iter().map(|(_, c)| c.sign_errors).sum();
            let wrong_shapes = done.iter().filter(|(_, c)| c.sign_errors > 0).count();
            let entered: usize = done.iter().map(|(_, c)| c.entered).sum();
            let entered_shapes = done.iter().filter(|(_, c)| c.entered > 0).count();
            let worst = done
                .iter()
                .map(|(_, c)| 100.0 * c.entered as f64 / c.samples.max(1) as f64)
                .fold(0.0, f64::max);
            let thin: usize = done.iter().map(|(_, c)| c.thin_loops.len()).sum();
            let thin_shapes = done
                .iter()
                .filter(|(_, c)| !c.thin_loops.is_empty())
                .count();
            let extra = |r: &Row| r.cavities.saturating_sub(r.gt_cavities);
            let cavities: usize = done.iter().map(|(r, _)| extra(r)).sum();
            let cavity_shapes = done.iter().filter(|(r, _)| extra(r) > 0).count();
            let right = done
                .iter()
                .filter(|(r, _)| r.genus.is_some() && r.genus == r.gt_genus && r.components == 1)
                .count();
            writeln!(
                s,
                "| {n} | {m} | {} of {} | {wrong} ({wrong_shapes}) | {entered} ({entered_shapes}) | {worst:.2} | {thin} ({thin_shapes}) | {cavities} ({cavity_shapes}) | {right} |",
                done.len(),
                sel.len()
            )?;
        }
        let mut shapes: Vec<&str> = rows
            .iter()
            .filter(|r| r.n == n)
            .map(|r| r.shape.as_str())
            .collect();
        shapes.sort_unstable();
        shapes.dedup();
        for m in ["mc", "rfta", "rfta-paper", "dcsdd"] {
            let known: Vec<bool> = shapes
                .iter()
                .filter_map(|sh| reference.get(&(sh.to_string(), n, m.to_string())))
                .filter_map(|v| v.right_topology)
                .collect();
            if known.is_empty() {
                continue;
            }
            writeln!(
                s,
                "| {n} | reference {m} | {} of {} | - | - | - | - | - | {} |",
                known.len(),
                shapes.len(),
                known.iter().filter(|&&k| k).count()
            )?;
        }
    }
    writeln!(s)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_topology_is_the_ground_truths_genus_with_one_component() -> Result<()> {
        let dir = std::env::temp_dir().join(format!("rfta-ref-{}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let csv = dir.join("gpytoolbox.csv");
        std::fs::write(
            &csv,
            "mesh,n,method,seconds,cpu_seconds,chamfer,hausdorff,sdf_energy,genus,gt_genus,components,status\n\
             a,20,mc,0,0.5,0.1,0.2,0.3,1,1,1,ok\n\
             b,20,mc,0,0.5,0.1,0.2,0.3,1,1,2,ok\n\
             c,20,mc,0,0.5,0.1,0.2,0.3,0,1,1,ok\n\
             d,20,mc,0,0.5,0.1,0.2,0.3,1,1,1,timeout\n\
             a,20,rfta_paper,0,7.0,0.4,0.5,0.6,2,2,1,ok\n",
        )?;
        let reference = read_reference(&csv);
        std::fs::remove_dir_all(&dir)?;
        let right = |shape: &str, m: &str| {
            reference
                .get(&(shape.to_string(), 20, m.to_string()))
                .and_then(|r| r.right_topology)
        };
        assert_eq!(right("a", "mc"), Some(true));
        assert_eq!(right("b", "mc"), Some(false), "two components");
        assert_eq!(right("c", "mc"), Some(false), "wrong genus");
        assert_eq!(right("d", "mc"), None, "not ok: not read");
        assert_eq!(right("a", "rfta-paper"), Some(true));
        let a = &reference[&("a".to_string(), 20, "rfta-paper".to_string())];
        assert_eq!((a.chamfer, a.cpu), (0.4, 7.0));

        let mut s = String::new();
        write_consistency(&mut s, &[], &reference, &[20], &[])?;
        assert!(
            !s.contains("| reference"),
            "no shapes evaluated, no reference rows"
        );
        Ok(())
    }
}
