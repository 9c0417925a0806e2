//! A reconstruction's three phases, each its own function: the octree over the merged samples
//! ([`Octree::build`]), the solve, re-solved while side points are on the wrong side
//! ([`solve_with_sides`]), and the extraction ([`extract_surface`]).

use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::flat::Leaves;
use crate::sides::{SIDE_PASSES, SIDE_RESOLVE_SWEEPS, SideSet, Sides};
use crate::{
    Error, OrientedPoints, Reconstruction, Result, SpsrParams, SpsrReport, TriMesh, extract, glam,
    solve, tree,
};

/// The three phases.
pub(crate) fn run(
    points: &OrientedPoints,
    params: &SpsrParams,
    sides: &dyn SideSet,
) -> Result<Reconstruction> {
    let mut octree = Octree::build(points, params)?;
    let solved = solve_with_sides(&mut octree, params, sides);
    extract_surface(points, params, octree, solved)
}

/// The first phase's result: the samples (points merged per finest cell, with their density
/// estimate) in the unit cube of `frame`, and the graded octree over them.
struct Octree {
    frame: tree::Frame,
    samples: Vec<tree::Sample>,
    levels: Vec<tree::Level>,
    depth: u32,
    /// The depth up to which the grids are complete.
    base: u32,
    /// Time spent building it (and rebuilding it, when side points refine it).
    time: Duration,
}

impl Octree {
    /// The samples' total weight, and the screening weight `alpha` scaled by their average area
    /// so that it does not depend on their number.
    fn screening(&self, params: &SpsrParams) -> (f64, f64) {
        let total_w: f64 = self.samples.iter().map(|s| s.weight).sum();
        let total_a: f64 = self.samples.iter().map(|s| s.area).sum();
        (total_w, params.screening * total_a / total_w)
    }

    /// The normal field's terms and the first pass's systems (no value constraints yet), built
    /// side by side: they do not depend on each other.
    fn first_pass(
        &self,
        params: &SpsrParams,
        alpha: f64,
    ) -> (
        (Vec<Vec<glam::DVec3>>, solve::DownPass),
        Vec<solve::LevelSystem>,
    ) {
        rayon::join(
            || {
                let v = solve::splat_normals(&self.levels, &self.samples);
                let down = solve::down_pass(&self.levels, &v);
                (v, down)
            },
            || solve::build_systems(&self.levels, &self.samples, &[], params, alpha),
        )
    }

    /// The levels rebuilt with `seeds` refined to the finest depth as the samples are. The levels
    /// before are dropped first: what reads them later (the warm start's node indices, the first
    /// solve's surface) was taken from them before.
    fn refine_around(&mut self, seeds: &[glam::DVec3]) {
        let t = Instant::now();
        drop(std::mem::take(&mut self.levels));
        self.levels = tree::build_levels(&self.samples, seeds, self.depth, self.base);
        self.time += t.elapsed();
    }

    fn build(points: &OrientedPoints, params: &SpsrParams) -> Result<Self> {
        if points.len() < 3 {
            return Err(Error::TooFewPoints {
                found: points.len(),
            });
        }
        let t = Instant::now();
        let frame = tree::Frame::around(points, params.box_scale)?;
        let depth = params.depth;
        let base = params.full_depth.min(depth);
        let mut samples = tree::merge(points, &frame, depth);
        if samples.len() < 3 {
            return Err(Error::DegenerateInput(format!(
                "the points fall into {} cell(s) of the depth-{depth} grid (or have zero weight): too few to define a surface",
                samples.len()
            )));
        }
        tree::estimate_density(&mut samples, params, base);
        let levels = tree::build_levels(&samples, &[], depth, base);
        Ok(Self {
            frame,
            samples,
            levels,
            depth,
            base,
            time: t.elapsed(),
        })
    }

    /// The iso-value of `sol`: the weighted mean of the function at the samples (summed in
    /// order, the same bits at any thread count).
    fn iso_value(&self, sol: &solve::Solution) -> f64 {
        let vals: Vec<f64> = self
            .samples
            .par_iter()
            .map_init(
                || solve::Evaluator::new(&self.levels, sol, self.base),
                |at, s| at.at(s.pos),
            )
            .collect();
        let (mut num, mut den) = (0.0, 0.0);
        for (s, f) in self.samples.iter().zip(&vals) {
            num += s.weight * f;
            den += s.weight;
        }
        num / den
    }
}

/// The solve's result before extraction: the solution and its iso-value, the first pass's (while
/// side re-solves ran), the side points on the wrong side after each pass, and the time spent.
struct Solved {
    sol: solve::Solution,
    iso: f64,
    first: Option<FirstSolve>,
    side_errors: Vec<usize>,
    system_time: Duration,
    solve_time: Duration,
}

/// The first solve's result, kept while side re-solves run: a re-solve that pulls the surface
/// out of the cube (where it would come out open) while the first solve's stayed inside is
/// dropped for the first solve's surface.
enum FirstSolve {
    /// Its solution and iso-value, on the octree the re-solves use (not refined since).
    Solution(solve::Solution, f64),
    /// Side points refined the octree since. Its surface, needed only in the rare case above, is
    /// then made again from the points ([`first_surface_again`]): neither the octree before nor
    /// its surface is kept beside the refined one through the re-solves, where the final solve's
    /// memory peaks (docs/speed.md, items 39 and 48).
    Refined,
}

/// An extracted surface `χ = iso`, in world coordinates.
struct Surface {
    mesh: TriMesh,
    iso: f64,
    broken_leaves: usize,
    finest_cell: f64,
}

/// The surface `χ = iso` of the nodal `values` on `levels` (flat cells taken whole as `params`
/// says), in world coordinates.
fn surface_of(
    levels: &[tree::Level],
    values: &[Vec<f64>],
    iso: f64,
    params: &SpsrParams,
    frame: &tree::Frame,
) -> Surface {
    let leaves = match params.flat_tolerance {
        Some(t) => Leaves::merged(levels, values, iso, t / frame.side),
        None => Leaves::of_tree(levels),
    };
    let mut ex = extract::extract(levels, values, iso, &leaves);
    extract::to_world(frame, &mut ex.vertices);
    Surface {
        mesh: TriMesh {
            vertices: ex.vertices,
            faces: ex.faces,
        },
        iso,
        broken_leaves: ex.broken_leaves,
        finest_cell: frame.side / f64::from(1u32 << (levels.len() - 1)),
    }
}

/// The first solve's surface on `levels`, if it stays inside the cube (else no re-solve's
/// surface falls back to it).
fn first_surface(
    levels: &[tree::Level],
    sol: &solve::Solution,
    iso: f64,
    params: &SpsrParams,
    frame: &tree::Frame,
) -> Option<Surface> {
    let values = extract::final_values(levels, &sol.u);
    (!extract::leaves_cube(levels, &values, iso))
        .then(|| surface_of(levels, &values, iso, params, frame))
}

/// [`first_surface`] after the octree was refined: the first solve made again, the solve of the
/// points' own octree without side points (the same bits as the first time, so the same
/// surface).
fn first_surface_again(points: &OrientedPoints, params: &SpsrParams) -> Result<Option<Surface>> {
    let mut octree = Octree::build(points, params)?;
    let plain = solve_with_sides(&mut octree, params, crate::sides::NO_SIDES);
    Ok(first_surface(
        &octree.levels,
        &plain.sol,
        plain.iso,
        params,
        &octree.frame,
    ))
}

/// The solve, then while side points are on the wrong side (at most [`SIDE_PASSES`] times)
/// screening terms for them and a re-solve from the solution before, on the same octree unless
/// a wrong point's cell needs refining ([`crate::reconstruct_with_sides`]).
fn solve_with_sides(octree: &mut Octree, params: &SpsrParams, sides: &dyn SideSet) -> Solved {
    let t = Instant::now();
    let (total_w, alpha) = octree.screening(params);
    let base = octree.base;
    let ((mut v, mut down), first_systems) = octree.first_pass(params, alpha);
    let mut first_systems = Some(first_systems);
    let frame = octree.frame;
    let mut sides = Sides::in_cube(sides, &frame);
    let mut system_time = t.elapsed();
    let mut solve_time = Duration::ZERO;
    // The first solve's result, kept while re-solves run.
    let mut first: Option<FirstSolve> = None;
    // Side points the octree was refined around.
    let mut seeds: Vec<glam::DVec3> = Vec::new();
    // A re-solve's start: the previous solve's coefficients, on the octree's nodes or, after it
    // was rebuilt, on those of the octree before.
    let mut resolve: Option<solve::WarmStart> = None;
    let resolve_params = SpsrParams {
        iterations: SIDE_RESOLVE_SWEEPS.min(params.iterations),
        ..params.clone()
    };
    let (sol, iso) = loop {
        let t1 = Instant::now();
        let systems = match first_systems.take() {
            Some(systems) => systems,
            None => solve::build_systems(
                &octree.levels,
                &octree.samples,
                sides.constraints(),
                params,
                alpha,
            ),
        };
        let last = sides.is_empty() || sides.errors().len() == SIDE_PASSES;
        system_time += t1.elapsed();
        let t2 = Instant::now();
        let (pass, start) = match &resolve {
            Some(start) => (&resolve_params, Some(start)),
            None => (params, None),
        };
        let sol = solve::solve(&octree.levels, &systems, &v, &down, pass, base, start);
        drop(systems);
        let iso = octree.iso_value(&sol);
        if sides.is_empty() {
            solve_time += t2.elapsed();
            break (sol, iso);
        }
        let at = || {
            let mut at = solve::Evaluator::new(&octree.levels, &sol, base);
            move |p: glam::DVec3| at.at(p)
        };
        let wrong = sides.wrong(&at, iso, last);
        solve_time += t2.elapsed();
        if last || wrong.is_empty() {
            break (sol, iso);
        }
        // This solve's coefficients lie on the octree's own nodes (unless it is refined below).
        let start = resolve.get_or_insert_with(solve::WarmStart::default);
        start.nodes = None;
        let coarse =
            sides.in_coarse_cells(&wrong, &octree.levels[octree.depth as usize], octree.depth);
        if first.is_none() {
            start.x = sol.x.clone();
            first = Some(FirstSolve::Solution(sol, iso));
        } else {
            start.x = sol.x;
        }
        sides.constrain(&wrong, iso, total_w, octree.samples.len());
        if !coarse.is_empty() {
            // A wrong side point in a cell the octree does not refine to its finest depth: its
            // constraint would act on the depths whose cells hold it, while the finer depths'
            // hats that reach it (around the finer cells beside it) are solved without it and
            // undo it. The octree is rebuilt with such points refined as the samples are; the
            // next solve starts from this one's coefficients on the nodes both octrees share.
            seeds.extend(coarse);
            refine_for_sides(octree, &seeds, &mut first, start);
            let t = Instant::now();
            v = solve::splat_normals(&octree.levels, &octree.samples);
            down = solve::down_pass(&octree.levels, &v);
            system_time += t.elapsed();
        }
    };
    Solved {
        sol,
        iso,
        first,
        side_errors: sides.into_errors(),
        system_time,
        solve_time,
    }
}

/// Rebuilds the octree around `seeds` (side points in coarse cells), first taking from the
/// levels before what the re-solves still need of them: the node indices `start`'s
/// coefficients lie on. The first solve's solution, on the levels before, is dropped.
fn refine_for_sides(
    octree: &mut Octree,
    seeds: &[glam::DVec3],
    first: &mut Option<FirstSolve>,
    start: &mut solve::WarmStart,
) {
    if first.is_some() {
        *first = Some(FirstSolve::Refined);
    }
    start.nodes = Some(
        octree
            .levels
            .iter_mut()
            .map(|l| std::mem::take(&mut l.node_index))
            .collect(),
    );
    octree.refine_around(seeds);
}

/// The surface of `solved` on the octree's levels (the first pass's, when a re-solve pulled it
/// out of the cube and the first pass's stayed inside), in world coordinates, with the report.
fn extract_surface(
    points: &OrientedPoints,
    params: &SpsrParams,
    octree: Octree,
    solved: Solved,
) -> Result<Reconstruction> {
    let Octree {
        frame,
        samples,
        levels,
        time: tree_time,
        ..
    } = octree;
    let Solved {
        sol,
        iso,
        first,
        mut side_errors,
        system_time,
        solve_time,
    } = solved;
    let t3 = Instant::now();
    let solve::Solution { x, u } = sol;
    let values = extract::final_values(&levels, &u);
    drop(u);
    drop(x);
    // A re-solve that pulls the surface out of the cube (where it would come out open) while the
    // first solve's stayed inside is dropped for the first solve's surface.
    let fallback = match first {
        Some(first) if extract::leaves_cube(&levels, &values, iso) => match first {
            FirstSolve::Solution(sol, first_iso) => {
                first_surface(&levels, &sol, first_iso, params, &frame)
            }
            FirstSolve::Refined => first_surface_again(points, params)?,
        },
        _ => None,
    };
    let surface = match fallback {
        Some(surface) => {
            side_errors.truncate(1);
            surface
        }
        None => surface_of(&levels, &values, iso, params, &frame),
    };
    if surface.mesh.faces.is_empty() || !surface.iso.is_finite() {
        return Err(Error::NoSurface { iso: surface.iso });
    }
    let extract_time = t3.elapsed();
    let report = SpsrReport {
        points: points.len(),
        samples: samples.len(),
        nodes_per_depth: levels.iter().map(|l| l.nodes.len()).collect(),
        cells_per_depth: levels.iter().map(|l| l.cells.len()).collect(),
        iso_value: surface.iso,
        finest_cell: surface.finest_cell,
        side_errors,
        broken_leaves: surface.broken_leaves,
        tree_time,
        system_time,
        solve_time,
        extract_time,
    };
    Ok(Reconstruction {
        mesh: surface.mesh,
        report,
    })
}
