//! What a reconstruction returns and reports: [`Reconstruction`], [`Report`], [`MeshCheck`], and
//! the [`Stage`]s a progress callback sees.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

use rfta_feasible::TangentPoints;
use rfta_geom::TriMesh;

use crate::Warning;
use serde::{Serialize, Serializer};

/// A pipeline stage, for progress reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Stage {
    /// Empty-space sampling and initial tangency points.
    Initial,
    /// Fine-tuning round `round` (1-based) of `of`.
    FineTune {
        /// This round.
        round: usize,
        /// All rounds.
        of: usize,
    },
    /// The final screened Poisson solve.
    Final,
    /// Progress within the current stage: `done` of `of` spheres, reported about twice a second
    /// while a stage runs longer than that.
    Progress {
        /// Spheres finished.
        done: usize,
        /// Spheres in the stage.
        of: usize,
    },
}

/// A timed step of a reconstruction ([`Report::timings`]); its `Display` is the step's name as
/// the CLI prints it and the Python report keys it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Step {
    /// The input check ([`crate::check`]).
    InputCheck,
    /// How the values read: as distances or as a level set ([`crate::field`]).
    Field,
    /// Empty-space rasterization of both sign sets.
    Rasterize,
    /// The initial tangency points.
    InitialPoints,
    /// Fine-tuning round `n` (1-based): its screened Poisson solve.
    RoundSolve(usize),
    /// Fine-tuning round `n`: moving the points against that surface.
    RoundTune(usize),
    /// The final screened Poisson solve.
    FinalSolve,
    /// Components judged and removed.
    Components,
    /// Dents, and sample spheres cleared.
    SpheresCleared,
    /// Handles narrower than the final solve's finest cells cut, and a known genus reached.
    Topology,
    /// Cavities the samples leave open opened (a final solve and a repair again).
    Cavities,
    /// The repaired mesh simplified.
    Simplify,
    /// The mesh check and the consistency check (with the spheres it finds entered cleared and
    /// checked again).
    Consistency,
}

impl std::fmt::Display for Step {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Step::InputCheck => write!(f, "input check"),
            Step::Field => write!(f, "field measured"),
            Step::Rasterize => write!(f, "rasterize"),
            Step::InitialPoints => write!(f, "initial points"),
            Step::RoundSolve(n) => write!(f, "round {n}: screened Poisson"),
            Step::RoundTune(n) => write!(f, "round {n}: fine-tuning"),
            Step::FinalSolve => write!(f, "final screened Poisson"),
            Step::Components => write!(f, "components judged"),
            Step::SpheresCleared => write!(f, "spheres cleared"),
            Step::Topology => write!(f, "topology"),
            Step::Cavities => write!(f, "cavities opened"),
            Step::Simplify => write!(f, "simplified"),
            Step::Consistency => write!(f, "consistency check"),
        }
    }
}

/// Runs `work` with a counter of finished spheres, reporting it through `progress` from a
/// monitor thread every half second until `work` returns (the result does not depend on it; no
/// reports where no thread can be started).
pub(crate) fn counted<T>(
    of: usize,
    progress: &mut (dyn FnMut(Stage) + Send),
    work: impl FnOnce(&AtomicUsize) -> T,
) -> T {
    let done = AtomicUsize::new(0);
    let finished = AtomicBool::new(false);
    std::thread::scope(|scope| {
        // Where no thread can be started (WebAssembly without threads), the work runs without
        // progress reports.
        let monitor = std::thread::Builder::new()
            .name("rfta-progress".into())
            .spawn_scoped(scope, || {
                let mut last = 0;
                loop {
                    std::thread::park_timeout(Duration::from_millis(500));
                    if finished.load(Ordering::Acquire) {
                        break;
                    }
                    let d = done.load(Ordering::Relaxed);
                    if d != last {
                        progress(Stage::Progress { done: d, of });
                        last = d;
                    }
                }
            })
            .ok();
        let out = work(&done);
        finished.store(true, Ordering::Release);
        if let Some(m) = monitor {
            m.thread().unpark();
            let _ = m.join();
        }
        out
    })
}

/// What a reconstruction did: each stage's own report, then the verdict on the output mesh.
///
/// Its serde form is the one definition of the report's figures for every front end (the
/// command line's `--report` JSON, the Python report dict, batch's status columns): one flat
/// object with every stage's fields (the mesh check's and the consistency check's too), and
/// `timings` as seconds by step name.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Report {
    /// The input check's.
    #[serde(flatten)]
    pub input: InputReport,
    /// How the samples were read ([`crate::field`]).
    #[serde(flatten)]
    pub field: crate::FieldReport,
    /// The initial points'.
    #[serde(flatten)]
    pub initial: InitialReport,
    /// The rounds'.
    #[serde(flatten)]
    pub rounds: RoundsReport,
    /// The final solve's.
    #[serde(flatten)]
    pub final_solve: FinalSolveReport,
    /// The repair's.
    #[serde(flatten)]
    pub repair: RepairReport,
    /// The simplification's.
    #[serde(flatten)]
    pub simplify: SimplifyReport,
    /// What the output mesh is like (checked before it is returned).
    #[serde(flatten)]
    pub mesh: MeshCheck,
    /// How the output mesh agrees with every sample: sign errors, entered spheres, gaps
    /// ([`crate::consistency`]).
    #[serde(flatten)]
    pub consistency: crate::Consistency,
    /// Things the caller should know: inconsistent samples, a detected clamp, more than 5% of the
    /// spheres without a point, a mesh that is not watertight.
    pub warnings: Vec<Warning>,
    /// Wall time of each step, in order.
    #[serde(serialize_with = "seconds_by_step")]
    pub timings: Vec<(Step, Duration)>,
}

/// What the input check found (step 1, [`crate::check`]; without [`crate::Params::check`], the
/// samples and the clamp given).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct InputReport {
    /// Samples (spheres).
    pub samples: usize,
    /// Samples that overlap a sample of the other sign (see [`crate::check`]; 0 when not checked).
    pub inconsistent_samples: usize,
    /// The clamp used: [`crate::Params::clamp`], or the one [`crate::Params::check`] detected.
    pub clamp: Option<f64>,
    /// The factor below 1 every sphere's radius `|s|` was shrunk by, when [`crate::Params::check`]
    /// measured noise above `NOISE_FLOOR` (0.001) (see [`crate::check`]); `None`: radii
    /// are `|s|`.
    pub radius_scale: Option<f64>,
}

/// What the empty-space sampling and the initial tangency points did (steps 2 and 3).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct InitialReport {
    /// Samples with `s < 0` and `s >= 0`.
    pub negative: usize,
    /// Samples with `s >= 0`.
    pub non_negative: usize,
    /// Rasterization resolution used (0: none, the empty space came from the gradients).
    pub raster_resolution: usize,
    /// Empty-space points sampled (both signs).
    pub empty_space_points: usize,
    /// Initial tangency points, all feasible: one per sphere that has one, or as many as a
    /// seeded sphere's seeds (an adaptive pass's points carry the rounds' extra ones).
    pub feasible_initial: usize,
    /// Of the initial points, those kept from an earlier pass (an adaptive run's pass before;
    /// 0 otherwise).
    pub seeded: usize,
    /// Read as bounds, the initial points that lay off the field's zero set and were moved onto
    /// it (the field module's `onto_zero_set`; 0 otherwise).
    pub moved_onto_zero_set: usize,
}

/// What the screened Poisson solves and fine-tuning rounds did (steps 4 and 5).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RoundsReport {
    /// Octree depth of the final screened Poisson solve.
    pub spsr_depth: u32,
    /// Octree depth of the solves inside the rounds: the final one's, or one less on fine grids
    /// (`ROUND_FULL_DEPTH` (10)).
    pub round_spsr_depth: u32,
    /// Tangency points before each fine-tuning round and at the end (`rounds + 1` entries unless
    /// stopped early).
    pub points_per_round: Vec<usize>,
    /// Why fine-tuning stopped before `Params::rounds` rounds, if it did.
    pub stopped_early: Option<String>,
}

/// What the final screened Poisson solve found (step 6, its first stage).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct FinalSolveReport {
    /// Samples the final screened Poisson function put on the wrong side, after its first solve
    /// and after each re-solve that screened them toward their side
    /// ([`rfta_spsr::reconstruct_with_sides`]); the last entry is the returned surface's.
    pub side_errors: Vec<usize>,
    /// Spheres without a tangency point at the end (clamped and zero-radius ones included).
    pub spheres_without_point: usize,
    /// Spheres farther than [`crate::Params::owner_band`] from the surface: constraints that own
    /// no point (not counted in `spheres_without_point`).
    pub far_spheres: usize,
    /// The side of the finest cells of the final solve, in the input's coordinates
    /// ([`rfta_spsr::SpsrReport::finest_cell`]).
    pub finest_cell: f64,
}

/// What the simplification did ([`crate::Params::simplify`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SimplifyReport {
    /// Faces of the repaired mesh, before simplification (the same as the output's when it is
    /// off; on fine grids its flat cells already extracted whole, `Params::flat_spacings`).
    #[serde(rename = "faces_unsimplified")]
    pub faces_before: usize,
    /// Faces after it (not serialized: the output's count is the mesh's own).
    #[serde(skip)]
    pub faces_after: usize,
    /// The largest distance measured between the simplified and the unsimplified surface, in
    /// sample spacings (0 without simplification).
    #[serde(rename = "simplify_deviation")]
    pub largest_deviation: f64,
}

/// What the repair changed (step 6, `rfta-repair`'s steps).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RepairReport {
    /// Small closed islands removed from the final mesh because no sample witnesses them (see
    /// [`crate::Params::min_island`]).
    pub islands_removed: usize,
    /// Handles cut because their loop is shorter than `SUB_CELL_LOOP` (2.0) of the final
    /// solve's finest cells: the extraction's choice at a saddle of the Poisson function near
    /// its iso-value, a thread or a pinhole a fraction of a cell across, not a feature of the
    /// function ([`rfta_repair::cut_sub_cell_handles`]).
    pub sub_cell_handles_cut: usize,
    /// Components removed from the final mesh because the samples contradict them: every vertex
    /// lies inside a sample sphere (by more than the tolerance), or they face inward with no
    /// other component around them.
    pub unsupported_removed: usize,
    /// Mesh vertices that were inside a sample sphere and moved out of it (`finish::push_out_of_spheres`
    /// and `finish::clear_spheres`), counting those added to be moved.
    pub vertices_pushed_out: usize,
    /// Of those, vertices added where a face or an edge cut a sample sphere with none of its
    /// vertices inside it.
    pub vertices_added: usize,
    /// Faces split so that a sample near the surface whose small sphere they cut lies on its own
    /// side (a dent; see `finish::dent_wrong_side`).
    pub dents: usize,
    /// Spheres the check of the output found entered and the verdict then cleared (of any size:
    /// the repair's clearing looks only at those up to a few owner radii, and the simplification
    /// keeps only what it is given); their vertices are counted in `vertices_pushed_out`.
    pub spheres_cleared_at_check: usize,
    /// Components joined to the largest by a tube to reach [`crate::Params::genus`] (0 without
    /// it).
    pub components_joined: usize,
    /// Handles cut (the loop around each cut and both sides capped) to reach
    /// [`crate::Params::genus`] (0 without it).
    pub handles_cut: usize,
    /// Components other than the largest, smaller than a base cell of an adaptive run, whose
    /// centre it asked the function at ([`crate::adaptive`]; 0 otherwise).
    pub small_components_asked: usize,
    /// Of those, the ones removed: the function did not put their centre inside (a part) or
    /// outside (a void) by an eighth of their size.
    pub small_components_removed: usize,
    /// Handles thinner than the samples resolve whose loop's centre an adaptive run asked the
    /// function at ([`crate::adaptive`]; 0 otherwise).
    pub thin_handles_asked: usize,
    /// Handles thinner than the samples resolve cut because nothing confirms them: on a grid no
    /// sample of their side lies next to them (unless [`crate::Params::keep_thin_handles`]); in an
    /// adaptive run, of those asked about, also the function put the centre on the other side
    /// than the mesh (a bar through empty space, a tunnel through material).
    pub thin_handles_cut: usize,
    /// The loops around those handles, in sample spacings (the finest, in an adaptive run),
    /// shortest first in each pass.
    pub thin_handle_loops: Vec<f64>,
    /// Closed components of the output that face inward: cavities in the solid, each around
    /// samples outside the shape (the island rule keeps no other). Unless
    /// [`crate::Params::keep_cavities`], those left are walled in by inside samples (a void the
    /// samples show) or could not be opened; a warning says which.
    pub cavities: usize,
    /// Cavities opened: the surface had closed a gap or a hole around outside samples that the
    /// grid connects to the outside through outside samples only
    /// ([`rfta_repair::cavity_openings`]).
    pub cavities_opened: usize,
}

impl Report {
    /// What the final solve and the repair changed on their own, one sentence each (nothing for a
    /// step that changed nothing): the command line's verbose lines, the HTML page's.
    pub fn changes(&self) -> Vec<String> {
        let (r, f) = (&self.repair, &self.final_solve);
        let mut out = Vec::new();
        if r.islands_removed > 0 {
            out.push(format!(
                "removed {} small closed island(s) that no sample witnesses",
                r.islands_removed
            ));
        }
        if r.unsupported_removed > 0 {
            out.push(format!(
                "removed {} component(s) the samples contradict (inside sample spheres, or an inward-facing shell around nothing)",
                r.unsupported_removed
            ));
        }
        if r.sub_cell_handles_cut > 0 {
            out.push(format!(
                "cut {} handle(s) whose loop is shorter than {} of the final solve's cells (side {:.3e}): threads or pinholes where its function has a saddle at the iso-value",
                r.sub_cell_handles_cut,
                crate::SUB_CELL_LOOP,
                f.finest_cell
            ));
        }
        if let [first, again @ ..] = f.side_errors.as_slice()
            && !again.is_empty()
        {
            let again: Vec<String> = again.iter().map(ToString::to_string).collect();
            out.push(format!(
                "the final solve put {first} samples on the wrong side of (or at) its surface; re-solved with them screened toward their side: {}",
                again.join(", then ")
            ));
        }
        if r.vertices_pushed_out > 0 {
            out.push(format!(
                "moved {} vertices out of the sample spheres they entered ({} of them added where a face cut a sphere with no vertex inside)",
                r.vertices_pushed_out, r.vertices_added
            ));
        }
        if r.spheres_cleared_at_check > 0 {
            out.push(format!(
                "cleared {} sample sphere(s) the check of the output found entered",
                r.spheres_cleared_at_check
            ));
        }
        if r.dents > 0 {
            out.push(format!(
                "split {} faces that cut a small sample sphere with the sample on the wrong side, and dented them past it",
                r.dents
            ));
        }
        if r.cavities_opened > 0 {
            out.push(format!(
                "opened {} cavit{} the surface had sealed around outside samples (a gap or a hole the samples leave open)",
                r.cavities_opened,
                if r.cavities_opened == 1 { "y" } else { "ies" }
            ));
        }
        let s = &self.simplify;
        if s.faces_after < s.faces_before {
            out.push(format!(
                "simplified {} faces to {}, at most {:.3} sample spacings from the surface before (measured at the vertices), every sample's side and sphere kept",
                s.faces_before, s.faces_after, s.largest_deviation
            ));
        }
        out
    }

    /// What was done at the caller's request, one sentence each: the genus asked reached
    /// ([`crate::Params::genus`]), the SDF asked about small components and thin handles (the
    /// adaptive mode). A front end says these even when it is quiet about [`Report::changes`].
    pub fn answers(&self) -> Vec<String> {
        let r = &self.repair;
        let mut out = Vec::new();
        if r.small_components_asked + r.thin_handles_asked > 0 {
            out.push(format!(
                "asked the SDF about {} small component(s) and {} thin handle(s): removed {} and cut {} it contradicts",
                r.small_components_asked,
                r.thin_handles_asked,
                r.small_components_removed,
                r.thin_handles_cut
            ));
        }
        if r.components_joined + r.handles_cut > 0 {
            out.push(format!(
                "to reach the genus asked: joined {} component(s) to the largest, cut {} handle(s)",
                r.components_joined, r.handles_cut
            ));
        }
        out
    }

    /// How the values read ([`crate::field`]), in one sentence: how far they reach towards their
    /// zero set, how many fall short of it, the gradient's norm at it, how many spheres others
    /// cover, and whether they were read as distances, a level set or bounds; `None` for
    /// scattered samples (not measured).
    pub fn field_quality(&self) -> Option<String> {
        let f = &self.field;
        let reach = f.reach?;
        let slope = f.slope.map_or_else(String::new, |[lo, mid, hi]| {
            format!(
                "; gradient norm at it {lo:.2}, {mid:.2}, {hi:.2} (10th, 50th, 90th percentile)"
            )
        });
        let covered = f.covered.map_or_else(String::new, |c| {
            format!(
                "; {:.1}% of the spheres near it have no point outside every other sphere",
                100.0 * c
            )
        });
        Some(format!(
            "the values, read as {}: far from their zero set they reach {:.0}% of the way to it, {:.1}% of them fall short of it by over two spacings{slope}{covered}",
            f.read_as,
            100.0 * reach,
            100.0 * f.short,
        ))
    }

    /// The agreement with the samples, in one sentence.
    pub fn agreement(&self) -> String {
        let c = &self.consistency;
        format!(
            "agreement with the {} samples (h = {:.4}): {} on the wrong side, {} spheres entered by more than {} h (deepest {:.2} h), {} gaps over {} h",
            c.samples,
            c.spacing,
            c.sign_errors,
            c.entered,
            crate::consistency::ENTER_MARGIN,
            c.deepest_entry,
            c.gaps,
            crate::consistency::GAP_MARGIN
        )
    }
}

/// What happened when, across the stages: the warnings and each step's time, in order (a
/// [`Report`]'s `warnings` and `timings`).
#[derive(Debug, Default)]
pub(crate) struct Journal {
    pub(crate) warnings: Vec<Warning>,
    pub(crate) timings: Vec<(Step, Duration)>,
}

impl Journal {
    /// `step` took from `start` until now.
    pub(crate) fn timed(&mut self, step: Step, start: std::time::Instant) {
        self.took(step, start.elapsed());
    }

    /// `step` took `time` (for a step timed in parts).
    pub(crate) fn took(&mut self, step: Step, time: Duration) {
        self.timings.push((step, time));
    }
}

/// `timings` as a map from each step's name to its seconds, in order.
fn seconds_by_step<S: Serializer>(
    timings: &[(Step, Duration)],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    s.collect_map(
        timings
            .iter()
            .map(|(step, t)| (step.to_string(), t.as_secs_f64())),
    )
}

/// Checks of the output mesh.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct MeshCheck {
    /// Faces with a repeated vertex index (none unless the extraction has a bug).
    pub degenerate_faces: usize,
    /// Faces of zero area left in the mesh (distinct vertices at one position or on one line).
    pub zero_area_faces: usize,
    /// Every edge has exactly two faces.
    pub watertight: bool,
    /// Edges with one face.
    pub boundary_edges: usize,
    /// Edges with more than two faces.
    pub nonmanifold_edges: usize,
    /// Connected components.
    pub components: usize,
    /// The genus (handles), when the mesh is closed and orientable.
    pub genus: Option<i64>,
}

/// A reconstructed mesh and how it was made.
#[derive(Debug, Clone)]
pub struct Reconstruction {
    /// The mesh, in the samples' coordinates, outward-oriented.
    pub mesh: TriMesh,
    /// The final tangency points, in the samples' coordinates.
    pub points: TangentPoints,
    /// Counts and timings.
    pub report: Report,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    /// The steps' names are the ones `rfta -v` printed and the Python report keyed before they
    /// were an enum, one per step.
    #[test]
    fn steps_keep_their_names() {
        let steps = [
            (Step::InputCheck, "input check"),
            (Step::Rasterize, "rasterize"),
            (Step::InitialPoints, "initial points"),
            (Step::RoundSolve(3), "round 3: screened Poisson"),
            (Step::RoundTune(10), "round 10: fine-tuning"),
            (Step::FinalSolve, "final screened Poisson"),
            (Step::Components, "components judged"),
            (Step::SpheresCleared, "spheres cleared"),
            (Step::Topology, "topology"),
            (Step::Cavities, "cavities opened"),
            (Step::Consistency, "consistency check"),
        ];
        for (step, name) in steps {
            assert_eq!(step.to_string(), name);
        }
    }

    /// The serde form is flat: every field once, the mesh check's and the consistency check's
    /// beside the report's own, the consistency's sample count given once, timings by name.
    #[test]
    fn the_report_serializes_flat_with_each_figure_once() {
        let report = Report {
            input: InputReport {
                samples: 5,
                ..InputReport::default()
            },
            repair: RepairReport {
                cavities: 1,
                ..RepairReport::default()
            },
            mesh: MeshCheck {
                components: 2,
                ..MeshCheck::default()
            },
            consistency: crate::Consistency {
                samples: 5,
                sign_errors: 3,
                ..crate::Consistency::default()
            },
            timings: vec![(Step::FinalSolve, Duration::from_millis(1500))],
            ..Report::default()
        };
        let text = serde_json::to_string(&report).expect("serializes");
        let json: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        assert_eq!(json["samples"], 5);
        assert_eq!(json["components"], 2);
        assert_eq!(json["sign_errors"], 3);
        assert_eq!(json["cavities"], 1);
        assert_eq!(json["timings"]["final screened Poisson"], 1.5);
        let keys = json.as_object().expect("an object").len();
        assert_eq!(
            text.matches("\":").count() - 1,
            keys,
            "a key repeated: {text}"
        );
        // The stages' 4 + 7 + 4 + 4 + 16 fields, how the values read 5, the simplification's 2
        // (its output faces left to the mesh), the mesh check's 7, the consistency check's 6 (its
        // sample count left to the input's), warnings and timings.
        assert_eq!(keys, 4 + 7 + 4 + 4 + 16 + 5 + 2 + 7 + 6 + 2, "{text}");
    }

    #[test]
    fn long_stages_report_progress_and_short_ones_stay_quiet() {
        let mut seen = Vec::new();
        let out = counted(12, &mut |s| seen.push(s), |done| {
            for _ in 0..12 {
                std::thread::sleep(Duration::from_millis(100));
                done.fetch_add(1, Ordering::Relaxed);
            }
            7
        });
        assert_eq!(out, 7);
        assert!(!seen.is_empty(), "a 1.2 s stage reports");
        let mut last = 0;
        for s in &seen {
            let Stage::Progress { done, of } = *s else {
                panic!("{s:?}");
            };
            assert!(of == 12 && done >= last && done <= 12, "{seen:?}");
            last = done;
        }
        let mut quiet = Vec::new();
        let start = Instant::now();
        counted(5, &mut |s| quiet.push(s), |done| {
            done.fetch_add(5, Ordering::Relaxed);
        });
        assert!(quiet.is_empty());
        // The monitor is woken when the work ends, not after its half-second nap.
        assert!(start.elapsed() < Duration::from_millis(400));
    }

    /// What the caller asked for is an answer a quiet front end still says; what the repair did
    /// on its own is a change; a step that did nothing says nothing.
    #[test]
    fn answers_and_changes_are_apart() {
        let report = Report {
            repair: RepairReport {
                components_joined: 1,
                handles_cut: 2,
                dents: 3,
                ..RepairReport::default()
            },
            ..Report::default()
        };
        assert_eq!(
            report.answers(),
            ["to reach the genus asked: joined 1 component(s) to the largest, cut 2 handle(s)"]
        );
        let changes = report.changes();
        assert_eq!(changes.len(), 1, "{changes:?}");
        assert!(changes[0].starts_with("split 3 faces"), "{changes:?}");
        assert!(Report::default().answers().is_empty() && Report::default().changes().is_empty());
    }
}
