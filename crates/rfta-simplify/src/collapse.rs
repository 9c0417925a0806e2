//! The greedy loop: edges collapsed cheapest first by quadric error, each collapse tried against
//! the topology, the faces' shape, the tolerance and the caller's judge, in that order.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use rfta_geom::glam::DVec3;

use crate::deviation::{Deviation, HandOver};
use crate::editable::{Change, Editable};
use crate::quadric::Quadric;
use crate::{Judge, Patch};

/// A new face may turn by at most this angle's cosine from the face it replaces (60 degrees).
const MIN_TURN_COS: f64 = 0.5;

/// A new face may be no thinner than this quality (`4 sqrt(3) area / sum of squared edges`, 1
/// for an equilateral triangle), or than the thinnest face it replaces when that is thinner.
const MIN_QUALITY: f64 = 0.1;

/// An edge in the queue: its collapse's error and target, and the vertices' edit counts when it
/// was priced (a stale entry is skipped).
struct Entry {
    cost: f64,
    keep: u32,
    drop: u32,
    stamps: [u32; 2],
    target: DVec3,
}

impl Ord for Entry {
    /// Cheapest first (the heap is a max-heap), ties by vertex ids: the order is total and does
    /// not depend on the heap's history.
    fn cmp(&self, o: &Self) -> Ordering {
        o.cost
            .total_cmp(&self.cost)
            .then_with(|| o.keep.cmp(&self.keep))
            .then_with(|| o.drop.cmp(&self.drop))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}

impl Eq for Entry {}

/// Collapses edges while the mesh has more than `max_faces` faces and some collapse passes;
/// returns the number made.
pub(crate) fn run(
    mesh: &mut Editable,
    deviation: &mut Deviation,
    max_faces: usize,
    judge: &mut dyn Judge,
) -> usize {
    let mut queue = Queue::new(mesh);
    let mut change = Change::default();
    let mut hand_over = HandOver::default();
    let mut scratch = [Vec::new(), Vec::new()];
    let mut collapses = 0;
    while mesh.live_faces > max_faces {
        let Some(e) = queue.heap.pop() else { break };
        let (a, b) = (e.keep, e.drop);
        if !mesh.is_alive(a)
            || !mesh.is_alive(b)
            || e.stamps != [queue.stamps[a as usize], queue.stamps[b as usize]]
            || !mesh.can_collapse(a, b, &mut scratch)
        {
            continue;
        }
        mesh.change(a, b, e.target, &mut change);
        if !keeps_shape(&change)
            || !deviation.allows(a, b, &change, &mut hand_over)
            || !judge.allows(&Patch {
                before: &change.before,
                after: &change.after,
            })
        {
            continue;
        }
        deviation.commit(a, b, &change, &hand_over);
        mesh.collapse(a, b, e.target);
        collapses += 1;
        queue.quadrics[a as usize] = queue.quadrics[a as usize].add(&queue.quadrics[b as usize]);
        queue.stamps[a as usize] += 1;
        queue.stamps[b as usize] += 1;
        mesh.neighbours(a, &mut scratch[0]);
        for &n in &scratch[0] {
            queue.push(mesh, a, n);
        }
    }
    collapses
}

/// The priority queue of edges and what prices them.
struct Queue {
    heap: BinaryHeap<Entry>,
    quadrics: Vec<Quadric>,
    stamps: Vec<u32>,
}

impl Queue {
    /// Each vertex's quadric is the planes of its faces, weighted by their areas; every edge
    /// between two free vertices is priced.
    fn new(mesh: &Editable) -> Self {
        let n = mesh.positions.len();
        let mut quadrics = vec![Quadric::default(); n];
        for v in 0..n as u32 {
            for &f in mesh.faces_of(v) {
                let [p, q, r] = mesh.faces[f as usize].map(|u| mesh.positions[u as usize]);
                let scaled = (q - p).cross(r - p);
                let area2 = scaled.length();
                if area2 > 0.0 {
                    let plane = Quadric::plane(p, scaled / area2, 0.5 * area2);
                    quadrics[v as usize] = quadrics[v as usize].add(&plane);
                }
            }
        }
        let mut queue = Self {
            heap: BinaryHeap::new(),
            quadrics,
            stamps: vec![0; n],
        };
        let mut around = Vec::new();
        for v in 0..n as u32 {
            if mesh.is_locked(v) {
                continue;
            }
            mesh.neighbours(v, &mut around);
            for &u in around.iter().filter(|&&u| u > v) {
                queue.push(mesh, v, u);
            }
        }
        queue
    }

    /// Prices the edge `u`-`v` (kept: the lower id) and queues it, unless either end is locked.
    fn push(&mut self, mesh: &Editable, u: u32, v: u32) {
        let (keep, drop) = (u.min(v), u.max(v));
        if mesh.is_locked(keep) || mesh.is_locked(drop) {
            return;
        }
        let q = self.quadrics[keep as usize].add(&self.quadrics[drop as usize]);
        let (pk, pd) = (
            mesh.positions[keep as usize],
            mesh.positions[drop as usize],
        );
        let mid = 0.5 * (pk + pd);
        // The minimizer, unless it lies farther from the edge's midpoint than the edge is long
        // (a nearly singular quadric's far-off point); else the best of the ends and the midpoint.
        let target = q
            .minimizer(mid)
            .filter(|x| x.distance_squared(mid) <= pk.distance_squared(pd))
            .unwrap_or_else(|| {
                [mid, pk, pd]
                    .into_iter()
                    .min_by(|x, y| q.error(*x).total_cmp(&q.error(*y)))
                    .unwrap_or(mid)
            });
        self.heap.push(Entry {
            cost: q.error(target),
            keep,
            drop,
            stamps: [self.stamps[keep as usize], self.stamps[drop as usize]],
            target,
        });
    }
}

/// Whether every new face keeps its old face's orientation (turns by at most 60 degrees), has
/// an area, and is not much thinner than before.
fn keeps_shape(change: &Change) -> bool {
    let worst_before = change
        .before
        .iter()
        .map(quality)
        .fold(f64::INFINITY, f64::min);
    let floor = MIN_QUALITY.min(worst_before);
    change.after.iter().zip(&change.was).all(|(t, &k)| {
        let o = &change.before[k];
        let n_new = (t[1] - t[0]).cross(t[2] - t[0]);
        let n_old = (o[1] - o[0]).cross(o[2] - o[0]);
        let lengths = n_new.length() * n_old.length();
        lengths > 0.0 && n_new.dot(n_old) >= MIN_TURN_COS * lengths && quality(t) >= floor
    })
}

/// `4 sqrt(3) area / (sum of squared edge lengths)`: 1 for an equilateral triangle, 0 for a flat
/// one.
fn quality(t: &[DVec3; 3]) -> f64 {
    let twice_area = (t[1] - t[0]).cross(t[2] - t[0]).length();
    let edges = t[0].distance_squared(t[1]) + t[1].distance_squared(t[2]) + t[2].distance_squared(t[0]);
    if edges > 0.0 {
        2.0 * 3f64.sqrt() * twice_area / edges
    } else {
        0.0
    }
}
