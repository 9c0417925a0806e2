//! Reach for the Arcs in the plane (Sellán, Ren, Batty and Stein, SIGGRAPH 2024, Figure 5): the 2D
//! pipeline, [`reconstruct`]`(&SdfSamples2, &PlaneParams)`, and its stages (`rfta::plane` runs it
//! with the input check and `rfta::Params`).
//!
//! Each 2D SDF sample `(p_i, s_i)` is a circle of radius `|s_i|` that the curve touches without
//! entering.
//! - [`raster::empty_space`]: cells no circle of one sign covers, next to covered ones;
//! - [`arcs`]: the exact free arcs of each circle, the initial points ([`initial_points`]), one
//!   fine-tuning round against a polyline ([`arcs::Owners::fine_tune`]);
//! - [`spsr`]: screened Poisson on a complete quadtree, the curve by marching squares;
//! - [`holes`]: the holes the curve closes around outside samples, opened.
//!
//! # Example
//! ```
//! use rfta_geom::glam::DVec2;
//! use rfta_plane::arcs::Circle;
//! use rfta_plane::{initial_points, spsr};
//!
//! // The SDF of the circle of radius 0.3 around (0.5, 0.5) on a 17 x 17 grid over the unit square;
//! // the samples within 3 spacings of the curve own points, the rest are constraints.
//! let (mut circles, mut values) = (Vec::new(), Vec::new());
//! for i in 0..17 {
//!     for j in 0..17 {
//!         let p = DVec2::new(i as f64, j as f64) / 16.0;
//!         let s = (p - DVec2::splat(0.5)).length() - 0.3;
//!         circles.push(Circle { center: p, radius: s.abs() });
//!         values.push(s);
//!     }
//! }
//! let owners: Vec<usize> = (0..circles.len()).filter(|&i| circles[i].radius < 3.0 / 16.0).collect();
//! let cloud = initial_points(&circles, &values, &owners, 1e-4, 128, DVec2::ZERO, 1.0);
//! let (points, normals) = cloud.oriented(&circles, &values);
//! let domain = spsr::Domain { min: DVec2::splat(-0.25), side: 1.5 };
//! let curve = spsr::solve(&points, &normals, domain, &spsr::SpsrParams::default()).expect("solves").curve();
//! assert_eq!(curve.loops(), 1);
//! for v in &curve.vertices {
//!     assert!(((*v - DVec2::splat(0.5)).length() - 0.3).abs() < 0.01);
//! }
//! ```

pub mod arcs;
pub mod holes;
mod islands;
mod params;
mod pipeline;
pub mod raster;
mod simplify;
pub mod spsr;

pub use params::{Error, PlaneParams, Result};
pub use pipeline::{Reconstruction2, Report2, reconstruct};

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use rfta_geom::glam::DVec2;

use arcs::{Circle, FreeArcs, Owners};

/// The initial tangency points (the paper's §4.1): for every owning circle, the free angle nearest
/// to the direction of the empty space (of its sign's raster over the square `min`, `side`)
/// nearest to its centre. Owners without a free arc are dropped; every other circle is a
/// constraint only.
pub fn initial_points(
    circles: &[Circle],
    values: &[f64],
    owners: &[usize],
    tolerance: f64,
    res: usize,
    min: DVec2,
    side: f64,
) -> Owners {
    let all: Vec<usize> = (0..circles.len()).collect();
    let free: Vec<FreeArcs> = owners
        .par_iter()
        .with_min_len(16)
        .map(|&i| FreeArcs::of(circles, i, &all, tolerance))
        .collect();
    // One raster and one tree of empty space per sign.
    let empty = |negative: bool| {
        let of_sign: Vec<Circle> = circles
            .iter()
            .zip(values)
            .filter(|&(_, &v)| (v < 0.0) == negative)
            .map(|(c, _)| *c)
            .collect();
        let band = raster::empty_space(&of_sign, res, min, side);
        let coords: Vec<[f64; 2]> = band.iter().map(|p| p.to_array()).collect();
        (band, ImmutableKdTree::<f64, 2>::new_from_slice(&coords))
    };
    let sides = [empty(false), empty(true)];
    let mut out = Owners {
        circle: Vec::new(),
        free: Vec::new(),
        angles: Vec::new(),
    };
    for (&i, free) in owners.iter().zip(free) {
        let (band, tree) = &sides[usize::from(values[i] < 0.0)];
        let c = circles[i];
        let toward = match tree {
            Ok(tree) if !band.is_empty() => {
                let nearest = tree
                    .query(&c.center.to_array())
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                c.angle_of(band[nearest.item as usize])
            }
            _ => 0.0,
        };
        if let Some(t) = free.nearest(toward) {
            out.circle.push(i);
            out.angles.push(vec![t]);
            out.free.push(free);
        }
    }
    out
}
