//! Oriented point clouds.

use glam::DVec3;

use crate::{Aabb, Error, Result};

/// Points with unit normals and optional non-negative weights: the input of screened Poisson
/// surface reconstruction.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OrientedPoints {
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    weights: Option<Vec<f64>>,
}

impl OrientedPoints {
    /// Points with normals (normalised here) and optional weights, validated.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] when the arrays differ in length, [`Error::NonFinitePosition`]
    /// for a NaN or infinite position, [`Error::DegenerateNormal`] for a zero or non-finite normal,
    /// [`Error::InvalidWeight`] for a negative or non-finite weight.
    pub fn new(
        positions: Vec<DVec3>,
        normals: Vec<DVec3>,
        weights: Option<Vec<f64>>,
    ) -> Result<Self> {
        if normals.len() != positions.len() {
            return Err(Error::LengthMismatch {
                expected_what: "positions",
                expected: positions.len(),
                found_what: "normals",
                found: normals.len(),
            });
        }
        if let Some(w) = &weights
            && w.len() != positions.len()
        {
            return Err(Error::LengthMismatch {
                expected_what: "positions",
                expected: positions.len(),
                found_what: "weights",
                found: w.len(),
            });
        }
        for (index, p) in positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(Error::NonFinitePosition {
                    what: "point",
                    index,
                    x: p.x,
                    y: p.y,
                    z: p.z,
                });
            }
        }
        let mut unit = Vec::with_capacity(normals.len());
        for (index, n) in normals.iter().enumerate() {
            let len = n.length();
            if !(len > 0.0 && len.is_finite()) {
                return Err(Error::DegenerateNormal { index });
            }
            unit.push(*n / len);
        }
        if let Some(w) = &weights
            && let Some((index, &value)) = w
                .iter()
                .enumerate()
                .find(|(_, w)| !(**w >= 0.0 && w.is_finite()))
        {
            return Err(Error::InvalidWeight { index, value });
        }
        Ok(Self {
            positions,
            normals: unit,
            weights,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Positions.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Unit normals.
    pub fn normals(&self) -> &[DVec3] {
        &self.normals
    }

    /// Per-point weights, if given.
    pub fn weights(&self) -> Option<&[f64]> {
        self.weights.as_deref()
    }

    /// Bounding box of the positions.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }
}
