//! A grid's index-to-world transform, for the maps that keep grid lines on world axes.
//!
//! OpenVDB writes a transform as the map's type name and its fields (`math/Maps.h`): the scale
//! maps hold the scale followed by four quantities derived from it, the scale-translate maps the
//! translation first, an affine map a row-major 4x4 matrix that multiplies row vectors
//! (`[i j k 1] M`, the translation in its last row). Voxel `(i, j, k)` lies at
//! `translation + scale * (i, j, k)`.

use rfta_geom::glam::DVec3;

use super::bytes::Bytes;
use crate::error::{ParseError, ParseResult};

/// A transform that maps index axes to world axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct AxisAligned {
    /// World distance between neighbouring voxels along each axis.
    pub(super) scale: DVec3,
    /// World position of voxel `(0, 0, 0)`.
    pub(super) translation: DVec3,
}

impl AxisAligned {
    /// World position of voxel `ijk`.
    pub(super) fn world(&self, ijk: [i32; 3]) -> DVec3 {
        self.translation + self.scale * DVec3::new(ijk[0].into(), ijk[1].into(), ijk[2].into())
    }
}

/// Reads a transform; one that rotates, shears, flips or is not linear is an error naming it.
pub(super) fn read(b: &mut Bytes<'_>) -> ParseResult<AxisAligned> {
    let kind = b.string("the transform's type")?;
    let what = "the transform";
    let (scale, translation) = match kind.as_str() {
        "ScaleMap" | "UniformScaleMap" => {
            let s = b.vec3d(what)?;
            skip_derived(b)?;
            (s, [0.0; 3])
        }
        "ScaleTranslateMap" | "UniformScaleTranslateMap" => {
            let t = b.vec3d(what)?;
            let s = b.vec3d(what)?;
            skip_derived(b)?;
            (s, t)
        }
        "TranslationMap" => ([1.0; 3], b.vec3d(what)?),
        "AffineMap" | "UnitaryMap" => {
            let mut m = [[0.0; 4]; 4];
            for row in &mut m {
                for v in row.iter_mut() {
                    *v = b.f64(what)?;
                }
            }
            let diagonal = (0..3).all(|r| {
                (0..3).all(|c| r == c || m[r][c].abs() <= 1e-12 * m[r][r].abs().max(m[c][c].abs()))
            });
            if !diagonal {
                return Err(ParseError::new(format!(
                    "the grid's {kind} rotates or shears the voxel axes; rfta reads grids whose \
                     axes are the world's (resample the level set onto an axis-aligned transform)"
                )));
            }
            ([m[0][0], m[1][1], m[2][2]], [m[3][0], m[3][1], m[3][2]])
        }
        other => {
            return Err(ParseError::new(format!(
                "the grid's transform is a {other:?}, which rfta does not read (it reads scale, \
                 translation and axis-aligned affine maps)"
            )));
        }
    };
    let (scale, translation) = (DVec3::from_array(scale), DVec3::from_array(translation));
    if !(scale.is_finite() && scale.min_element() > 0.0 && translation.is_finite()) {
        return Err(ParseError::new(format!(
            "the grid's {kind} has voxel size {scale} and translation {translation}: rfta needs a \
             positive, finite voxel size along every axis"
        )));
    }
    Ok(AxisAligned { scale, translation })
}

/// The inverse scale, its square, half of it and the voxel size: recomputed from the scale, so
/// skipped.
fn skip_derived(b: &mut Bytes<'_>) -> ParseResult<()> {
    b.take(4 * 24, "the transform").map(|_| ())
}
