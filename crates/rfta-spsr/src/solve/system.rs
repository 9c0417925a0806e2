//! Each depth's system: the screening cells and value constraints, the stiffness and mass
//! tables, and the splatted normal field's divergence.

use super::*;

/// Aggregated screening sample of one cell (all samples inside it, weight-averaged).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScreenCell {
    /// Cell index in its level.
    pub cell: u32,
    /// Screening weight `α ā Σ w`.
    pub weight: f64,
    /// Weight-averaged position, unit cube.
    pub pos: DVec3,
    /// Hat values at the eight corners.
    pub hats: [f64; 8],
    /// The value the screening pulls the function toward here: 1/2 at the samples, a side's value
    /// at a [`ValueConstraint`].
    pub target: f64,
}

/// A point where the function is screened toward a value of its own (unit cube): the side
/// constraints of [`crate::reconstruct_with_sides`], with a weight in the samples' units
/// ([`Sample::weight`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ValueConstraint {
    pub pos: DVec3,
    pub target: f64,
    pub weight: f64,
}

/// Everything a depth needs to relax its own system.
pub(crate) struct LevelSystem {
    pub tables: AxisTables,
    pub screen: Vec<ScreenCell>,
    /// CSR: for node `i`, `inc[inc_off[i]..inc_off[i + 1]]` = `screen index << 3 | corner`.
    pub inc_off: Vec<u32>,
    pub inc: Vec<u32>,
    pub diag: Vec<f64>,
    /// Dirichlet: nodes on the cube's faces are pinned to 0.
    pub fixed: Vec<bool>,
    pub(super) interior: [f64; 27],
}

impl LevelSystem {
    /// Laplacian entry between node `c` and its neighbour at offset `o`.
    #[inline]
    pub(super) fn k(&self, c: [u32; 3], o: usize, n: u32) -> f64 {
        if c.iter().all(|&v| v >= 1 && v < n) {
            return self.interior[o];
        }
        let t = &self.tables.same;
        let off = offset(o);
        let a = |axis: usize| &t[c[axis] as usize][(off[axis] + 1) as usize];
        combine(a(0), a(1), a(2)).0
    }
}

/// Build the per-depth systems: neighbour tables, screening cells and diagonals.
pub(crate) fn build_systems(
    levels: &[Level],
    samples: &[Sample],
    constraints: &[ValueConstraint],
    params: &SpsrParams,
    alpha: f64,
) -> Vec<LevelSystem> {
    let depth = levels.len() as u32 - 1;
    levels
        .par_iter()
        .map(|level| {
            let d = level.depth;
            let n = level.n();
            let tables = AxisTables::new(d);

            let screen = screening_cells(level, samples, constraints, alpha, depth);
            let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(screen.len() * 8);
            for (s, sc) in screen.iter().enumerate() {
                for (k, &node) in level.corners[sc.cell as usize].iter().enumerate() {
                    pairs.push((node, ((s as u32) << 3) | k as u32));
                }
            }
            pairs.par_sort_unstable();
            let mut inc_off = vec![0u32; level.nodes.len() + 1];
            for &(node, _) in &pairs {
                inc_off[node as usize + 1] += 1;
            }
            for i in 0..level.nodes.len() {
                inc_off[i + 1] += inc_off[i];
            }
            let inc: Vec<u32> = pairs.iter().map(|p| p.1).collect();
            let mut interior = [0.0; 27];
            if n >= 2 {
                for (o, v) in interior.iter_mut().enumerate() {
                    let off = offset(o);
                    let a = |axis: usize| &tables.same[1][(off[axis] + 1) as usize];
                    *v = combine(a(0), a(1), a(2)).0;
                }
            }
            let fixed: Vec<bool> = level
                .nodes
                .par_iter()
                .map(|c| {
                    params.boundary == Boundary::Dirichlet && c.iter().any(|&v| v == 0 || v == n)
                })
                .collect();
            let mut sys = LevelSystem {
                tables,
                screen,
                inc_off,
                inc,
                diag: Vec::new(),
                fixed,
                interior,
            };
            let diag: Vec<f64> = (0..level.nodes.len())
                .into_par_iter()
                .map(|i| {
                    let mut v = sys.k(level.nodes[i], 13, n);
                    for &e in &sys.inc[sys.inc_off[i] as usize..sys.inc_off[i + 1] as usize] {
                        let sc = &sys.screen[(e >> 3) as usize];
                        let h = sc.hats[(e & 7) as usize];
                        v += sc.weight * h * h;
                    }
                    v
                })
                .collect();
            sys.diag = diag;
            sys
        })
        .collect()
}

/// The screening terms of `level`: the samples grouped by their depth-`d` cell (Morton order is
/// preserved), then the value constraints the level's tree reaches, each on its own.
fn screening_cells(
    level: &Level,
    samples: &[Sample],
    constraints: &[ValueConstraint],
    alpha: f64,
    depth: u32,
) -> Vec<ScreenCell> {
    let d = level.depth;
    // Screening cells: samples grouped by their depth-d cell (Morton order is preserved).
    // As in PoissonRecon (Kazhdan and Hoppe 2013, §4.3; `adaptiveExponent` 1), the
    // screening weight grows as 2^d with depth: the Laplacian's entries shrink with the
    // cell width while a cell's samples keep their weight, and this keeps the pull toward
    // the samples equally strong against the smoothness term at every depth.
    let depth_scale = f64::from(1u32 << d);
    let shift = 3 * (depth - d);
    let mut screen = Vec::new();
    let mut i = 0;
    while i < samples.len() {
        let key = samples[i].key >> shift;
        let mut j = i;
        let (mut w, mut p) = (0.0, DVec3::ZERO);
        while j < samples.len() && samples[j].key >> shift == key {
            w += samples[j].weight;
            p += samples[j].weight * samples[j].pos;
            j += 1;
        }
        let cc = crate::keys::demorton(key);
        if let Some(cell) = level.cell(ic(cc))
            && alpha > 0.0
        {
            let pos = p / w;
            screen.push(ScreenCell {
                cell,
                weight: alpha * depth_scale * w,
                pos,
                hats: hats_in(pos, cc, d),
                target: SAMPLE_TARGET,
            });
        }
        i = j;
    }
    // Value constraints act on the depths whose tree reaches them, each on its own.
    if alpha > 0.0 {
        for c in constraints {
            let cc = cell_of(c.pos, d);
            if let Some(cell) = level.cell(ic(cc)) {
                screen.push(ScreenCell {
                    cell,
                    weight: alpha * depth_scale * c.weight,
                    pos: c.pos,
                    hats: hats_in(c.pos, cc, d),
                    target: c.target,
                });
            }
        }
    }
    screen
}

/// Splat the (inward) normal field: each sample's area-weighted normal goes to the hats of the two
/// depths bracketing its fractional depth, linearly weighted. Returns per depth the coefficients
/// of `V` in that depth's hat basis (divided by the cell volume so that `V` integrates to the
/// sample's area times its normal).
pub(crate) fn splat_normals(levels: &[Level], samples: &[Sample]) -> Vec<Vec<DVec3>> {
    // One depth per task: a depth's coefficients receive the samples in their order, as a single
    // pass over the samples would add them.
    levels
        .par_iter()
        .map(|level| {
            let d = level.depth;
            let mut v = vec![DVec3::ZERO; level.nodes.len()];
            let nf = f64::from(1u32 << d);
            let inv_vol = nf.powi(3);
            for s in samples {
                let d0 = s.depth.floor() as u32;
                let t = s.depth - f64::from(d0);
                let w = if d == d0 {
                    1.0 - t
                } else if d == d0 + 1 {
                    t
                } else {
                    continue;
                };
                if w <= 0.0 {
                    continue;
                }
                let normal = -s.normal * (s.area / s.weight);
                // Quadratic B-spline weights of the three nearest nodes per axis: the normal
                // field is the hat interpolation of a degree-2 kernel around the sample (as
                // smooth as PoissonRecon's degree-2 normal splat; the weights sum to 1 so V keeps
                // its integral).
                let mut idx = [[0i64; 3]; 3];
                let mut wts = [[0.0f64; 3]; 3];
                for axis in 0..3 {
                    let x = s.pos[axis] * nf;
                    let r = x.round() as i64;
                    for (k, j) in (r - 1..=r + 1).enumerate() {
                        idx[axis][k] = j;
                        wts[axis][k] = quadratic_bspline(j as f64 - x);
                    }
                }
                for (kz, &jz) in idx[2].iter().enumerate() {
                    for (ky, &jy) in idx[1].iter().enumerate() {
                        for (kx, &jx) in idx[0].iter().enumerate() {
                            let h = wts[0][kx] * wts[1][ky] * wts[2][kz];
                            if h == 0.0 {
                                continue;
                            }
                            if let Some(node) = level.node([jx, jy, jz]) {
                                v[node as usize] += normal * (w * h * inv_vol);
                            }
                        }
                    }
                }
            }
            v
        })
        .collect()
}

/// The centred quadratic B-spline (support `[-1.5, 1.5]`, integral 1).
#[inline]
pub(crate) fn quadratic_bspline(t: f64) -> f64 {
    let a = t.abs();
    if a <= 0.5 {
        0.75 - a * a
    } else if a < 1.5 {
        0.5 * (1.5 - a) * (1.5 - a)
    } else {
        0.0
    }
}

/// `∫ ∇B_i · V_d` for every node of a depth, `V_d` given by same-depth coefficients.
pub(super) fn apply_g(level: &Level, tables: &AxisTables, nbr: Stencil, v: &[DVec3]) -> Vec<f64> {
    let t = &tables.same;
    (0..level.nodes.len())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|i| {
            let c = level.nodes[i];
            let mut acc = 0.0;
            for (o, j) in nbr.of(i).into_iter().enumerate() {
                if j == NONE {
                    continue;
                }
                let vj = v[j as usize];
                if vj == DVec3::ZERO {
                    continue;
                }
                let off = offset(o);
                let a = |axis: usize| &t[c[axis] as usize][(off[axis] + 1) as usize];
                let (_, g) = combine(a(0), a(1), a(2));
                acc += g[0] * vj.x + g[1] * vj.y + g[2] * vj.z;
            }
            acc
        })
        .collect()
}
