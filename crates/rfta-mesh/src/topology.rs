//! Combinatorial checks of a triangle mesh: boundary and non-manifold edges, non-manifold
//! vertices, orientation, connected components, Euler characteristic and genus.

use rayon::prelude::*;
use rfta_geom::TriMesh;

use crate::UnionFind;

/// Combinatorial facts about a triangle mesh.
///
/// Only vertices that some face uses count (an unused vertex would change the Euler
/// characteristic without changing the surface).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Topology {
    /// Vertices used by at least one face.
    pub n_vertices: usize,
    /// Distinct undirected edges.
    pub n_edges: usize,
    /// Faces.
    pub n_faces: usize,
    /// Faces with a repeated vertex index (zero area by construction).
    pub degenerate_faces: usize,
    /// Edges with exactly one incident face.
    pub boundary_edges: usize,
    /// Edges with more than two incident faces.
    pub nonmanifold_edges: usize,
    /// Vertices whose incident faces form more than one fan (a "bow tie").
    pub nonmanifold_vertices: usize,
    /// Interior edges whose two faces traverse it in the same direction (inconsistent orientation).
    pub misoriented_edges: usize,
    /// Connected components (faces sharing a vertex are connected).
    pub components: usize,
}

impl Topology {
    /// Analyses `mesh`.
    ///
    /// The faces' directed edges are sorted by their undirected edge, so that each edge's uses
    /// are a run: its count, the direction balance and the first two faces (in face order) come
    /// from the run. Corners joined across an edge form the fans around each vertex; faces
    /// sharing a vertex form the components.
    pub fn of(mesh: &TriMesh) -> Self {
        let n_faces = mesh.n_faces();
        let n_all = mesh.n_vertices();
        let mut used = vec![false; n_all];
        let mut degenerate_faces = 0;
        for f in &mesh.faces {
            for &v in f {
                if let Some(u) = used.get_mut(v as usize) {
                    *u = true;
                }
            }
            if f[0] == f[1] || f[1] == f[2] || f[2] == f[0] {
                degenerate_faces += 1;
            }
        }
        let n_vertices = used.iter().filter(|&&u| u).count();
        // (undirected edge, corner of its first vertex): sorted, each edge's uses follow in
        // face order.
        let mut uses: Vec<(u64, u32)> = mesh
            .faces
            .par_iter()
            .enumerate()
            .flat_map_iter(|(fi, f)| {
                (0..3).filter_map(move |k| {
                    let (a, b) = (f[k], f[(k + 1) % 3]);
                    let key = u64::from(a.min(b)) << 32 | u64::from(a.max(b));
                    (a != b).then_some((key, (fi * 3 + k) as u32))
                })
            })
            .collect();
        uses.par_sort_unstable();
        let mut n_edges = 0;
        let mut boundary_edges = 0;
        let mut nonmanifold_edges = 0;
        let mut misoriented_edges = 0;
        // Union-find over corners (face, slot) to count fans per vertex, and over faces for
        // components.
        let mut corners = UnionFind::new(n_faces * 3);
        let comps = UnionFind::new(n_faces);
        let slot = |face: usize, v: u32| -> usize {
            let f = mesh.faces[face];
            face * 3 + f.iter().position(|&x| x == v).unwrap_or(0)
        };
        for run in uses.chunk_by(|x, y| x.0 == y.0) {
            n_edges += 1;
            match run {
                [_] => boundary_edges += 1,
                [(key, c1), (_, c2)] => {
                    let (a, b) = ((key >> 32) as u32, *key as u32);
                    let (f1, f2) = (*c1 as usize / 3, *c2 as usize / 3);
                    // Whether each use goes from `a` to `b`.
                    let forward = |c: u32| mesh.faces[c as usize / 3][c as usize % 3] == a;
                    if forward(*c1) == forward(*c2) {
                        misoriented_edges += 1;
                    }
                    corners.union(slot(f1, a), slot(f2, a));
                    corners.union(slot(f1, b), slot(f2, b));
                }
                _ => nonmanifold_edges += 1,
            }
        }
        let components = components(mesh, comps);
        // A vertex is non-manifold if its corners form more than one fan.
        let mut fans_per_vertex = vec![0u32; n_all];
        for (fi, f) in mesh.faces.iter().enumerate() {
            for (k, &v) in f.iter().enumerate() {
                let c = fi * 3 + k;
                // Count each fan once, at its root corner (duplicated vertices in a face counted
                // once).
                if corners.find(c) == c
                    && f.iter().position(|&x| x == v) == Some(k)
                    && let Some(n) = fans_per_vertex.get_mut(v as usize)
                {
                    *n += 1;
                }
            }
        }
        let nonmanifold_vertices = fans_per_vertex.iter().filter(|&&n| n > 1).count();
        Self {
            n_vertices,
            n_edges,
            n_faces,
            degenerate_faces,
            boundary_edges,
            nonmanifold_edges,
            nonmanifold_vertices,
            misoriented_edges,
            components,
        }
    }

    /// `V - E + F`.
    pub fn euler_characteristic(&self) -> i64 {
        self.n_vertices as i64 - self.n_edges as i64 + self.n_faces as i64
    }

    /// Every edge has exactly two faces (closed surface, no boundary and no fins).
    pub fn is_watertight(&self) -> bool {
        self.n_faces > 0 && self.boundary_edges == 0 && self.nonmanifold_edges == 0
    }

    /// Edge- and vertex-manifold (boundary edges allowed).
    pub fn is_manifold(&self) -> bool {
        self.nonmanifold_edges == 0 && self.nonmanifold_vertices == 0
    }

    /// Neighbouring faces agree on orientation across every interior edge.
    pub fn is_consistently_oriented(&self) -> bool {
        self.misoriented_edges == 0
    }

    /// Total genus of a closed, manifold, orientable surface: `(2 c - chi) / 2` summed over its
    /// `c` components; `None` when the mesh is not watertight and manifold (genus is undefined).
    pub fn genus(&self) -> Option<i64> {
        if !(self.is_watertight() && self.is_manifold()) {
            return None;
        }
        let twice = 2 * self.components as i64 - self.euler_characteristic();
        (twice % 2 == 0).then_some(twice / 2)
    }
}

/// The components of `mesh`: `comps` (over faces) joined where faces share a vertex.
fn components(mesh: &TriMesh, mut comps: UnionFind) -> usize {
    let mut first_face_of_vertex = vec![u32::MAX; mesh.n_vertices()];
    for (fi, f) in mesh.faces.iter().enumerate() {
        for &v in f {
            let Some(slot) = first_face_of_vertex.get_mut(v as usize) else {
                continue;
            };
            if *slot == u32::MAX {
                *slot = fi as u32;
            } else {
                comps.union(*slot as usize, fi);
            }
        }
    }
    (0..mesh.n_faces()).filter(|&f| comps.find(f) == f).count()
}
