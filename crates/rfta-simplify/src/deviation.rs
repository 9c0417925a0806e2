//! How far the simplified surface is from the input, both ways, kept within the tolerance.
//!
//! Input to output: every input vertex a collapse moves or removes is handed to a face of the
//! collapse's new faces within the tolerance of it (the one it lay on when that face remains,
//! else the nearest) and must have one; later collapses of that face hand it on (the bookkeeping
//! of Hausdorff-bounded simplifiers since Klein, Liebich and Strasser, "Mesh reduction with error
//! control", 1996). Output to input: each collapse's new vertex and its new faces' centroids
//! must lie within the tolerance of the input surface (`nearest.rs` finds how near). The largest
//! distance either way is kept.

use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;
use rfta_geom::kernels::closest_point_on_triangle;
use rfta_mesh::MeshIndex;

use crate::editable::Change;
use crate::nearest::Nearest;

/// Input vertex ids carried by the current faces, and the largest deviation so far.
pub(crate) struct Deviation<'a> {
    input: Nearest<'a>,
    input_vertices: &'a [DVec3],
    tolerance_squared: f64,
    /// For each current vertex, the input vertex at whose place it still is (`u32::MAX`: moved).
    unmoved: Vec<u32>,
    /// For each current vertex, an input face near it (`u32::MAX`: none known).
    foot: Vec<u32>,
    /// For each face, an input face near its centroid: itself at first, then the one found when
    /// a collapse last moved it (a collapse moves a face's centroid by a third of its vertex's
    /// move, so the walk from there is short).
    centroid_foot: Vec<u32>,
    /// For each face, the input vertices it carries.
    carried: Vec<Vec<u32>>,
    pub(crate) largest: f64,
}

/// A collapse's hand-over: (input vertex, index into the change's `after`), and the largest
/// distance it measured.
#[derive(Default)]
pub(crate) struct HandOver {
    moves: Vec<(u32, usize)>,
    largest: f64,
    /// The input face nearest the new vertex.
    foot: u32,
    /// The input face nearest each new face's centroid.
    centroid_feet: Vec<u32>,
}

impl<'a> Deviation<'a> {
    /// The bookkeeping of `mesh`, whose index is `input`.
    pub(crate) fn new(mesh: &'a TriMesh, input: &'a MeshIndex, tolerance: f64) -> Self {
        let input = Nearest::new(mesh, input);
        Self {
            foot: (0..mesh.n_vertices() as u32)
                .map(|v| input.a_face_of(v))
                .collect(),
            input,
            input_vertices: &mesh.vertices,
            tolerance_squared: tolerance * tolerance,
            unmoved: (0..mesh.n_vertices() as u32).collect(),
            centroid_foot: (0..mesh.n_faces() as u32).collect(),
            carried: vec![Vec::new(); mesh.n_faces()],
            largest: 0.0,
        }
    }

    /// Whether collapsing `b` into `a` as `change` says stays within the tolerance both ways;
    /// the hand-over into `out` when it does.
    pub(crate) fn allows(&self, a: u32, b: u32, change: &Change, out: &mut HandOver) -> bool {
        out.moves.clear();
        out.centroid_feet.clear();
        out.largest = 0.0;
        let tol2 = self.tolerance_squared;
        // Output to input: the new vertex (walked to from `a`'s face) and the new faces'
        // centroids (each from its face's centroid before).
        let Some((foot, d2)) = self
            .input
            .within(change.target, self.foot[a as usize], tol2)
        else {
            return false;
        };
        out.foot = foot;
        out.largest = d2;
        for (t, &f) in change.after.iter().zip(&change.after_ids) {
            let from = self.centroid_foot[f as usize];
            match self.input.within((t[0] + t[1] + t[2]) / 3.0, from, tol2) {
                Some((g, d2)) => {
                    out.largest = out.largest.max(d2);
                    out.centroid_feet.push(g);
                }
                None => return false,
            }
        }
        // Input to output: what the changed faces carry (tried first on the face it was on,
        // when that face remains), and the two vertices if unmoved (on a face of theirs).
        let carried = change.before_ids.iter().flat_map(|&f| {
            let was = change.after_ids.iter().position(|&g| g == f);
            self.carried[f as usize].iter().map(move |&i| (i, was))
        });
        let own = [a, b]
            .into_iter()
            .map(|v| self.unmoved[v as usize])
            .filter(|&i| i != u32::MAX)
            .map(|i| (i, Some(0)));
        let distance2 = |p: DVec3, k: usize| {
            let t = &change.after[k];
            p.distance_squared(closest_point_on_triangle(p, t[0], t[1], t[2]).0)
        };
        for (i, first) in carried.chain(own) {
            let p = self.input_vertices[i as usize];
            let on_first = first
                .filter(|&k| k < change.after.len())
                .map(|k| (distance2(p, k), k))
                .filter(|&(d2, _)| d2 <= tol2);
            let best = on_first.unwrap_or_else(|| {
                (0..change.after.len())
                    .map(|k| (distance2(p, k), k))
                    .fold((f64::INFINITY, 0), |b, c| if c.0 < b.0 { c } else { b })
            });
            if best.0 > tol2 {
                return false;
            }
            out.largest = out.largest.max(best.0);
            out.moves.push((i, best.1));
        }
        true
    }

    /// Records an accepted collapse of `b` into `a`.
    pub(crate) fn commit(&mut self, a: u32, b: u32, change: &Change, hand_over: &HandOver) {
        for &f in &change.before_ids {
            self.carried[f as usize].clear();
        }
        for &(i, k) in &hand_over.moves {
            self.carried[change.after_ids[k] as usize].push(i);
        }
        self.unmoved[a as usize] = u32::MAX;
        self.unmoved[b as usize] = u32::MAX;
        self.foot[a as usize] = hand_over.foot;
        for (&f, &g) in change.after_ids.iter().zip(&hand_over.centroid_feet) {
            self.centroid_foot[f as usize] = g;
        }
        self.largest = self.largest.max(hand_over.largest.sqrt());
    }
}
