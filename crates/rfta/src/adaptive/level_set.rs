//! The adaptive mode on a function that is not a distance ([`crate::field`]: a trained network,
//! whose values flatten away from its zero set, so no sphere bounds where the surface is).
//!
//! Refinement by sign, as MISE does (Mescheder et al., "Occupancy Networks", CVPR 2019): from the
//! base grid, each level halves the spacing and asks the function at the new points of the cells
//! whose corners change sign (and, at the base level, of their neighbours: a part thinner than a
//! base cell shows in one of them); every other point of the finer grid takes the value of the
//! coarser grid's cubic interpolant ([`rfta_geom::CubicField`]). Levels go on while the next one
//! fits in the budget. The finest grid is then read as a level set: its zero set's points by
//! Newton's method, one screened Poisson solve, the repair and the verdict
//! ([`crate::reconstruct`] with [`Field::LevelSet`]); pieces a strut thinner than the finest
//! spacing left apart are joined where the function, asked with what the budget has left, is
//! inside between them (`bridge.rs`).

use std::time::Instant;

use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{CubicField, Grid, SdfSamples};

use super::{AdaptiveReconstruction, AdaptiveReport, Asker, Pass};
use crate::field::{Field, FieldReport};
use crate::{Params, Result, Stage};

/// The finest grid's cells per axis at most (a dense grid of that many points is held).
const MAX_CELLS: usize = 512;

/// The base grid and its measure when the function is read as a level set ([`crate::field`]).
pub(super) fn base_if_level_set(
    lattice: &super::lattice::Lattice,
    params: &Params,
) -> Result<Option<(SdfSamples, FieldReport)>> {
    match params.field {
        Field::Distance => return Ok(None),
        Field::Bound => {
            return Err(crate::Error::InvalidParams(
                "field = bound reads a grid's samples; a function is asked adaptively as distances or as a level set (field = distance, level-set or auto)".into(),
            ));
        }
        Field::Auto | Field::LevelSet => {}
    }
    let (grid, values) = lattice.base_grid()?;
    let base = SdfSamples::grid(grid, values)?;
    let field = crate::field::measure(&base, params.field, params.clamp);
    Ok((field.read_as == crate::Reading::LevelSet).then_some((base, field)))
}

/// Refines `base` (the base grid, every value asked) by sign within `budget` evaluations in all,
/// then reads the finest grid as a level set (the module docs). `field` is the base grid's
/// measure, reported.
pub(super) fn refine_and_read(
    (base, field): (SdfSamples, FieldReport),
    asker: &mut Asker<'_>,
    budget: usize,
    params: &Params,
    progress: &mut (dyn FnMut(Stage) + Send),
    on_pass: &mut dyn FnMut(&Pass),
) -> Result<AdaptiveReconstruction> {
    let grid = *base.as_grid().ok_or_else(|| {
        crate::Error::InvalidParams("the adaptive base samples are a grid".into())
    })?;
    let values = base.values().to_vec();
    let mut report = AdaptiveReport {
        budget,
        ..AdaptiveReport::default()
    };
    let mut asked: Vec<(DVec3, f64)> = (0..grid.len())
        .map(|i| (grid.position(i), values[i]))
        .collect();
    let (mut grid, mut values) = (grid, values);
    let mut known = vec![true; grid.len()];
    let mut dilate = true;
    loop {
        let t = Instant::now();
        let oracle_before = asker.seconds;
        let fine = finer(&grid)?;
        if fine.dims().iter().any(|&d| d > MAX_CELLS + 1) {
            break;
        }
        let marked = crossed_cells(&grid, &values, dilate);
        let need = nodes_to_ask(&grid, &fine, &marked, &known);
        if need.is_empty() || asked.len() + need.len() > budget {
            break;
        }
        let (mut next, mut now_known) = carried(&grid, &values, &known, &fine)?;
        let points: Vec<DVec3> = need.iter().map(|&i| fine.position(i)).collect();
        let found = asker.values(&points)?;
        for ((&i, &v), &p) in need.iter().zip(&found).zip(&points) {
            next[i] = v;
            now_known[i] = true;
            asked.push((p, v));
        }
        (grid, values, known) = (fine, next, now_known);
        dilate = false;
        let pass = Pass {
            samples: asked.len(),
            refined: marked.iter().filter(|&&m| m).count(),
            oracle_seconds: asker.seconds - oracle_before,
            rfta_seconds: t.elapsed().as_secs_f64() - (asker.seconds - oracle_before),
            ..Pass::default()
        };
        on_pass(&pass);
        report.passes.push(pass);
    }
    let t = Instant::now();
    report.finest_spacing = grid.spacing().max_element();
    let samples = SdfSamples::grid(grid, values)?;
    // The grid's values between the asked ones are interpolated: the input check would judge
    // the interpolation, not the function, and only asked samples start zero-set points.
    let read = Params {
        field: Field::LevelSet,
        check: false,
        ..params.clone()
    };
    let points = crate::field::zero_set_points(&samples, Some(&known));
    let mut reconstruction = crate::run(&samples, &read, Some(&points), progress, asker.cancel)?;
    join_pieces(
        &mut reconstruction,
        asker,
        &mut asked,
        budget,
        report.finest_spacing,
    )?;
    let (positions, asked_values): (Vec<DVec3>, Vec<f64>) = asked.into_iter().unzip();
    let asked =
        SdfSamples::scattered(positions, asked_values)?.with_spacing(report.finest_spacing)?;
    agree_with_asked(&mut reconstruction, &asked)?;
    if let (Field::Auto, Some(reach)) = (params.field, field.reach) {
        (reconstruction.report.warnings).insert(0, crate::Warning::LevelSet { reach });
    }
    reconstruction.report.field = field;
    let last = Pass {
        samples: asked.len(),
        rfta_seconds: t.elapsed().as_secs_f64(),
        ..Pass::default()
    };
    on_pass(&last);
    report.passes.push(last);
    report.evaluations = asked.len();
    report.oracle_seconds = asker.seconds;
    report.rfta_seconds = report.passes.iter().map(|p| p.rfta_seconds).sum();
    Ok(AdaptiveReconstruction {
        reconstruction,
        samples: asked,
        report,
    })
}

/// Pieces a strut thinner than the finest spacing `h` left apart, joined where the function is
/// inside between them (`bridge.rs`), asked with what `budget` has left after `asked`, to which
/// the answers are added.
fn join_pieces(
    reconstruction: &mut crate::Reconstruction,
    asker: &mut Asker<'_>,
    asked: &mut Vec<(DVec3, f64)>,
    budget: usize,
    h: f64,
) -> Result<()> {
    let left = budget.saturating_sub(asked.len());
    let mut ask = |p: &[DVec3]| {
        let values = asker.values(p)?;
        asked.extend(p.iter().copied().zip(values.iter().copied()));
        Ok(values)
    };
    let mesh = &mut reconstruction.mesh;
    let (_, joined) = super::bridge::join_where_inside(mesh, h, left, &mut ask)?;
    reconstruction.report.repair.components_joined += joined;
    Ok(())
}

/// The reconstruction's agreement measured against the samples asked for, not the finest grid's
/// interpolated values: its sign errors and the warning about them.
pub(super) fn agree_with_asked(
    reconstruction: &mut crate::Reconstruction,
    asked: &SdfSamples,
) -> Result<()> {
    let mesh = &reconstruction.mesh;
    let topology = rfta_mesh::Topology::of(mesh);
    let (c, _) = crate::consistency::measure_with(asked, mesh, &topology, None)?;
    let report = &mut reconstruction.report;
    report.consistency = crate::Consistency {
        thin_loops: std::mem::take(&mut report.consistency.thin_loops),
        ..c
    };
    report
        .warnings
        .retain(|w| !matches!(w, crate::Warning::Disagrees { .. }));
    if report.consistency.sign_errors > 0 {
        report.warnings.push(crate::Warning::Disagrees {
            wrong_side: report.consistency.sign_errors,
            entered: report.consistency.entered,
            deepest: report.consistency.deepest_entry,
        });
    }
    Ok(())
}

/// The values of `fine` (`grid` halved) before any is asked: the asked ones of `grid` (`known`)
/// where its points are, its cubic interpolant elsewhere; and which of them were asked.
pub(super) fn carried(
    grid: &Grid,
    values: &[f64],
    known: &[bool],
    fine: &Grid,
) -> Result<(Vec<f64>, Vec<bool>)> {
    let coarse = CubicField::new(grid, values).ok_or_else(|| {
        crate::Error::InvalidParams("the base grid needs two points per axis".into())
    })?;
    // The point of `grid` at fine point `i`, if there is one.
    let on_grid = |i: usize| {
        let ijk = fine.ijk(i);
        ijk.iter().all(|c| c % 2 == 0).then(|| {
            let c = ijk.map(|c| c / 2);
            grid.index(c[0], c[1], c[2])
        })
    };
    Ok((0..fine.len())
        .into_par_iter()
        .map(|i| match on_grid(i) {
            Some(j) if known[j] => (values[j], true),
            _ => (coarse.value_gradient(fine.position(i)).0, false),
        })
        .unzip())
}

/// `grid` with its spacing halved over the same box.
pub(super) fn finer(grid: &Grid) -> Result<Grid> {
    Ok(Grid::new(
        grid.dims().map(|d| 2 * d - 1),
        grid.origin(),
        grid.spacing() / 2.0,
    )?)
}

/// For each cell of `grid` (flat, `(dims - 1)` per axis), whether its corners change sign, or,
/// with `dilate`, a neighbouring cell's (26 neighbours) do.
fn crossed_cells(grid: &Grid, values: &[f64], dilate: bool) -> Vec<bool> {
    let c = grid.dims().map(|d| d - 1);
    let cell = |a: usize, b: usize, k: usize| (a * c[1] + b) * c[2] + k;
    let crossed: Vec<bool> = (0..c[0] * c[1] * c[2])
        .into_par_iter()
        .map(|i| {
            let (a, b, k) = (i / (c[1] * c[2]), (i / c[2]) % c[1], i % c[2]);
            let corner =
                |m: usize| values[grid.index(a + (m & 1), b + ((m >> 1) & 1), k + (m >> 2))];
            let inside = corner(0) < 0.0;
            (1..8).any(|m| (corner(m) < 0.0) != inside)
        })
        .collect();
    if !dilate {
        return crossed;
    }
    (0..crossed.len())
        .into_par_iter()
        .map(|i| {
            let ijk = [i / (c[1] * c[2]), (i / c[2]) % c[1], i % c[2]];
            let span = |a: usize| ijk[a].saturating_sub(1)..=(ijk[a] + 1).min(c[a] - 1);
            span(0).any(|a| span(1).any(|b| span(2).any(|k| crossed[cell(a, b, k)])))
        })
        .collect()
}

/// The points of `fine` (`grid` halved) in a marked cell of `grid` that have no value asked yet.
fn nodes_to_ask(grid: &Grid, fine: &Grid, marked: &[bool], known: &[bool]) -> Vec<usize> {
    let c = grid.dims().map(|d| d - 1);
    (0..fine.len())
        .into_par_iter()
        .filter(|&i| {
            let ijk = fine.ijk(i);
            if ijk.iter().all(|x| x % 2 == 0) {
                let k = ijk.map(|x| x / 2);
                if known[grid.index(k[0], k[1], k[2])] {
                    return false;
                }
            }
            // The cells of `grid` this point lies in or on, per axis.
            let span = |a: usize| {
                let x = ijk[a] / 2;
                if ijk[a] % 2 == 1 {
                    x..=x
                } else {
                    x.saturating_sub(1)..=x.min(c[a] - 1)
                }
            };
            span(0).any(|a| span(1).any(|b| span(2).any(|k| marked[(a * c[1] + b) * c[2] + k])))
        })
        .collect()
}
