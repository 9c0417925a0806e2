//! Crack-free iso-surface extraction on the adaptive octree (after Kazhdan, Klein, Dalal and
//! Hoppe 2007, "Unconstrained isosurface extraction on arbitrary octrees").
//!
//! Iso-vertices live only on *minimal edges*: the pieces into which leaf corners cut an edge.
//! A face between two leaves belongs to the finer one; a coarse leaf whose face borders finer
//! leaves takes the segments of their faces. Every face is cut by a rule that depends only on
//! the values along its boundary, so both cells on either side of it see the same segments, with
//! opposite orientation. Each leaf chains its segments into closed loops, and each loop is
//! triangulated without new vertices where that cannot create a non-manifold edge (minimal area,
//! diagonals through the cell's interior only), else as a fan around its centroid. Hence the mesh
//! is watertight and manifold wherever the surface stays inside the cube.

use crate::triangulate::triangulate;
use rayon::prelude::*;
use rfta_geom::glam::DVec3;

use crate::flat::Leaves;
use crate::keys::NONE;
use crate::tree::{Frame, Level};

/// A point in finest-depth integer coordinates.
type P = [u32; 3];

/// Packs the lower end of a minimal edge and its axis.
fn vkey(q: P, axis: usize) -> u64 {
    (u64::from(q[0]) << 38) | (u64::from(q[1]) << 20) | (u64::from(q[2]) << 2) | axis as u64
}

fn unpack(k: u64) -> (P, usize) {
    let m = (1u64 << 18) - 1;
    (
        [
            ((k >> 38) & m) as u32,
            ((k >> 20) & m) as u32,
            ((k >> 2) & m) as u32,
        ],
        (k & 3) as usize,
    )
}

const CENTRE: u64 = 1 << 63;

struct Ctx<'a> {
    levels: &'a [Level],
    values: &'a [Vec<f64>],
    iso: f64,
    depth: u32,
    leaves: &'a Leaves,
}

#[derive(Clone, Copy)]
struct BPoint {
    q: P,
    v: f64,
}

impl Ctx<'_> {
    fn finest(&self, d: u32, c: [i64; 3]) -> P {
        let s = self.depth - d;
        [(c[0] as u32) << s, (c[1] as u32) << s, (c[2] as u32) << s]
    }

    /// Final value at a node of depth `d` (level coordinates).
    fn value(&self, near: &Around, d: u32, c: [i64; 3]) -> Option<f64> {
        if let Some(v) = near.value(d, c) {
            return v;
        }
        let node = self.levels[d as usize].node(c)?;
        Some(self.values[d as usize][node as usize])
    }

    /// Whether the extraction splits the depth-`d` cell `c` (a cell taken whole is a leaf).
    fn refined_cell(&self, near: &Around, d: u32, c: [i64; 3]) -> bool {
        if let Some(split) = near.split(d, c) {
            return split;
        }
        let level = &self.levels[d as usize];
        level.cell(c).is_some_and(|i| self.leaves.is_split(d, i))
    }

    /// What the faces of leaf `ci` (depth `d`, level coordinates `c`) ask of their own depth.
    fn around(&self, d: u32, ci: u32, c: [i64; 3]) -> Around {
        let level = &self.levels[d as usize];
        let vals = &self.values[d as usize];
        let block = level.cell_index.block27(c);
        Around {
            d,
            c,
            split: block.map(|i| i != NONE && self.leaves.is_split(d, i)),
            corners: level.corners[ci as usize].map(|n| vals.get(n as usize).copied()),
        }
    }

    /// Leaf corners strictly inside the depth-`d` edge from `start` along `axis`, ascending.
    fn edge_points(
        &self,
        near: &Around,
        d: u32,
        start: [i64; 3],
        axis: usize,
        out: &mut Vec<BPoint>,
    ) -> bool {
        let (o1, o2) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut split = false;
        for b in 0..4 {
            let mut k = start;
            k[o1] -= b & 1;
            k[o2] -= b >> 1;
            if self.refined_cell(near, d, k) {
                split = true;
                break;
            }
        }
        if !split {
            return true;
        }
        let s2 = start.map(|v| 2 * v);
        let mut mid = s2;
        mid[axis] += 1;
        let Some(v) = self.value(near, d + 1, mid) else {
            return false;
        };
        let ok = self.edge_points(near, d + 1, s2, axis, out);
        out.push(BPoint {
            q: self.finest(d + 1, mid),
            v,
        });
        ok && self.edge_points(near, d + 1, mid, axis, out)
    }
}

/// A leaf's neighbourhood at its own depth, looked up once for its six faces (each edge is on
/// two of them and each corner on three): whether each cell of the 3x3x3 block around it is
/// split, and the values at its corners (`None` where a corner is not a node).
struct Around {
    d: u32,
    c: [i64; 3],
    /// By `(x + 1) + 3 (y + 1) + 9 (z + 1)` (offsets from `c`), as `SparseIndex::block27`.
    split: [bool; 27],
    /// By `x + 2 y + 4 z`, as `tree::corner`.
    corners: [Option<f64>; 8],
}

impl Around {
    /// Whether depth-`d` cell `k` is split, if it is in the block.
    #[inline]
    fn split(&self, d: u32, k: [i64; 3]) -> Option<bool> {
        let o = [k[0] - self.c[0], k[1] - self.c[1], k[2] - self.c[2]];
        (d == self.d && o.iter().all(|v| (-1..=1).contains(v)))
            .then(|| self.split[(o[0] + 1 + 3 * (o[1] + 1) + 9 * (o[2] + 1)) as usize])
    }

    /// The value at depth-`d` node `k` (`Some(None)`: not a node), if it is a corner of the leaf.
    #[inline]
    fn value(&self, d: u32, k: [i64; 3]) -> Option<Option<f64>> {
        let o = [k[0] - self.c[0], k[1] - self.c[1], k[2] - self.c[2]];
        (d == self.d && o.iter().all(|v| (0..=1).contains(v)))
            .then(|| self.corners[(o[0] + 2 * o[1] + 4 * o[2]) as usize])
    }
}

/// Segments and vertices gathered for one leaf, and the space in which [`Ctx::leaf`] chains
/// them into loops (kept from leaf to leaf: one allocation per task, not per leaf).
#[derive(Default)]
struct LeafOut {
    verts: Vec<(u64, DVec3)>,
    segs: Vec<(u64, u64)>,
    broken: bool,
    /// Per segment, whether a loop holds it.
    used: Vec<bool>,
    /// The loop being chained: its vertex keys, positions and face masks.
    lp: Vec<u64>,
    pos: Vec<DVec3>,
    masks: Vec<u8>,
    /// The loop's triangles (corner indices) and [`triangulate`]'s stack of spans.
    tris: Vec<[usize; 3]>,
    spans: Vec<(usize, usize)>,
}

/// What one task of [`extract`] gathers from its leaves, in leaf order: each leaf's vertices
/// (by key, once per leaf), its triangles (vertex keys, or `CENTRE` and the index of a centre
/// in `centres`), the centres of its fans, and how many of its leaves had a broken loop.
#[derive(Default)]
struct Patch {
    verts: Vec<(u64, DVec3)>,
    tris: Vec<[u64; 3]>,
    centres: Vec<DVec3>,
    broken_leaves: usize,
}

impl Ctx<'_> {
    fn vertex(&self, near: &Around, a: BPoint, b: BPoint, out: &mut LeafOut) -> u64 {
        let (lo, hi) = if a.q <= b.q { (a, b) } else { (b, a) };
        let axis = (0..3).find(|&i| lo.q[i] != hi.q[i]).unwrap_or(0);
        let key = vkey(lo.q, axis);
        let (lo, hi) = if self.leaves.merged {
            self.bracket(near, lo, hi, axis)
        } else {
            (lo, hi)
        };
        let t = ((self.iso - lo.v) / (hi.v - lo.v)).clamp(0.0, 1.0);
        let ql = DVec3::new(f64::from(lo.q[0]), f64::from(lo.q[1]), f64::from(lo.q[2]));
        let qh = DVec3::new(f64::from(hi.q[0]), f64::from(hi.q[1]), f64::from(hi.q[2]));
        out.verts.push((key, ql + (qh - ql) * t));
        key
    }

    /// The shortest piece of the edge from `lo` to `hi` (along `axis`, the iso-value between
    /// their values) in which the finer depths' nodes on it bracket the crossing: the edge halved
    /// while its middle is a node, keeping the half whose ends straddle the iso-value. An edge of
    /// a cell taken whole thereby gets the vertex the tree's own leaves would give it.
    fn bracket(
        &self,
        near: &Around,
        mut lo: BPoint,
        mut hi: BPoint,
        axis: usize,
    ) -> (BPoint, BPoint) {
        let inside = |v: f64| v > self.iso;
        loop {
            // Edges run between corners of cells, so their lengths are powers of two.
            let half = (hi.q[axis] - lo.q[axis]) / 2;
            if half == 0 {
                return (lo, hi);
            }
            let d = self.depth - half.trailing_zeros();
            let s = self.depth - d;
            let mut q = lo.q;
            q[axis] += half;
            let Some(v) = self.value(near, d, q.map(|v| i64::from(v >> s))) else {
                return (lo, hi);
            };
            let mid = BPoint { q, v };
            if inside(lo.v) == inside(v) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }

    fn face(&self, near: &Around, d: u32, c: [i64; 3], f: usize, out: &mut LeafOut) {
        let a = f / 2;
        let side = (f % 2) as i64;
        let n = 1i64 << d;
        let mut nb = c;
        nb[a] += 2 * side - 1;
        if (0..n).contains(&nb[a]) && self.refined_cell(near, d, nb) {
            let (u, v) = ((a + 1) % 3, (a + 2) % 3);
            for s in 0..4 {
                let mut cc = c.map(|x| 2 * x);
                cc[a] += side;
                cc[u] += s & 1;
                cc[v] += s >> 1;
                self.face(near, d + 1, cc, f, out);
            }
        } else {
            self.atomic_face(near, d, c, f, out);
        }
    }

    fn atomic_face(&self, near: &Around, d: u32, c: [i64; 3], f: usize, out: &mut LeafOut) {
        let a = f / 2;
        let side = (f % 2) as i64;
        let (u, v) = ((a + 1) % 3, (a + 2) % 3);
        let mut p0 = c;
        p0[a] += side;
        let corner = |du: i64, dv: i64| {
            let mut q = p0;
            q[u] += du;
            q[v] += dv;
            q
        };
        let order: [(i64, i64); 4] = if side == 1 {
            [(0, 0), (1, 0), (1, 1), (0, 1)]
        } else {
            [(0, 0), (0, 1), (1, 1), (1, 0)]
        };
        let mut corner_vals = [0.0; 4];
        let mut boundary: Vec<BPoint> = Vec::with_capacity(8);
        let mut scratch = Vec::new();
        for e in 0..4 {
            let (au, av) = order[e];
            let (bu, bv) = order[(e + 1) % 4];
            let ca = corner(au, av);
            let Some(va) = self.value(near, d, ca) else {
                out.broken = true;
                return;
            };
            corner_vals[e] = va;
            boundary.push(BPoint {
                q: self.finest(d, ca),
                v: va,
            });
            let cb = corner(bu, bv);
            let axis = if au != bu { u } else { v };
            let start = if ca[axis] < cb[axis] { ca } else { cb };
            scratch.clear();
            if !self.edge_points(near, d, start, axis, &mut scratch) {
                out.broken = true;
                return;
            }
            if ca[axis] < cb[axis] {
                boundary.extend(scratch.iter().copied());
            } else {
                boundary.extend(scratch.iter().rev().copied());
            }
        }
        // Crossings in boundary order: (vertex, true for outside -> inside).
        let inside = |v: f64| v > self.iso;
        let mut xs: Vec<(u64, bool)> = Vec::new();
        for k in 0..boundary.len() {
            let (p, q) = (boundary[k], boundary[(k + 1) % boundary.len()]);
            if inside(p.v) != inside(q.v) {
                let key = self.vertex(near, p, q, out);
                xs.push((key, !inside(p.v)));
            }
        }
        if xs.is_empty() {
            return;
        }
        let m = xs.len();
        let join_inside = m > 2 && inside(corner_vals.iter().sum::<f64>() / 4.0);
        for k in 0..m {
            let next = xs[(k + 1) % m];
            if !join_inside && xs[k].1 {
                out.segs.push((xs[k].0, next.0));
            } else if join_inside && !xs[k].1 {
                out.segs.push((next.0, xs[k].0));
            }
        }
    }
}

/// Faces of the cell `[lo, lo + size]` (finest coordinates) a vertex lies on, as a bit mask.
fn face_mask(key: u64, lo: P, size: u32) -> u8 {
    let (q, axis) = unpack(key);
    let mut m = 0u8;
    for a in 0..3 {
        if a == axis {
            continue;
        }
        if q[a] == lo[a] {
            m |= 1 << (2 * a);
        }
        if q[a] == lo[a] + size {
            m |= 1 << (2 * a + 1);
        }
    }
    m
}

/// Result of the extraction, in unit-cube coordinates.
pub(crate) struct Extracted {
    pub vertices: Vec<DVec3>,
    pub faces: Vec<[u32; 3]>,
    /// Leaves whose segments did not close into loops (0 unless something is wrong).
    pub broken_leaves: usize,
}

/// Final value of every node: the nodal value at the finest depth where the node is active.
pub(crate) fn final_values(levels: &[Level], u: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = vec![Vec::new(); levels.len()];
    for d in (0..levels.len()).rev() {
        let level = &levels[d];
        let vals: Vec<f64> = if d + 1 < levels.len() {
            let finer = &levels[d + 1];
            let fv = &out[d + 1];
            level
                .nodes
                .par_iter()
                .enumerate()
                .map(|(i, c)| {
                    let k = [
                        2 * i64::from(c[0]),
                        2 * i64::from(c[1]),
                        2 * i64::from(c[2]),
                    ];
                    finer.node(k).map_or(u[d][i], |j| fv[j as usize])
                })
                .collect()
        } else {
            u[d].clone()
        };
        out[d] = vals;
    }
    out
}

/// Whether the iso-surface reaches the cube's faces: some node on them is inside (`χ > iso`).
/// The extraction closes the surface only inside the cube, so such a surface comes out open.
pub(crate) fn leaves_cube(levels: &[Level], values: &[Vec<f64>], iso: f64) -> bool {
    levels.iter().zip(values).any(|(level, vals)| {
        let n = level.n();
        level
            .nodes
            .par_iter()
            .zip(vals)
            .any(|(c, &f)| f > iso && c.iter().any(|&v| v == 0 || v == n))
    })
}

/// Most cut leaves a parallel task of [`extract`] takes.
const LEAVES_PER_TASK: usize = 64;

/// Extract the iso-surface `χ = iso` (triangles oriented toward decreasing χ, i.e. outward) over
/// `leaves`.
pub(crate) fn extract(
    levels: &[Level],
    values: &[Vec<f64>],
    iso: f64,
    leaves: &Leaves,
) -> Extracted {
    let depth = levels.len() as u32 - 1;
    let ctx = Ctx {
        levels,
        values,
        iso,
        depth,
        leaves,
    };
    let cand = leaves.cut(levels, values, iso);

    // Leaves vary in work (most hold one small loop, a few several): tasks of at most
    // `LEAVES_PER_TASK` keep both threads busy to the end. Each task gathers its leaves' output
    // in one `Patch`, reusing one leaf's scratch space.
    let patches: Vec<Patch> = cand
        .par_chunks(LEAVES_PER_TASK)
        .map(|leaves| {
            // Room for what a leaf typically gives (a loop or two of 3 to 6 vertices), so that
            // the vectors seldom grow: growing them on two threads at once is where the
            // allocator's locks were contended.
            let mut patch = Patch {
                verts: Vec::with_capacity(8 * leaves.len()),
                tris: Vec::with_capacity(6 * leaves.len()),
                ..Patch::default()
            };
            let mut out = LeafOut {
                verts: Vec::with_capacity(32),
                segs: Vec::with_capacity(16),
                ..LeafOut::default()
            };
            for &(d, ci) in leaves {
                ctx.leaf(d, ci, &mut out, &mut patch);
            }
            patch
        })
        .collect();

    let mut keys: Vec<(u64, DVec3)> = patches
        .par_iter()
        .flat_map_iter(|p| p.verts.iter().copied())
        .collect();
    keys.par_sort_unstable_by_key(|v| v.0);
    keys.dedup_by_key(|v| v.0);
    let scale = 1.0 / f64::from(1u32 << depth);
    // Centre vertices follow the edge vertices, leaf by leaf.
    let mut first_centre = Vec::with_capacity(patches.len());
    let mut next = keys.len() as u32;
    for p in &patches {
        first_centre.push(next);
        next += p.centres.len() as u32;
    }
    let mut vertices: Vec<DVec3> = keys.par_iter().map(|v| v.1 * scale).collect();
    vertices.extend(
        patches
            .iter()
            .flat_map(|p| p.centres.iter().map(|c| *c * scale)),
    );
    let broken_leaves = patches.iter().map(|p| p.broken_leaves).sum();
    let faces: Vec<[u32; 3]> = patches
        .par_iter()
        .zip(&first_centre)
        .flat_map_iter(|(p, &fc)| {
            let keys = &keys;
            p.tris.iter().map(move |t| {
                t.map(|k| {
                    if k & CENTRE != 0 {
                        fc + (k & !CENTRE) as u32
                    } else {
                        keys.partition_point(|v| v.0 < k) as u32
                    }
                })
            })
        })
        .collect();
    Extracted {
        vertices,
        faces,
        broken_leaves,
    }
}

impl Ctx<'_> {
    /// Leaf `ci` of depth `d`: its faces' segments chained into loops and triangulated, appended
    /// to `patch` (`out`: scratch space, whatever it held before).
    fn leaf(&self, d: u32, ci: u32, out: &mut LeafOut, patch: &mut Patch) {
        out.verts.clear();
        out.segs.clear();
        out.broken = false;
        let level = &self.levels[d as usize];
        let c = crate::keys::demorton(level.cells[ci as usize]);
        let c = [i64::from(c[0]), i64::from(c[1]), i64::from(c[2])];
        let near = self.around(d, ci, c);
        for f in 0..6 {
            self.face(&near, d, c, f, out);
        }
        if out.segs.is_empty() {
            patch.verts.extend_from_slice(&out.verts);
            patch.broken_leaves += usize::from(out.broken);
            return;
        }
        // Positions by key (first occurrence; duplicates are identical).
        out.verts.sort_by_key(|v| v.0);
        out.verts.dedup_by_key(|v| v.0);
        let LeafOut {
            verts,
            segs,
            broken,
            used,
            lp,
            pos,
            masks,
            tris,
            spans,
        } = out;
        let pos_of = |k: u64| {
            let i = verts.partition_point(|v| v.0 < k);
            verts[i].1
        };
        let lo = self.finest(d, c);
        let size = 1u32 << (self.depth - d);
        used.clear();
        used.resize(segs.len(), false);
        for s0 in 0..segs.len() {
            if used[s0] {
                continue;
            }
            used[s0] = true;
            lp.clear();
            lp.push(segs[s0].0);
            let mut cur = segs[s0].1;
            let mut closed = false;
            for _ in 0..segs.len() {
                if cur == lp[0] {
                    closed = true;
                    break;
                }
                lp.push(cur);
                match (0..segs.len()).find(|&s| !used[s] && segs[s].0 == cur) {
                    Some(s) => {
                        used[s] = true;
                        cur = segs[s].1;
                    }
                    None => break,
                }
            }
            if !closed {
                *broken = true;
                continue;
            }
            if lp.len() < 3 {
                // Two segments joining the same two vertices on two faces of this cell: the
                // surface only grazes the cell (an edge whose middle has the other sign). The
                // patch here has no area; the two cells across those faces each hold the edge
                // once, with opposite orientations, so nothing is emitted.
                continue;
            }
            if lp.len() == 3 {
                patch.tris.push([lp[0], lp[1], lp[2]]);
                continue;
            }
            pos.clear();
            pos.extend(lp.iter().map(|&k| pos_of(k)));
            masks.clear();
            masks.extend(lp.iter().map(|&k| face_mask(k, lo, size)));
            if triangulate(pos, masks, tris, spans) {
                patch
                    .tris
                    .extend(tris.iter().map(|t| [lp[t[0]], lp[t[1]], lp[t[2]]]));
            } else {
                let centre = pos.iter().copied().sum::<DVec3>() / pos.len() as f64;
                let ck = CENTRE | patch.centres.len() as u64;
                patch.centres.push(centre);
                for k in 0..lp.len() {
                    patch.tris.push([ck, lp[k], lp[(k + 1) % lp.len()]]);
                }
            }
        }
        patch.verts.extend_from_slice(verts);
        patch.broken_leaves += usize::from(*broken);
    }
}

/// Map extracted unit-cube vertices to the world.
pub(crate) fn to_world(frame: &Frame, vertices: &mut [DVec3]) {
    vertices.iter_mut().for_each(|v| *v = frame.to_world(*v));
}
