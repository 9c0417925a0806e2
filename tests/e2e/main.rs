//! End-to-end tests: one binary, one module per area.

/// Mesh loading, topology and exact SDF sampling against the prepared inputs.
mod data_inputs;

/// Sphere tree and rasterizer on the real SDF grids.
mod spheres;

/// Marching cubes against the reference (libigl) results.
mod mc_reference;

/// The reconstruction on an analytic torus.
mod reconstruct;

/// The bad-input corpus through the library.
mod bad_inputs;

/// The simplification on every dev output.
mod simplify;
