//! [`Warning`]: what a reconstruction tells its caller beside the mesh, one variant per kind,
//! each with the figures it states; its `Display` is the one wording every front end shows (the
//! command line, Python's `warnings.warn`, the HTML page, the JSON report).

use std::fmt;

use serde::{Serialize, Serializer};

use crate::consistency;

/// Something the caller should know about a reconstruction ([`crate::Report::warnings`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Warning {
    /// The values change faster than a distance can, or overlap the other sign's, by up to
    /// `fraction` of their magnitude; spheres were shrunk to match.
    Noisy {
        /// The relative noise, as a fraction.
        fraction: f64,
    },
    /// The values fall short of the distance to their zero set (median `reach` of it, far from
    /// it): not a distance; the mesh is the field's zero set ([`crate::Field::LevelSet`]).
    LevelSet {
        /// [`crate::FieldReport::reach`].
        reach: f64,
    },
    /// The values reach their zero set but their spheres do not all touch it: `covered` of the
    /// spheres near it lie inside the union of others, as a bound's (a CSG tree's) do; they were
    /// read as bounds ([`crate::Field::Bound`]).
    Bound {
        /// [`crate::FieldReport::covered`].
        covered: f64,
    },
    /// A function asked adaptively whose spheres are bounds (`covered` of those near its zero set
    /// lie inside the union of others) and whose mesh read as distances entered more of them
    /// than its zero set does: the mesh is the zero set of the samples asked
    /// (`crates/rfta/src/adaptive/bounds.rs`).
    BoundFunction {
        /// [`crate::FieldReport::covered`].
        covered: f64,
    },
    /// Flat plateaus of the values at magnitude `at` (`samples` on them): a clamp, detected.
    Clamped {
        /// The clamp.
        at: f64,
        /// Samples on the plateaus.
        samples: usize,
    },
    /// Samples whose value is larger than the distance to the other sign's nearest sample.
    Overlap {
        /// Samples that overlap.
        inconsistent: usize,
        /// Samples compared.
        checked: usize,
        /// The worst pair, described (positions, values, distance, factor).
        worst: Option<String>,
    },
    /// The mesh's genus is below the genus asked ([`crate::Params::genus`]).
    GenusBelow {
        /// The mesh's.
        genus: i64,
        /// The genus asked.
        asked: usize,
    },
    /// The mesh's genus is above the genus asked: handles could not all be cut.
    GenusAbove {
        /// The mesh's.
        genus: i64,
        /// The genus asked.
        asked: usize,
    },
    /// The mesh puts samples on the wrong side or enters their spheres.
    Disagrees {
        /// Samples on the wrong side.
        wrong_side: usize,
        /// Spheres entered beyond the margin.
        entered: usize,
        /// The deepest entry, in spacings.
        deepest: f64,
    },
    /// The mesh encloses cavities around outside samples.
    Cavities {
        /// How many.
        count: usize,
        /// Whether they were left as they are ([`crate::Params::keep_cavities`], or samples
        /// that are not a grid) rather than tried and found walled in.
        kept: bool,
    },
    /// Handles around which a loop is shorter than the thin-loop margin
    /// ([`crate::Margins::thin_loop`]).
    ThinHandles {
        /// Independent short loops.
        loops: usize,
        /// The shortest, in spacings.
        shortest: f64,
        /// Whether they are the ones the samples keep: the handles no sample confirms were cut
        /// (a grid, unless [`crate::Params::keep_thin_handles`]), so a sample next to each of
        /// these confirms it or cutting it would put one on the wrong side.
        kept_by_samples: bool,
    },
    /// Handles thinner than the samples resolve that no sample confirms, cut
    /// ([`crate::Params::keep_thin_handles`]).
    ThinHandlesCut {
        /// Their loops, in spacings.
        loops: Vec<f64>,
    },
    /// More than a twentieth of the spheres ended without a tangency point.
    SpheresWithoutPoint {
        /// Spheres without a point.
        without: usize,
        /// Spheres that could have one.
        eligible: usize,
    },
    /// The mesh is not watertight.
    NotWatertight {
        /// Edges with one face.
        boundary_edges: usize,
        /// Edges with more than two faces.
        nonmanifold_edges: usize,
    },
    /// Faces of zero area in the mesh.
    ZeroAreaFaces {
        /// How many.
        faces: usize,
        /// Of them, those with a repeated vertex.
        degenerate: usize,
    },
}

/// How a grid of bounds was read ([`Warning::Bound`]).
const BOUND_READING: &str = "read as bounds: every sphere stays empty space, but the tangency points off the zero set of the grid's smooth interpolant were moved onto it by Newton's method and the spheres were not fitted";

/// How a function of bounds was read ([`Warning::BoundFunction`]).
const BOUND_FUNCTION_READING: &str = "read as distances the mesh entered more of the spheres than the function's zero set does, so the mesh is that zero set (the samples asked carried onto a grid at the finest spacing reached, points put on it by Newton's method on the grid's smooth interpolant)";

/// The sentence of a bound reading: `covered` the share of the spheres near the zero set that
/// others cover, `reading` how the values were read ([`BOUND_READING`] or
/// [`BOUND_FUNCTION_READING`]).
fn fmt_bounds(f: &mut fmt::Formatter<'_>, covered: f64, reading: &str) -> fmt::Result {
    write!(
        f,
        "the values are not distances: {:.1}% of the spheres near their zero set have no point outside every other sphere (a distance's sphere touches the surface where no other reaches), as a CSG tree's min and max or a smooth blend give; {reading} (field = distance reads them as distances)",
        100.0 * covered
    )
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Noisy { fraction } => write!(
                f,
                "the values look noisy, by up to {:.2}% of their magnitude (they change faster than a distance can, or overlap the other sign's): a point counts as inside another sample's sphere only deeper than that (twice over), so that noise does not cover tangency points",
                100.0 * fraction
            ),
            Self::LevelSet { reach } => write!(
                f,
                "the values are not distances: far from their zero set they reach {:.0}% of the way to it (a distance reaches all of it), as a trained network's or a CSG bound's do; the mesh is the field's zero set (points put on it by Newton's method on the grid's smooth interpolant), not the spheres' (field = distance reads them as distances)",
                100.0 * reach
            ),
            Self::Bound { covered } => fmt_bounds(f, *covered, BOUND_READING),
            Self::BoundFunction { covered } => fmt_bounds(f, *covered, BOUND_FUNCTION_READING),
            Self::Clamped { at, samples } => write!(
                f,
                "the values look clamped at {at}: {samples} samples sit on flat plateaus at that magnitude; they are treated as at least {at} from the surface (set a clamp to override, or turn the check off)"
            ),
            Self::Overlap {
                inconsistent,
                checked,
                worst,
            } => {
                write!(
                    f,
                    "{inconsistent} of {checked} samples ({:.1}%) overlap the nearest sample of the other sign, so |s| is larger than the distance to the surface there",
                    100.0 * *inconsistent as f64 / (*checked).max(1) as f64
                )?;
                match worst {
                    Some(w) => write!(f, "; worst: {w}"),
                    None => Ok(()),
                }
            }
            Self::GenusBelow { genus, asked } => write!(
                f,
                "the mesh has genus {genus}, below the {asked} asked: the samples show no more handles (a handle is never added)"
            ),
            Self::GenusAbove { genus, asked } => write!(
                f,
                "the mesh has genus {genus}, above the {asked} asked: handles are cut on meshes of genus up to {}, along loops up to 64 spacings",
                consistency::THIN_LOOP_MAX_GENUS
            ),
            Self::Disagrees {
                wrong_side,
                entered,
                deepest,
            } => write!(
                f,
                "the mesh disagrees with the samples: {wrong_side} on the wrong side of it, {entered} whose sphere it enters by more than {} spacing (deepest: {deepest:.2} spacings)",
                consistency::ENTER_MARGIN
            ),
            Self::Cavities { count, kept } => {
                let what = if *count == 1 { "y" } else { "ies" };
                if *kept {
                    write!(
                        f,
                        "the mesh encloses {count} cavit{what} around samples outside the shape: unless the shape is hollow there, a hole or a gap the surface closed around them, which finer samples can open"
                    )
                } else {
                    write!(
                        f,
                        "the mesh encloses {count} cavit{what} around samples outside the shape that could not be opened: walled in by inside samples (a void the samples show), or closed again by the surface"
                    )
                }
            }
            Self::ThinHandles {
                loops,
                shortest,
                kept_by_samples,
            } => thin_handles(f, *loops, *shortest, *kept_by_samples),
            Self::ThinHandlesCut { loops } => {
                let lengths: Vec<String> = loops.iter().map(|l| format!("{l:.2}")).collect();
                write!(
                    f,
                    "cut {} handle(s) less than about a spacing across that no sample confirms (loops of {} spacings around): a bar the samples do not show cut through, a tunnel they do not show filled, as marching cubes of the same samples leaves them; finer samples can show them, keep_thin_handles (--keep-thin-handles) keeps them",
                    loops.len(),
                    lengths.join(", ")
                )
            }
            Self::SpheresWithoutPoint { without, eligible } => write!(
                f,
                "{without} of {eligible} spheres ended without a tangency point (clamped, zero-valued, or covered by other spheres)"
            ),
            Self::NotWatertight {
                boundary_edges,
                nonmanifold_edges,
            } => write!(
                f,
                "the mesh is not watertight: {boundary_edges} boundary and {nonmanifold_edges} non-manifold edges"
            ),
            Self::ZeroAreaFaces { faces, degenerate } => write!(
                f,
                "the mesh has {faces} faces of zero area ({degenerate} with a repeated vertex)"
            ),
        }
    }
}

/// [`Warning::ThinHandles`]' sentence.
fn thin_handles(
    f: &mut fmt::Formatter<'_>,
    loops: usize,
    shortest: f64,
    kept: bool,
) -> fmt::Result {
    write!(
        f,
        "the mesh has {loops} loop(s) around handles shorter than {:.2} spacings (the shortest {shortest:.2}): parts less than about a spacing across, ",
        consistency::THIN_LOOP
    )?;
    if kept {
        write!(
            f,
            "kept because a sample next to each confirms it or cutting it would put one on the wrong side; finer samples can tell more"
        )
    } else {
        write!(
            f,
            "which the samples can neither confirm nor rule out; finer samples can"
        )
    }
}

/// A warning's serde form is its sentence (the JSON report, Python's report dict).
impl Serialize for Warning {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sentences_state_their_figures() {
        let w = Warning::Overlap {
            inconsistent: 3,
            checked: 200,
            worst: None,
        };
        assert!(w.to_string().starts_with("3 of 200 samples (1.5%) overlap"));
        let w = Warning::BoundFunction { covered: 0.05 };
        assert!(
            w.to_string().contains(": 5.0% of the spheres")
                && w.to_string().contains("the mesh is that zero set"),
            "{w}"
        );
        let w = Warning::Cavities {
            count: 1,
            kept: true,
        };
        assert!(w.to_string().contains("1 cavity around"));
        let w = Warning::ThinHandles {
            loops: 2,
            shortest: 0.5,
            kept_by_samples: true,
        };
        assert!(
            w.to_string().contains("(the shortest 0.50)")
                && w.to_string().contains("kept because a sample"),
            "{w}"
        );
        let w = Warning::ThinHandles {
            loops: 2,
            shortest: 0.5,
            kept_by_samples: false,
        };
        assert!(
            w.to_string().contains("can neither confirm nor rule out"),
            "{w}"
        );
        let w = Warning::ThinHandlesCut {
            loops: vec![1.234, 2.0],
        };
        assert!(
            w.to_string()
                .starts_with("cut 2 handle(s) less than about a spacing across that no sample confirms (loops of 1.23, 2.00 spacings around)"),
            "{w}"
        );
        assert_eq!(
            serde_json::to_value(Warning::ZeroAreaFaces {
                faces: 2,
                degenerate: 0
            })
            .ok(),
            Some(serde_json::json!(
                "the mesh has 2 faces of zero area (0 with a repeated vertex)"
            ))
        );
    }
}
