//! [`PlaneParams`]: the 2D pipeline's settings, and its [`Error`].

/// The settings of [`crate::reconstruct`], named as `rfta::Params` names them (the ones that apply
/// to curves); the defaults are `rfta::Params`' (a test in `rfta` holds them equal).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneParams {
    /// Fine-tuning rounds.
    pub rounds: usize,
    /// Most tangency points per circle.
    pub max_points_per_sphere: usize,
    /// The fine-tuning's step along a circle, in unit-square lengths.
    pub transport_step: f64,
    /// Feasibility tolerance, in unit-square lengths.
    pub tolerance: f64,
    /// The empty-space raster's resolution (`None`: from the number of samples).
    pub raster_resolution: Option<usize>,
    /// Values at or beyond this magnitude are clamped: their circles own no point.
    pub clamp: Option<f64>,
    /// The quadtree's depth (`None`: from the sample spacing).
    pub spsr_depth: Option<u32>,
    /// On a grid, only circles within this many spacings of the curve own points (`None`: all).
    pub owner_band: Option<f64>,
    /// Loops smaller than this many spacings (bounding-box diagonal) that no sample supports are
    /// removed (0: none).
    pub min_island: f64,
    /// Keep the holes around outside samples that the samples leave open.
    pub keep_cavities: bool,
    /// Simplify the final curve: vertices on nearly straight runs removed while every sample
    /// keeps its side and no circle is entered past the margin.
    pub simplify: bool,
    /// How far the simplified curve may lie from the unsimplified one, in sample spacings
    /// (`None`: [`rfta_simplify::default_tolerance`]).
    pub simplify_tolerance: Option<f64>,
    /// Simplify to at most this many edges (`None`: as far as the tolerance allows).
    pub max_edges: Option<usize>,
}

impl Default for PlaneParams {
    fn default() -> Self {
        Self {
            rounds: 10,
            max_points_per_sphere: 3,
            transport_step: 0.01,
            tolerance: 1e-4,
            raster_resolution: None,
            clamp: None,
            spsr_depth: None,
            owner_band: Some(3.0),
            min_island: 2.0,
            keep_cavities: false,
            simplify: true,
            simplify_tolerance: None,
            max_edges: None,
        }
    }
}

/// A curve counts as entering a circle when it comes closer than `|s| - ENTER_MARGIN h`.
pub(crate) const ENTER_MARGIN: f64 = 0.1;

/// A curve counts as leaving a gap when it is farther than `|s| + GAP_MARGIN h`.
pub(crate) const GAP_MARGIN: f64 = 0.25;

/// Why a 2D reconstruction gave no curve.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The samples are all of one sign and no circle has a free arc of the side a curve needs.
    #[error("all {samples} samples are {sign} and no circle leaves room for a curve")]
    NoSurface {
        /// Samples given.
        samples: usize,
        /// Their sign, in words.
        sign: &'static str,
    },
    /// Fewer than 2 circles have a feasible point.
    #[error("only {feasible} feasible tangency points for {spheres} circles")]
    TooFewPoints {
        /// Points found.
        feasible: usize,
        /// Circles given.
        spheres: usize,
    },
    /// A screened Poisson solve failed.
    #[error("{0}")]
    Solve(String),
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, Error>;
