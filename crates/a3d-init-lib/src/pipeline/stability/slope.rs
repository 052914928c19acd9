//! Limit equilibrium on an Anura3D model: the section from the GOM mesh
//! (its elements with their materials; the ground is the mesh's upper
//! boundary), unit weights as Anura3D forms them from each material's
//! densities, porosity and the degree of saturation, the pore pressure at the
//! slice bases from the mapped state (the MPs, or FEM nodes, interpolated with
//! the kernel on a raster), and the search of [`crate::slope`]. Materials
//! without Mohr–Coulomb strength are named and left unbreakable. Writes
//! nothing; [`write_surface_plot`] draws the critical surface over the pore
//! pressure.

use std::path::Path;

use plotters::style::RGBColor;

use crate::kernel::KernelKind;
use crate::kernel::mapper;
use crate::model::{AnuraModel, Dimension, Material, MaterialPoint, MpState};
use crate::pipeline::PipelineError;
use crate::pipeline::io::plot;
use crate::slope::{
    self, Domain, Method, Problem, Raster, RasterSettings, Scattered, SearchSettings,
    SlopeMaterial, Strength, Suction,
};

/// How a limit-equilibrium analysis runs.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LeOptions {
    pub method: Method,
    pub suction: Suction,
    pub search: SearchSettings,
    /// Equal slices between a surface's ends.
    pub n_slices: usize,
    /// Shallowest admissible surface (m); `None`: 5 % of the ground's height
    /// range.
    pub min_depth: Option<f64>,
    /// Relative tolerance on every factor.
    pub tolerance: f64,
    /// Smoothing length of the pore-pressure interpolation (m); `None`: the
    /// spacing rule on the points (h = factor · median spacing).
    pub h: Option<f64>,
}

impl Default for LeOptions {
    fn default() -> Self {
        LeOptions {
            method: Method::MorgensternPrice(slope::Interslice::HalfSine),
            suction: Suction::Bishop,
            search: SearchSettings::default(),
            n_slices: 30,
            min_depth: None,
            tolerance: 1e-6,
            h: None,
        }
    }
}

/// A material as the analysis used it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MaterialUse {
    /// 1-based GOM index.
    pub index: u32,
    pub name: String,
    pub model: String,
    /// Mohr–Coulomb strength; `None`: unbreakable.
    pub strength: Option<Strength>,
    /// Unit weight at full saturation and dry (kN/m³).
    pub unit_weight_saturated: f64,
    pub unit_weight_dry: f64,
}

/// Where the pore pressure at the slice bases came from.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FieldNote {
    /// "material points" or "FEM nodes".
    pub source: String,
    pub points: usize,
    pub kernel: String,
    pub h: f64,
    pub raster_spacing: f64,
}

/// The section of a model: the domain, its materials and what they are.
pub struct Section {
    pub domain: Domain,
    pub materials: Vec<SlopeMaterial>,
    pub uses: Vec<MaterialUse>,
    pub gravity: f64,
    /// The element of each region.
    region_element: Vec<usize>,
}

/// The analysis of one state, with what it was run on.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LeReport {
    pub method: &'static str,
    pub factor: f64,
    pub interslice: Option<slope::Interslice>,
    /// F_f and F_m at the final λ (Janbu: F_f uncorrected; Bishop and the
    /// ordinary method: F_m only).
    pub force_factor: Option<f64>,
    pub moment_factor: Option<f64>,
    pub lambda: Option<f64>,
    pub janbu_f0: Option<f64>,
    pub converged: bool,
    pub tolerance: f64,
    /// "non-circular" (refined) or "circular".
    pub surface_kind: &'static str,
    /// The critical slip surface, left to right.
    pub critical_surface: Vec<[f64; 2]>,
    pub suction: Suction,
    /// In words, with the φᵇ used.
    pub suction_rule: String,
    pub analysis: slope::Analysis,
    pub materials: Vec<MaterialUse>,
    pub pore_field: FieldNote,
    /// The ground surface of the section, left to right.
    pub ground: Vec<[f64; 2]>,
    pub gravity: f64,
    pub runtime_s: f64,
    /// What the result does not account for (water ponding above the
    /// ground).
    pub warnings: Vec<String>,
}

fn strength_of(m: &Material) -> Option<Strength> {
    (m.model.as_deref() == Some("mohr_coulomb"))
        .then_some(())
        .and(m.friction_angle)
        .map(|phi| Strength {
            cohesion: m.cohesion.unwrap_or(0.0),
            friction_angle: phi,
            phi_b: None,
        })
}

/// The section of `model`: one region per active element, its unit weight
/// γ = ((1 − n)·ρs + n·S·ρw)·g/1000 at the element's degree of saturation
/// (dry materials: (1 − n)·ρs·g/1000).
pub fn build_section(
    model: &AnuraModel,
    gravity: f64,
    element_saturation: &[f64],
) -> Result<Section, PipelineError> {
    if model.mesh.dimension != Dimension::PlaneStrain {
        return Err(PipelineError::Model(format!(
            "limit equilibrium works on 2D plane-strain sections; the model is {}",
            model.mesh.dimension.gom_name()
        )));
    }
    let materials: Vec<SlopeMaterial> = model
        .materials
        .iter()
        .map(|m| SlopeMaterial {
            name: m.name.clone(),
            strength: strength_of(m),
        })
        .collect();
    let uses = model
        .materials
        .iter()
        .zip(&materials)
        .map(|(m, s)| MaterialUse {
            index: m.index,
            name: m.name.clone(),
            model: m.model.clone().unwrap_or_default(),
            strength: s.strength,
            unit_weight_saturated: m.gamma_at_saturation(1.0, gravity),
            unit_weight_dry: m.gamma_dry(gravity),
        })
        .collect();
    let mut region_element = Vec::new();
    let element_region: Vec<Option<(usize, f64)>> = (0..model.mesh.n_elements())
        .map(|e| {
            let m = model.material_of(e)?;
            region_element.push(e);
            let s = element_saturation.get(e).copied().unwrap_or(1.0);
            Some(((m.index - 1) as usize, m.gamma_at_saturation(s, gravity)))
        })
        .collect();
    let domain = Domain::from_mesh(&model.mesh, &element_region)
        .map_err(|e| PipelineError::Model(e.to_string()))?;
    Ok(Section {
        domain,
        materials,
        uses,
        gravity,
        region_element,
    })
}

impl Section {
    /// The elements' centroids, by region.
    fn centroids(&self) -> Vec<[f64; 2]> {
        self.domain
            .regions()
            .iter()
            .map(|r| {
                let n = r.polygon.len() as f64;
                let (x, y) = r
                    .polygon
                    .iter()
                    .fold((0.0, 0.0), |(a, b), p| (a + p[0], b + p[1]));
                [x / n, y / n]
            })
            .collect()
    }

    /// The element each region is.
    pub fn region_elements(&self) -> &[usize] {
        &self.region_element
    }
}

/// Per element: the mean degree of saturation of its MPs (volume weighted);
/// 1 for an element without MPs.
pub fn element_saturation(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
) -> Vec<f64> {
    let n = model.mesh.n_elements();
    let mut sum = vec![0.0; n];
    let mut weight = vec![0.0; n];
    for (p, s) in points.iter().zip(states) {
        let e = p.element as usize;
        if e < n && s.saturation.is_finite() {
            let w = p.volume.abs().max(1e-300);
            sum[e] += w * s.saturation;
            weight[e] += w;
        }
    }
    sum.iter()
        .zip(&weight)
        .map(|(s, w)| if *w > 0.0 { s / w } else { 1.0 })
        .collect()
}

/// The smoothing length by the paper's spacing rule on `positions`.
fn spacing_h(positions: &[[f64; 3]], kernel: KernelKind) -> f64 {
    kernel.spacing_factor() * mapper::median_spacing(positions, 2)
}

/// Pore pressures at scattered points (MPs or FEM nodes).
pub struct PointValues<'a> {
    pub positions: &'a [[f64; 3]],
    /// Anura3D sign.
    pub pwp: &'a [f64],
    /// `None`: from each material's retention curve.
    pub saturation: Option<&'a [f64]>,
    /// Each point's 1-based GOM material index.
    pub material: &'a [u32],
    /// "material points" or "FEM nodes", for the report.
    pub source: &'a str,
}

/// The pore field from scattered values (the kernel onto the section's
/// raster): a point of a material without water or outside the section is
/// left out; without saturations a material's retention curve gives them
/// (1 without one, 0 for a dry material).
pub fn raster_field(
    section: &Section,
    model: &AnuraModel,
    values: &PointValues<'_>,
    h: Option<f64>,
) -> Result<(Raster, FieldNote), PipelineError> {
    let PointValues {
        positions,
        pwp,
        saturation,
        material,
        source,
    } = *values;
    let kernel = KernelKind::Cubic;
    let h = match h {
        Some(h) => h,
        None => spacing_h(positions, kernel),
    };
    let slots: Vec<u32> = material.iter().map(|&m| m.saturating_sub(1)).collect();
    let scattered = Scattered {
        positions,
        pwp,
        saturation,
        material: &slots,
    };
    let materials = &model.materials;
    let saturation_of = |slot: usize, pwp: f64| -> f64 {
        materials.get(slot).map_or(1.0, |m| {
            if m.has_water() {
                m.saturation(pwp)
            } else {
                0.0
            }
        })
    };
    let settings = RasterSettings {
        kernel,
        h,
        spacing: 0.5 * h,
    };
    let raster = Raster::from_scattered(&section.domain, &scattered, &settings, &saturation_of)
        .map_err(|e| PipelineError::Numerical(e.to_string()))?;
    let note = FieldNote {
        source: source.to_string(),
        points: positions.len(),
        kernel: "cubic".into(),
        h,
        raster_spacing: raster.spacing(),
    };
    Ok((raster, note))
}

/// Unit weights from the pore field: each element at the saturation the
/// field gives at its centroid.
pub fn weights_from_field(
    model: &AnuraModel,
    section: &Section,
    field: &dyn slope::PoreField,
) -> Result<Section, PipelineError> {
    let mut saturation = vec![1.0; model.mesh.n_elements()];
    for (k, c) in section.centroids().iter().enumerate() {
        saturation[section.region_element[k]] = field.sample(c[0], c[1]).saturation;
    }
    build_section(model, section.gravity, &saturation)
}

/// The default minimum depth: 5 % of the ground's height range.
pub fn default_min_depth(domain: &Domain) -> f64 {
    let (lo, hi) = domain
        .ground()
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[1]), b.max(p[1]))
        });
    0.05 * (hi - lo)
}

/// Runs the search on a section with a pore field.
pub fn analyse(
    section: &Section,
    field: &dyn slope::PoreField,
    note: FieldNote,
    options: &LeOptions,
) -> Result<LeReport, PipelineError> {
    let started = std::time::Instant::now();
    let min_depth = options
        .min_depth
        .unwrap_or_else(|| default_min_depth(&section.domain));
    let problem = Problem {
        domain: &section.domain,
        materials: &section.materials,
        field,
        suction: options.suction,
        n_slices: options.n_slices,
        min_depth,
        tolerance: options.tolerance,
    };
    let analysis =
        slope::analyse(&problem, options.method, &options.search).map_err(|e| match e {
            slope::SlopeError::Settings(_) => PipelineError::Option(e.to_string()),
            slope::SlopeError::NoSurface(_) => PipelineError::Numerical(e.to_string()),
            _ => PipelineError::Model(e.to_string()),
        })?;
    let s = &analysis.critical.solution;
    let suction_rule = match options.suction {
        Suction::Bishop => "Bishop's effective stress with χ = S: τ = c′ + (σ − S·u)·tan φ′".into(),
        Suction::Ignored => "suction ignored: τ = c′ + (σ − max(u, 0))·tan φ′".into(),
        Suction::PhiB(phi_b) => format!(
            "Fredlund's φᵇ: τ = c′ + σ·tan φ′ + s·tan φᵇ under suction s, φᵇ = {}",
            phi_b.map_or("φ′/2 of each material".to_string(), |v| format!("{v}°"))
        ),
    };
    Ok(LeReport {
        method: options.method.name(),
        factor: analysis.critical.factor,
        interslice: options.method.interslice(),
        force_factor: s.force_factor,
        moment_factor: s.moment_factor,
        lambda: s.lambda,
        janbu_f0: s.janbu_f0,
        converged: s.converged,
        tolerance: options.tolerance,
        surface_kind: if analysis.search.polyline_refinement.is_some() {
            "non-circular"
        } else {
            "circular"
        },
        critical_surface: analysis.critical.surface.clone(),
        suction: options.suction,
        suction_rule,
        materials: section.uses.clone(),
        pore_field: note,
        ground: section.domain.ground().to_vec(),
        gravity: section.gravity,
        runtime_s: started.elapsed().as_secs_f64(),
        warnings: ponding(&section.domain, field).into_iter().collect(),
        analysis,
    })
}

/// Water pressure (kPa, positive in compression) at the ground above which
/// the field is taken to stand above the ground: 0.5 kPa, 5 cm of water.
pub const PONDING_KPA: f64 = 0.5;

/// A warning when the pore pressure at the ground is compressive (above
/// [`PONDING_KPA`]) somewhere: water stands above the ground there, and its
/// weight and thrust are not loads on the section here (slope programs add
/// a ponded reservoir as a surface load).
pub fn ponding(domain: &Domain, field: &dyn slope::PoreField) -> Option<String> {
    let (x0, x1) = domain.x_range();
    let n = 200;
    let (mut worst, mut at) = (PONDING_KPA, None);
    for i in 0..=n {
        let x = x0 + (x1 - x0) * (i as f64 + 0.5) / (n as f64 + 1.0);
        let Some(y) = domain.ground_y(x) else {
            continue;
        };
        let u = -field.sample(x, y).pwp;
        if u > worst {
            (worst, at) = (u, Some(x));
        }
    }
    at.map(|x| {
        format!(
            "the pore pressure at the ground is compressive (water ponding above it), up to {worst:.2} kPa at x = {x:.3} m: its weight and thrust are not surface loads in this analysis, so the factor does not account for them"
        )
    })
}

/// The section of a model with its MPs' saturation and the pore raster of
/// their state.
fn state_section(
    model: &AnuraModel,
    gravity: f64,
    points: &[MaterialPoint],
    states: &[MpState],
    h: Option<f64>,
) -> Result<(Section, Raster, FieldNote), PipelineError> {
    let section = build_section(model, gravity, &element_saturation(model, points, states))?;
    let positions: Vec<[f64; 3]> = points.iter().map(|p| p.position).collect();
    let pwp: Vec<f64> = states.iter().map(|s| s.pwp).collect();
    let saturation: Vec<f64> = states.iter().map(|s| s.saturation).collect();
    let material: Vec<u32> = points.iter().map(|p| p.material).collect();
    let values = PointValues {
        positions: &positions,
        pwp: &pwp,
        saturation: Some(&saturation),
        material: &material,
        source: "material points",
    };
    let (raster, note) = raster_field(&section, model, &values, h)?;
    Ok((section, raster, note))
}

/// Limit equilibrium on a model's MP state: the section with the MPs'
/// saturation, the MPs' pore pressure on the raster.
pub fn analyse_state(
    model: &AnuraModel,
    gravity: f64,
    points: &[MaterialPoint],
    states: &[MpState],
    options: &LeOptions,
) -> Result<LeReport, PipelineError> {
    let started = std::time::Instant::now();
    let (section, raster, note) = state_section(model, gravity, points, states, options.h)?;
    let mut report = analyse(&section, &raster, note, options)?;
    report.runtime_s = started.elapsed().as_secs_f64();
    Ok(report)
}

/// The strength a continuum with dilatancy ψ mobilises at reduction `factor`
/// (Davis 1968): φ′_F and c′_F reduced by F, ψ_F = min(ψ, φ′_F), then both
/// times β = cos ψ_F cos φ′_F / (1 − sin ψ_F sin φ′_F).
pub fn davis_strength(strength: Strength, dilatancy: f64, factor: f64) -> Strength {
    let phi = (strength.friction_angle.to_radians().tan() / factor).atan();
    let psi = dilatancy.to_radians().min(phi).max(0.0);
    let beta = psi.cos() * phi.cos() / (1.0 - psi.sin() * phi.sin());
    Strength {
        cohesion: beta * strength.cohesion / factor,
        friction_angle: (beta * phi.tan()).atan().to_degrees(),
        phi_b: strength.phi_b,
    }
}

/// The reduction factor at which limit equilibrium on Davis-reduced
/// strengths ([`davis_strength`]) reaches 1 on the given surface.
pub fn davis_factor(
    model: &AnuraModel,
    gravity: f64,
    points: &[MaterialPoint],
    states: &[MpState],
    options: &LeOptions,
    surface: &[[f64; 2]],
    axis: [f64; 2],
) -> Result<f64, PipelineError> {
    let (section, raster, _) = state_section(model, gravity, points, states, options.h)?;
    let surface = slope::Surface::polyline(&section.domain, surface.to_vec(), Some(axis))
        .map_err(|r| PipelineError::Numerical(format!("the critical surface {}", r.describe())))?;
    let at = |factor: f64| -> Result<f64, PipelineError> {
        let materials: Vec<SlopeMaterial> = section
            .materials
            .iter()
            .zip(&model.materials)
            .map(|(m, g)| SlopeMaterial {
                name: m.name.clone(),
                strength: m
                    .strength
                    .map(|s| davis_strength(s, g.dilatancy_angle.unwrap_or(0.0), factor)),
            })
            .collect();
        let problem = Problem {
            domain: &section.domain,
            materials: &materials,
            field: &raster,
            suction: options.suction,
            n_slices: options.n_slices,
            min_depth: 0.0,
            tolerance: options.tolerance,
        };
        let (_, solution) = slope::evaluate_surface(&problem, options.method, &surface)
            .map_err(|e| PipelineError::Numerical(e.to_string()))?;
        if solution.converged {
            Ok(solution.factor)
        } else {
            Err(PipelineError::Numerical(
                solution.failure.unwrap_or("no convergence").into(),
            ))
        }
    };
    // The factor on reduced strengths falls as the reduction grows: bisect.
    let (mut lo, mut hi) = (0.05, 20.0);
    if at(lo)? < 1.0 || at(hi)? > 1.0 {
        return Err(PipelineError::Numerical(
            "the Davis factor lies outside [0.05, 20]".into(),
        ));
    }
    while hi - lo > 1e-6 * hi {
        let mid = 0.5 * (lo + hi);
        if at(mid)? > 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// The critical surface (and the best circle when it differs) over the MPs'
/// pore pressure, with the ground line.
pub fn write_surface_plot(
    path: &Path,
    title: &str,
    report: &LeReport,
    field: &[(f64, f64, f64)],
    ground: &[[f64; 2]],
) -> Result<(), PipelineError> {
    let line = |p: &[[f64; 2]]| p.iter().map(|q| (q[0], q[1])).collect::<Vec<_>>();
    let mut overlays = vec![plot::Overlay {
        label: "ground",
        points: line(ground),
        color: RGBColor(0, 0, 0),
        width: 1,
    }];
    if report.surface_kind == "non-circular" {
        overlays.push(plot::Overlay {
            label: "best circle",
            points: line(&report.analysis.circular.surface),
            color: RGBColor(255, 127, 14),
            width: 2,
        });
    }
    overlays.push(plot::Overlay {
        label: "critical surface",
        points: line(&report.critical_surface),
        color: RGBColor(214, 39, 40),
        width: 3,
    });
    plot::field_map_with(path, title, "pwp (kPa, Anura3D sign)", field, &overlays)
}
