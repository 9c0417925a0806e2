//! The mesh being simplified: positions, faces and each vertex's faces, edited one edge collapse
//! at a time, with the combinatorial test that keeps a closed manifold closed and manifold.

use rayon::prelude::*;
use rfta_geom::TriMesh;
use rfta_geom::glam::DVec3;

/// A triangle mesh open to edge collapses.
pub(crate) struct Editable {
    pub(crate) positions: Vec<DVec3>,
    pub(crate) faces: Vec<[u32; 3]>,
    face_alive: Vec<bool>,
    /// Each vertex's live faces, in no particular order.
    incident: Vec<Vec<u32>>,
    /// Vertices never moved nor removed: those on a boundary or non-manifold edge, or whose faces
    /// do not form one fan.
    locked: Vec<bool>,
    pub(crate) live_faces: usize,
}

/// What collapsing an edge would change: the faces before (with their ids) and the faces after
/// (the same ids less the two on the edge, with the collapsed vertex at its new place).
#[derive(Default)]
pub(crate) struct Change {
    /// Where the collapsed vertex goes.
    pub(crate) target: DVec3,
    pub(crate) before: Vec<[DVec3; 3]>,
    pub(crate) before_ids: Vec<u32>,
    pub(crate) after: Vec<[DVec3; 3]>,
    pub(crate) after_ids: Vec<u32>,
    /// For each face after, its index in `before`.
    pub(crate) was: Vec<usize>,
}

impl Editable {
    pub(crate) fn new(mesh: &TriMesh) -> Self {
        let n = mesh.n_vertices();
        let mut incident = vec![Vec::new(); n];
        for (f, face) in mesh.faces.iter().enumerate() {
            for &v in face {
                incident[v as usize].push(f as u32);
            }
        }
        let mut e = Self {
            positions: mesh.vertices.clone(),
            faces: mesh.faces.clone(),
            face_alive: mesh
                .faces
                .iter()
                .map(|f| f[0] != f[1] && f[1] != f[2] && f[2] != f[0])
                .collect(),
            incident,
            locked: vec![false; n],
            live_faces: 0,
        };
        e.live_faces = e.face_alive.iter().filter(|&&a| a).count();
        let face_alive = &e.face_alive;
        let trimmed: Vec<bool> = e
            .incident
            .par_iter_mut()
            .map(|faces| {
                let all = faces.len();
                faces.retain(|f| face_alive[*f as usize]);
                faces.len() != all
            })
            .collect();
        e.locked = (0..n)
            .into_par_iter()
            .map(|v| trimmed[v] || !e.is_one_fan(v as u32))
            .collect();
        e
    }

    /// Whether `v`'s faces form a single closed fan: the pairs `(x, y)` that follow `v` in its
    /// faces chain into one cycle through all of them.
    fn is_one_fan(&self, v: u32) -> bool {
        let pairs: Vec<(u32, u32)> = self.incident[v as usize]
            .iter()
            .map(|&f| self.after(f, v))
            .collect();
        if pairs.len() < 3 {
            return false;
        }
        let mut from: Vec<u32> = pairs.iter().map(|p| p.0).collect();
        from.sort_unstable();
        if from.windows(2).any(|w| w[0] == w[1]) {
            return false;
        }
        let next = |x: u32| pairs.iter().find(|p| p.0 == x).map(|p| p.1);
        let start = pairs[0].0;
        let mut at = start;
        for step in 1..=pairs.len() {
            match next(at) {
                Some(y) if y == start => return step == pairs.len(),
                Some(y) => at = y,
                None => return false,
            }
        }
        false
    }

    /// The two vertices that follow `v` in face `f`, in order.
    fn after(&self, f: u32, v: u32) -> (u32, u32) {
        let [a, b, c] = self.faces[f as usize];
        if a == v {
            (b, c)
        } else if b == v {
            (c, a)
        } else {
            (a, b)
        }
    }

    pub(crate) fn is_locked(&self, v: u32) -> bool {
        self.locked[v as usize]
    }

    pub(crate) fn faces_of(&self, v: u32) -> &[u32] {
        &self.incident[v as usize]
    }

    /// `v`'s neighbours, sorted, into `out`.
    pub(crate) fn neighbours(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        for &f in &self.incident[v as usize] {
            out.extend(self.faces[f as usize].iter().filter(|&&u| u != v));
        }
        out.sort_unstable();
        out.dedup();
    }

    /// Whether collapsing `a` and `b` into one vertex keeps a closed manifold of the same
    /// topology: both are free, exactly two faces share the edge, the vertices both neighbour are
    /// just those two faces' third vertices (the link condition of Dey, Edelsbrunner, Guha and
    /// Nekhayev, "Topology preserving edge contraction", 1999), and no vertex is left with fewer
    /// than three neighbours (which also keeps a tetrahedron from collapsing flat).
    pub(crate) fn can_collapse(&self, a: u32, b: u32, scratch: &mut [Vec<u32>; 2]) -> bool {
        if self.locked[a as usize] || self.locked[b as usize] {
            return false;
        }
        let mut shared = [u32::MAX; 2];
        let mut n_shared = 0;
        for &f in &self.incident[a as usize] {
            if self.faces[f as usize].contains(&b) {
                if n_shared == 2 {
                    return false;
                }
                shared[n_shared] = f;
                n_shared += 1;
            }
        }
        if n_shared != 2 {
            return false;
        }
        let third = |f: u32| {
            let face = self.faces[f as usize];
            face.into_iter().find(|&u| u != a && u != b).unwrap_or(a)
        };
        let (c, d) = (third(shared[0]), third(shared[1]));
        // Free vertices' faces form one closed fan: the vertex after `a` in each of its faces is
        // each of its neighbours once (no sorting out of repeats); `c` and `d` are among them.
        let [na, nb] = scratch;
        for (v, out) in [(a, &mut *na), (b, &mut *nb)] {
            out.clear();
            out.extend(
                self.incident[v as usize]
                    .iter()
                    .map(|&f| self.after(f, v).0),
            );
        }
        let common = na.iter().filter(|x| nb.contains(x)).count();
        if common != 2 || c == d {
            return false;
        }
        // The merged vertex has |na| + |nb| - 4 neighbours (a, b and the two shared ones go);
        // c and d lose one each.
        na.len() + nb.len() >= 7
            && self.incident[c as usize].len() > 3
            && self.incident[d as usize].len() > 3
    }

    /// The faces collapsing `b` into `a` at `target` changes, into `change`.
    pub(crate) fn change(&self, a: u32, b: u32, target: DVec3, change: &mut Change) {
        change.target = target;
        change.before.clear();
        change.before_ids.clear();
        change.after.clear();
        change.after_ids.clear();
        change.was.clear();
        let (ia, ib) = (&self.incident[a as usize], &self.incident[b as usize]);
        for &f in ia.iter().chain(ib.iter().filter(|f| !ia.contains(f))) {
            let face = self.faces[f as usize];
            let before = face.map(|v| self.positions[v as usize]);
            change.before.push(before);
            change.before_ids.push(f);
            if face.contains(&a) && face.contains(&b) {
                continue;
            }
            let mut after = before;
            for (k, &v) in face.iter().enumerate() {
                if v == a || v == b {
                    after[k] = target;
                }
            }
            change.after.push(after);
            change.after_ids.push(f);
            change.was.push(change.before.len() - 1);
        }
    }

    /// Collapses `b` into `a`, which moves to `target`.
    pub(crate) fn collapse(&mut self, a: u32, b: u32, target: DVec3) {
        let faces_b = std::mem::take(&mut self.incident[b as usize]);
        for f in faces_b {
            let face = &mut self.faces[f as usize];
            if face.contains(&a) {
                self.face_alive[f as usize] = false;
                self.live_faces -= 1;
                let face = *face;
                for v in face {
                    if v != b {
                        self.incident[v as usize].retain(|&g| g != f);
                    }
                }
            } else {
                for v in face.iter_mut() {
                    if *v == b {
                        *v = a;
                    }
                }
                self.incident[a as usize].push(f);
            }
        }
        self.positions[a as usize] = target;
    }

    /// The live faces and the vertices they use, both in their original order.
    pub(crate) fn into_mesh(self) -> TriMesh {
        let live = || {
            self.faces
                .iter()
                .zip(&self.face_alive)
                .filter(|(_, alive)| **alive)
                .map(|(f, _)| f)
        };
        let mut index = vec![u32::MAX; self.positions.len()];
        for f in live() {
            for &v in f {
                index[v as usize] = 0;
            }
        }
        let mut vertices = Vec::new();
        for (v, slot) in index.iter_mut().enumerate() {
            if *slot == 0 {
                *slot = vertices.len() as u32;
                vertices.push(self.positions[v]);
            }
        }
        let faces = live().map(|f| f.map(|v| index[v as usize])).collect();
        TriMesh { vertices, faces }
    }
}
