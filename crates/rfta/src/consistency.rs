//! How a mesh agrees with every sample: the method's promise, measured.
//!
//! Reach for the Arcs (Sellán, Ren, Batty, Stein 2024, §3) asks for a surface that touches every
//! sample sphere `B(p_i, |s_i|)` and enters none, with `p_i` outside where `s_i > 0` and inside
//! where `s_i < 0`. [`measure`] checks each sample against a mesh, with tolerances in units of the
//! sample spacing `h` ([`SdfSamples::spacing`]: the grid spacing; for scattered samples that of a
//! grid with as many samples in their box):
//!
//! - a **sign error**: `|s_i| > 0.01 h` and the generalized winding number of the mesh puts `p_i`
//!   on the other side;
//! - an **entered sphere**: the distance `d_i` from `p_i` to the mesh is below `|s_i| - 0.1 h`;
//! - a **gap**: `d_i > |s_i| + 0.25 h`, the surface is farther than the sample says.
//!
//! It also finds the mesh's **thin handles**: independent non-contractible loops shorter than
//! `π h` (`THIN_LOOP` (π); `rfta_mesh::short_loops`), each around a bar or a tunnel less than about
//! one spacing across. Samples `h` apart do not resolve such a part (a sphere tangent to it fits
//! between its neighbours whether it is there or not), so they can neither confirm nor rule the
//! handle out: a true thin handle and a spurious one both pass the three checks above
//! (docs/faithfulness.md). They are reported, not counted against the mesh.
//!
//! A clamped sample (`|s_i|` at or beyond the clamp) says only that the surface is at least that
//! far: it can be entered or on the wrong side, never have a gap. The same function scores the
//! pipeline's output ([`crate::Report::consistency`]) and any other method's mesh (`cargo xtask
//! eval`), so the numbers compare.

use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{Grid, SdfSamples, TriMesh};
use rfta_mesh::{MeshIndex, Shell, Topology, UnionFind};

#[cfg(doc)]
use crate::Error;
use crate::Result;

/// A sign error needs `|s| > SIGN_MARGIN h`: samples closer to the surface than that carry no
/// reliable side.
pub(crate) const SIGN_MARGIN: f64 = 0.01;

/// A sphere counts as entered when the mesh comes closer than `|s| - ENTER_MARGIN h`.
pub(crate) const ENTER_MARGIN: f64 = 0.1;

/// A gap is a mesh farther than `|s| + GAP_MARGIN h`.
pub(crate) const GAP_MARGIN: f64 = 0.25;

/// A non-contractible loop shorter than `THIN_LOOP h` makes a thin handle: the circumference of a
/// circle one spacing across.
pub(crate) const THIN_LOOP: f64 = std::f64::consts::PI;

/// The margins an agreement is judged with, in sample spacings `h`: `SIGN_MARGIN` (0.01),
/// `ENTER_MARGIN` (0.1), `GAP_MARGIN` (0.25) and `THIN_LOOP` (π) (the default is the only setting).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Margins {
    /// A sample on the wrong side counts when `|s| >` this.
    pub sign: f64,
    /// A sphere counts as entered when the mesh comes closer than `|s| -` this.
    pub enter: f64,
    /// A gap is a mesh farther than `|s| +` this.
    pub gap: f64,
    /// A handle is thin when a loop around it is shorter than this.
    pub thin_loop: f64,
}

impl Default for Margins {
    fn default() -> Self {
        Self {
            sign: SIGN_MARGIN,
            enter: ENTER_MARGIN,
            gap: GAP_MARGIN,
            thin_loop: THIN_LOOP,
        }
    }
}

/// What [`measure`] found.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Consistency {
    /// Samples checked (not serialized: a [`crate::Report`] holds it as its own `samples`).
    #[serde(skip)]
    pub samples: usize,
    /// The spacing `h` the margins are stated in (the samples' units).
    pub spacing: f64,
    /// Samples on the wrong side of the mesh (by winding number) with `|s| > 0.01 h`.
    pub sign_errors: usize,
    /// Samples whose sphere the mesh enters by more than `0.1 h`.
    pub entered: usize,
    /// Samples from which the mesh is more than `0.25 h` farther than their value.
    pub gaps: usize,
    /// The deepest entry into a sphere, `max_i (min(|s_i|, clamp) - d_i) / h` over all samples
    /// (0 when the mesh enters none).
    pub deepest_entry: f64,
    /// The lengths, in spacings and ascending, of a shortest set of independent loops around the
    /// mesh's handles that are shorter than `THIN_LOOP` (π) spacings (a handle thin one way has
    /// one, a handle small both ways two); empty when the mesh has none, is not closed, or has a
    /// genus above `THIN_LOOP_MAX_GENUS` (256).
    pub thin_loops: Vec<f64>,
}

impl Consistency {
    /// No sign error and no entered sphere.
    pub fn is_consistent(&self) -> bool {
        self.sign_errors == 0 && self.entered == 0
    }
}

/// Checks `mesh` against every sample (see the module documentation); `clamp` is the magnitude at
/// and beyond which values are clamped (`None`: none are). The result does not depend on the
/// thread count.
///
/// # Errors
/// [`Error::Consistency`] if the mesh cannot be indexed (no faces, non-finite vertices).
pub fn measure(samples: &SdfSamples, mesh: &TriMesh, clamp: Option<f64>) -> Result<Consistency> {
    Ok(measure_with(samples, mesh, &Topology::of(mesh), clamp)?.0)
}

/// Which samples [`measure`] counts: those on the wrong side of the mesh, those whose sphere it
/// enters (by the same margins), and the loops around its thin handles as vertex paths.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Marked {
    /// Samples on the wrong side (by winding number) with `|s| > SIGN_MARGIN h`.
    pub wrong_side: Vec<usize>,
    /// Samples whose sphere the mesh enters by more than `ENTER_MARGIN h`.
    pub entered: Vec<usize>,
    /// The loops of [`Consistency::thin_loops`], each a cycle of mesh vertices.
    pub thin_loops: Vec<Vec<u32>>,
}

/// The samples and loops [`measure`] counts, one sample at a time (for showing them: a winding
/// number and a distance per sample, without the grid's shortcuts).
pub fn marked(samples: &SdfSamples, mesh: &TriMesh, clamp: Option<f64>) -> Result<Marked> {
    if mesh.faces.is_empty() {
        return Ok(Marked::default());
    }
    let h = samples.spacing();
    let clamp = clamp.unwrap_or(f64::INFINITY);
    let index = MeshIndex::new(mesh)?;
    let values = samples.values();
    let flags: Vec<(bool, bool)> = (0..samples.len())
        .into_par_iter()
        .map(|i| {
            let (p, s) = (samples.position(i), values[i]);
            let wrong = s.abs() > SIGN_MARGIN * h && (index.winding_number(p) > 0.5) != (s < 0.0);
            let entered = index.unsigned_distance(p) < s.abs().min(clamp) - ENTER_MARGIN * h;
            (wrong, entered)
        })
        .collect();
    let topology = Topology::of(mesh);
    let thin_loops = if topology
        .genus()
        .is_none_or(|g| g == 0 || g > THIN_LOOP_MAX_GENUS)
    {
        Vec::new()
    } else {
        rfta_mesh::short_loops(mesh, THIN_LOOP * h)
            .map(|l| l.loops)
            .unwrap_or_default()
    };
    Ok(Marked {
        wrong_side: (0..flags.len()).filter(|&i| flags[i].0).collect(),
        entered: (0..flags.len()).filter(|&i| flags[i].1).collect(),
        thin_loops,
    })
}

/// [`measure`] with the mesh's topology already at hand (the pipeline computes it once for its
/// mesh check and this), and the samples whose spheres the mesh enters, ascending.
pub(crate) fn measure_with(
    samples: &SdfSamples,
    mesh: &TriMesh,
    topology: &Topology,
    clamp: Option<f64>,
) -> Result<(Consistency, Vec<usize>)> {
    let h = samples.spacing();
    let clamp = clamp.unwrap_or(f64::INFINITY);
    let values = samples.values();
    if mesh.faces.is_empty() {
        // No surface: every negative sample is on the wrong side, every unclamped one has a gap.
        let c = Consistency {
            samples: samples.len(),
            spacing: h,
            sign_errors: values.iter().filter(|&&s| s < -SIGN_MARGIN * h).count(),
            entered: 0,
            gaps: values.iter().filter(|s| s.abs() < clamp).count(),
            deepest_entry: 0.0,
            thin_loops: Vec::new(),
        };
        return Ok((c, Vec::new()));
    }
    let index = MeshIndex::new(mesh)?;
    let closed =
        topology.is_watertight() && topology.is_manifold() && topology.is_consistently_oriented();
    let on_grid = samples.as_grid().filter(|_| closed);
    // The pseudonormals serve only the per-sample check.
    let normals = (closed && on_grid.is_none()).then(|| Pseudonormals::of(mesh));
    let check = Check {
        mesh,
        index: &index,
        normals: normals.as_ref(),
        h,
        clamp,
    };
    let found = match on_grid {
        Some(grid) => check.grid(grid, values),
        None => check.each(&samples.positions(), values),
    };
    let c = Consistency {
        samples: samples.len(),
        spacing: h,
        sign_errors: found.sign_errors,
        entered: found.entered.len(),
        gaps: found.gaps,
        deepest_entry: found.deepest_entry,
        thin_loops: thin_loops(mesh, topology, h),
    };
    let mut entered = found.entered;
    entered.sort_unstable();
    Ok((c, entered))
}

/// Above this genus [`Consistency::thin_loops`] is not searched: the search keeps a class of
/// `2 genus` bits per edge (64 bytes per edge here).
pub(crate) const THIN_LOOP_MAX_GENUS: i64 = 256;

/// [`Consistency::thin_loops`]: only a closed surface with handles has loops to find.
fn thin_loops(mesh: &TriMesh, topology: &Topology, h: f64) -> Vec<f64> {
    if topology
        .genus()
        .is_none_or(|g| g == 0 || g > THIN_LOOP_MAX_GENUS)
    {
        return Vec::new();
    }
    rfta_mesh::short_loops(mesh, THIN_LOOP * h)
        .map(|loops| loops.lengths.iter().map(|l| l / h).collect())
        .unwrap_or_default()
}

/// One mesh against samples: the two ways of counting.
struct Check<'a> {
    mesh: &'a TriMesh,
    index: &'a MeshIndex,
    /// Present when the mesh is closed, manifold and consistently oriented.
    normals: Option<&'a Pseudonormals>,
    h: f64,
    clamp: f64,
}

/// Counts over samples, summed in order (so the same whatever the thread count), with the
/// samples whose spheres are entered.
#[derive(Debug, Clone, Default, PartialEq)]
struct Counts {
    sign_errors: usize,
    /// Ascending.
    entered: Vec<usize>,
    gaps: usize,
    deepest_entry: f64,
}

impl Counts {
    /// `self` then `o` (whose samples come after `self`'s).
    fn add(mut self, mut o: Counts) -> Counts {
        self.entered.append(&mut o.entered);
        Counts {
            sign_errors: self.sign_errors + o.sign_errors,
            entered: self.entered,
            gaps: self.gaps + o.gaps,
            deepest_entry: self.deepest_entry.max(o.deepest_entry),
        }
    }
}

/// How far the mesh is from one sample, as far as the margins need it.
struct Distance {
    entered: bool,
    gap: bool,
    /// `min(|s|, clamp) - d` over `h` when positive, else 0.
    entry: f64,
    /// A radius about the sample that no point of the mesh is nearer than (the exact distance
    /// when the sphere is entered, the margin's bound otherwise).
    empty: f64,
}

impl Check<'_> {
    /// The distance part of the check, by a shell query: exact only where the sphere is entered.
    fn distance(&self, p: DVec3, s: f64) -> Distance {
        let (r, h) = (s.abs().min(self.clamp), self.h);
        let (lo, hi) = (r - ENTER_MARGIN * h, r + GAP_MARGIN * h);
        match self.index.shell(p, lo, hi) {
            Shell::Closer(c) => {
                let d = c.distance_squared.sqrt();
                Distance {
                    entered: true,
                    gap: false,
                    entry: (r - d) / h.max(f64::MIN_POSITIVE),
                    empty: d,
                }
            }
            Shell::Within => Distance {
                entered: false,
                gap: false,
                entry: 0.0,
                empty: lo.max(0.0),
            },
            Shell::Beyond => Distance {
                entered: false,
                gap: s.abs() < self.clamp,
                entry: 0.0,
                empty: hi,
            },
        }
    }

    /// Every sample on its own: one nearest-point query within the gap margin, the side by the
    /// pseudonormal of the nearest feature where the mesh is closed, manifold and consistently
    /// oriented, else (or on the mesh) by the winding number. A pseudonormal can be wrong where
    /// faces fold over (the mesh intersects itself there), so a sign error it finds is confirmed
    /// by the winding number.
    fn each(&self, positions: &[DVec3], values: &[f64]) -> Counts {
        let (h, clamp) = (self.h, self.clamp);
        (0..positions.len())
            .into_par_iter()
            .map(|i| {
                let (p, s) = (positions[i], values[i]);
                let r = s.abs().min(clamp);
                // Nothing farther than the gap margin matters for the distances: the bound lets
                // the search prune almost every box (the mesh is about |s| away).
                let reach = r + GAP_MARGIN * h;
                let near = self.index.closest_point_within(p, reach * reach);
                let d = near
                    .as_ref()
                    .map_or(f64::INFINITY, |c| c.distance_squared.sqrt());
                let entry = r - d;
                let by_winding = || self.index.winding_number(p) > 0.5;
                let sign_error = s.abs() > SIGN_MARGIN * h && {
                    let side = match (self.normals, &near) {
                        (Some(n), Some(c)) if c.distance_squared > 0.0 => {
                            let dot = (p - c.point).dot(n.at(self.mesh, c));
                            (dot != 0.0).then_some(dot < 0.0)
                        }
                        _ => None,
                    };
                    let wrong = |inside: bool| inside != (s < 0.0);
                    match side {
                        Some(inside) => wrong(inside) && wrong(by_winding()),
                        None => wrong(by_winding()),
                    }
                };
                Counts {
                    sign_errors: usize::from(sign_error),
                    entered: if entry > ENTER_MARGIN * h {
                        vec![i]
                    } else {
                        Vec::new()
                    },
                    gaps: usize::from(s.abs() < clamp && d > s.abs() + GAP_MARGIN * h),
                    deepest_entry: entry.max(0.0) / h.max(f64::MIN_POSITIVE),
                }
            })
            .reduce(Counts::default, Counts::add)
    }

    /// Samples on a grid against a closed mesh. The side of the mesh is the same all along a
    /// segment that does not meet it, and no point of the mesh is nearer to a sample than its
    /// [`Distance::empty`] radius: two neighbouring samples whose empty balls together cover the
    /// segment between them are on the same side. The side is computed once per group of samples
    /// so joined (the far samples form a few large groups), by the union of those segments.
    fn grid(&self, grid: &Grid, values: &[f64]) -> Counts {
        // The distance part of the counts, and each sample's empty radius for the groups (8
        // bytes a sample: a 257^3 grid has 17 million).
        const CHUNK: usize = 1024;
        let mut empty = vec![0.0; grid.len()];
        let distances = empty
            .par_chunks_mut(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut counts = Counts::default();
                for (k, e) in chunk.iter_mut().enumerate() {
                    let i = c * CHUNK + k;
                    let d = self.distance(grid.position(i), values[i]);
                    *e = d.empty;
                    if d.entered {
                        counts.entered.push(i);
                    }
                    counts.gaps += usize::from(d.gap);
                    counts.deepest_entry = counts.deepest_entry.max(d.entry);
                }
                counts
            })
            .reduce(Counts::default, Counts::add);
        let mut groups = UnionFind::new(grid.len());
        let [nx, ny, nz] = grid.dims();
        let step = grid.spacing();
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    let a = grid.index(i, j, k);
                    let mut join = |b: usize, gap: f64| {
                        if empty[a] + empty[b] > gap {
                            groups.union(a, b);
                        }
                    };
                    if i + 1 < nx {
                        join(grid.index(i + 1, j, k), step.x);
                    }
                    if j + 1 < ny {
                        join(grid.index(i, j + 1, k), step.y);
                    }
                    if k + 1 < nz {
                        join(grid.index(i, j, k + 1), step.z);
                    }
                }
            }
        }
        let roots: Vec<usize> = (0..grid.len()).map(|i| groups.find(i)).collect();
        // The side of each group at its first sample, by the winding number (a few thousand
        // groups at 129^3).
        let inside: Vec<bool> = (0..grid.len())
            .into_par_iter()
            .map(|i| roots[i] == i && self.index.winding_number(grid.position(i)) > 0.5)
            .collect();
        let sign_errors = (0..grid.len())
            .into_par_iter()
            .filter(|&i| {
                values[i].abs() > SIGN_MARGIN * self.h && inside[roots[i]] != (values[i] < 0.0)
            })
            .count();
        Counts {
            sign_errors,
            ..distances
        }
    }
}

/// Angle-weighted pseudonormals of a closed mesh's vertices and edges (Bærentzen and Aanæs, "Signed
/// distance computation using the angle weighted pseudonormal", IEEE TVCG 2005): the side of a
/// point is the sign of `(p - c) . n`, with `c` its nearest point on the mesh and `n` the
/// pseudonormal of the face, edge or vertex `c` lies on. Exact for closed, manifold, consistently
/// oriented meshes; far cheaper than a winding number.
struct Pseudonormals {
    /// Unit normal of each face (zero for a face of zero area).
    face: Vec<DVec3>,
    /// Per vertex: the sum of its faces' unit normals weighted by the face's angle there.
    vertex: Vec<DVec3>,
    /// Per edge (smaller vertex index first): the sum of its two faces' unit normals.
    edge: std::collections::HashMap<(u32, u32), DVec3>,
}

impl Pseudonormals {
    fn of(mesh: &TriMesh) -> Self {
        let face: Vec<DVec3> = (0..mesh.faces.len())
            .map(|f| mesh.face_normal_scaled(f).normalize_or_zero())
            .collect();
        let mut vertex = vec![DVec3::ZERO; mesh.vertices.len()];
        let mut edge = std::collections::HashMap::with_capacity(mesh.faces.len() * 3 / 2);
        let p = |v: u32| mesh.vertices[v as usize];
        for (f, ids) in mesh.faces.iter().enumerate() {
            let n = face[f];
            for k in 0..3 {
                let (a, b, c) = (ids[k], ids[(k + 1) % 3], ids[(k + 2) % 3]);
                let angle = (p(b) - p(a)).angle_between(p(c) - p(a));
                if angle.is_finite() {
                    vertex[a as usize] += angle * n;
                }
                *edge.entry((a.min(b), a.max(b))).or_insert(DVec3::ZERO) += n;
            }
        }
        Self { face, vertex, edge }
    }

    /// The pseudonormal at a nearest point: the face's when it lies inside the face, the edge's
    /// or the vertex's when one or two barycentric coordinates are zero (the nearest-point
    /// kernel returns exact zeros there).
    fn at(&self, mesh: &TriMesh, c: &rfta_mesh::ClosestPoint) -> DVec3 {
        let ids = mesh.faces[c.face as usize];
        let mut on = [0u32; 3];
        let mut k = 0;
        for (v, &b) in ids.iter().zip(&c.barycentric) {
            if b != 0.0 {
                on[k] = *v;
                k += 1;
            }
        }
        match k {
            1 => self.vertex[on[0] as usize],
            2 => self
                .edge
                .get(&(on[0].min(on[1]), on[0].max(on[1])))
                .copied()
                .unwrap_or(DVec3::ZERO),
            _ => self.face[c.face as usize],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::{Grid, shapes};

    /// The sphere of radius 0.5 sampled on 21^3 points of [-1, 1]^3 (h = 0.1).
    fn ball_grid() -> SdfSamples {
        let grid = Grid::cube(20, -1.0, 1.0).expect("grid");
        let values = (0..grid.len())
            .map(|i| grid.position(i).length() - 0.5)
            .collect();
        SdfSamples::grid(grid, values).expect("samples")
    }

    #[test]
    fn the_true_surface_agrees_with_every_sample() {
        let samples = ball_grid();
        // Chord error of the 5-times subdivided icosphere: about 1e-4, far below the margins.
        let c = measure(&samples, &shapes::icosphere(0.5, 5), None).expect("measure");
        assert_eq!(c.samples, 21 * 21 * 21);
        assert!((c.spacing - 0.1).abs() < 1e-12);
        assert_eq!((c.sign_errors, c.entered, c.gaps), (0, 0, 0));
        assert!(c.deepest_entry < 0.01, "{}", c.deepest_entry);
        assert!(c.is_consistent());
    }

    /// A surface inflated by `e`: a sample at distance `t = |p|` from the centre is `|t - R|` from
    /// it. Counted from that formula, with no sample within 5e-4 of a margin (checked) so the
    /// tessellation cannot tip one; the samples found entered are those the formula says.
    #[test]
    fn an_inflated_surface_is_counted_sample_by_sample() {
        let samples = ball_grid();
        let radius = 0.5 + 0.037;
        let mesh = shapes::icosphere(radius, 5);
        let (c, entered_at) =
            measure_with(&samples, &mesh, &Topology::of(&mesh), None).expect("measure");
        let h = 0.1;
        let (mut wrong, mut entered, mut gaps) = (0, 0, 0);
        let mut by_formula = Vec::new();
        for (i, (p, &s)) in samples.positions().iter().zip(samples.values()).enumerate() {
            let d = (p.length() - radius).abs();
            let inside = p.length() < radius;
            for edge in [
                s.abs() - SIGN_MARGIN * h,
                s.abs() - d - ENTER_MARGIN * h,
                d - s.abs() - GAP_MARGIN * h,
            ] {
                assert!(edge.abs() > 5e-4, "sample {p} is on a margin");
            }
            wrong += usize::from(s.abs() > SIGN_MARGIN * h && inside != (s < 0.0));
            entered += usize::from(d < s.abs() - ENTER_MARGIN * h);
            if d < s.abs() - ENTER_MARGIN * h {
                by_formula.push(i);
            }
            gaps += usize::from(d > s.abs() + GAP_MARGIN * h);
        }
        // Outside samples are entered by 0.037 (more than 0.01), inside ones are 0.037 farther
        // from the mesh than their value (more than 0.025), and samples between the two radii
        // are inside the mesh with a positive value.
        assert!(
            entered > 1000 && gaps > 100 && wrong > 0,
            "{entered} {gaps} {wrong}"
        );
        assert_eq!((c.sign_errors, c.entered, c.gaps), (wrong, entered, gaps));
        assert_eq!(entered_at, by_formula);
        assert!((c.deepest_entry - 0.37).abs() < 0.01, "{}", c.deepest_entry);
    }

    /// The grid's shortcut (sides by groups of samples joined through their empty balls) counts
    /// as checking every sample on its own does, on closed meshes that disagree with the samples
    /// in every way: shifted (sign errors, entered spheres, gaps on either side), with a spurious
    /// ball among the outside samples and a cavity inside the shape (each a component of its own),
    /// and a coarse torus whose hole and tube are far from the ball's samples.
    #[test]
    fn groups_of_grid_samples_count_as_each_sample_does() {
        let samples = ball_grid();
        let shifted = |m: TriMesh, by: DVec3| TriMesh {
            vertices: m.vertices.iter().map(|v| *v + by).collect(),
            ..m
        };
        let union = |parts: Vec<TriMesh>| {
            let mut out = TriMesh::default();
            for m in &parts {
                out.append(m);
            }
            out
        };
        let mut cavity = shapes::icosphere(0.2, 3);
        cavity.flip();
        for mesh in [
            shifted(shapes::icosphere(0.5, 4), DVec3::new(0.13, -0.06, 0.02)),
            union(vec![
                shapes::icosphere(0.5, 4),
                shifted(shapes::icosphere(0.15, 3), DVec3::new(0.7, 0.1, -0.2)),
                cavity,
            ]),
            shapes::torus(0.55, 0.2, 24, 12),
        ] {
            let topology = Topology::of(&mesh);
            assert!(topology.is_watertight() && topology.is_consistently_oriented());
            let index = MeshIndex::new(&mesh).expect("index");
            let normals = Pseudonormals::of(&mesh);
            let check = Check {
                mesh: &mesh,
                index: &index,
                normals: Some(&normals),
                h: samples.spacing(),
                clamp: f64::INFINITY,
            };
            let grid = samples.as_grid().expect("grid");
            let by_groups = check.grid(grid, samples.values());
            let each = check.each(&samples.positions(), samples.values());
            assert!(
                by_groups.sign_errors > 10 && by_groups.entered.len() > 10,
                "{by_groups:?}"
            );
            assert_eq!(by_groups.sign_errors, each.sign_errors);
            assert_eq!(by_groups.entered, each.entered);
            assert_eq!(by_groups.gaps, each.gaps);
            assert!((by_groups.deepest_entry - each.deepest_entry).abs() < 1e-9);
        }
    }

    /// A torus whose tube is 0.06 across (0.19 around) agrees with its own samples at 21^3
    /// (h = 0.1) and at 101^3 (h = 0.02): only the coarse grid cannot resolve the tube (its loop
    /// is 1.9 h < pi h there, 9.4 h on the fine grid); the hole, 2 pi 0.47 around, is not thin.
    #[test]
    fn a_tube_thinner_than_a_spacing_is_a_thin_handle() {
        let torus = shapes::torus(0.5, 0.03, 96, 12);
        let tube = 24.0 * 0.03 * (std::f64::consts::PI / 12.0).sin();
        for (n, thin) in [(20, true), (100, false)] {
            let grid = Grid::cube(n, -1.0, 1.0).expect("grid");
            let shape = rfta_testkit::Analytic::Torus {
                major: 0.5,
                minor: 0.03,
            };
            let values = (0..grid.len())
                .map(|i| shape.sdf(grid.position(i)))
                .collect();
            let samples = SdfSamples::grid(grid, values).expect("samples");
            let c = measure(&samples, &torus, None).expect("measure");
            let h = 2.0 / n as f64;
            if thin {
                assert_eq!(c.thin_loops.len(), 1, "{:?}", c.thin_loops);
                assert!(
                    (c.thin_loops[0] - tube / h).abs() < 1e-9,
                    "{:?}",
                    c.thin_loops
                );
            } else {
                assert!(c.thin_loops.is_empty(), "{:?}", c.thin_loops);
            }
        }
        // A sphere has no handle to be thin.
        let c = measure(&ball_grid(), &shapes::icosphere(0.5, 3), None).expect("measure");
        assert!(c.thin_loops.is_empty());
    }

    #[test]
    fn no_surface_puts_every_inside_sample_on_the_wrong_side() {
        let samples = ball_grid();
        let c = measure(&samples, &TriMesh::default(), Some(0.8)).expect("measure");
        let inside = samples.values().iter().filter(|&&s| s < -0.001).count();
        let unclamped = samples.values().iter().filter(|s| s.abs() < 0.8).count();
        assert_eq!((c.sign_errors, c.entered, c.gaps), (inside, 0, unclamped));
    }

    /// On closed meshes with sharp vertices and edges (a coarse torus, a cube), the pseudonormal
    /// of the nearest feature and the winding number agree on the side of every query point.
    #[test]
    fn pseudonormals_tell_the_side_as_the_winding_number_does() {
        let mut rng = rfta_geom::rng::Rng::new(3);
        for mesh in [
            shapes::torus(0.6, 0.25, 9, 5),
            shapes::cuboid(DVec3::new(0.5, 0.3, 0.2)),
            shapes::octahedron(0.7),
        ] {
            let index = MeshIndex::new(&mesh).expect("index");
            let normals = Pseudonormals::of(&mesh);
            let (mut features, mut checked) = ([0usize; 4], 0);
            for _ in 0..4000 {
                let p = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.2
                    - DVec3::splat(1.1);
                let c = index.closest_point(p);
                let nonzero = c.barycentric.iter().filter(|&&b| b != 0.0).count();
                features[nonzero] += 1;
                let w = index.winding_number_exact(p);
                if c.distance_squared < 1e-12 || (w - 0.5).abs() < 0.25 {
                    continue;
                }
                let by_normal = (p - c.point).dot(normals.at(&mesh, &c)) < 0.0;
                assert_eq!(by_normal, w > 0.5, "{p} (winding {w})");
                checked += 1;
            }
            // Vertices, edges and faces were all nearest features.
            assert!(
                features[1] > 50 && features[2] > 50 && features[3] > 50,
                "{features:?}"
            );
            assert!(checked > 3900, "{checked}");
        }
    }

    /// The samples `marked` lists are the ones `measure` counts (a ball's mesh against a torus's
    /// grid: many on the wrong side, many spheres entered), on a grid and scattered.
    #[test]
    fn the_marked_samples_are_the_counted_ones() {
        let grid = rfta_geom::Grid::cube(12, -1.0, 1.0).expect("grid");
        let torus = |p: DVec3| {
            let ring = (p.x * p.x + p.y * p.y).sqrt() - 0.55;
            (ring * ring + p.z * p.z).sqrt() - 0.25
        };
        let values: Vec<f64> = (0..grid.len()).map(|i| torus(grid.position(i))).collect();
        let mesh = rfta_geom::shapes::icosphere(0.6, 3);
        let positions: Vec<DVec3> = (0..grid.len()).map(|i| grid.position(i)).collect();
        for samples in [
            SdfSamples::grid(grid, values.clone()).expect("samples"),
            SdfSamples::scattered(positions, values).expect("samples"),
        ] {
            let counted = measure(&samples, &mesh, None).expect("measure");
            let found = marked(&samples, &mesh, None).expect("marked");
            assert!(
                counted.sign_errors > 10 && counted.entered > 10,
                "{counted:?}"
            );
            assert_eq!(found.wrong_side.len(), counted.sign_errors);
            assert_eq!(found.entered.len(), counted.entered);
            assert!(found.thin_loops.is_empty());
        }
    }
}
