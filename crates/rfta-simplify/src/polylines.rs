//! The 2D counterpart: vertices removed from closed polylines, where the two edges through a
//! vertex are nearly one straight run, cheapest (nearest the chord that replaces them) first.
//!
//! A removal keeps the loops simple and apart (no other vertex lies in the triangle the chord
//! cuts off, so the chord crosses no edge the two edges did not), never leaves a loop with fewer
//! than three vertices, keeps every input vertex it removes or hands on within the tolerance of
//! the chord and the chord's midpoint within it of the input, and asks the caller's
//! [`PolylineJudge`]. Vertices that do not start and end exactly one edge never go, nor do
//! their neighbours.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use rfta_geom::glam::DVec2;
use rfta_geom::plane::{Polylines, Segment};
use rfta_mesh::PolylineIndex;

use crate::{Error, Options};

/// The two edges a removal replaces and the chord that replaces them: `before` is `u -> v -> w`,
/// `after` is `u -> w`.
#[derive(Debug, Clone, Copy)]
pub struct Patch2 {
    /// The vertices `u`, `v`, `w` in order along the curve.
    pub before: [DVec2; 3],
}

impl Patch2 {
    /// The chord `u -> w`.
    pub fn after(&self) -> Segment {
        Segment {
            a: self.before[0],
            b: self.before[2],
        }
    }

    /// Whether the removal moves the curve across `p`: `p` lies in the triangle `u, v, w`.
    pub fn sweeps(&self, p: DVec2) -> bool {
        let [u, v, w] = self.before;
        let side = |a: DVec2, b: DVec2| (b - a).perp_dot(p - a);
        let (s1, s2, s3) = (side(u, v), side(v, w), side(w, u));
        (s1 >= 0.0 && s2 >= 0.0 && s3 >= 0.0) || (s1 <= 0.0 && s2 <= 0.0 && s3 <= 0.0)
    }

    /// The distance from `p` to the two edges before.
    pub fn distance_before(&self, p: DVec2) -> f64 {
        let [u, v, w] = self.before;
        let d = |a, b| p.distance(Segment { a, b }.closest_point(p));
        d(u, v).min(d(v, w))
    }

    /// The distance from `p` to the chord.
    pub fn distance_after(&self, p: DVec2) -> f64 {
        p.distance(self.after().closest_point(p))
    }
}

/// The caller's say over each removal.
pub trait PolylineJudge {
    /// Whether the removal `patch` describes may be made.
    fn allows(&self, patch: &Patch2) -> bool;
}

impl<F: Fn(&Patch2) -> bool> PolylineJudge for F {
    fn allows(&self, patch: &Patch2) -> bool {
        self(patch)
    }
}

/// Simplified polylines and what it took.
#[derive(Debug, Clone)]
pub struct SimplifiedPolylines {
    /// The output: the input's surviving vertices in their order, each edge where the edge
    /// leaving its start was.
    pub curve: Polylines,
    /// Vertices removed.
    pub removals: usize,
    /// The largest distance measured between the input and the output (input vertices to the
    /// output, chords' midpoints to the input).
    pub largest_deviation: f64,
}

/// `curve` simplified as `options` allow ([`Options::max_faces`] counts edges here) and `judge`
/// agrees (see the module documentation).
///
/// # Errors
/// [`Error::Tolerance`] for a negative or NaN tolerance.
pub fn simplify_polylines(
    curve: &Polylines,
    options: &Options,
    judge: &dyn PolylineJudge,
) -> Result<SimplifiedPolylines, Error> {
    if options.tolerance.is_nan() || options.tolerance < 0.0 {
        return Err(Error::Tolerance(options.tolerance));
    }
    let mut state = Chain::new(curve);
    let index = PolylineIndex::new(curve);
    let tol = options.tolerance;
    let mut heap = BinaryHeap::new();
    for v in 0..curve.vertices.len() as u32 {
        if let Some(cost) = state.cost(v) {
            heap.push(Candidate { cost, v, stamp: 0 });
        }
    }
    let (mut removals, mut largest) = (0, 0.0f64);
    let mut edges = curve.edges.len();
    while edges > options.max_faces.unwrap_or(0) {
        let Some(c) = heap.pop() else { break };
        if !state.alive[c.v as usize] || state.stamp[c.v as usize] != c.stamp {
            continue;
        }
        let v = c.v;
        let (u, w) = (state.prev[v as usize], state.next[v as usize]);
        let patch = Patch2 {
            before: [u, v, w].map(|x| state.at(x)),
        };
        let chord = patch.after();
        let midpoint = 0.5 * (chord.a + chord.b);
        let back = index.closest(midpoint).distance;
        if c.cost > tol {
            break;
        }
        if back > tol
            || state.loop_len(v) <= 3
            || state.vertex_in(&patch, [u, v, w])
            || !judge.allows(&patch)
        {
            continue;
        }
        largest = largest.max(c.cost).max(back);
        state.remove(v);
        removals += 1;
        edges -= 1;
        for x in [u, w] {
            state.stamp[x as usize] += 1;
            if let Some(cost) = state.cost(x) {
                let stamp = state.stamp[x as usize];
                heap.push(Candidate { cost, v: x, stamp });
            }
        }
    }
    Ok(SimplifiedPolylines {
        curve: state.into_polylines(curve),
        removals,
        largest_deviation: largest,
    })
}

/// A vertex to remove and the largest distance its removal would put an input vertex from the
/// chord.
struct Candidate {
    cost: f64,
    v: u32,
    stamp: u32,
}

impl Ord for Candidate {
    fn cmp(&self, o: &Self) -> Ordering {
        o.cost.total_cmp(&self.cost).then_with(|| o.v.cmp(&self.v))
    }
}

impl PartialOrd for Candidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl PartialEq for Candidate {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}

impl Eq for Candidate {}

/// The curve as linked vertices, with what each edge carries and a bucket grid of the vertices.
struct Chain {
    positions: Vec<DVec2>,
    next: Vec<u32>,
    prev: Vec<u32>,
    /// Whether each vertex starts and ends exactly one edge (only those are removed).
    free: Vec<bool>,
    alive: Vec<bool>,
    stamp: Vec<u32>,
    /// Input vertices the edge leaving each vertex carries.
    carried: Vec<Vec<u32>>,
    /// Each vertex's loop, and the loops' vertex counts.
    loop_of: Vec<u32>,
    loop_size: Vec<usize>,
    cell: f64,
    buckets: HashMap<[i64; 2], Vec<u32>>,
}

impl Chain {
    fn new(curve: &Polylines) -> Self {
        let n = curve.vertices.len();
        let (mut next, mut prev) = (vec![u32::MAX; n], vec![u32::MAX; n]);
        let (mut outs, mut ins) = (vec![0u32; n], vec![0u32; n]);
        for &[a, b] in &curve.edges {
            next[a as usize] = b;
            prev[b as usize] = a;
            outs[a as usize] += 1;
            ins[b as usize] += 1;
        }
        let free: Vec<bool> = (0..n).map(|v| outs[v] == 1 && ins[v] == 1).collect();
        // Loops: walk each free cycle once.
        let mut loop_of = vec![u32::MAX; n];
        let mut loop_size = Vec::new();
        for start in 0..n {
            if !free[start] || loop_of[start] != u32::MAX {
                continue;
            }
            let id = loop_size.len() as u32;
            let (mut at, mut size) = (start, 0);
            while at != u32::MAX as usize && loop_of[at] == u32::MAX {
                loop_of[at] = id;
                size += 1;
                at = next[at] as usize;
            }
            loop_size.push(size);
        }
        let length: f64 = curve.length();
        let cell = (2.0 * length / curve.edges.len().max(1) as f64).max(f64::MIN_POSITIVE);
        let mut buckets: HashMap<[i64; 2], Vec<u32>> = HashMap::new();
        for (v, &p) in curve.vertices.iter().enumerate() {
            if outs[v] + ins[v] > 0 {
                buckets.entry(key(p, cell)).or_default().push(v as u32);
            }
        }
        Self {
            positions: curve.vertices.clone(),
            next,
            prev,
            free,
            alive: vec![true; n],
            stamp: vec![0; n],
            carried: vec![Vec::new(); n],
            loop_of,
            loop_size,
            cell,
            buckets,
        }
    }

    fn at(&self, v: u32) -> DVec2 {
        self.positions[v as usize]
    }

    fn loop_len(&self, v: u32) -> usize {
        self.loop_size
            .get(self.loop_of[v as usize] as usize)
            .copied()
            .unwrap_or(0)
    }

    /// The largest distance from the chord replacing `v` of `v` and of what its two edges
    /// carry; `None` when `v` cannot go.
    fn cost(&self, v: u32) -> Option<f64> {
        if !self.free[v as usize] || !self.alive[v as usize] {
            return None;
        }
        let (u, w) = (self.prev[v as usize], self.next[v as usize]);
        if !self.free[u as usize] || !self.free[w as usize] {
            return None;
        }
        let chord = Segment {
            a: self.at(u),
            b: self.at(w),
        };
        let d = |p: DVec2| p.distance(chord.closest_point(p));
        let carried = self.carried[u as usize]
            .iter()
            .chain(&self.carried[v as usize])
            .map(|&i| d(self.at(i)));
        Some(carried.fold(d(self.at(v)), f64::max))
    }

    /// Whether a live vertex other than `uvw` lies in the triangle the chord cuts off.
    fn vertex_in(&self, patch: &Patch2, uvw: [u32; 3]) -> bool {
        let (lo, hi) = patch
            .before
            .iter()
            .fold((patch.before[0], patch.before[0]), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let (a, b) = (key(lo, self.cell), key(hi, self.cell));
        (a[0]..=b[0]).any(|x| {
            (a[1]..=b[1]).any(|y| {
                self.buckets.get(&[x, y]).is_some_and(|vs| {
                    vs.iter().any(|&q| {
                        self.alive[q as usize] && !uvw.contains(&q) && patch.sweeps(self.at(q))
                    })
                })
            })
        })
    }

    /// Removes `v`: its neighbours joined, the chord carrying what both edges carried and `v`.
    fn remove(&mut self, v: u32) {
        let (u, w) = (self.prev[v as usize], self.next[v as usize]);
        let mut carried = std::mem::take(&mut self.carried[v as usize]);
        carried.push(v);
        self.carried[u as usize].append(&mut carried);
        self.next[u as usize] = w;
        self.prev[w as usize] = u;
        self.alive[v as usize] = false;
        if let Some(size) = self.loop_size.get_mut(self.loop_of[v as usize] as usize) {
            *size -= 1;
        }
    }

    /// The surviving vertices in their order; each edge where the input's edge leaving its
    /// start was.
    fn into_polylines(self, curve: &Polylines) -> Polylines {
        let mut index = vec![u32::MAX; self.positions.len()];
        let mut vertices = Vec::new();
        for (v, &p) in self.positions.iter().enumerate() {
            if self.alive[v] {
                index[v] = vertices.len() as u32;
                vertices.push(p);
            }
        }
        let edges = curve
            .edges
            .iter()
            .filter(|e| self.alive[e[0] as usize])
            .map(|e| {
                let to = if self.free[e[0] as usize] {
                    self.next[e[0] as usize]
                } else {
                    e[1]
                };
                [index[e[0] as usize], index[to as usize]]
            })
            .collect();
        Polylines { vertices, edges }
    }
}

fn key(p: DVec2, cell: f64) -> [i64; 2] {
    let k = (p / cell).floor();
    [k.x as i64, k.y as i64]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_patch_sweeps_its_triangle() {
        let patch = Patch2 {
            before: [DVec2::ZERO, DVec2::new(1.0, 1.0), DVec2::new(2.0, 0.0)],
        };
        assert!(patch.sweeps(DVec2::new(1.0, 0.5)));
        assert!(!patch.sweeps(DVec2::new(1.0, -0.5)));
        assert!(!patch.sweeps(DVec2::new(1.0, 1.5)));
        assert!((patch.distance_after(DVec2::new(1.0, 1.0)) - 1.0).abs() < 1e-15);
        assert!(patch.distance_before(DVec2::new(1.0, 1.0)) < 1e-15);
    }
}
