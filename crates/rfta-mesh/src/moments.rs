//! Far-field moments of the mesh index's nodes (Barill et al. 2018, "Fast winding numbers for
//! soups and clouds"): each node's area, summed normal, centre and first moment, for the winding
//! number's approximation far from it.

use rfta_geom::glam::{DMat3, DVec3};

use crate::node::Node;

/// Far-field data of one node.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Moments {
    /// Total area.
    pub(crate) area: f64,
    /// Sum of area-weighted unit normals (`sum_t a_t n_t`); also the direction of the node's
    /// oriented box (`bvh::OrientedBox`).
    pub(crate) normal: DVec3,
    /// Expansion centre (area-weighted centroid).
    pub(crate) center: DVec3,
    /// `sum_t a_t n_t (c_t - center)^T`: column j holds `sum a_t n_t (c_t - center)_j`.
    pub(crate) first: DMat3,
    /// Distance from `center` to the farthest point of the node's box.
    pub(crate) radius: f64,
}

/// Computes every node's moments bottom-up (children have larger indices than parents).
pub(crate) fn node_moments(nodes: &[Node], tris: &[[DVec3; 3]]) -> Vec<Moments> {
    use rayon::prelude::*;
    let zero = Moments {
        area: 0.0,
        normal: DVec3::ZERO,
        center: DVec3::ZERO,
        first: DMat3::ZERO,
        radius: 0.0,
    };
    // The leaves (most of the work: every triangle) side by side, then the inner nodes from the
    // bottom up (children come after their parent); each node's sums are the same either way.
    let mut m: Vec<Moments> = nodes
        .par_iter()
        .map(|node| {
            if node.leaf {
                with_radius(leaf_moments(tris, node), node)
            } else {
                zero
            }
        })
        .collect();
    for idx in (0..nodes.len()).rev() {
        let node = nodes[idx];
        if node.leaf {
            continue;
        }
        let (l, r) = (m[node.a as usize], m[node.b as usize]);
        let area = l.area + r.area;
        let center = if area > 0.0 {
            (l.area * l.center + r.area * r.center) / area
        } else {
            node.bounds.center()
        };
        let first = l.first
            + outer(l.normal, l.center - center)
            + r.first
            + outer(r.normal, r.center - center);
        let out = Moments {
            area,
            normal: l.normal + r.normal,
            center,
            first,
            radius: 0.0,
        };
        m[idx] = with_radius(out, &node);
    }
    m
}

/// The moments of a leaf's triangles about their area-weighted centroid (the box centre when
/// they have no area).
fn leaf_moments(tris: &[[DVec3; 3]], node: &Node) -> Moments {
    let tris = &tris[node.a as usize..(node.a + node.b) as usize];
    let mut area = 0.0;
    let mut normal = DVec3::ZERO;
    let mut weighted = DVec3::ZERO;
    for [a, b, c] in tris {
        let an = 0.5 * (*b - *a).cross(*c - *a);
        let ar = an.length();
        area += ar;
        normal += an;
        weighted += ar * (*a + *b + *c) / 3.0;
    }
    let center = if area > 0.0 {
        weighted / area
    } else {
        node.bounds.center()
    };
    let mut first = DMat3::ZERO;
    for [a, b, c] in tris {
        let an = 0.5 * (*b - *a).cross(*c - *a);
        first += outer(an, (*a + *b + *c) / 3.0 - center);
    }
    Moments {
        area,
        normal,
        center,
        first,
        radius: 0.0,
    }
}

/// `m` with the radius of its node's box about its centre.
fn with_radius(mut m: Moments, node: &Node) -> Moments {
    let far = (m.center - node.bounds.min)
        .abs()
        .max((node.bounds.max - m.center).abs());
    m.radius = far.length();
    m
}

/// `u v^T`.
pub(crate) fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}
