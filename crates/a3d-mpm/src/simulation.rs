//! [`Simulation`], the public handle on a running explicit MPM solver: it
//! picks the solver for the mesh's element type through the element seam
//! ([`a3d_element::with_element`]: a linear simplex of the model's
//! dimension runs, anything else is [`MpmError::Unsupported`]) and hides the
//! solver's dimension `D` and corner count `NC` behind the [`Run`] trait
//! object, so nothing past this file matches on the element type. The scheme
//! itself is in [`super::step`].

use super::liquid::Formulation;
use super::step::{Solver, StepOutcome};
use super::{MpmError, RunSettings};
use a3d_element::{Element, ElementVisitor, widen, with_element};
use a3d_model::{AnuraModel, Dimension, MaterialPoint, MpState};

/// A running explicit MPM simulation of an Anura3D model: the state between
/// steps, for a plane-strain or axisymmetric TRI3 model or a 3D
/// `tetrahedral_old` one.
pub struct Simulation {
    inner: Box<dyn Run + Send + Sync>,
}

/// One material point as [`Run::for_each_point`] shows it (vectors with three
/// components, z = 0 in 2D).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointView {
    pub position: [f64; 3],
    pub displacement: [f64; 3],
    pub velocity: [f64; 3],
    /// Effective stress σ′ (kPa).
    pub stress: [f64; 6],
    /// The 0-based element it is in now.
    pub element: u32,
    /// Has yielded: accumulated plastic strain above 1e-6 (`particle::PLASTIC_STRAIN_FLOOR`).
    pub plastic: bool,
    /// Left the mesh.
    pub lost: bool,
    /// Its initial stress was outside the yield surface.
    pub inadmissible: bool,
    /// Pore pressure (kPa, Anura3D's sign).
    pub pwp: f64,
    /// The liquid's velocity (coupled MPs; zero otherwise).
    pub liquid_velocity: [f64; 3],
    /// Degree of saturation.
    pub saturation: f64,
}

/// What [`Simulation`] asks of the solver of any dimension.
pub(crate) trait Run {
    fn step(&mut self) -> StepOutcome;
    fn dt(&self) -> f64;
    fn time(&self) -> f64;
    fn steps(&self) -> usize;
    fn n_points(&self) -> usize;
    fn wave_speed(&self) -> f64;
    fn min_altitude(&self) -> f64;
    fn displacement_stats(&self) -> (f64, f64);
    fn tie(&mut self, pairs: &[(u32, u32)]) -> Result<(), MpmError>;
    /// Calls `f` on every MP in order.
    fn for_each_point(&self, f: &mut dyn FnMut(PointView));
    /// Per element: the sum of the last step's residual force over its corners.
    fn element_residuals(&self) -> Vec<f64>;
    fn set_nodal_loads(&mut self, loads: &[(u32, [f64; 3])]) -> Result<(), MpmError>;
    fn formulations(&self) -> Vec<(u32, Formulation)>;
    fn hydraulic(&self) -> super::seepage::HydraulicBoundaries;
    /// What the runner was asked to apply and did not (loads), and why.
    fn notes(&self) -> Vec<String>;
}

impl<const D: usize, const NC: usize> Run for Solver<D, NC> {
    fn step(&mut self) -> StepOutcome {
        Solver::step(self)
    }
    fn dt(&self) -> f64 {
        self.dt
    }
    fn time(&self) -> f64 {
        self.time
    }
    fn steps(&self) -> usize {
        self.steps
    }
    fn n_points(&self) -> usize {
        self.particles.len()
    }
    fn wave_speed(&self) -> f64 {
        self.wave_speed
    }
    fn min_altitude(&self) -> f64 {
        self.min_altitude
    }
    fn displacement_stats(&self) -> (f64, f64) {
        Solver::displacement_stats(self)
    }
    fn tie(&mut self, pairs: &[(u32, u32)]) -> Result<(), MpmError> {
        self.grid.tie(pairs)
    }
    fn for_each_point(&self, f: &mut dyn FnMut(PointView)) {
        for (p, &inadmissible) in self.particles.iter().zip(&self.inadmissible) {
            f(PointView {
                position: widen(&p.position),
                displacement: widen(&p.displacement),
                velocity: widen(&p.velocity),
                stress: p.stress,
                element: p.element,
                plastic: p.plastic,
                lost: p.lost,
                inadmissible,
                pwp: p.pwp,
                liquid_velocity: widen(&p.liquid_velocity),
                saturation: p.saturation,
            });
        }
    }
    fn element_residuals(&self) -> Vec<f64> {
        self.grid
            .elements
            .iter()
            .map(|e| {
                e.corners
                    .iter()
                    .map(|&c| self.node_residual[c as usize])
                    .sum()
            })
            .collect()
    }
    fn set_nodal_loads(&mut self, loads: &[(u32, [f64; 3])]) -> Result<(), MpmError> {
        Solver::set_nodal_loads(self, loads)
    }
    fn formulations(&self) -> Vec<(u32, Formulation)> {
        self.waters
            .iter()
            .enumerate()
            .filter_map(|(i, w)| w.map(|w| (i as u32 + 1, w.formulation())))
            .collect()
    }
    fn hydraulic(&self) -> super::seepage::HydraulicBoundaries {
        self.surface_boundaries()
    }
    fn notes(&self) -> Vec<String> {
        self.external
            .as_ref()
            .map(|e| e.notes.clone())
            .unwrap_or_default()
    }
}

/// Builds the solver for the element type `E`, if the runner takes it.
struct Build<'a> {
    model: &'a AnuraModel,
    points: &'a [MaterialPoint],
    states: &'a [MpState],
    settings: &'a RunSettings,
}

impl ElementVisitor for Build<'_> {
    type Output = Result<Box<dyn Run + Send + Sync>, MpmError>;
    fn visit<const D: usize, const NC: usize, E: Element<D, NC>>(self) -> Self::Output {
        let dimension = self.model.mesh.dimension;
        if !E::AFFINE || dimension.n_dim() != D || dimension == Dimension::Cylindrical3D {
            return Err(MpmError::Unsupported(format!(
                "{} with {} elements (supported: 2D-plane_strain and 2D-axisymmetric with \
                 triangular_3-noded, 3D-cartesian with tetrahedral_old)",
                dimension.gom_name(),
                E::TYPE.gom_name()
            )));
        }
        let solver =
            Solver::<D, NC>::new::<E>(self.model, self.points, self.states, self.settings)?;
        Ok(Box::new(solver))
    }
}

impl Simulation {
    /// Sets up the solver: checks the model, locates every MP, builds masses,
    /// effective stresses and the time step. Fails on unsupported dimensions or
    /// element types, unknown material models, MPs outside the mesh and
    /// inconsistent inputs.
    pub fn new(
        model: &AnuraModel,
        points: &[MaterialPoint],
        states: &[MpState],
        settings: &RunSettings,
    ) -> Result<Simulation, MpmError> {
        settings.validate()?;
        super::check_points(points, states)?;
        let build = Build {
            model,
            points,
            states,
            settings,
        };
        let inner = with_element(model.mesh.element_type, build)?;
        Ok(Simulation { inner })
    }

    /// Advances by one explicit time step.
    pub fn step(&mut self) -> StepOutcome {
        self.inner.step()
    }

    /// The time step Δt (s).
    pub fn time_step(&self) -> f64 {
        self.inner.dt()
    }

    /// Simulated time so far (s).
    pub fn time(&self) -> f64 {
        self.inner.time()
    }

    /// Steps taken so far.
    pub fn steps(&self) -> usize {
        self.inner.steps()
    }

    /// Number of material points.
    pub fn n_points(&self) -> usize {
        self.inner.n_points()
    }

    /// Largest P-wave speed √((K + 4G/3)/ρ) over the MPs (m/s).
    pub fn wave_speed(&self) -> f64 {
        self.inner.wave_speed()
    }

    /// Smallest element altitude (m), the length behind the time step.
    pub fn min_element_size(&self) -> f64 {
        self.inner.min_altitude()
    }

    /// Largest and mean MP displacement magnitude (m).
    pub fn displacement_stats(&self) -> (f64, f64) {
        self.inner.displacement_stats()
    }

    /// Calls `f` on every MP in order.
    pub(crate) fn for_each_point(&self, mut f: impl FnMut(&PointView)) {
        self.inner.for_each_point(&mut |p| f(&p));
    }

    /// One value per MP, in MP order.
    fn per_point<T>(&self, f: impl Fn(&PointView) -> T) -> Vec<T> {
        let mut out = Vec::with_capacity(self.n_points());
        self.for_each_point(|p| out.push(f(p)));
        out
    }

    /// MP positions (z = 0 in 2D).
    pub fn positions(&self) -> Vec<[f64; 3]> {
        self.per_point(|p| p.position)
    }

    /// MP displacements (z = 0 in 2D).
    pub fn displacements(&self) -> Vec<[f64; 3]> {
        self.per_point(|p| p.displacement)
    }

    /// MP effective stresses σ′ (xx, yy, zz, xy, yz, xz; kPa).
    pub fn effective_stresses(&self) -> Vec<[f64; 6]> {
        self.per_point(|p| p.stress)
    }

    /// MP velocities (m/s; z = 0 in 2D).
    pub fn velocities(&self) -> Vec<[f64; 3]> {
        self.per_point(|p| p.velocity)
    }

    /// Number of MPs that left the mesh.
    pub fn lost_points(&self) -> usize {
        self.per_point(|p| p.lost)
            .into_iter()
            .filter(|&b| b)
            .count()
    }

    /// Ties pairs of mesh nodes (0-based: primary, secondary) so that they
    /// share their degrees of freedom, e.g. the two ends of a periodic layer;
    /// see [`super::grid::Grid::tie`]. Call it before the first step.
    pub fn tie_nodes(&mut self, pairs: &[(u32, u32)]) -> Result<(), MpmError> {
        if self.steps() > 0 {
            return Err(MpmError::InvalidSettings(
                "nodes can only be tied before the first step".into(),
            ));
        }
        self.inner.tie(pairs)
    }

    /// Per MP: has yielded (accumulated plastic strain above 1e-6).
    pub fn plastic_flags(&self) -> Vec<bool> {
        self.per_point(|p| p.plastic)
    }

    /// Per MP: the 0-based element it is in now.
    pub fn elements(&self) -> Vec<u32> {
        self.per_point(|p| p.element)
    }

    /// Per element: the sum of the last step's residual force over its corners.
    pub(crate) fn element_residuals(&self) -> Vec<f64> {
        self.inner.element_residuals()
    }

    /// MP pore pressures (kPa, Anura3D's sign: negative in compression).
    /// Frozen for drained materials; they evolve for coupled and undrained
    /// ones ([`super::liquid`]).
    pub fn pore_pressures(&self) -> Vec<f64> {
        self.per_point(|p| p.pwp)
    }

    /// MP liquid velocities (m/s; zero where the water does not flow).
    pub fn liquid_velocities(&self) -> Vec<[f64; 3]> {
        self.per_point(|p| p.liquid_velocity)
    }

    /// MP degrees of saturation (from the retention curve where the water
    /// flows in unsaturated materials, else as mapped).
    pub fn saturations(&self) -> Vec<f64> {
        self.per_point(|p| p.saturation)
    }

    /// The seepage face and infiltration this run applies (none where the
    /// analysis is not partially saturated).
    pub fn hydraulic(&self) -> super::seepage::HydraulicBoundaries {
        self.inner.hydraulic()
    }

    /// What the runner was asked to apply and did not (GOM loads that reach
    /// no node or MP, liquid loads without a two-phase material), and why.
    pub fn notes(&self) -> Vec<String> {
        self.inner.notes()
    }

    /// Constant external forces on mesh nodes (0-based node, force in kN per
    /// metre in plane strain; z ignored in 2D), added to gravity from the
    /// next step on; a later call replaces them.
    pub fn set_nodal_loads(&mut self, loads: &[(u32, [f64; 3])]) -> Result<(), MpmError> {
        self.inner.set_nodal_loads(loads)
    }

    /// The formulation each material with MPs runs with (1-based material
    /// index).
    pub fn formulations(&self) -> Vec<(u32, Formulation)> {
        self.inner.formulations()
    }
}
