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

/// Input vertices carried by the current faces, and the largest deviation so far.
///
/// A collapse reads a dozen faces in a part of the mesh the one before did not touch, so each
/// separate thing it reads there costs it a miss of the cache: what it reads of a face lies
/// together, and the points the faces carry lie in one array, each face's in one run, the runs
/// of one collapse's new faces side by side (written together). A collapse leaves its faces'
/// old runs behind; the array is compacted when they are most of it.
pub(crate) struct Deviation<'a> {
    input: Nearest<'a>,
    input_vertices: &'a [DVec3],
    tolerance_squared: f64,
    faces: Vec<FaceState>,
    vertices: Vec<VertexState>,
    /// The carried points' runs.
    carried: Vec<DVec3>,
    /// How many of `carried` are in a current face's run.
    live: usize,
    pub(crate) largest: f64,
}

/// What a current face carries and where its centroid is near.
#[derive(Clone, Copy)]
struct FaceState {
    /// Its run of carried points: `carried[start..start + len]`.
    start: u32,
    len: u32,
    /// An input face near its centroid: itself at first, then the one found when a collapse
    /// last moved it (a collapse moves a face's centroid by a third of its vertex's move, so
    /// the walk from there is short).
    centroid_foot: u32,
}

/// Where a current vertex is.
#[derive(Clone, Copy)]
struct VertexState {
    /// Whether it is still where the input vertex of its id is.
    unmoved: bool,
    /// An input face near it (`u32::MAX`: none known).
    foot: u32,
}

/// A collapse's hand-over: (input point, index into the change's `after`), and the largest
/// distance it measured.
#[derive(Default)]
pub(crate) struct HandOver {
    moves: Vec<(DVec3, usize)>,
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
            vertices: (0..mesh.n_vertices() as u32)
                .map(|v| VertexState {
                    unmoved: true,
                    foot: input.a_face_of(v),
                })
                .collect(),
            input,
            input_vertices: &mesh.vertices,
            tolerance_squared: tolerance * tolerance,
            faces: (0..mesh.n_faces() as u32)
                .map(|f| FaceState {
                    start: 0,
                    len: 0,
                    centroid_foot: f,
                })
                .collect(),
            carried: Vec::new(),
            live: 0,
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
        // Input to output, first (it searches no more than the new faces, and fails about as
        // often as the rest): what the changed faces carry (tried first on the face it was on,
        // when that face remains), and the two vertices if unmoved (on a face of theirs).
        let carried = change.before_ids.iter().flat_map(|&f| {
            let was = change.after_ids.iter().position(|&g| g == f);
            self.carried_by(f).iter().map(move |&p| (p, was))
        });
        let own = [a, b]
            .into_iter()
            .filter(|&v| self.vertices[v as usize].unmoved)
            .map(|v| (self.input_vertices[v as usize], Some(0)));
        let distance2 = |p: DVec3, k: usize| {
            let t = &change.after[k];
            p.distance_squared(closest_point_on_triangle(p, t[0], t[1], t[2]).0)
        };
        for (p, first) in carried.chain(own) {
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
            out.moves.push((p, best.1));
        }
        // Output to input: the new vertex (walked to from `a`'s face) and the new faces'
        // centroids (each from its face's centroid before).
        let Some((foot, d2)) =
            self.input
                .within(change.target, self.vertices[a as usize].foot, tol2)
        else {
            return false;
        };
        out.foot = foot;
        out.largest = out.largest.max(d2);
        for (t, &f) in change.after.iter().zip(&change.after_ids) {
            let from = self.faces[f as usize].centroid_foot;
            match self.input.within((t[0] + t[1] + t[2]) / 3.0, from, tol2) {
                Some((g, d2)) => {
                    out.largest = out.largest.max(d2);
                    out.centroid_feet.push(g);
                }
                None => return false,
            }
        }
        true
    }

    /// The input points face `f` carries.
    fn carried_by(&self, f: u32) -> &[DVec3] {
        let face = &self.faces[f as usize];
        &self.carried[face.start as usize..(face.start + face.len) as usize]
    }

    /// Records an accepted collapse of `b` into `a`.
    pub(crate) fn commit(&mut self, a: u32, b: u32, change: &Change, hand_over: &HandOver) {
        for &f in &change.before_ids {
            let face = &mut self.faces[f as usize];
            self.live -= face.len as usize;
            face.len = 0;
        }
        for (k, &f) in change.after_ids.iter().enumerate() {
            let start = self.carried.len();
            let run = hand_over.moves.iter().filter(|m| m.1 == k).map(|m| m.0);
            self.carried.extend(run);
            let face = &mut self.faces[f as usize];
            face.start = start as u32;
            face.len = (self.carried.len() - start) as u32;
        }
        self.live += hand_over.moves.len();
        self.vertices[a as usize] = VertexState {
            unmoved: false,
            foot: hand_over.foot,
        };
        self.vertices[b as usize].unmoved = false;
        for (&f, &g) in change.after_ids.iter().zip(&hand_over.centroid_feet) {
            self.faces[f as usize].centroid_foot = g;
        }
        self.largest = self.largest.max(hand_over.largest.sqrt());
        if self.carried.len() > 2 * self.live + 4096 {
            self.compact();
        }
    }

    /// Drops the runs no current face has, keeping the faces' runs in their order.
    fn compact(&mut self) {
        let mut carried = Vec::with_capacity(2 * self.live);
        for face in &mut self.faces {
            let run = &self.carried[face.start as usize..(face.start + face.len) as usize];
            face.start = carried.len() as u32;
            carried.extend_from_slice(run);
        }
        self.carried = carried;
    }
}
