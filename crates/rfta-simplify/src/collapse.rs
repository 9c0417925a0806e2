//! The greedy loop: edges collapsed cheapest first by quadric error (to the grain of the bucket
//! queue, `buckets.rs`), each collapse tried against the topology, the faces' shape, the
//! tolerance and the caller's judge, in that order.

use rayon::prelude::*;
use rfta_geom::glam::DVec3;

use crate::buckets::Buckets;
use crate::deviation::{Deviation, HandOver};
use crate::editable::{Change, Editable};
use crate::quadric::Quadric;
use crate::{Judge, Patch};

/// A new face may turn by at most this angle's cosine from the face it replaces (60 degrees).
const MIN_TURN_COS: f64 = 0.5;

/// A new face may be no thinner than this quality (`4 sqrt(3) area / sum of squared edges`, 1
/// for an equilateral triangle), or than the thinnest face it replaces when that is thinner.
const MIN_QUALITY: f64 = 0.1;

/// An edge is not queued when its collapse would leave the new vertex farther from the planes
/// of the faces it merges than this many tolerances (as the quadric's weighted root mean square
/// distance): such a collapse almost always fails the tolerance test, whose points lie on those
/// faces, and trying it costs what a collapse that passes does. On the 129^3 bunny, of the
/// 26,189 collapses tried beyond two tolerances 25 passed; of the 117,610 within one, 92%
/// (docs/speed.md).
const HOPELESS: f64 = 2.0;

/// An edge in the queue: its vertices and their edit counts when it was priced (a stale entry
/// is skipped). The target is priced again when the edge is taken: a small entry keeps the
/// queue, which holds several stale entries per edge, in cache.
struct Entry {
    keep: u32,
    drop: u32,
    stamps: [u32; 2],
}

impl Entry {
    /// Whether neither end was collapsed since the edge was priced, by the vertices' edit
    /// counts `stamps` (a removed vertex's count moved on when it was removed, so an edge of it
    /// is not current either).
    fn is_current(&self, stamps: &[u32]) -> bool {
        self.stamps == [stamps[self.keep as usize], stamps[self.drop as usize]]
    }
}

/// Collapses edges while the mesh has more than `max_faces` faces and some collapse passes;
/// returns the number made.
///
/// The cheapest edges are taken in batches of up to `BATCH` whose changes touch no common
/// vertex (an edge whose change meets one taken waits for the next batch); a batch is tried in
/// parallel (every test only reads the mesh) and the collapses that pass are made in the order
/// they were taken. Which edges make a batch depends only on the queue, so the output does not
/// depend on the number of threads.
pub(crate) fn run(
    mesh: &mut Editable,
    deviation: &mut Deviation<'_>,
    tolerance: f64,
    max_faces: usize,
    judge: &dyn Judge,
) -> usize {
    let mut queue = Queue::new(mesh, tolerance);
    let mut taken_by = vec![u32::MAX; mesh.positions.len()];
    let mut around = Vec::new();
    let mut tries: Vec<Try> = (0..BATCH).map(|_| Try::default()).collect();
    let mut collapses = 0;
    let mut round = 0u32;
    while mesh.live_faces > max_faces {
        let batch = queue.take(mesh, &mut taken_by, round, &mut around);
        round += 1;
        if batch.is_empty() {
            break;
        }
        tries[..batch.len()]
            .par_iter_mut()
            .zip(&batch)
            .for_each(|(t, e)| t.run(mesh, deviation, judge, &queue, e));
        for (e, t) in batch.iter().zip(&tries) {
            if !t.passed {
                continue;
            }
            if mesh.live_faces <= max_faces {
                break;
            }
            let (a, b) = (e.keep, e.drop);
            deviation.commit(a, b, &t.change, &t.hand_over);
            mesh.collapse(a, b, t.change.target);
            collapses += 1;
            let q = queue.quadrics[a as usize].add(&queue.quadrics[b as usize]);
            queue.quadrics[a as usize] = q;
            queue.stamps[a as usize] += 1;
            queue.stamps[b as usize] += 1;
            queue.push_priced(a, &t.edges);
        }
        queue.drop_stale(mesh);
    }
    collapses
}

/// Edges taken together: no two changes share a vertex.
const BATCH: usize = 64;

/// One collapse tried: its change and hand-over when it passed, and the prices of the edges its
/// vertex will have. A batch's tries are kept from one batch to the next, so their lists are
/// allocated once.
#[derive(Default)]
struct Try {
    passed: bool,
    change: Change,
    hand_over: HandOver,
    neighbours: [Vec<u32>; 2],
    /// The kept vertex's neighbours after the collapse, in order, each with the price of its edge
    /// to it (error, weight); `None` for a locked one.
    edges: Vec<(u32, Option<(f64, f64)>)>,
    around: Vec<u32>,
}

impl Try {
    /// Tries collapsing `e` with its vertex where `queue` prices it: the topology, the faces'
    /// shape, the tolerance and the judge, in that order.
    fn run(
        &mut self,
        mesh: &Editable,
        deviation: &Deviation<'_>,
        judge: &dyn Judge,
        queue: &Queue,
        e: &Entry,
    ) {
        let (a, b) = (e.keep, e.drop);
        self.passed = mesh.can_collapse(a, b, &mut self.neighbours) && {
            let target = queue.price(mesh, a, b).1;
            mesh.change(a, b, target, &mut self.change);
            keeps_shape(&self.change)
                && deviation.allows(a, b, &self.change, &mut self.hand_over)
                && judge.allows(&Patch {
                    before: &self.change.before,
                    after: &self.change.after,
                })
        };
        if self.passed {
            self.price_edges(mesh, queue, a, b);
        }
    }

    /// The edges of `a` once `b` has collapsed into it at the change's target, priced: its
    /// neighbours are both ends' but themselves (the link condition held), whose positions and
    /// quadrics no other collapse of the batch changes (their changes share no vertex), so these
    /// are the prices the edges have right after the collapse.
    fn price_edges(&mut self, mesh: &Editable, queue: &Queue, a: u32, b: u32) {
        let [na, nb] = &self.neighbours;
        let q = queue.quadrics[a as usize].add(&queue.quadrics[b as usize]);
        let target = self.change.target;
        let around = &mut self.around;
        around.clear();
        around.extend(na.iter().chain(nb).filter(|&&n| n != a && n != b));
        around.sort_unstable();
        around.dedup();
        self.edges.clear();
        self.edges.extend(around.iter().map(|&n| {
            // `a` is free (the collapse passed).
            let price = (!mesh.is_locked(n)).then(|| {
                let qn = &queue.quadrics[n as usize];
                let pn = mesh.positions[n as usize];
                let ((cost, weight), _) = if a < n {
                    price_of(&q.add(qn), target, pn)
                } else {
                    price_of(&qn.add(&q), pn, target)
                };
                (cost, weight)
            });
            (n, price)
        }));
    }
}

/// The priority queue of edges and what prices them.
struct Queue {
    queue: Buckets<Entry>,
    /// Edges passed over by the last batch for meeting it, cheapest first.
    waiting: Vec<Entry>,
    quadrics: Vec<Quadric>,
    stamps: Vec<u32>,
    /// The error per unit weight beyond which an edge is not queued ([`HOPELESS`]).
    hopeless: f64,
}

impl Queue {
    /// Up to `BATCH` current edges, cheapest first, whose changes (the vertices of both ends'
    /// faces) share no vertex, marking those vertices with `round` in `taken_by`. The edges
    /// passed over for meeting one wait (at most `BATCH`: then the batch is closed) and are the
    /// first looked at next time, before the queue.
    fn take(
        &mut self,
        mesh: &Editable,
        taken_by: &mut [u32],
        round: u32,
        around: &mut Vec<u32>,
    ) -> Vec<Entry> {
        let mut batch = Vec::new();
        let mut waited = std::mem::take(&mut self.waiting).into_iter();
        while batch.len() < BATCH {
            let Some(e) = waited.next().or_else(|| self.queue.pop()) else {
                break;
            };
            let (a, b) = (e.keep, e.drop);
            if !e.is_current(&self.stamps) {
                continue;
            }
            around.clear();
            for v in [a, b] {
                for &f in mesh.faces_of(v) {
                    around.extend(mesh.faces[f as usize]);
                }
            }
            if around.iter().any(|&v| taken_by[v as usize] == round) {
                self.waiting.push(e);
                if self.waiting.len() == BATCH {
                    break;
                }
                continue;
            }
            for &v in around.iter() {
                taken_by[v as usize] = round;
            }
            batch.push(e);
        }
        // What waited and was not looked at goes back to the queue.
        for e in waited {
            let cost = self.price(mesh, e.keep, e.drop).0.0;
            self.queue.push(cost, e);
        }
        batch
    }

    /// Each vertex's quadric is the planes of its faces, weighted by their areas; every edge
    /// between two free vertices is priced, those within [`HOPELESS`] `tolerance`s queued.
    fn new(mesh: &Editable, tolerance: f64) -> Self {
        let n = mesh.positions.len();
        let quadrics = (0..n as u32)
            .into_par_iter()
            .map(|v| {
                let mut quadric = Quadric::default();
                for &f in mesh.faces_of(v) {
                    let [p, q, r] = mesh.faces[f as usize].map(|u| mesh.positions[u as usize]);
                    let scaled = (q - p).cross(r - p);
                    let area2 = scaled.length();
                    if area2 > 0.0 {
                        let plane = Quadric::plane(p, scaled / area2, 0.5 * area2);
                        quadric = quadric.add(&plane);
                    }
                }
                quadric
            })
            .collect();
        let mut queue = Self {
            queue: Buckets::new(),
            waiting: Vec::new(),
            quadrics,
            stamps: vec![0; n],
            hopeless: (HOPELESS * tolerance).powi(2),
        };
        let edges: Vec<(u32, u32)> = (0..n as u32)
            .into_par_iter()
            .filter(|&v| !mesh.is_locked(v))
            .flat_map_iter(|v| {
                let mut around = Vec::new();
                mesh.neighbours(v, &mut around);
                around
                    .into_iter()
                    .filter(move |&u| u > v)
                    .map(move |u| (v, u))
            })
            .collect();
        queue.push_all(mesh, &edges);
        queue
    }

    /// Prices the edges `u`-`v` (kept: the lower id), in parallel, and queues them in their
    /// order, but those with a locked end and the hopeless ones.
    fn push_all(&mut self, mesh: &Editable, edges: &[(u32, u32)]) {
        let priced: Vec<Option<(f64, Entry)>> = edges
            .par_iter()
            .map(|&(u, v)| {
                let (keep, drop) = (u.min(v), u.max(v));
                if mesh.is_locked(keep) || mesh.is_locked(drop) {
                    return None;
                }
                let entry = Entry {
                    keep,
                    drop,
                    stamps: [self.stamps[keep as usize], self.stamps[drop as usize]],
                };
                let (cost, weight) = self.price(mesh, keep, drop).0;
                self.worth_trying(cost, weight).then_some((cost, entry))
            })
            .collect();
        for (cost, entry) in priced.into_iter().flatten() {
            self.queue.push(cost, entry);
        }
    }

    /// Queues the edges of `a` a collapse into it priced ([`Try::price_edges`]), but the locked
    /// and the hopeless ones.
    fn push_priced(&mut self, a: u32, edges: &[(u32, Option<(f64, f64)>)]) {
        for &(n, price) in edges {
            let Some((cost, weight)) = price else {
                continue;
            };
            if self.worth_trying(cost, weight) {
                let (keep, drop) = (a.min(n), a.max(n));
                let stamps = [self.stamps[keep as usize], self.stamps[drop as usize]];
                self.queue.push(cost, Entry { keep, drop, stamps });
            }
        }
    }

    /// Whether a collapse of this error and quadric weight is not hopeless ([`HOPELESS`]).
    fn worth_trying(&self, cost: f64, weight: f64) -> bool {
        cost <= self.hopeless * weight
    }

    /// Drops the stale entries once they are most of the queue (three for each live edge).
    fn drop_stale(&mut self, mesh: &Editable) {
        let live_edges = 3 * mesh.live_faces / 2;
        if self.queue.len() > 4 * live_edges {
            let stamps = &self.stamps;
            self.queue.retain(|e| e.is_current(stamps));
        }
    }

    /// The error of collapsing `keep` and `drop` with its quadric's weight, and where the vertex
    /// goes.
    fn price(&self, mesh: &Editable, keep: u32, drop: u32) -> ((f64, f64), DVec3) {
        let q = self.quadrics[keep as usize].add(&self.quadrics[drop as usize]);
        price_of(
            &q,
            mesh.positions[keep as usize],
            mesh.positions[drop as usize],
        )
    }
}

/// The error of collapsing the edge from `pk` (the kept end) to `pd` whose ends' quadrics sum to
/// `q`, with `q`'s weight, and where the vertex goes.
fn price_of(q: &Quadric, pk: DVec3, pd: DVec3) -> ((f64, f64), DVec3) {
    let mid = 0.5 * (pk + pd);
    // The minimizer, unless it lies farther from the edge's midpoint than the edge is long (a
    // nearly singular quadric's far-off point); else the best of the ends and the midpoint.
    let target = q
        .minimizer(mid)
        .filter(|x| x.distance_squared(mid) <= pk.distance_squared(pd))
        .unwrap_or_else(|| {
            [mid, pk, pd]
                .into_iter()
                .min_by(|x, y| q.error(*x).total_cmp(&q.error(*y)))
                .unwrap_or(mid)
        });
    ((q.error(target), q.weight()), target)
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
    let edges =
        t[0].distance_squared(t[1]) + t[1].distance_squared(t[2]) + t[2].distance_squared(t[0]);
    if edges > 0.0 {
        2.0 * 3f64.sqrt() * twice_area / edges
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::shapes;

    /// A cube's every edge joins two corners a side apart: within a side's tenth every collapse
    /// is hopeless, within ten sides none is.
    #[test]
    fn only_hopeless_edges_are_left_out_of_the_queue() {
        let cube = shapes::cuboid(DVec3::splat(0.5));
        let mesh = Editable::new(&cube);
        let edges = 3 * cube.n_faces() / 2;
        assert_eq!(Queue::new(&mesh, 0.1).queue.len(), 0);
        assert_eq!(Queue::new(&mesh, 10.0).queue.len(), edges);
        // A fine ball's edges are short against the tolerance: none is hopeless.
        let ball = shapes::icosphere(1.0, 4);
        let mesh = Editable::new(&ball);
        assert_eq!(Queue::new(&mesh, 0.01).queue.len(), 3 * ball.n_faces() / 2);
    }
}
