//! The error type of the geometry kernel.

/// What is wrong with data handed to a constructor of this crate.
///
/// Every variant names the offending index or shape so that a user can find it in their file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An SDF value is NaN or infinite.
    #[error("SDF value at sample {index} is not finite ({value})")]
    NonFiniteValue {
        /// Index of the sample (flat index for a grid, see [`crate::Grid::index`]).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A position (sample, vertex or point) has a NaN or infinite coordinate.
    #[error("{what} {index} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinitePosition {
        /// What kind of position: "sample", "vertex", "point".
        what: &'static str,
        /// Its index.
        index: usize,
        /// x coordinate.
        x: f64,
        /// y coordinate.
        y: f64,
        /// z coordinate.
        z: f64,
    },
    /// Two arrays that must have one entry per item differ in length.
    #[error("length mismatch: {expected_what} has {expected} entries but {found_what} has {found}")]
    LengthMismatch {
        /// The array whose length is taken as right.
        expected_what: &'static str,
        /// Its length.
        expected: usize,
        /// The other array.
        found_what: &'static str,
        /// Its length.
        found: usize,
    },
    /// Too few samples to describe a surface.
    #[error("too few samples: {found} given, at least {needed} needed")]
    TooFewSamples {
        /// How many were given.
        found: usize,
        /// How many are needed.
        needed: usize,
    },
    /// Every SDF value is zero, so the samples say nothing of either side of a surface.
    #[error(
        "no sign change: all {n} SDF values are {sign} (min {min}, max {max}), so the samples describe no surface"
    )]
    NoSignChange {
        /// Number of samples.
        n: usize,
        /// Which: "zero" (samples of one sign are accepted; see `SdfSamples::grid`).
        sign: &'static str,
        /// Smallest value.
        min: f64,
        /// Largest value.
        max: f64,
    },
    /// A grid description is unusable.
    #[error("invalid grid: {0}")]
    InvalidGrid(String),
    /// A stated sample spacing is not positive and finite.
    #[error("the sample spacing must be positive and finite, not {0}")]
    InvalidSpacing(f64),
    /// A triangle refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {vertex}, but the mesh has only {n_vertices} vertices")]
    FaceIndexOutOfRange {
        /// The face index.
        face: usize,
        /// The vertex index it names.
        vertex: u32,
        /// The number of vertices.
        n_vertices: usize,
    },
    /// A normal has zero or non-finite length.
    #[error("normal {index} has zero or non-finite length")]
    DegenerateNormal {
        /// Its index.
        index: usize,
    },
    /// Two samples at the same position carry different values: a distance function has one value
    /// per point.
    #[error(
        "samples {first} and {second} are both at ({x}, {y}, {z}) but have different values ({first_value} and {second_value})"
    )]
    ConflictingSamples {
        /// The first sample.
        first: usize,
        /// The second sample.
        second: usize,
        /// x coordinate of the shared position.
        x: f64,
        /// y coordinate.
        y: f64,
        /// z coordinate.
        z: f64,
        /// Value of the first sample.
        first_value: f64,
        /// Value of the second sample.
        second_value: f64,
    },
    /// A weight is negative or non-finite.
    #[error("weight {index} is negative or not finite ({value})")]
    InvalidWeight {
        /// Its index.
        index: usize,
        /// The value.
        value: f64,
    },
}
