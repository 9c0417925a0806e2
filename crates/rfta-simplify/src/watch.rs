//! Which samples a judge must watch: the rule the 3D and 2D judges share.

/// The samples whose verdict a simplification within `tolerance` can change, for a judge that
/// refuses to move the surface across a sample with a side or into a sample's sphere (circle)
/// deeper than `slack` (lengths in the mesh's units, `spacing` the samples').
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Watch {
    /// How deep the surface may newly enter a sphere.
    pub slack: f64,
    /// The simplification's tolerance.
    pub tolerance: f64,
    /// The sample spacing.
    pub spacing: f64,
}

/// The deviation is measured at points (vertices, new faces' centroids): a sample is watched
/// within this many tolerances of being touched...
const TOLERANCES: f64 = 1.2;

/// ... and at least this many spacings (a sample with a side) or this many beyond the slack (a
/// sphere): between the points, a face can stray further than the tolerance (the 129^3 bunny
/// simplified within 0.02 spacings put a sample on the other side with the tolerance alone
/// watched).
const SIDES: f64 = 0.25;
const SPHERES: f64 = 0.05;

impl Watch {
    /// How near the unsimplified surface a sample's centre must be for its verdict to be at
    /// risk: a sample with a side (`sided`) within `max(1.2 tolerance, 0.25 spacing)`; a sphere
    /// of `radius` above the slack within `radius - slack + max(1.2 tolerance, 0.05 spacing)`.
    /// 0 when neither holds.
    pub fn reach(&self, radius: f64, sided: bool) -> f64 {
        let measured = TOLERANCES * self.tolerance;
        let side = if sided {
            measured.max(SIDES * self.spacing)
        } else {
            0.0
        };
        let sphere = if radius > self.slack {
            radius - self.slack + measured.max(SPHERES * self.spacing)
        } else {
            0.0
        };
        side.max(sphere)
    }

    /// How far beyond the mesh near a watched sample a collapse that changes its verdict can
    /// reach: half a spacing (a face's extent there) and the side watch, at most a spacing more.
    pub fn margin(&self) -> f64 {
        0.5 * self.spacing
            + (TOLERANCES * self.tolerance)
                .max(SIDES * self.spacing)
                .min(self.spacing)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_and_spheres_are_watched_by_their_own_reach() {
        let w = Watch {
            slack: 0.08,
            tolerance: 0.05,
            spacing: 1.0,
        };
        // A small sample with a side: a quarter spacing (above 1.2 tolerances).
        assert!((w.reach(0.05, true) - 0.25).abs() < 1e-12);
        assert_eq!(w.reach(0.05, false), 0.0);
        // A sphere of radius 2: entered past 0.08 - 0.06 = 0.02.
        assert!((w.reach(2.0, false) - (2.0 - 0.08 + 0.06)).abs() < 1e-12);
        // A large tolerance widens both.
        let wide = Watch {
            tolerance: 1.0,
            ..w
        };
        assert!((wide.reach(0.05, true) - 1.2).abs() < 1e-12);
        assert!((wide.margin() - 1.5).abs() < 1e-12);
    }
}
