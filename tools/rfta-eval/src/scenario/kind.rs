//! [`Scenario`]: what each scenario does to a grid, its levels and which rfta runs it compares.

use super::{CLAMP_LEVELS, NEAR_SURFACE, NOISE_LEVELS, UNIFORM};

/// A scenario: what it does to a grid and which rfta runs it compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scenario {
    Noise,
    Clamp,
    /// Figure 13: fine-tuning rounds.
    Rounds,
    /// Figure 11: rasterization resolution.
    Raster,
    /// Figure 12: spheres per feasibility batch.
    Batch,
    /// Scattered samples (uniform, or near the surface as DeepSDF draws them) as many as a grid's.
    Scattered,
    /// Figure 25: the pseudo-SDF of a swept volume.
    Swept,
    /// Figure 22: segments against the ground truth and the reconstructions.
    Collision,
}

impl Scenario {
    pub(crate) const ALL: [Scenario; 8] = [
        Scenario::Noise,
        Scenario::Clamp,
        Scenario::Scattered,
        Scenario::Swept,
        Scenario::Collision,
        Scenario::Rounds,
        Scenario::Raster,
        Scenario::Batch,
    ];

    /// `params` names the three parameter sweeps.
    pub(crate) const PARAMS: [Scenario; 3] = [Scenario::Rounds, Scenario::Raster, Scenario::Batch];

    pub(crate) fn name(self) -> &'static str {
        match self {
            Scenario::Noise => "noise",
            Scenario::Clamp => "clamp",
            Scenario::Rounds => "rounds",
            Scenario::Raster => "raster",
            Scenario::Batch => "batch",
            Scenario::Scattered => "scattered",
            Scenario::Swept => "swept",
            Scenario::Collision => "collision",
        }
    }

    /// The parameter sweeps run on two shapes (the paper's Figures 11 to 13 use a few).
    pub(crate) fn shapes(self) -> usize {
        match self {
            Scenario::Rounds | Scenario::Raster | Scenario::Batch => 2,
            _ => usize::MAX,
        }
    }

    /// The default levels (see [`NOISE_LEVELS`], [`CLAMP_LEVELS`]).
    pub(crate) fn levels(self) -> Vec<f64> {
        match self {
            Scenario::Noise => NOISE_LEVELS.to_vec(),
            Scenario::Clamp => CLAMP_LEVELS.to_vec(),
            Scenario::Rounds => vec![0.0, 1.0, 3.0, 5.0, 10.0, 20.0],
            Scenario::Raster => vec![32.0, 64.0, 128.0, 256.0, 512.0],
            // 0: every sphere in one batch.
            Scenario::Batch => vec![300.0, 1000.0, 3000.0, 10000.0, 0.0],
            Scenario::Scattered => vec![UNIFORM, NEAR_SURFACE],
            // Sweep lengths (0: the shape standing still, its exact SDF).
            Scenario::Swept => vec![0.0, 0.3, 0.6],
            // Projectile lengths.
            Scenario::Collision => vec![0.05, 0.2, 0.8],
        }
    }

    /// The levels of the CI's quick run.
    pub(crate) fn quick_levels(self) -> Vec<f64> {
        match self {
            Scenario::Noise => vec![0.01, 0.02],
            Scenario::Clamp => vec![2.0],
            Scenario::Rounds => vec![1.0, 3.0],
            Scenario::Raster => vec![64.0, 128.0],
            Scenario::Batch => vec![1000.0, 0.0],
            Scenario::Scattered => vec![NEAR_SURFACE],
            Scenario::Swept => vec![0.3],
            Scenario::Collision => vec![0.2],
        }
    }

    /// The level a clean grid has (added to every run as the baseline), if the scenario has one.
    pub(super) fn clean_level(self) -> Option<f64> {
        match self {
            Scenario::Noise => Some(0.0),
            Scenario::Clamp => None,
            // The default setting.
            Scenario::Rounds => Some(10.0),
            Scenario::Raster
            | Scenario::Batch
            | Scenario::Scattered
            | Scenario::Swept
            | Scenario::Collision => None,
        }
    }

    pub(super) fn level_label(self, level: f64) -> String {
        match self {
            Scenario::Noise => format!("{}%", 100.0 * level),
            Scenario::Clamp => format!("{level} h"),
            Scenario::Batch if level == 0.0 => "all".into(),
            Scenario::Scattered if level == UNIFORM => "uniform".into(),
            Scenario::Scattered => "near-surface".into(),
            _ => format!("{level}"),
        }
    }

    /// Where level `level`, the `i`-th, goes on a chart's x axis: at its value, or in order for
    /// the batch sizes (whose last, "all", is 0).
    pub(super) fn chart_x(self, i: usize, level: f64) -> f64 {
        match self {
            Scenario::Batch | Scenario::Scattered => i as f64,
            _ => level,
        }
    }

    pub(super) fn axis_label(self) -> &'static str {
        match self {
            Scenario::Noise => "noise (% of the value)",
            Scenario::Clamp => "clamp (grid spacings)",
            Scenario::Rounds => "fine-tuning rounds",
            Scenario::Raster => "rasterization cells per axis",
            Scenario::Batch => "spheres per batch (last: all)",
            Scenario::Scattered => "sample distribution",
            Scenario::Swept => "sweep length (and radians turned)",
            Scenario::Collision => "projectile length",
        }
    }

    pub(super) fn title(self) -> &'static str {
        match self {
            Scenario::Noise => "noise (the paper's Figure 23)",
            Scenario::Clamp => "clamp (the paper's Figure 24)",
            Scenario::Rounds => "fine-tuning rounds (the paper's Figure 13)",
            Scenario::Raster => "rasterization resolution (the paper's Figure 11)",
            Scenario::Batch => "batch size (the paper's Figure 12)",
            Scenario::Scattered => "scattered samples",
            Scenario::Swept => "swept volumes (the paper's Figure 25)",
            Scenario::Collision => "collision queries (the paper's Figure 22)",
        }
    }

    pub(super) fn explanation(self) -> &'static str {
        match self {
            Scenario::Noise => {
                "Relative noise `s (1 + p u)`, `u` uniform in [-1, 1], seeded; `rfta-default` is the default preset on the noisy grid; \"measured\" is the noise the check found (a fraction of the values)."
            }
            Scenario::Clamp => {
                "Values clamped at `k h` (`h` the grid spacing): `sign(s) min(|s|, k h)`; `rfta-given` is the default preset told the clamp, `rfta-detected` the default preset left to detect it; \"measured\" is the clamp the check detected, in spacings (0: none)."
            }
            Scenario::Rounds => {
                "The default preset with `Params::rounds` (the paper's k_max) set to each level on the clean grid; the default is 10."
            }
            Scenario::Raster => {
                "The default preset with `Params::raster_resolution` set to each level on the clean grid; the default is the paper's `64 ceil(n^(1/3) / 16)` (128 at N = 20 and 30)."
            }
            Scenario::Scattered => {
                "As many samples as the grid of each N has, at exact signed distances from the ground truth: uniform in the grid's box, or near the surface as DeepSDF draws them (scaled to the box side L: 5% uniform, the rest on the surface plus Gaussian offsets of 0.008 L for one half and 0.025 L for the other); `rfta-default` is the default preset on them (the spheres within three of their own spacings of the surface own points, a sample's spacing the distance to its fourth nearest), `rfta-grid` the default preset on the grid of the same count; marching cubes cannot run on scattered samples, so both mc columns are the grid's."
            }
            Scenario::Swept => {
                "Each shape, scaled by 0.6 about its box's centre, moves by the level along x while turning the level in radians about z, sampled at copies no point of which moves more than 0.02 between two; the grid holds the least of the copies' exact signed distances (a pseudo-SDF: exact outside, a lower bound of the depth inside). The ground truth is the zero set of the same function, marching cubes on a 257^3 grid evaluated exactly near the surface; level 0 is the scaled shape standing still (an exact SDF). Both mc columns are marching cubes on the same grid."
            }
            Scenario::Collision => {
                "20,000 segments of the level's length per shape (seeded; midpoints uniform in the ground truth's box grown by 0.1, directions uniform), each tested against the ground truth and against each method's mesh (`MeshIndex::segment_hits`): a false negative is a segment that hits the ground truth and misses the mesh (a projectile that passes through), a false positive one that misses the ground truth and hits the mesh; given as shares of the segments that hit, and that miss, the ground truth. The same segments at every N."
            }
            Scenario::Batch => {
                "The default preset with `Params::batch_size` (the paper's b) set to each level on the clean grid (all: every sphere in every feasibility test); the default is 10^4, which holds all of a 21^3 or 31^3 grid."
            }
        }
    }

    /// The rfta runs: label and whether the clamp is given.
    pub(super) fn runs(self) -> &'static [(&'static str, bool)] {
        match self {
            Scenario::Clamp => &[("rfta-given", true), ("rfta-detected", false)],
            Scenario::Scattered => &[("rfta-default", false), ("rfta-grid", false)],
            _ => &[("rfta-default", false)],
        }
    }

    /// The grid's values at `level` (`h` the spacing; `rng` seeded for this grid and level).
    pub(super) fn apply(
        self,
        clean: &[f64],
        level: f64,
        h: f64,
        rng: &mut rfta_geom::rng::Rng,
    ) -> Vec<f64> {
        match self {
            Scenario::Noise => clean
                .iter()
                .map(|&s| s * (1.0 + level * (2.0 * rng.next_f64() - 1.0)))
                .collect(),
            Scenario::Clamp => clean
                .iter()
                .map(|&s| s.signum() * s.abs().min(level * h))
                .collect(),
            Scenario::Rounds
            | Scenario::Raster
            | Scenario::Batch
            | Scenario::Scattered
            | Scenario::Swept
            | Scenario::Collision => clean.to_vec(),
        }
    }

    /// The default preset on one thread (the clean row it is compared with runs the same), set
    /// for `level`: the clamp when `given` (`level` spacings of `h`), or the swept parameter.
    pub(super) fn params(self, level: f64, h: f64, given: bool) -> rfta::Params {
        let base = rfta::Params {
            threads: Some(1),
            clamp: given.then_some(level * h),
            ..rfta::Params::default()
        };
        match self {
            Scenario::Rounds => rfta::Params {
                rounds: Some(level as usize),
                ..base
            },
            Scenario::Raster => rfta::Params {
                raster_resolution: Some(level as usize),
                ..base
            },
            Scenario::Batch => rfta::Params {
                batch_size: level as usize,
                ..base
            },
            Scenario::Noise
            | Scenario::Clamp
            | Scenario::Scattered
            | Scenario::Swept
            | Scenario::Collision => base,
        }
    }
}
