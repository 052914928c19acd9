//! Limit-equilibrium slope stability: the methods of slices on a 2D section.
//!
//! * [`geometry`]: the section (regions with a material and a unit weight;
//!   the ground surface, the upper envelope of their edges), from polygons or
//!   from an Anura3D mesh's elements;
//! * [`field`]: pore pressure and saturation at a point (none, a piezometric
//!   line, or the mapped state on a kernel-interpolated raster);
//! * [`surface`]: circular and polyline slip surfaces below the ground;
//! * [`slices`]: slices with weights, base strength and pore pressure, in the
//!   frame the methods use;
//! * [`methods`]: Morgenstern–Price (constant, half-sine), Spencer, Bishop's
//!   simplified, Janbu's simplified with f₀, the ordinary method;
//! * [`search`]: entry–exit and grid-and-radius circles in parallel, circle
//!   and vertex-moving refinement;
//! * [`composite`]: circles held up at material interfaces (weak layers);
//! * [`series`]: the first time a factor falls to 1, bisected between saved
//!   times.
//!
//! [`analyse`] runs a search; [`evaluate_surface`] one given surface. The
//! equations and references are in `docs/slope-stability.md`. This module
//! does no I/O and never prints.

pub mod composite;
pub mod field;
pub mod geometry;
pub mod methods;
pub mod search;
pub mod series;
pub mod slices;
pub mod surface;

pub use field::{Dry, PoreField, PoreSample, Raster, RasterSettings, Scattered, WaterTable};
pub use geometry::{Domain, Region};
pub use methods::{Interslice, Method, Solution};
pub use search::{CircleSearch, SearchSettings};
pub use surface::{Circle, Reject, Surface};

use rayon::prelude::*;
use slices::{SliceInputs, SliceSet};

/// Why an analysis could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SlopeError {
    #[error("slope geometry: {0}")]
    Geometry(String),
    #[error("pore-pressure field: {0}")]
    Field(String),
    #[error("{0}")]
    Settings(String),
    #[error("no admissible slip surface: {0}")]
    NoSurface(String),
}

/// Mohr–Coulomb strength (kPa, degrees). `phi_b` is Fredlund's angle for the
/// suction term (default φ′/2).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Strength {
    pub cohesion: f64,
    pub friction_angle: f64,
    pub phi_b: Option<f64>,
}

impl Strength {
    /// φᵇ in degrees: the given one, else φ′/2.
    pub fn phi_b(&self) -> f64 {
        self.phi_b.unwrap_or(0.5 * self.friction_angle)
    }
}

/// A material as the analysis sees it: a name and its strength; `None` is a
/// material without Mohr–Coulomb strength, which slip surfaces may not cross.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SlopeMaterial {
    pub name: String,
    pub strength: Option<Strength>,
}

/// How suction (pwp > 0 in Anura3D's sign) enters the strength. With u = −pwp
/// the water pressure (positive in compression) at a slice base:
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Suction {
    /// Bishop's effective stress with χ = S: τ = c′ + (σ − S·u)·tan φ′ (what
    /// the runner and Anura3D use).
    Bishop,
    /// Fredlund's φᵇ: τ = c′ + (σ − u)·tan φ′ for u ≥ 0, c′ + σ·tan φ′ +
    /// s·tan φᵇ for suction s = −u > 0 (φᵇ given, else each material's φ′/2).
    PhiB(Option<f64>),
    /// Suction ignored: τ = c′ + (σ − max(u, 0))·tan φ′.
    Ignored,
}

impl Suction {
    pub fn name(self) -> &'static str {
        match self {
            Suction::Bishop => "bishop",
            Suction::PhiB(_) => "phi-b",
            Suction::Ignored => "none",
        }
    }
}

/// One analysis: the section, its materials, the pore field and the slicing.
pub struct Problem<'a> {
    pub domain: &'a Domain,
    /// By slot ([`Region::material`]).
    pub materials: &'a [SlopeMaterial],
    pub field: &'a dyn PoreField,
    pub suction: Suction,
    /// Equal slices between a surface's ends (more at ground and surface
    /// vertices).
    pub n_slices: usize,
    /// Shallowest admissible surface: its largest depth below the ground (m).
    pub min_depth: f64,
    /// Relative tolerance on every factor.
    pub tolerance: f64,
}

impl Problem<'_> {
    fn inputs(&self) -> SliceInputs<'_> {
        SliceInputs {
            domain: self.domain,
            materials: self.materials,
            field: self.field,
            suction: self.suction,
            n_slices: self.n_slices,
            min_depth: self.min_depth,
        }
    }

    fn check(&self) -> Result<(), SlopeError> {
        let bad = |s: String| Err(SlopeError::Settings(s));
        if self.n_slices < 2 {
            return bad(format!(
                "{} slices; a surface needs at least 2",
                self.n_slices
            ));
        }
        if self.n_slices > MAX_SLICES {
            return bad(format!(
                "{} slices; at most {MAX_SLICES} (30 to 100 resolve any surface)",
                self.n_slices
            ));
        }
        if let Suction::PhiB(Some(phi_b)) = self.suction
            && !(0.0..90.0).contains(&phi_b)
        {
            return bad(format!("φᵇ = {phi_b}° must lie in [0°, 90°)"));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 0.1) {
            return bad(format!("tolerance {} must lie in (0, 0.1)", self.tolerance));
        }
        if !(self.min_depth >= 0.0 && self.min_depth.is_finite()) {
            return bad(format!("minimum depth {} must be ≥ 0", self.min_depth));
        }
        if let Some(r) = self
            .domain
            .regions()
            .iter()
            .find(|r| r.material >= self.materials.len())
        {
            return bad(format!(
                "a region names material slot {} of {}",
                r.material,
                self.materials.len()
            ));
        }
        if !self.materials.iter().any(|m| m.strength.is_some()) {
            return Err(SlopeError::NoSurface(
                "no material has Mohr–Coulomb strength: every surface is unbreakable".into(),
            ));
        }
        Ok(())
    }
}

/// One slice as reported, in real coordinates.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SliceRow {
    pub x: f64,
    pub width: f64,
    pub base_y: f64,
    /// Base inclination (degrees, real frame: positive rising with x).
    pub alpha: f64,
    pub weight: f64,
    pub cohesion: f64,
    pub friction_angle: f64,
    pub pwp: f64,
    pub saturation: f64,
    /// Pore pressure entering the strength (kPa, + compression).
    pub pore_pressure: f64,
    pub material: String,
}

/// A surface with its factor, as reported.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Found {
    pub factor: f64,
    pub solution: Solution,
    /// Left end to right end.
    pub surface: Vec<[f64; 2]>,
    pub axis: [f64; 2],
    pub circle: Option<Circle>,
}

/// What the search did.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SearchReport {
    /// The circles' search space, in words.
    pub space: String,
    pub counts: search::TrialCounts,
    pub circle_refinement: Option<search::Refinement>,
    /// The non-circular refinement (vertex moves); `None` when not asked.
    pub polyline_refinement: Option<search::Refinement>,
    pub polyline_segments: Option<usize>,
    /// The composite surfaces: the best circles clipped at each material
    /// interface (with the non-circular refinement only).
    pub composites: search::CompositeCounts,
}

/// The result of [`analyse`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Analysis {
    pub method: Method,
    pub interslice: Option<Interslice>,
    pub suction: Suction,
    pub tolerance: f64,
    /// The critical surface: non-circular when refined, else the best circle.
    pub critical: Found,
    /// The best circle (after its own refinement).
    pub circular: Found,
    pub slices: Vec<SliceRow>,
    pub search: SearchReport,
    pub n_slices: usize,
    pub min_depth: f64,
}

fn found(surface: &Surface, solution: Solution) -> Found {
    Found {
        factor: solution.factor,
        solution,
        surface: surface.points.clone(),
        axis: surface.axis,
        circle: surface.circle,
    }
}

/// The slices of `set` in real coordinates.
pub fn slice_rows(set: &SliceSet, materials: &[SlopeMaterial]) -> Vec<SliceRow> {
    let mut rows: Vec<SliceRow> = set
        .slices
        .iter()
        .map(|s| SliceRow {
            x: set.real_x(s.x),
            width: s.width,
            base_y: s.base[1],
            alpha: if set.mirrored { -s.alpha } else { s.alpha }.to_degrees(),
            weight: s.weight,
            cohesion: s.cohesion,
            friction_angle: s.tan_phi.atan().to_degrees(),
            pwp: s.pwp,
            saturation: s.saturation,
            pore_pressure: s.pore_pressure,
            material: materials[s.material].name.clone(),
        })
        .collect();
    rows.sort_by(|a, b| a.x.total_cmp(&b.x));
    rows
}

/// The factor of one given surface.
pub fn evaluate_surface(
    problem: &Problem<'_>,
    method: Method,
    surface: &Surface,
) -> Result<(SliceSet, Solution), SlopeError> {
    problem.check()?;
    let set = slices::slice(surface, &problem.inputs())
        .map_err(|r| SlopeError::NoSurface(format!("the surface {}", r.describe())))?;
    let solution = methods::solve(&set, method, problem.tolerance);
    Ok((set, solution))
}

/// Circles refined from distinct places of the search.
const STARTS: usize = 3;

/// Most rounds of the non-circular refinement of the best two starts.
const POLISH_ROUNDS: usize = 8;

/// Most slices a surface is cut into.
pub const MAX_SLICES: usize = 10_000;

/// Most trial circles one search generates.
pub const MAX_TRIALS: usize = 1_000_000;

/// Searches the critical surface for `method`.
pub fn analyse(
    problem: &Problem<'_>,
    method: Method,
    settings: &SearchSettings,
) -> Result<Analysis, SlopeError> {
    problem.check()?;
    if settings.trials > MAX_TRIALS {
        return Err(SlopeError::Settings(format!(
            "{} trial circles; at most {MAX_TRIALS} (the search refines the best of them)",
            settings.trials
        )));
    }
    let inputs = problem.inputs();
    let (list, space) = search::circles(&inputs, settings);
    let tol = problem.tolerance;
    // The best circles of distinct places, each refined: the refinements
    // end in nearby local minima, and taking the lowest of several keeps the
    // answer from hopping between them when the inputs change slightly.
    let (mut best, counts) =
        search::best_circles(&list, &inputs, method, tol, problem.n_slices, STARTS);
    if best.is_empty() {
        let reasons = counts
            .rejected
            .iter()
            .map(|(r, n)| format!("{n} {r}"))
            .chain(
                (counts.not_converged > 0)
                    .then(|| format!("{} did not converge", counts.not_converged)),
            )
            .collect::<Vec<_>>()
            .join(", ");
        if counts.generated == 0 {
            // Entry–exit pairs need an entry higher than the exit: a level
            // ground has none, and no slope to be unstable.
            return Err(SlopeError::NoSurface(format!(
                "no trial circle could be formed ({space}); is the ground level?"
            )));
        }
        return Err(SlopeError::NoSurface(format!(
            "of {} trial circles ({space}): {reasons}",
            counts.generated
        )));
    }
    best.truncate(STARTS);
    let mut circles: Vec<((Surface, Solution), search::Refinement)> = best
        .into_par_iter()
        .map(|b| {
            search::refine_circle(
                b,
                &inputs,
                method,
                tol,
                problem.n_slices,
                settings.max_refinements,
            )
        })
        .collect();
    circles.sort_by(|a, b| a.0.1.factor.total_cmp(&b.0.1.factor));
    let (circle, circle_refinement) = circles[0].clone();
    // The ordinary method satisfies no force equilibrium: moving a polyline's
    // vertices only exploits that, so it keeps to circles.
    let refine = settings.refine && method != Method::Ordinary;
    let lines = if refine {
        composite::interfaces(inputs.domain)
    } else {
        Vec::new()
    };
    let (composite, composites) = if refine {
        let (found, mut counts) =
            search::best_composite(&list, &lines, &inputs, method, tol, problem.n_slices);
        let found = found.map(|(c, recipe)| {
            search::refine_composite(
                c,
                recipe,
                &inputs,
                method,
                tol,
                problem.n_slices,
                settings.max_refinements,
            )
        });
        counts.refined_factor = found.as_ref().map(|c| c.1.factor);
        (found, counts)
    } else {
        (None, search::CompositeCounts::default())
    };
    let (critical, polyline_refinement) = if refine {
        let (translational, _) =
            search::best_translational(&inputs, method, tol, settings.segments, 2);
        // Of the given starts, the best that can be analysed.
        let given: Option<(Surface, Solution)> = settings
            .starts
            .iter()
            .filter_map(|points| {
                search::start_from(points, &inputs, method, tol, settings.segments)
            })
            .min_by(|a, b| a.1.factor.total_cmp(&b.1.factor));
        let starts: Vec<&(Surface, Solution)> = circles
            .iter()
            .take(2)
            .map(|(c, _)| c)
            .chain(composite.as_ref())
            .chain(&translational)
            .chain(&given)
            .collect();
        // Every start polished for one round (the depths below the ground);
        // the best two polished on until they settle.
        let mut first: Vec<((Surface, Solution), search::Refinement)> = starts
            .into_par_iter()
            .map(|c| search::refine_polyline(c, &inputs, method, tol, settings, 1))
            .collect();
        first.sort_by(|a, b| a.0.1.factor.total_cmp(&b.0.1.factor));
        first.truncate(2);
        first
            .into_par_iter()
            .map(|(c, r)| {
                let (c, more) =
                    search::refine_polyline(&c, &inputs, method, tol, settings, POLISH_ROUNDS);
                let total = search::Refinement {
                    evaluations: r.evaluations + more.evaluations,
                    start_factor: r.start_factor,
                    end_factor: more.end_factor,
                    final_step_ratio: more.final_step_ratio,
                };
                (c, total)
            })
            .collect::<Vec<_>>()
            .into_iter()
            .min_by(|a, b| a.0.1.factor.total_cmp(&b.0.1.factor))
            .map(|(c, r)| (c, Some(r)))
            .unwrap_or((circle.clone(), None))
    } else {
        (circle.clone(), None)
    };
    let set = slices::slice(&critical.0, &inputs)
        .map_err(|r| SlopeError::NoSurface(format!("the critical surface {}", r.describe())))?;
    Ok(Analysis {
        method,
        interslice: method.interslice(),
        suction: problem.suction,
        tolerance: tol,
        critical: found(&critical.0, critical.1),
        circular: found(&circle.0, circle.1),
        slices: slice_rows(&set, problem.materials),
        search: SearchReport {
            space,
            counts,
            circle_refinement: Some(circle_refinement),
            polyline_refinement,
            polyline_segments: refine.then_some(settings.segments),
            composites,
        },
        n_slices: problem.n_slices,
        min_depth: problem.min_depth,
    })
}
