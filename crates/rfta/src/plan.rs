//! [`Plan`]: what a run derives from its parameters and its samples, once, before the first
//! stage: the working scale, the input check's findings, the samples as spheres in the unit box,
//! the radii that decide which spheres own points and which are drawn, and each stage's solver
//! settings. The stages read their settings here and compute none of them.

use std::borrow::Cow;

use rfta_feasible::TangentPoints;
use rfta_geom::SdfSamples;
use rfta_spsr::SpsrParams;

use crate::field::{self, Field, FieldReport, Reading};
use crate::normalize::{self, UnitBox};
use crate::report::{InputReport, Journal};
use crate::{Error, Params, RASTER_REACH, Reconstruction, Result, Step, Warning, check};

/// `stages` run on the plan of `params` on `samples` (with the journal its input check began),
/// on the pool of [`Params::threads`], once the parameters are valid and the memory the run
/// needs is there.
///
/// # Errors
/// [`crate::Error::InvalidParams`], [`crate::Error::TooLarge`], as [`Plan::new`], and those of
/// `stages`.
pub(crate) fn with_plan<T: Send>(
    samples: &SdfSamples,
    params: &Params,
    stages: impl FnOnce(Plan<'_>, Journal) -> Result<T> + Send,
) -> Result<T> {
    params.validate()?;
    crate::check_memory(samples.len(), params)?;
    crate::pool::on_pool(params.threads, || {
        let mut journal = Journal::default();
        let plan = Plan::new(samples, params, &mut journal)?;
        stages(plan, journal)
    })
}

/// A run's settings and the samples it works on, derived once.
pub(crate) struct Plan<'a> {
    /// The caller's parameters, the clamp at the working scale.
    pub(crate) params: Params,
    /// The samples at the working scale: the caller's, unless they needed rescaling.
    pub(crate) samples: Cow<'a, SdfSamples>,
    /// The power of two the samples were multiplied by ([`normalize::working_scale`]), if any.
    factor: Option<f64>,
    /// The input check's findings (the clamp used, the noise shrink of the radii).
    pub(crate) input: InputReport,
    /// How the samples are read: as distances, as a level set or as bounds ([`crate::field`]);
    /// the last two run no rounds ([`Params::rounds`] is 0).
    pub(crate) field: FieldReport,
    /// The samples as spheres in the unit box.
    pub(crate) unit: UnitBox,
    /// Spheres at least this large own no tangency point (unit box): the clamp, or, on a grid,
    /// [`Params::owner_band`] sample spacings when that is smaller. They stay constraints.
    pub(crate) owner_radius: f64,
    /// Spheres at least this large are not rasterized (`RASTER_REACH` owner radii; all are
    /// without an owner band).
    pub(crate) raster_radius: f64,
    /// The tangency-point settings of the initial points and the rounds.
    pub(crate) feasible: rfta_feasible::Params,
    /// The screened Poisson setting of the solves inside the rounds.
    pub(crate) round_spsr: SpsrParams,
    /// The screened Poisson setting of the final solve.
    pub(crate) final_spsr: SpsrParams,
    /// Whether the rounds solve a depth coarser than the final solve and draw their batches
    /// from the spheres near the surface ([`Params::fine_rounds`]).
    pub(crate) fine_rounds: bool,
    /// The fine-tuning rounds ([`Params::rounds_for`]).
    pub(crate) rounds: usize,
    /// Spheres that own no tangency point for being farther than [`Params::owner_band`] (not
    /// clamped ones).
    pub(crate) far_spheres: usize,
}

impl<'a> Plan<'a> {
    /// The plan of a run of `params` on `samples`: rescaled to the working scale when their
    /// size needs it, checked unless [`Params::check`] is off (its warnings to `journal`).
    ///
    /// # Errors
    /// As [`check::samples`].
    pub(crate) fn new(
        samples: &'a SdfSamples,
        params: &Params,
        journal: &mut Journal,
    ) -> Result<Self> {
        let (samples, factor, params) = match normalize::working_scale(samples) {
            // Reconstructed at a scale of ordinary size, then scaled back (exactly: a power of
            // two).
            Some((scaled, factor)) => (
                Cow::Owned(scaled),
                Some(factor),
                Params {
                    clamp: params.clamp.map(|c| c * factor),
                    ..params.clone()
                },
            ),
            None => (Cow::Borrowed(samples), None, params.clone()),
        };
        let input = if params.check {
            let t = std::time::Instant::now();
            let input = check::samples(&samples, &params, journal)?;
            journal.timed(Step::InputCheck, t);
            input
        } else {
            InputReport {
                samples: samples.len(),
                clamp: params.clamp,
                ..InputReport::default()
            }
        };
        if matches!(params.field, Field::LevelSet | Field::Bound) && samples.as_grid().is_none() {
            return Err(Error::InvalidParams(
                "field = level-set and field = bound read the samples on a grid (its smooth interpolant's zero set); these are scattered (read them as distances: field = distance or auto)".into(),
            ));
        }
        let mut unit = UnitBox::new(&samples, input.clamp, input.radius_scale);
        let (owner_radius, far_spheres) = unit.band(params.owner_band);
        let spacing = Some(unit.spacing());
        let mut feasible = params.feasible_params(unit.len(), owner_radius, unit.owner_scale());
        let raster_radius = RASTER_REACH * owner_radius;
        let t = std::time::Instant::now();
        let mut field = field::measure(&samples, params.field, input.clamp);
        let radii = (owner_radius, raster_radius);
        field::cover_check(
            &mut field,
            params.field,
            &samples,
            &unit,
            radii,
            &feasible,
            None,
        );
        journal.timed(Step::Field, t);
        if field.read_as == Reading::Bounds {
            feasible.k_search = feasible.k_search.min(field::NEAR_K_SEARCH);
        }
        if params.field == Field::Auto {
            journal
                .warnings
                .extend(match (field.read_as, field.covered, field.reach) {
                    (Reading::Bounds, Some(covered), _) => Some(Warning::Bound { covered }),
                    (Reading::LevelSet, _, Some(reach)) => Some(Warning::LevelSet { reach }),
                    _ => None,
                });
        }
        Ok(Self {
            far_spheres,
            feasible,
            round_spsr: params.round_spsr_params(spacing),
            final_spsr: params.spsr_params(spacing),
            fine_rounds: params.fine_rounds(spacing),
            // A level set's and bounds' points are not fine-tuned.
            rounds: if field.read_as.fine_tunes() {
                params.rounds_for(unit.on_grid(), spacing)
            } else {
                0
            },
            raster_radius,
            owner_radius,
            params,
            samples,
            factor,
            input,
            field,
            unit,
        })
    }

    /// Tangency points in the caller's coordinates (an earlier run's) at the working scale.
    pub(crate) fn scaled(&self, points: &TangentPoints) -> TangentPoints {
        match self.factor {
            None => points.clone(),
            Some(factor) => TangentPoints {
                points: points.points.iter().map(|&p| p * factor).collect(),
                normals: points.normals.clone(),
                owners: points.owners.clone(),
            },
        }
    }

    /// `edit` applied to `mesh` in the caller's coordinates (an adaptive run's questions to its
    /// function), the mesh at the working scale before and after.
    pub(crate) fn in_caller_scale<T>(
        &self,
        mesh: &mut rfta_geom::TriMesh,
        edit: impl FnOnce(&mut rfta_geom::TriMesh) -> T,
    ) -> T {
        let Some(factor) = self.factor else {
            return edit(mesh);
        };
        mesh.map_vertices(|v| v / factor);
        let out = edit(mesh);
        mesh.map_vertices(|v| v * factor);
        out
    }

    /// A reconstruction at the working scale in the caller's coordinates: its mesh, points, clamp
    /// and spacing divided by the factor (exact: a power of two).
    pub(crate) fn to_caller(&self, mut out: Reconstruction) -> Reconstruction {
        let Some(factor) = self.factor else {
            return out;
        };
        out.mesh.map_vertices(|v| v / factor);
        for p in &mut out.points.points {
            *p /= factor;
        }
        out.report.input.clamp = out.report.input.clamp.map(|c| c / factor);
        out.report.consistency.spacing /= factor;
        out
    }
}
