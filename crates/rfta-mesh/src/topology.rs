//! Combinatorial checks of a triangle mesh: boundary and non-manifold edges, non-manifold
//! vertices, orientation, connected components, Euler characteristic and genus.

use std::collections::HashMap;

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
    pub fn of(mesh: &TriMesh) -> Self {
        let n_faces = mesh.n_faces();
        let mut used = vec![false; mesh.n_vertices()];
        let mut degenerate_faces = 0;
        // Undirected edge -> (count, faces seen (first two), direction of first, direction balance).
        let mut edges: HashMap<(u32, u32), EdgeUse> = HashMap::with_capacity(n_faces * 3 / 2 + 1);
        for (fi, f) in mesh.faces.iter().enumerate() {
            for &v in f {
                if let Some(u) = used.get_mut(v as usize) {
                    *u = true;
                }
            }
            if f[0] == f[1] || f[1] == f[2] || f[2] == f[0] {
                degenerate_faces += 1;
            }
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                if a == b {
                    continue;
                }
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                e.count += 1;
                e.forward += i32::from(a < b);
                if e.faces.len() < 2 {
                    e.faces.push(fi as u32);
                }
            }
        }
        let n_vertices = used.iter().filter(|&&u| u).count();
        let mut boundary_edges = 0;
        let mut nonmanifold_edges = 0;
        let mut misoriented_edges = 0;
        // Union-find over corners (face, slot) to count fans per vertex, and over faces for components.
        let mut corners = UnionFind::new(n_faces * 3);
        let mut comps = UnionFind::new(n_faces);
        let slot = |face: u32, v: u32| -> usize {
            let f = mesh.faces[face as usize];
            face as usize * 3 + f.iter().position(|&x| x == v).unwrap_or(0)
        };
        for (&(a, b), e) in &edges {
            match e.count {
                1 => boundary_edges += 1,
                2 => {
                    if e.forward != 1 {
                        misoriented_edges += 1;
                    }
                    let (f1, f2) = (e.faces[0], e.faces[1]);
                    corners.union(slot(f1, a), slot(f2, a));
                    corners.union(slot(f1, b), slot(f2, b));
                }
                _ => nonmanifold_edges += 1,
            }
        }
        // Faces sharing a vertex are in one component.
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
        let components = (0..n_faces).filter(|&f| comps.find(f) == f).count();
        // A vertex is non-manifold if its corners form more than one fan.
        let mut fans_per_vertex: HashMap<u32, usize> = HashMap::new();
        for (fi, f) in mesh.faces.iter().enumerate() {
            for (k, &v) in f.iter().enumerate() {
                let c = fi * 3 + k;
                // Count each fan once, at its root corner (duplicated vertices in a face counted once).
                if corners.find(c) == c && f.iter().position(|&x| x == v) == Some(k) {
                    *fans_per_vertex.entry(v).or_default() += 1;
                }
            }
        }
        let nonmanifold_vertices = fans_per_vertex.values().filter(|&&n| n > 1).count();
        Self {
            n_vertices,
            n_edges: edges.len(),
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

#[derive(Default)]
struct EdgeUse {
    count: u32,
    forward: i32,
    faces: Vec<u32>,
}
