//! The inexact evaluation's fields: the dev shapes' trained networks ([`super::mlp`]) and CSG
//! trees of exact distances (bounds, not distances, wherever min or max switches), each with
//! the reference its meshes are scored against: its own zero set, by marching cubes on a fine
//! grid evaluated where the zero set passes.

use std::path::Path;

use anyhow::{Context, Result};
use rayon::prelude::*;
use rfta_geom::glam::DVec3;
use rfta_geom::{Grid, TriMesh};

use super::mlp::Mlp;

/// What a field is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A network fitted to a dev shape's distance.
    Network,
    /// A CSG tree of exact distances (1-Lipschitz).
    Csg,
}

impl Kind {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Kind::Network => "network",
            Kind::Csg => "csg",
        }
    }
}

type Eval = Box<dyn Fn(&[DVec3]) -> Vec<f64> + Sync>;

/// A field that is not a distance.
pub(crate) struct Field {
    pub(crate) name: String,
    pub(crate) kind: Kind,
    /// A network's weights.
    pub(crate) path: Option<std::path::PathBuf>,
    eval: Eval,
}

impl Field {
    /// The field's values at `points`.
    pub(crate) fn values(&self, points: &[DVec3]) -> Vec<f64> {
        (self.eval)(points)
    }

    /// The field on `linspace(-1, 1, n + 1)^3`.
    pub(crate) fn grid(&self, n: usize) -> Result<(Grid, Vec<f64>)> {
        let grid = Grid::cube(n, -1.0, 1.0)?;
        let points: Vec<DVec3> = (0..grid.len()).map(|i| grid.position(i)).collect();
        Ok((grid, self.values(&points)))
    }

    /// The zero set by marching cubes on `linspace(-1, 1, res + 1)^3`: CSG fields are
    /// 1-Lipschitz, evaluated where their bound does not rule the surface out
    /// ([`crate::swept::band_limited`]); networks by refining the cells around sign changes
    /// ([`sign_refined`]).
    pub(crate) fn reference(&self, res: usize) -> Result<TriMesh> {
        let (grid, values) = match self.kind {
            Kind::Csg => {
                let f = |p: DVec3| self.values(&[p])[0];
                crate::swept::band_limited(&f, res)?
            }
            Kind::Network => sign_refined(self, res)?,
        };
        Ok(rfta_mc::marching_cubes(&grid, &values, 0.0))
    }
}

/// Each `NAME.npy` network in `dir`, sorted by name, as a field `network-NAME`; `only` keeps
/// those named.
pub(crate) fn networks(dir: &Path, only: &[String]) -> Result<Vec<Field>> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot list {}", dir.display()))?
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            name.strip_suffix(".npy").map(str::to_string)
        })
        .filter(|n| only.is_empty() || only.contains(n))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|name| {
            let path = dir.join(format!("{name}.npy"));
            let net = Mlp::load(&path)?;
            Ok(Field {
                name: format!("network-{name}"),
                kind: Kind::Network,
                path: Some(path),
                eval: Box::new(move |p| net.values(p)),
            })
        })
        .collect()
}

fn boxed(p: DVec3, half: DVec3) -> f64 {
    let q = p.abs() - half;
    q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
}

fn ball(p: DVec3, centre: DVec3, r: f64) -> f64 {
    (p - centre).length() - r
}

/// A torus about the z axis through `centre`.
fn torus(p: DVec3, centre: DVec3, major: f64, minor: f64) -> f64 {
    let q = p - centre;
    let ring = q.truncate().length() - major;
    (ring * ring + q.z * q.z).sqrt() - minor
}

fn capsule(p: DVec3, a: DVec3, b: DVec3, r: f64) -> f64 {
    let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
    (p - a - t * (b - a)).length() - r
}

/// An infinite cylinder of radius `r` along axis `axis` through the origin.
fn cylinder(p: DVec3, axis: usize, r: f64) -> f64 {
    let mut q = p;
    q[axis] = 0.0;
    q.length() - r
}

/// The polynomial smooth minimum of blend width `k` (a bound below the distance near the
/// blend).
fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k / 4.0
}

/// The CSG fields, each a name and its function.
type Csg = (&'static str, fn(DVec3) -> f64);

const CSG: [Csg; 4] = [
    // A box with a corner bitten off by a ball, united with a torus that leaves and re-enters
    // its four sides.
    ("csg-box-ball-torus", |p| {
        let bitten =
            boxed(p, DVec3::new(0.45, 0.45, 0.2)).max(-ball(p, DVec3::new(0.45, 0.45, 0.2), 0.3));
        bitten.min(torus(p, DVec3::ZERO, 0.55, 0.12))
    }),
    // A cube and a ball intersected.
    ("csg-rounded-cube", |p| {
        boxed(p, DVec3::splat(0.5)).max(ball(p, DVec3::ZERO, 0.65))
    }),
    // The classic CSG tree: a cube and a ball intersected, three cylinders drilled through.
    ("csg-drilled", |p| {
        let body = boxed(p, DVec3::splat(0.45)).max(ball(p, DVec3::ZERO, 0.6));
        let drills = (0..3)
            .map(|a| cylinder(p, a, 0.2))
            .fold(f64::INFINITY, f64::min);
        body.max(-drills)
    }),
    // A ball and a capsule blended by a smooth minimum.
    ("csg-blend", |p| {
        smooth_min(
            ball(p, DVec3::new(-0.3, 0.0, 0.0), 0.35),
            capsule(
                p,
                DVec3::new(0.1, -0.4, 0.0),
                DVec3::new(0.3, 0.45, 0.1),
                0.15,
            ),
            0.25,
        )
    }),
];

/// The CSG fields; `only` keeps those named.
pub(crate) fn csg(only: &[String]) -> Vec<Field> {
    CSG.iter()
        .filter(|(name, _)| only.is_empty() || only.iter().any(|o| o == name))
        .map(|&(name, f)| Field {
            name: name.into(),
            kind: Kind::Csg,
            path: None,
            eval: Box::new(move |p| p.iter().map(|&q| f(q)).collect()),
        })
        .collect()
}

/// `field` on `linspace(-1, 1, res + 1)^3`, exact at every corner of a cell around a sign
/// change and of the right sign elsewhere, for fields with no bound on their slope (a network's
/// values flatten far from the surface): a coarse grid (32 or more cells) everywhere, then at
/// each halving of the spacing the nodes of the cells whose corners change sign and of their
/// neighbours (MISE's rule, with a cell of margin); every other node takes its nearest coarser
/// node's value.
pub(crate) fn sign_refined(field: &Field, res: usize) -> Result<(Grid, Vec<f64>)> {
    let mut m = res;
    while m.is_multiple_of(2) && m / 2 >= 32 {
        m /= 2;
    }
    let (_, mut values) = field.grid(m)?;
    while m < res {
        let coarse = Grid::cube(m, -1.0, 1.0)?;
        let fine = Grid::cube(2 * m, -1.0, 1.0)?;
        let marked = dilate(&crossed_cells(&coarse, &values), m);
        let need: Vec<usize> = (0..fine.len())
            .into_par_iter()
            .filter(|&i| {
                let ijk = fine.ijk(i);
                // The coarse cells touching the node, per axis.
                let range = |a: usize| {
                    let c = ijk[a] / 2;
                    if ijk[a] % 2 == 1 {
                        c..=c
                    } else {
                        c.saturating_sub(1)..=c.min(m - 1)
                    }
                };
                range(0).any(|a| range(1).any(|b| range(2).any(|c| marked[(a * m + b) * m + c])))
            })
            .collect();
        let points: Vec<DVec3> = need.iter().map(|&i| fine.position(i)).collect();
        let found = field.values(&points);
        let mut next: Vec<f64> = (0..fine.len())
            .into_par_iter()
            .map(|i| {
                let [a, b, c] = fine.ijk(i).map(|x| x.div_ceil(2).min(m));
                values[coarse.index(a, b, c)]
            })
            .collect();
        for (&i, v) in need.iter().zip(found) {
            next[i] = v;
        }
        values = next;
        m *= 2;
    }
    Ok((Grid::cube(m, -1.0, 1.0)?, values))
}

/// For each cell of `grid` (`m^3`, flat), whether its corners change sign.
fn crossed_cells(grid: &Grid, values: &[f64]) -> Vec<bool> {
    let m = grid.dims()[0] - 1;
    (0..m * m * m)
        .into_par_iter()
        .map(|cell| {
            let (a, b, c) = (cell / (m * m), (cell / m) % m, cell % m);
            let corner =
                |k: usize| values[grid.index(a + (k & 1), b + ((k >> 1) & 1), c + (k >> 2))];
            let inside = corner(0) < 0.0;
            (1..8).any(|k| (corner(k) < 0.0) != inside)
        })
        .collect()
}

/// The cells marked or next to a marked one (26 neighbours), of `m^3`.
fn dilate(marked: &[bool], m: usize) -> Vec<bool> {
    (0..m * m * m)
        .into_par_iter()
        .map(|cell| {
            let ijk = [cell / (m * m), (cell / m) % m, cell % m];
            let span = |x: usize| x.saturating_sub(1)..=(x + 1).min(m - 1);
            span(ijk[0])
                .any(|a| span(ijk[1]).any(|b| span(ijk[2]).any(|c| marked[(a * m + b) * m + c])))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A field with no slope bound (a sphere's distance, flattened by tanh far out as a network
    /// trained on a clamp is): the refined grid's marching cubes equals the full grid's.
    #[test]
    fn sign_refinement_gives_marching_cubes_of_the_full_grid() {
        let f = Field {
            name: "flat sphere".into(),
            kind: Kind::Network,
            path: None,
            eval: Box::new(|p| {
                p.iter()
                    .map(|q| 0.05 * ((q.length() - 0.5 + 0.1 * q.x * q.y) / 0.05).tanh())
                    .collect()
            }),
        };
        let (grid, refined) = sign_refined(&f, 128).expect("grid");
        let (_, full) = f.grid(128).expect("grid");
        let exact = refined.iter().zip(&full).filter(|(a, b)| a == b).count();
        assert!(
            exact < grid.len() / 3,
            "{exact} of {} evaluated",
            grid.len()
        );
        let m1 = rfta_mc::marching_cubes(&grid, &refined, 0.0);
        let m2 = rfta_mc::marching_cubes(&grid, &full, 0.0);
        assert_eq!(m1.vertices, m2.vertices);
        assert_eq!(m1.faces, m2.faces);
    }

    #[test]
    fn csg_fields_are_bounds_of_their_shapes() {
        // Exact at points where one primitive rules: the rounded cube's face centre is 0.5 from
        // the centre, inside the ball.
        let cube = &csg(&["csg-rounded-cube".into()])[0];
        let v = cube.values(&[DVec3::new(0.0, 0.0, 0.3), DVec3::new(0.9, 0.0, 0.0)]);
        assert!(
            (v[0] + 0.2).abs() < 1e-12 && (v[1] - 0.4).abs() < 1e-12,
            "{v:?}"
        );
        // A drilled hole: the centre is outside (inside every drill).
        let drilled = &csg(&["csg-drilled".into()])[0];
        assert!(drilled.values(&[DVec3::ZERO])[0] > 0.0);
        assert!(drilled.values(&[DVec3::new(0.3, 0.3, 0.3)])[0] < 0.0);
        assert_eq!(csg(&[]).len(), CSG.len());
    }
}
