//! Step 1: the samples as spheres in the reference's unit box.

use rfta_feasible::TangentPoints;
use rfta_geom::glam::DVec3;
use rfta_geom::{Grid, SdfSamples, Sphere, SphereSet};

/// The side points of the final solve ([`UnitBox::sides`]): index `i` below the sample count is
/// sample `i` when its value is beyond the margin, the rest are the extra points.
pub(crate) struct SampleSides<'a> {
    unit: &'a UnitBox,
    margin: f64,
    extra: &'a [rfta_spsr::SidePoint],
}

impl rfta_spsr::SideSet for SampleSides<'_> {
    fn len(&self) -> usize {
        self.unit.len() + self.extra.len()
    }

    fn get(&self, i: usize) -> Option<rfta_spsr::SidePoint> {
        let Some(&v) = self.unit.values.get(i) else {
            return self.extra.get(i - self.unit.len()).copied();
        };
        (v.abs() > self.margin).then(|| rfta_spsr::SidePoint {
            position: self.unit.center(i),
            inside: v < 0.0,
        })
    }
}

/// The samples moved into the unit box as the reference does (subtract the per-axis minimum,
/// divide by the largest extent), as spheres of radius `|s|` (times the noise shrink
/// [`crate::InputReport::radius_scale`]) capped at the clamp.
pub(crate) struct UnitBox {
    trans: DVec3,
    scale: f64,
    /// The samples' largest coordinates (their box is `trans..upper`).
    upper: DVec3,
    /// Signed values, scaled.
    pub(crate) values: Vec<f64>,
    /// Where the spheres' centres come from ([`SphereSet`]: the spheres are worked out as they
    /// are read, from the centres and the values).
    centers: Centers,
    /// The clamp, scaled (`+inf` when none).
    pub(crate) clamp: f64,
    /// The sample spacing in the samples' coordinates ([`sample_spacing`]).
    pub(crate) input_spacing: f64,
    /// The samples' grid in the unit box, when they lie on one.
    grid: Option<Grid>,
    /// The noise shrink of the radii ([`crate::InputReport::radius_scale`]; 1: none).
    shrink: f64,
    /// Which spheres may own tangency points, when not all may ([`UnitBox::band_locally`]).
    owners: Option<Vec<bool>>,
}

impl UnitBox {
    pub(crate) fn new(samples: &SdfSamples, clamp: Option<f64>, radius_scale: Option<f64>) -> Self {
        let n = samples.len();
        let (lo, hi) = (0..n).fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), i| {
                let p = samples.position(i);
                (lo.min(p), hi.max(p))
            },
        );
        let extent = (hi - lo).max_element();
        let (trans, scale) = (lo, if extent > 0.0 { extent } else { 1.0 });
        let values: Vec<f64> = samples.values().iter().map(|&s| s / scale).collect();
        let cap = clamp.map_or(f64::INFINITY, |c| c / scale);
        let shrink = radius_scale.unwrap_or(1.0);
        let centers = match samples.layout() {
            rfta_geom::Layout::Grid(g) => Centers::Grid(*g),
            rfta_geom::Layout::Scattered(p) => {
                Centers::Points(p.iter().map(|&p| (p - trans) / scale).collect())
            }
        };
        Self {
            trans,
            scale,
            upper: hi,
            values,
            centers,
            clamp: cap,
            input_spacing: samples.spacing(),
            grid: samples.as_grid().and_then(|g| {
                Grid::new(g.dims(), (g.origin() - trans) / scale, g.spacing() / scale).ok()
            }),
            shrink,
            owners: None,
        }
    }

    /// The owner band ([`crate::Params::owner_band`], in sample spacings): the owner radius (the
    /// spheres at least this large own no point: the clamp, and on a grid `band` spacings) and
    /// the count of spheres below the clamp that the band keeps as constraints only. Scattered
    /// samples' spacing varies, and each sphere is measured against its own
    /// ([`UnitBox::band_locally`]).
    pub(crate) fn band(&mut self, band: Option<f64>) -> (f64, usize) {
        match band {
            Some(k) if self.on_grid() => {
                let r = self.clamp.min(k * self.spacing());
                let far = (self.spheres())
                    .filter(|s| s.radius >= r && s.radius < self.clamp)
                    .count();
                (r, far)
            }
            Some(k) => (self.clamp, self.band_locally(k)),
            None => (self.clamp, 0),
        }
    }

    /// Scattered samples' owner band: the spheres at least `band` local spacings large (the
    /// distance from the centre to the [`LOCAL_SPACING_NEIGHBOUR`]th nearest other sample) own
    /// no point; they stay constraints. On a grid that distance is the spacing, and the grid's
    /// band is the owner radius instead. Returns how many spheres it keeps as constraints only
    /// (below the clamp, which keeps its own). Nothing changes for a grid, or for samples a k-d
    /// tree cannot hold.
    fn band_locally(&mut self, band: f64) -> usize {
        use kiddo::{ImmutableKdTree, SquaredEuclidean};
        use rayon::prelude::*;
        let Centers::Points(centers) = &self.centers else {
            return 0;
        };
        if centers.len() <= LOCAL_SPACING_NEIGHBOUR {
            return 0;
        }
        let pts: Vec<[f64; 3]> = centers.iter().map(|p| p.to_array()).collect();
        let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(&pts) else {
            return 0;
        };
        // The sample itself is among its nearest, at distance 0.
        let Some(k) = std::num::NonZero::new(LOCAL_SPACING_NEIGHBOUR + 1) else {
            return 0;
        };
        let owners: Vec<bool> = (0..centers.len())
            .into_par_iter()
            .map(|i| {
                let nearest = tree
                    .query(&pts[i])
                    .nearest_n::<SquaredEuclidean<f64>>(k)
                    .execute();
                let spacing = nearest
                    .iter()
                    .map(|n| n.distance)
                    .fold(0.0, f64::max)
                    .sqrt();
                // Coincident samples have no spacing to speak of: they keep their points.
                spacing == 0.0 || self.radius(i) < band * spacing
            })
            .collect();
        let kept = (0..owners.len())
            .filter(|&i| !owners[i] && self.radius(i) < self.clamp)
            .count();
        self.owners = Some(owners);
        kept
    }

    /// How much larger than its (shrunk) sphere a sample's own tangency points lie: its value
    /// `|s|` itself, while it constrains the other spheres' points at the shrunk radius.
    pub(crate) fn owner_scale(&self) -> f64 {
        1.0 / self.shrink
    }

    /// Number of samples.
    pub(crate) fn len(&self) -> usize {
        self.values.len()
    }

    /// Sample `i`'s sphere centre: its position in the unit box.
    pub(crate) fn center(&self, i: usize) -> DVec3 {
        match &self.centers {
            Centers::Grid(g) => (g.position(i) - self.trans) / self.scale,
            Centers::Points(p) => p[i],
        }
    }

    /// Every sample's sphere, in index order.
    pub(crate) fn spheres(&self) -> impl Iterator<Item = Sphere> + '_ {
        (0..self.len()).map(|i| self.sphere(i))
    }

    /// The map from the samples' coordinates into the unit box.
    pub(crate) fn frame(&self) -> rfta_repair::Frame {
        rfta_repair::Frame {
            origin: self.trans,
            scale: self.scale,
        }
    }

    /// The spheres as repair takes them: in the unit box, with the way there.
    pub(crate) fn sphere_set(&self) -> rfta_repair::Spheres<'_> {
        rfta_repair::Spheres {
            spheres: self,
            values: &self.values,
            frame: self.frame(),
            spacing: self.spacing(),
        }
    }

    /// A point of the samples' coordinates in the unit box.
    pub(crate) fn to_unit(&self, p: DVec3) -> DVec3 {
        self.frame().to_frame(p)
    }

    /// Tangency points in the unit box moved to the input's coordinates (normals and owners as
    /// they are: the map is a scale and a shift).
    pub(crate) fn points_to_input(&self, cloud: TangentPoints) -> TangentPoints {
        TangentPoints {
            points: cloud.points.iter().map(|&p| self.to_input(p)).collect(),
            ..cloud
        }
    }

    /// A unit-box length in the samples' coordinates.
    pub(crate) fn to_input_length(&self, length: f64) -> f64 {
        length * self.scale
    }

    /// A unit-box point back in the samples' coordinates.
    pub(crate) fn to_input(&self, p: DVec3) -> DVec3 {
        self.frame().to_mesh(p)
    }

    /// Every sample far enough from the surface to have a reliable side
    /// ([`crate::consistency::SIGN_MARGIN`]), as a point the surface must leave on that side,
    /// then `extra`: read off the spheres as the solve asks (no list of millions).
    pub(crate) fn sides<'a>(&'a self, extra: &'a [rfta_spsr::SidePoint]) -> SampleSides<'a> {
        SampleSides {
            unit: self,
            margin: crate::consistency::SIGN_MARGIN * self.spacing(),
            extra,
        }
    }

    /// Whether the samples lie on a grid.
    pub(crate) fn on_grid(&self) -> bool {
        self.grid.is_some()
    }

    /// The samples' grid in the unit box, when they lie on one.
    pub(crate) fn grid(&self) -> Option<&Grid> {
        self.grid.as_ref()
    }

    /// On a grid, for each sample of `set` that `keep` takes, the point its gradient points to
    /// from its value away: `c - s g / |g|`, with `g` the central difference of the values (one
    /// sided at the grid's faces); for an exact SDF the closest surface point. `None` for
    /// scattered samples. Samples whose difference vanishes are skipped.
    pub(crate) fn gradient_points(
        &self,
        set: &[u32],
        keep: impl Fn(usize) -> bool + Sync,
    ) -> Option<Vec<DVec3>> {
        use rayon::prelude::*;
        let g = self.grid.as_ref()?;
        let points = set
            .par_iter()
            .map(|&i| i as usize)
            .filter(|&i| keep(i))
            .filter_map(|i| {
                let grad = g.central_difference(&self.values, i);
                let len = grad.length();
                (len > 1e-12).then(|| self.center(i) - self.values[i] * grad / len)
            })
            .collect();
        Some(points)
    }

    /// The sample nearest to a unit-box point, on grids.
    pub(crate) fn nearest_sample(&self, p: DVec3) -> Option<usize> {
        let g = self.grid.as_ref()?;
        let t = (p - g.origin()) / g.spacing();
        let dims = g.dims();
        let at = |a: usize| (t[a].round().max(0.0) as usize).min(dims[a] - 1);
        Some(g.index(at(0), at(1), at(2)))
    }

    /// The box of the samples' positions, in the samples' coordinates.
    pub(crate) fn samples_box(&self) -> rfta_geom::Aabb {
        rfta_geom::Aabb::new(self.trans, self.upper)
    }

    /// The samples inside `bounds` (a box in the samples' coordinates), in index order: on grids
    /// the nodes in the box, read off the grid; otherwise every sample tested.
    pub(crate) fn samples_within(&self, bounds: rfta_geom::Aabb) -> Vec<usize> {
        let lo = self.to_unit(bounds.min);
        let hi = self.to_unit(bounds.max);
        let inside = |i: &usize| {
            let c = self.center(*i);
            c.cmpge(lo).all() && c.cmple(hi).all()
        };
        let Some(g) = &self.grid else {
            return (0..self.len()).filter(inside).collect();
        };
        let dims = g.dims();
        // Node ranges one node wider than the box (empty beyond the grid), each node then
        // tested exactly.
        let range = |a: usize| {
            let t = |x: f64| (x - g.origin()[a]) / g.spacing()[a];
            let first = (t(lo[a]).floor() - 1.0).max(0.0) as usize;
            let last = (t(hi[a]).ceil() + 1.0).min(dims[a] as f64 - 1.0) as usize;
            first..=last
        };
        let mut out = Vec::new();
        for i in range(0) {
            for j in range(1) {
                out.extend(range(2).map(|k| g.index(i, j, k)).filter(inside));
            }
        }
        out
    }

    /// The sample spacing in the unit box.
    pub(crate) fn spacing(&self) -> f64 {
        self.input_spacing / self.scale
    }
}

/// Where the samples' sphere centres come from.
enum Centers {
    /// The input grid (in the samples' coordinates): a centre is its node moved into the unit
    /// box, worked out when read (on a 513^3 grid a copy of the centres would be 3.2 GB).
    Grid(Grid),
    /// Scattered samples' positions, in the unit box.
    Points(Vec<DVec3>),
}

/// Sample `i` as a sphere in the unit box: radius `radius_scale |s|`, or the clamp for a clamped
/// sample (`|s| >= clamp`: it owns no point).
impl SphereSet for UnitBox {
    fn len(&self) -> usize {
        UnitBox::len(self)
    }

    fn sphere(&self, i: usize) -> Sphere {
        Sphere::new(self.center(i), self.radius(i))
    }

    fn radius(&self, i: usize) -> f64 {
        let s = self.values[i].abs();
        if s >= self.clamp {
            self.clamp
        } else {
            self.shrink * s
        }
    }

    fn owns(&self, i: usize) -> bool {
        self.owners.as_ref().is_none_or(|o| o[i])
    }
}

/// The neighbour whose distance is a scattered sample's local spacing
/// ([`UnitBox::band_locally`]): on a grid the fourth nearest sample is one spacing away, and for
/// samples drawn uniformly at random the mean distance to the fourth nearest is
/// `Gamma(4 + 1/3) / Gamma(4) (3 / (4 pi))^(1/3)`, 0.96 times the spacing the volume per sample
/// gives (the k-th nearest neighbour distances of a Poisson process).
const LOCAL_SPACING_NEIGHBOUR: usize = 4;

/// The samples at a scale where squared distances neither overflow nor underflow, or `None` when
/// they are at one already (every input of ordinary size). Positions and values are multiplied by
/// the power of two `factor` that brings the samples' box to a side between 1 and 2: exact in
/// floating point, so the reconstruction at the working scale, divided by `factor`, is the one
/// the samples describe. (A box 2e155 wide, or 1e-200, made the input check index past its
/// arrays and the pipeline's squared distances infinite or zero.)
pub(crate) fn working_scale(samples: &SdfSamples) -> Option<(SdfSamples, f64)> {
    /// Box sides between 2^-64 and 2^64 keep every squared distance of the pipeline normal.
    const LIMIT: i32 = 64;
    let b = samples.bounds();
    let extent = (b.max - b.min).max_element().max(
        samples
            .values()
            .iter()
            .fold(0.0, |m: f64, v| m.max(v.abs())),
    );
    if !(extent.is_finite() && extent > 0.0) {
        return None;
    }
    let exponent = rfta_geom::math::log2(extent).floor() as i32;
    if exponent.abs() <= LIMIT {
        return None;
    }
    let factor = 2f64.powi(-exponent);
    let values = samples.values().iter().map(|v| v * factor).collect();
    let scaled = match samples.layout() {
        rfta_geom::Layout::Grid(g) => {
            let grid = Grid::new(g.dims(), g.origin() * factor, g.spacing() * factor).ok()?;
            SdfSamples::grid(grid, values)
        }
        rfta_geom::Layout::Scattered(p) => {
            SdfSamples::scattered(p.iter().map(|&p| p * factor).collect(), values)
        }
    };
    let scaled = match samples.stated_spacing() {
        Some(h) => scaled.and_then(|s| s.with_spacing(h * factor)),
        None => scaled,
    };
    Some((scaled.ok()?, factor))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rfta_geom::{Aabb, Grid};

    /// A sample's sphere is its position moved into the unit box (less the box's corner, over
    /// its largest side) with radius `shrink |s|` scaled the same way, or the clamp when `|s|`
    /// reaches it; worked out from the grid, it is the one the same samples give scattered, to
    /// the bit.
    #[test]
    fn spheres_are_the_samples_in_the_unit_box() {
        // Sides 2 * 0.25, 6 * 0.5 = 3 (the largest) and 4 * 0.125: the box's corner at the
        // origin, the scale 3.
        let origin = DVec3::new(-1.0, 0.5, 2.0);
        let grid = Grid::new([3, 7, 5], origin, DVec3::new(0.25, 0.5, 0.125)).expect("grid");
        let values: Vec<f64> = (0..grid.len()).map(|i| (i as f64 - 50.0) * 0.02).collect();
        let on_grid = SdfSamples::grid(grid, values.clone()).expect("samples");
        let scattered =
            SdfSamples::scattered(on_grid.positions(), values.clone()).expect("samples");
        let (clamp, shrink) = (0.9, 0.75);
        let a = UnitBox::new(&on_grid, Some(clamp), Some(shrink));
        let b = UnitBox::new(&scattered, Some(clamp), Some(shrink));
        assert_eq!((SphereSet::len(&a), SphereSet::len(&b)), (105, 105));
        let (mut clamped, mut shrunk) = (0, 0);
        for (i, &v) in values.iter().enumerate() {
            let want_center = (grid.position(i) - origin) / 3.0;
            let want_radius = if v.abs() >= clamp {
                clamped += 1;
                clamp / 3.0
            } else {
                shrunk += 1;
                shrink * (v / 3.0).abs()
            };
            let s = a.sphere(i);
            assert!((s.center - want_center).abs().max_element() < 1e-15, "{i}");
            assert!((s.radius - want_radius).abs() < 1e-15, "{i}: {}", s.radius);
            assert_eq!(s.radius, a.radius(i));
            assert_eq!(s, b.sphere(i), "sample {i}: grid and scattered differ");
        }
        assert!(clamped > 10 && shrunk > 10, "{clamped} {shrunk}");
        assert_eq!(a.spheres().count(), 105);
    }

    /// The grid's shortcut finds exactly the samples a scan over all of them finds, for boxes
    /// inside, across and beyond the grid.
    #[test]
    fn samples_within_a_box_are_those_a_scan_finds() {
        let grid = Grid::new(
            [9, 7, 5],
            DVec3::new(-1.0, 0.5, 2.0),
            DVec3::new(0.25, 0.3, 0.5),
        )
        .expect("grid");
        let values = (0..grid.len()).map(|i| i as f64 * 0.01 - 0.1).collect();
        let samples = SdfSamples::grid(grid, values).expect("samples");
        let unit = UnitBox::new(&samples, None, None);
        let mut rng = rfta_geom::rng::Rng::new(5);
        let mut r = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        let mut found = 0;
        for _ in 0..500 {
            let (a, b) = (r() * 4.0 - DVec3::splat(1.5), r() * 4.0 - DVec3::splat(1.5));
            let bounds = Aabb::from_points(&[
                a + DVec3::new(-1.0, 0.5, 2.0),
                b + DVec3::new(-1.0, 0.5, 2.0),
            ]);
            let scan: Vec<usize> = (0..samples.len())
                .filter(|&i| {
                    let c = unit.center(i);
                    c.cmpge(unit.to_unit(bounds.min)).all()
                        && c.cmple(unit.to_unit(bounds.max)).all()
                })
                .collect();
            found += scan.len();
            assert_eq!(unit.samples_within(bounds), scan);
        }
        assert!(found > 1000, "{found}");
        assert!(unit.samples_within(Aabb::EMPTY).is_empty());
    }

    /// The final solve's side points read off the samples are, index by index, every sample
    /// whose value is beyond the margin (on its sign's side) and none for those within it, then
    /// the extra points; nothing past the end.
    #[test]
    fn the_side_points_are_the_samples_beyond_the_margin_then_the_extra_ones() {
        use rfta_spsr::{SidePoint, SideSet};
        let grid = Grid::new([4, 3, 2], DVec3::ZERO, DVec3::splat(0.5)).expect("grid");
        // 0.001 and -0.0012 lie within the margin of 0.01 spacings (0.005); 16 samples beyond it.
        let values: Vec<f64> = (0..grid.len())
            .map(|i| [0.4, -0.3, 0.001, -0.0012, 0.7, -0.9][i % 6])
            .collect();
        let samples = SdfSamples::grid(grid, values.clone()).expect("samples");
        let unit = UnitBox::new(&samples, None, None);
        let extra = [SidePoint {
            position: DVec3::splat(7.0),
            inside: true,
        }];
        let sides = unit.sides(&extra);
        assert_eq!(sides.len(), values.len() + 1);
        for (i, &v) in values.iter().enumerate() {
            let want = (v.abs() > 0.01 * 0.5).then(|| SidePoint {
                position: unit.center(i),
                inside: v < 0.0,
            });
            assert_eq!(sides.get(i), want, "sample {i} ({v})");
        }
        assert_eq!(sides.get(values.len()), Some(extra[0]));
        assert_eq!(sides.get(values.len() + 1), None);
        assert_eq!(
            (0..sides.len()).filter(|&i| sides.get(i).is_some()).count(),
            17
        );
    }
}
