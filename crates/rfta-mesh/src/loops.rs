//! The handles of a closed surface that a short loop goes around: the shortest independent
//! non-contractible loops up to a length, counted over Z2 homology.
//!
//! A handle thinner than a sampling can resolve (a bar or a tunnel less than one sample spacing
//! across) has a loop around it shorter than `π` spacings; [`short_loops`] finds how many
//! independent such loops a mesh has, so that a caller can say which of its handles the samples
//! cannot confirm.
//!
//! The method is the greedy shortest homology basis of Erickson and Whittlesey ("Greedy optimal
//! homotopy and homology generators", SODA 2005): every loop of a shortest basis is a shortest
//! path from a base vertex to the two ends of one edge, closed by that edge; a loop's homology
//! class comes from a tree-cotree decomposition (Eppstein, "Dynamic generators of topologically
//! embedded graphs", SODA 2003): the edges outside a spanning tree of the vertices and a
//! spanning tree of the faces across the remaining edges are `2g`, one basis vector each, and
//! every other edge is expressed in them by peeling the face tree from its leaves. Loops are
//! searched only within `max_length / 2` of each base vertex, so the cost grows with the mesh
//! and the bound, not with the mesh squared.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use rayon::prelude::*;
use rfta_geom::TriMesh;

/// Independent non-contractible loops shorter than a bound (see [`short_loops`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ShortLoops {
    /// Genus of the surface (summed over its components).
    pub genus: usize,
    /// The lengths of a shortest set of independent loops below the bound, ascending: a handle
    /// thin one way contributes one (the loop around it), a handle short both ways two. At most
    /// `2 genus`.
    pub lengths: Vec<f64>,
    /// The loops themselves, in the same order: simple cycles of vertex indices, each vertex
    /// joined to the next (and the last to the first) by an edge of the mesh.
    pub loops: Vec<Vec<u32>>,
}

/// The shortest independent non-contractible loops of `mesh` shorter than `max_length` (over Z2
/// homology, edge paths between vertices). `None` when the mesh is not closed and manifold along
/// its edges (an edge without exactly two faces, or a face with a repeated vertex), where
/// homology over edges is not defined this way.
///
/// # Example
/// ```
/// use rfta_geom::shapes;
///
/// // A torus whose tube is 2 pi 0.1 = 0.63 around and whose hole is 2 pi 0.9 = 5.7 around.
/// let torus = shapes::torus(1.0, 0.1, 64, 16);
/// let loops = rfta_mesh::short_loops(&torus, 1.0).expect("closed");
/// assert_eq!(loops.genus, 1);
/// assert_eq!(loops.lengths.len(), 1);
/// assert!((loops.lengths[0] - 0.62).abs() < 0.01);
/// ```
pub fn short_loops(mesh: &TriMesh, max_length: f64) -> Option<ShortLoops> {
    let graph = Graph::new(mesh)?;
    let classes = graph.classes();
    let genus = classes.bits / 2;
    if classes.bits == 0 || max_length.is_nan() || max_length <= 0.0 {
        return Some(ShortLoops {
            genus,
            lengths: Vec::new(),
            loops: Vec::new(),
        });
    }
    // A non-contractible loop has an edge of non-zero class, so a set of vertices that holds
    // an end of each such edge meets every loop; through any vertex x of a loop, its class is a
    // sum of classes of loops through x no longer than it (x's tree paths closed by each of the
    // loop's edges), so the greedy basis over these bases is as short as over all vertices.
    let bases = cover(&graph, &classes);
    let mut candidates: Vec<Candidate> = bases
        .par_iter()
        .map_init(
            || Search::new(graph.offsets.len() - 1, classes.words),
            |search, &x| search.loops_through(&graph, &classes, x, max_length),
        )
        .flatten_iter()
        .collect();
    // Each base vertex's own greedy basis (at most 2g loops), in the bases' order, then one
    // over all of them (a stable sort: the same on any thread count).
    candidates.sort_by(|a, b| a.length.total_cmp(&b.length));
    let mut basis = Basis::new(classes.bits);
    candidates.retain(|c| basis.insert(c.class.clone()));
    let mut search = Search::new(graph.offsets.len() - 1, classes.words);
    let loops = candidates
        .iter()
        .map(|c| search.cycle(&graph, &classes, c, max_length))
        .collect();
    Some(ShortLoops {
        genus,
        lengths: candidates.iter().map(|c| c.length).collect(),
        loops,
    })
}

/// Base vertices for the searches: an end of every edge of non-zero class, ascending. Greedy:
/// each edge not yet met takes the end that more such edges share (the lower index on a tie),
/// so a strip of such edges across a handle is met at the fans' shared vertices, about one
/// vertex for two edges where both ends of every edge took twice as many searches.
fn cover(graph: &Graph, classes: &Classes) -> Vec<u32> {
    let non_zero: Vec<u32> = (0..graph.ends.len() as u32)
        .filter(|&e| classes.of(e).iter().any(|&c| c != 0))
        .collect();
    let mut shared = vec![0u32; graph.offsets.len() - 1];
    for &e in &non_zero {
        for v in graph.ends[e as usize] {
            shared[v as usize] += 1;
        }
    }
    let mut chosen = vec![false; shared.len()];
    for &e in &non_zero {
        let [a, b] = graph.ends[e as usize];
        if chosen[a as usize] || chosen[b as usize] {
            continue;
        }
        let pick = match shared[a as usize].cmp(&shared[b as usize]) {
            Ordering::Greater => a,
            Ordering::Less => b,
            Ordering::Equal => a.min(b),
        };
        chosen[pick as usize] = true;
    }
    (0..chosen.len() as u32)
        .filter(|&v| chosen[v as usize])
        .collect()
}

/// The mesh's edges and vertex adjacency.
struct Graph {
    /// Each edge's two vertices.
    ends: Vec<[u32; 2]>,
    /// Each face's three edges.
    face_edges: Vec<[u32; 3]>,
    /// Each edge's two faces.
    edge_faces: Vec<[u32; 2]>,
    /// Vertex `v`'s neighbours are `adjacent[offsets[v]..offsets[v + 1]]`, as (vertex, edge).
    offsets: Vec<usize>,
    adjacent: Vec<(u32, u32)>,
    /// Each edge's length.
    lengths: Vec<f64>,
}

impl Graph {
    fn new(mesh: &TriMesh) -> Option<Self> {
        let nv = mesh.vertices.len();
        let mut corners: Vec<(u64, u32)> = Vec::with_capacity(3 * mesh.faces.len());
        for (f, t) in mesh.faces.iter().enumerate() {
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] || t.iter().any(|&v| v as usize >= nv) {
                return None;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                corners.push((key, (f * 3 + k) as u32));
            }
        }
        corners.sort_unstable();
        let mut ends = Vec::with_capacity(corners.len() / 2);
        let mut edge_faces = Vec::with_capacity(corners.len() / 2);
        let mut face_edges = vec![[0u32; 3]; mesh.faces.len()];
        for pair in corners.chunk_by(|a, b| a.0 == b.0) {
            let [(key, c0), (_, c1)] = pair else {
                return None;
            };
            let e = ends.len() as u32;
            ends.push([(key >> 32) as u32, *key as u32]);
            edge_faces.push([c0 / 3, c1 / 3]);
            face_edges[(c0 / 3) as usize][(c0 % 3) as usize] = e;
            face_edges[(c1 / 3) as usize][(c1 % 3) as usize] = e;
        }
        let mut offsets = vec![0usize; nv + 1];
        for &[a, b] in &ends {
            offsets[a as usize + 1] += 1;
            offsets[b as usize + 1] += 1;
        }
        for v in 0..nv {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets.clone();
        let mut adjacent = vec![(0u32, 0u32); 2 * ends.len()];
        for (e, &[a, b]) in ends.iter().enumerate() {
            adjacent[fill[a as usize]] = (b, e as u32);
            fill[a as usize] += 1;
            adjacent[fill[b as usize]] = (a, e as u32);
            fill[b as usize] += 1;
        }
        let lengths = ends
            .iter()
            .map(|&[a, b]| mesh.vertices[a as usize].distance(mesh.vertices[b as usize]))
            .collect();
        Some(Graph {
            ends,
            lengths,
            face_edges,
            edge_faces,
            offsets,
            adjacent,
        })
    }

    fn neighbours(&self, v: u32) -> &[(u32, u32)] {
        &self.adjacent[self.offsets[v as usize]..self.offsets[v as usize + 1]]
    }

    fn length(&self, e: u32) -> f64 {
        self.lengths[e as usize]
    }

    /// Every edge's homology class, from a tree-cotree decomposition: a spanning forest of the
    /// vertices (breadth first), a spanning forest of the faces across the other edges; each
    /// remaining edge is one basis vector, tree edges are zero, and a face-tree edge is the sum
    /// of its leaf-side face's other edges (a face's boundary is zero), peeled from the leaves.
    fn classes(&self) -> Classes {
        let ne = self.ends.len();
        let nv = self.offsets.len() - 1;
        let mut in_tree = vec![false; ne];
        let mut seen = vec![false; nv];
        let mut queue = std::collections::VecDeque::new();
        for root in 0..nv as u32 {
            if seen[root as usize] || self.neighbours(root).is_empty() {
                continue;
            }
            seen[root as usize] = true;
            queue.push_back(root);
            while let Some(v) = queue.pop_front() {
                for &(w, e) in self.neighbours(v) {
                    if !seen[w as usize] {
                        seen[w as usize] = true;
                        in_tree[e as usize] = true;
                        queue.push_back(w);
                    }
                }
            }
        }
        let nf = self.face_edges.len();
        let mut in_cotree = vec![false; ne];
        let mut parent_edge = vec![u32::MAX; nf];
        let mut reached = vec![false; nf];
        let mut order = Vec::with_capacity(nf);
        for root in 0..nf {
            if reached[root] {
                continue;
            }
            reached[root] = true;
            order.push(root as u32);
            let mut next = order.len() - 1;
            while next < order.len() {
                let f = order[next] as usize;
                next += 1;
                for &e in &self.face_edges[f] {
                    if in_tree[e as usize] {
                        continue;
                    }
                    let [f0, f1] = self.edge_faces[e as usize];
                    let g = if f0 as usize == f { f1 } else { f0 } as usize;
                    if !reached[g] {
                        reached[g] = true;
                        in_cotree[e as usize] = true;
                        parent_edge[g] = e;
                        order.push(g as u32);
                    }
                }
            }
        }
        let leftover: Vec<usize> = (0..ne).filter(|&e| !in_tree[e] && !in_cotree[e]).collect();
        let bits = leftover.len();
        let words = bits.div_ceil(64);
        let mut of_edge = vec![0u64; ne * words];
        for (j, &e) in leftover.iter().enumerate() {
            of_edge[e * words + j / 64] |= 1 << (j % 64);
        }
        for &f in order.iter().rev() {
            let p = parent_edge[f as usize];
            if p == u32::MAX {
                continue;
            }
            let mut sum = vec![0u64; words];
            for &e in &self.face_edges[f as usize] {
                if e != p {
                    xor(
                        &mut sum,
                        &of_edge[e as usize * words..(e as usize + 1) * words],
                    );
                }
            }
            of_edge[p as usize * words..(p as usize + 1) * words].copy_from_slice(&sum);
        }
        Classes {
            bits,
            words,
            of_edge,
        }
    }
}

/// Each edge's Z2 homology class, `words` words per edge.
struct Classes {
    bits: usize,
    words: usize,
    of_edge: Vec<u64>,
}

impl Classes {
    fn of(&self, e: u32) -> &[u64] {
        &self.of_edge[e as usize * self.words..(e as usize + 1) * self.words]
    }
}

fn xor(into: &mut [u64], from: &[u64]) {
    for (a, b) in into.iter_mut().zip(from) {
        *a ^= b;
    }
}

/// A loop: the tree paths from `base` to the ends of `edge`, closed by it.
struct Candidate {
    length: f64,
    class: Vec<u64>,
    base: u32,
    edge: u32,
}

/// A bounded Dijkstra search from one base vertex, with scratch space reused across searches.
struct Search {
    distance: Vec<f64>,
    parent: Vec<u32>,
    /// The class of the tree path from the base vertex, `words` per vertex.
    path: Vec<u64>,
    settled: Vec<u32>,
    done: Vec<bool>,
    heap: BinaryHeap<Near>,
    words: usize,
}

/// A heap entry ordered by distance, nearest first.
struct Near(f64, u32);

impl PartialEq for Near {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Near {}
impl PartialOrd for Near {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Near {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

impl Search {
    fn new(nv: usize, words: usize) -> Self {
        Search {
            distance: vec![f64::INFINITY; nv],
            parent: vec![u32::MAX; nv],
            path: vec![0; nv * words],
            settled: Vec::new(),
            done: vec![false; nv],
            heap: BinaryHeap::new(),
            words,
        }
    }

    /// The loops through `x` shorter than `max_length` that are independent of the shorter ones
    /// through `x`: a shortest path to each end of an edge outside the search tree, closed by the
    /// edge.
    fn loops_through(
        &mut self,
        graph: &Graph,
        classes: &Classes,
        x: u32,
        max_length: f64,
    ) -> Vec<Candidate> {
        self.grow(graph, classes, x, max_length / 2.0);
        let w = self.words;
        let mut found = Vec::new();
        for &u in &self.settled {
            for &(v, e) in graph.neighbours(u) {
                if v < u
                    || !self.done[v as usize]
                    || self.parent[u as usize] == e
                    || self.parent[v as usize] == e
                {
                    continue;
                }
                let length =
                    self.distance[u as usize] + graph.length(e) + self.distance[v as usize];
                if length >= max_length {
                    continue;
                }
                let (pu, pv) = (u as usize * w, v as usize * w);
                let (cu, cv, ce) = (
                    &self.path[pu..pu + w],
                    &self.path[pv..pv + w],
                    classes.of(e),
                );
                if (0..w).any(|k| cu[k] ^ cv[k] ^ ce[k] != 0) {
                    let class = (0..w).map(|k| cu[k] ^ cv[k] ^ ce[k]).collect();
                    found.push(Candidate {
                        length,
                        class,
                        base: x,
                        edge: e,
                    });
                }
            }
        }
        found.sort_by(|a, b| a.length.total_cmp(&b.length));
        let mut basis = Basis::new(classes.bits);
        found.retain(|c| basis.insert(c.class.clone()));
        found
    }

    /// The loop of `candidate` as a simple cycle of vertices: the tree paths from its base to
    /// the two ends of its edge, without the stretch they share.
    fn cycle(
        &mut self,
        graph: &Graph,
        classes: &Classes,
        candidate: &Candidate,
        max_length: f64,
    ) -> Vec<u32> {
        self.grow(graph, classes, candidate.base, max_length / 2.0);
        let to_base = |mut v: u32| {
            let mut path = vec![v];
            while self.parent[v as usize] != u32::MAX {
                let [a, b] = graph.ends[self.parent[v as usize] as usize];
                v = if a == v { b } else { a };
                path.push(v);
            }
            path
        };
        let [u, v] = graph.ends[candidate.edge as usize];
        let (mut pu, mut pv) = (to_base(u), to_base(v));
        // Both end at the base: drop the shared stretch but its first vertex.
        while pu.len() > 1 && pv.len() > 1 && pu[pu.len() - 2] == pv[pv.len() - 2] {
            pu.pop();
            pv.pop();
        }
        pv.pop();
        pv.reverse();
        pu.extend(pv);
        pu
    }

    /// Dijkstra from `x` to distance `reach`, with each settled vertex's tree-path class.
    fn grow(&mut self, graph: &Graph, classes: &Classes, x: u32, reach: f64) {
        let w = self.words;
        for &v in &self.settled {
            let v = v as usize;
            self.distance[v] = f64::INFINITY;
            self.parent[v] = u32::MAX;
            self.done[v] = false;
            self.path[v * w..(v + 1) * w].fill(0);
        }
        self.settled.clear();
        // Empty: every search pops until none is left.
        let heap = &mut self.heap;
        self.distance[x as usize] = 0.0;
        heap.push(Near(0.0, x));
        while let Some(Near(d, v)) = heap.pop() {
            if self.done[v as usize] {
                continue;
            }
            self.done[v as usize] = true;
            self.settled.push(v);
            let e = self.parent[v as usize];
            if e != u32::MAX {
                let [a, b] = graph.ends[e as usize];
                let from = if a == v { b } else { a } as usize;
                let v = v as usize;
                self.path.copy_within(from * w..(from + 1) * w, v * w);
                xor(&mut self.path[v * w..(v + 1) * w], classes.of(e));
            }
            for &(u, e) in graph.neighbours(v) {
                let du = d + graph.length(e);
                if du <= reach && du < self.distance[u as usize] {
                    self.distance[u as usize] = du;
                    self.parent[u as usize] = e;
                    heap.push(Near(du, u));
                }
            }
        }
    }
}

/// A Z2 basis in echelon form: each vector stored under its highest set bit.
struct Basis {
    by_pivot: Vec<Option<Vec<u64>>>,
}

impl Basis {
    fn new(bits: usize) -> Self {
        Basis {
            by_pivot: vec![None; bits],
        }
    }

    /// Adds `v` if it is independent of the basis; returns whether it was.
    fn insert(&mut self, mut v: Vec<u64>) -> bool {
        loop {
            let Some(word) = v.iter().rposition(|&c| c != 0) else {
                return false;
            };
            let pivot = word * 64 + 63 - v[word].leading_zeros() as usize;
            match &self.by_pivot[pivot] {
                Some(b) => xor(&mut v, b),
                None => {
                    self.by_pivot[pivot] = Some(v);
                    return true;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{PI, TAU};

    use rfta_geom::glam::DVec3;
    use rfta_geom::shapes;

    use super::*;

    /// A regular `n`-gon of circumradius `r`: the edge loop a torus mesh has around a circle.
    fn polygon(n: u32, r: f64) -> f64 {
        2.0 * f64::from(n) * r * rfta_geom::math::sin(PI / f64::from(n))
    }

    /// The greedy basis over every vertex as a base, with an unbounded search from each.
    fn brute_force(mesh: &TriMesh, max_length: f64) -> Vec<f64> {
        let graph = Graph::new(mesh).expect("closed");
        let classes = graph.classes();
        let mut search = Search::new(graph.offsets.len() - 1, classes.words);
        let mut all: Vec<Candidate> = (0..mesh.vertices.len() as u32)
            .flat_map(|x| search.loops_through(&graph, &classes, x, f64::INFINITY))
            .filter(|c| c.length < max_length)
            .collect();
        all.sort_by(|a, b| a.length.total_cmp(&b.length));
        let mut basis = Basis::new(classes.bits);
        all.into_iter()
            .filter_map(|c| basis.insert(c.class).then_some(c.length))
            .collect()
    }

    fn two_tori() -> TriMesh {
        let mut mesh = shapes::torus(1.0, 0.1, 48, 12);
        let mut thick = shapes::torus(0.8, 0.4, 24, 16);
        thick.map_vertices(|v| v + DVec3::new(5.0, 0.0, 0.0));
        let offset = mesh.vertices.len() as u32;
        mesh.vertices.extend(thick.vertices);
        mesh.faces
            .extend(thick.faces.iter().map(|f| f.map(|v| v + offset)));
        mesh
    }

    #[test]
    fn a_thin_tube_has_one_short_loop_and_a_small_torus_two() {
        // Tube 2 pi 0.1 around; the hole 2 pi 0.9 around its inner equator.
        let torus = shapes::torus(1.0, 0.1, 64, 16);
        let tube = polygon(16, 0.1);
        let hole = polygon(64, 0.9);
        let one = short_loops(&torus, 1.0).expect("closed");
        assert_eq!((one.genus, one.lengths.len()), (1, 1));
        assert!((one.lengths[0] - tube).abs() < 1e-9, "{:?}", one.lengths);
        let none = short_loops(&torus, 0.9 * tube).expect("closed");
        assert!(none.lengths.is_empty());
        let both = short_loops(&torus, 1.05 * hole).expect("closed");
        assert_eq!(both.lengths.len(), 2, "{:?}", both.lengths);
        assert!((both.lengths[1] - hole).abs() < 1e-9, "{:?}", both.lengths);
    }

    /// Each loop is a simple cycle of the mesh's edges as long as its length says.
    #[test]
    fn the_loops_are_simple_cycles_of_edges() {
        let mesh = two_tori();
        let graph = Graph::new(&mesh).expect("closed");
        let edge = |a: u32, b: u32| {
            graph
                .neighbours(a)
                .iter()
                .find(|&&(v, _)| v == b)
                .map(|&(_, e)| graph.length(e))
        };
        let loops = short_loops(&mesh, 100.0).expect("closed");
        assert_eq!(loops.loops.len(), 4);
        for (cycle, length) in loops.loops.iter().zip(&loops.lengths) {
            let mut sorted = cycle.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), cycle.len(), "{cycle:?}");
            let total: f64 = (0..cycle.len())
                .map(|i| edge(cycle[i], cycle[(i + 1) % cycle.len()]).expect("an edge"))
                .sum();
            assert!((total - length).abs() < 1e-9, "{total} vs {length}");
        }
    }

    #[test]
    fn a_sphere_has_no_loop_and_an_open_mesh_no_answer() {
        let sphere = shapes::icosphere(1.0, 3);
        let loops = short_loops(&sphere, 100.0).expect("closed");
        assert_eq!((loops.genus, loops.lengths.len()), (0, 0));
        let mut open = shapes::torus(1.0, 0.1, 16, 8);
        open.faces.pop();
        assert_eq!(short_loops(&open, 1.0), None);
    }

    #[test]
    fn each_component_has_its_own_loops() {
        // The thin torus's tube (0.62) and its hole (5.65), the thick one's tube (2.5) and hole
        // (2.5 around: 2 pi 0.4 inside).
        let mesh = two_tori();
        let loops = short_loops(&mesh, 2.0).expect("closed");
        assert_eq!(loops.genus, 2);
        assert_eq!(loops.lengths.len(), 1, "{:?}", loops.lengths);
        let all = short_loops(&mesh, 100.0).expect("closed");
        assert_eq!(all.lengths.len(), 4, "a full basis: {:?}", all.lengths);
    }

    #[test]
    fn bases_on_the_non_zero_edges_find_what_every_vertex_finds() {
        let mesh = two_tori();
        // The same loops; their lengths summed along other paths, so equal to rounding.
        let same = |mesh: &TriMesh, max: f64| {
            let fast = short_loops(mesh, max).expect("closed").lengths;
            let brute = brute_force(mesh, max);
            assert_eq!(fast.len(), brute.len(), "bound {max}");
            for (a, b) in fast.iter().zip(&brute) {
                assert!((a - b).abs() < 1e-12, "bound {max}: {fast:?} vs {brute:?}");
            }
        };
        for max in [0.5, 1.0, 2.6, 3.0, 6.0, 100.0] {
            same(&mesh, max);
        }
        // A twisted ring, so that no loop follows a parameter line.
        let mut twisted = shapes::torus(1.0, 0.3, 40, 10);
        twisted.map_vertices(|v| {
            let a = 0.5 * v.z + 0.2 * v.x;
            DVec3::new(
                v.x * rfta_geom::math::cos(a) - v.y * rfta_geom::math::sin(a),
                v.x * rfta_geom::math::sin(a) + v.y * rfta_geom::math::cos(a),
                v.z,
            )
        });
        for max in [1.0, 2.0, TAU, 100.0] {
            same(&twisted, max);
        }
    }

    #[test]
    fn the_bases_meet_every_edge_of_non_zero_class_with_fewer_vertices_than_their_ends() {
        for mesh in [two_tori(), shapes::torus(1.0, 0.3, 40, 10)] {
            let graph = Graph::new(&mesh).expect("closed");
            let classes = graph.classes();
            let bases = cover(&graph, &classes);
            let non_zero: Vec<u32> = (0..graph.ends.len() as u32)
                .filter(|&e| classes.of(e).iter().any(|&c| c != 0))
                .collect();
            assert!(!non_zero.is_empty());
            for &e in &non_zero {
                let [a, b] = graph.ends[e as usize];
                assert!(
                    bases.binary_search(&a).is_ok() || bases.binary_search(&b).is_ok(),
                    "edge {e} ({a}, {b}) has no base"
                );
            }
            let mut ends: Vec<u32> = non_zero
                .iter()
                .flat_map(|&e| graph.ends[e as usize])
                .collect();
            ends.sort_unstable();
            ends.dedup();
            assert!(
                bases.len() < ends.len(),
                "{} bases, {} ends",
                bases.len(),
                ends.len()
            );
        }
    }

    #[test]
    fn the_loops_do_not_depend_on_the_thread_count() {
        let mesh = two_tori();
        let on = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| short_loops(&mesh, 100.0))
        };
        assert_eq!(on(1), on(3));
    }
}
