//! [`Workspace`]: solves that start from the previous solve's coefficients.

use crate::run::{Keep, run};
use crate::{OrientedPoints, Reconstruction, Result, SpsrParams, solve};

/// What one reconstruction leaves for the next, for clouds that change little from one solve to
/// the next (the fine-tuning rounds of Reach for the Arcs move every point by a small step).
///
/// Each solve after the first starts its Gauss-Seidel relaxation from the previous solve's
/// coefficients at the nodes both octrees share, so the same sweeps
/// ([`SpsrParams::iterations`]) land nearer the converged solution. The octree itself is rebuilt every time: moving points change its
/// refinement (measured on the rounds at 21^3: 2% to 8% of the refined cells are new each
/// round), and a tree kept from before would no longer be the one the density estimate asks
/// for. Results depend only on the sequence of inputs, never on the thread count.
///
/// The Reach for the Arcs pipeline measured it and solves cold: at 4 sweeps a warm start left
/// the dev set's mean Chamfer and CPU time unchanged and put more samples on the wrong side of
/// the mesh (docs/speed.md).
///
/// ```
/// use rfta_spsr::{OrientedPoints, SpsrParams, Workspace, glam::DVec3};
///
/// let sphere = |r: f64| {
///     let pts: Vec<DVec3> = (0..2000)
///         .map(|i| {
///             let z = 1.0 - 2.0 * (i as f64 + 0.5) / 2000.0;
///             let phi = i as f64 * 2.399963229728653;
///             let s = (1.0 - z * z).sqrt();
///             DVec3::new(s * phi.cos(), s * phi.sin(), z)
///         })
///         .collect();
///     OrientedPoints::new(pts.iter().map(|p| r * *p).collect(), pts, None)
/// };
/// let params = SpsrParams { depth: 6, iterations: 2, ..SpsrParams::default() };
/// let mut ws = Workspace::new();
/// for r in [1.0, 1.01, 1.02] {
///     let out = ws.reconstruct(&sphere(r)?, &params)?;
///     let v = out.mesh.signed_volume();
///     assert!((v - 4.18879 * r * r * r).abs() < 0.15, "{v}");
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    last: Option<solve::WarmStart>,
}

impl Workspace {
    /// An empty workspace: its first solve starts cold, as [`crate::reconstruct`] does.
    pub fn new() -> Self {
        Self::default()
    }

    /// Reconstruct `points`, starting from this workspace's previous solution, and keep this
    /// solution for the next call.
    ///
    /// # Errors
    /// As [`crate::reconstruct`]; a failed solve leaves the previous solution in place.
    pub fn reconstruct(
        &mut self,
        points: &OrientedPoints,
        params: &SpsrParams,
    ) -> Result<Reconstruction> {
        params.validate()?;
        let (out, warm) = run(
            points,
            params,
            crate::sides::NO_SIDES,
            self.last.as_ref(),
            Keep::Coefficients,
        )?;
        self.last = warm;
        Ok(out)
    }

    /// Forget the previous solution: the next solve starts cold.
    pub fn clear(&mut self) {
        self.last = None;
    }
}
