//! The small loops of a 2D curve that no sample supports, removed.

use rfta_geom::glam::DVec2;
use rfta_geom::plane::Polylines;
use rfta_mesh::PolylineIndex;

use crate::arcs::Circle;
use crate::params::{ENTER_MARGIN, GAP_MARGIN};

/// Samples whose circles a small loop must touch, nearest, for the loop to stay without a sample
/// of its inside sign in it (the 3D pipeline asks for 3; a feature between the grid points of a
/// 2D grid touches fewer circles).
const GAP_WITNESSES_2D: usize = 2;

/// Removes the loops smaller than `min_island` spacings (bounding-box diagonal) that no sample
/// supports: none of their inside's sign lies in them (an outer loop's inside is negative, a
/// hole's positive), and fewer than [`GAP_WITNESSES_2D`] samples touch them (within the
/// consistency margins) while the rest of the curve is farther than the gap margin. Screened
/// Poisson leaves such loops next to isolated points, a fraction of a spacing across; a thin part
/// between grid points touches the circles around it and stays. Returns the curve, without the
/// removed loops' vertices, and the number of loops removed.
pub(crate) fn drop_islands(
    curve: Polylines,
    circles: &[Circle],
    values: &[f64],
    spacing: f64,
    min_island: f64,
) -> (Polylines, usize) {
    if min_island <= 0.0 || curve.is_empty() {
        return (curve, 0);
    }
    let (loops, label) = loops_of(&curve);
    let whole = PolylineIndex::new(&curve);
    let mut keep = vec![true; loops.len()];
    for (k, edges) in loops.values().enumerate() {
        let one = Polylines {
            vertices: curve.vertices.clone(),
            edges: edges.clone(),
        };
        if diagonal(&curve.vertices, edges) >= min_island * spacing {
            continue;
        }
        let area: f64 = edges
            .iter()
            .map(|&e| {
                let s = one.segment(e);
                s.a.perp_dot(s.b)
            })
            .sum();
        let inside_negative = area > 0.0;
        let index = PolylineIndex::new(&one);
        // The rest of the curve, built and indexed once per small loop, if a sample needs it.
        let others = std::cell::OnceCell::new();
        let rest_index = std::cell::OnceCell::new();
        let mut witnesses = 0;
        let mut supported = false;
        for (c, &v) in circles.iter().zip(values) {
            if index.winding(c.center) != 0 && (v < 0.0) == inside_negative {
                supported = true;
                break;
            }
            let d = index.closest(c.center).distance;
            if d < c.radius - ENTER_MARGIN * spacing || d > c.radius + GAP_MARGIN * spacing {
                continue;
            }
            // The rest of the curve: the whole curve's nearest edge, unless it is this loop's.
            let nearest = whole.closest(c.center);
            let rest = if label[nearest.edge] == k {
                rest_index
                    .get_or_init(|| {
                        PolylineIndex::new(others.get_or_init(|| {
                            Polylines {
                                vertices: curve.vertices.clone(),
                                edges: (0..curve.edges.len())
                                    .filter(|&e| label[e] != k)
                                    .map(|e| curve.edges[e])
                                    .collect(),
                            }
                        }))
                    })
                    .closest(c.center)
                    .distance
            } else {
                nearest.distance
            };
            if rest > c.radius + GAP_MARGIN * spacing {
                witnesses += 1;
                if witnesses >= GAP_WITNESSES_2D {
                    supported = true;
                    break;
                }
            }
        }
        keep[k] = supported;
    }
    let removed = keep.iter().filter(|&&k| !k).count();
    if removed == 0 || removed == loops.len() {
        return (curve, 0);
    }
    let edges = loops
        .values()
        .zip(&keep)
        .filter(|&(_, &k)| k)
        .flat_map(|(e, _)| e.iter().copied())
        .collect();
    let mut kept = Polylines {
        vertices: curve.vertices,
        edges,
    };
    kept.remove_unreferenced_vertices();
    (kept, removed)
}

/// The loops of `curve` (edges grouped by connected vertices, in the order of their roots) and
/// each edge's loop.
fn loops_of(curve: &Polylines) -> (std::collections::BTreeMap<usize, Vec<[u32; 2]>>, Vec<usize>) {
    let mut sets = rfta_mesh::UnionFind::new(curve.vertices.len());
    for &[a, b] in &curve.edges {
        sets.union(a as usize, b as usize);
    }
    let mut loops: std::collections::BTreeMap<usize, Vec<[u32; 2]>> = Default::default();
    for &e in &curve.edges {
        loops.entry(sets.find(e[0] as usize)).or_default().push(e);
    }
    let number: std::collections::HashMap<usize, usize> = loops
        .keys()
        .enumerate()
        .map(|(k, &root)| (root, k))
        .collect();
    let label = curve
        .edges
        .iter()
        .map(|e| number[&sets.find(e[0] as usize)])
        .collect();
    (loops, label)
}

/// The diagonal of the bounding box of `edges`' vertices.
fn diagonal(vertices: &[DVec2], edges: &[[u32; 2]]) -> f64 {
    let (lo, hi) = edges.iter().flatten().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(vertices[v as usize]), hi.max(vertices[v as usize])),
    );
    (hi - lo).length()
}

/// Mean distance from each circle's centre to the nearest other centre (the spacing of scattered
/// samples).
pub(crate) fn mean_nearest(circles: &[Circle]) -> f64 {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    let coords: Vec<[f64; 2]> = circles.iter().map(|c| c.center.to_array()).collect();
    let Ok(tree) = ImmutableKdTree::<f64, 2>::new_from_slice(&coords) else {
        return 1.0 / (circles.len() as f64).sqrt();
    };
    let total: f64 = coords
        .iter()
        .map(|p| {
            let near = tree
                .query(p)
                .nearest_n::<SquaredEuclidean<f64>>(
                    std::num::NonZero::<usize>::MIN.saturating_add(1),
                )
                .execute();
            near.get(1).map_or(0.0, |n| n.distance.sqrt())
        })
        .sum();
    (total / circles.len() as f64).max(1e-9)
}
