//! Materials as read from the GOM's positional material block.

/// Water retention curve of an unsaturated material (`$$WATER_RETENTION_CURVE`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum RetentionCurve {
    /// Anura3D's van Genuchten form: S = Smin + (Smax − Smin)·(1 + (s/P0)^(1/(1−λ)))^(−λ),
    /// with suction s in kPa.
    VanGenuchten {
        s_min: f64,
        s_max: f64,
        p0: f64,
        lambda: f64,
    },
    /// Linear: S = max(0, 1 − av·s), suction s in kPa.
    Linear { av: f64 },
}

impl RetentionCurve {
    /// Degree of saturation for a suction `s` (kPa, positive = suction).
    /// Returns 1 for s ≤ 0.
    pub fn saturation(&self, s: f64) -> f64 {
        self.anura3d_saturation(s).1
    }

    /// dS/ds at suction `s` (1/kPa; 0 for s ≤ 0), as the kernel's
    /// `CalculateDerivDegreeSaturation` forms it.
    pub fn derivative(&self, s: f64) -> f64 {
        if s <= 0.0 {
            return 0.0;
        }
        match *self {
            RetentionCurve::VanGenuchten {
                s_min,
                s_max,
                p0,
                lambda,
            } => {
                let x = s / p0;
                (s_max - s_min)
                    * (-lambda / (1.0 - lambda))
                    * (1.0 + x.powf(1.0 / (1.0 - lambda))).powf(-lambda - 1.0)
                    * x.powf(lambda / (1.0 - lambda))
                    / p0
            }
            RetentionCurve::Linear { av } => -av,
        }
    }

    /// Anura3D's retention routines at suction `s` (gas pressure 0): the Sr the
    /// kernel uses in σ' = σ − Sr·p, and the Sr it stores on the MP. They
    /// differ only for the linear curve past full desaturation, where the
    /// kernel clamps the stored value at 0 but not the one it uses.
    pub fn anura3d_saturation(&self, s: f64) -> (f64, f64) {
        if s <= 0.0 {
            return (1.0, 1.0);
        }
        match *self {
            RetentionCurve::VanGenuchten {
                s_min,
                s_max,
                p0,
                lambda,
            } => {
                let n = 1.0 / (1.0 - lambda);
                let sr = s_min + (s_max - s_min) * (1.0 + (s / p0).powf(n)).powf(-lambda);
                (sr, sr)
            }
            RetentionCurve::Linear { av } => {
                let sr = 1.0 - av * s;
                (sr, sr.max(0.0))
            }
        }
    }
}

/// One material record. Known parameters are typed; every name/value pair is
/// also kept verbatim in `properties`, in file order.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Material {
    /// 1-based position in the material block.
    pub index: u32,
    pub name: String,
    /// `$$MATERIAL_TYPE`, e.g. `dry_material`.
    pub material_type: String,
    /// `$$MATERIAL_MODEL_SOLID` (or `_LIQUID`), e.g. `mohr_coulomb`.
    pub model: Option<String>,
    pub porosity: Option<f64>,
    /// kg/m³
    pub density_solid: Option<f64>,
    /// kg/m³
    pub density_liquid: Option<f64>,
    pub k0: Option<f64>,
    /// kPa
    pub young_modulus: Option<f64>,
    pub poisson_ratio: Option<f64>,
    /// degrees
    pub friction_angle: Option<f64>,
    /// kPa
    pub cohesion: Option<f64>,
    /// degrees
    pub dilatancy_angle: Option<f64>,
    /// kPa
    pub tensile_strength: Option<f64>,
    pub retention: Option<RetentionCurve>,
    /// Every (keyword, value line) pair of the record after the head, in order.
    pub properties: Vec<(String, String)>,
}

/// Looking materials up by what a user types: a name or a 1-based index.
pub mod lookup {
    use super::Material;

    /// The index of the material named `name` (ASCII case ignored).
    pub fn by_name(materials: &[Material], name: &str) -> Option<u32> {
        materials
            .iter()
            .find(|m| m.name.eq_ignore_ascii_case(name))
            .map(|m| m.index)
    }

    /// `text` as a 1-based index of one of `materials`.
    pub fn by_number(materials: &[Material], text: &str) -> Option<u32> {
        text.parse::<u32>()
            .ok()
            .filter(|&i| i >= 1 && i as usize <= materials.len())
    }

    /// `1 sand, 2 clay`: the materials, for messages.
    pub fn list(materials: &[Material]) -> String {
        materials
            .iter()
            .map(|m| format!("{} {}", m.index, m.name))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl Material {
    /// A material with only its head (index, name, type) and no properties.
    pub fn new(index: u32, name: impl Into<String>, material_type: impl Into<String>) -> Material {
        Material {
            index,
            name: name.into(),
            material_type: material_type.into(),
            model: None,
            porosity: None,
            density_solid: None,
            density_liquid: None,
            k0: None,
            young_modulus: None,
            poisson_ratio: None,
            friction_angle: None,
            cohesion: None,
            dilatancy_angle: None,
            tensile_strength: None,
            retention: None,
            properties: Vec::new(),
        }
    }

    /// True for `unsaturated_material_*` types.
    pub fn is_unsaturated(&self) -> bool {
        self.material_type.starts_with("unsaturated_material")
    }

    /// True for types that carry a liquid phase (saturated or unsaturated).
    pub fn has_water(&self) -> bool {
        self.material_type.starts_with("saturated_material") || self.is_unsaturated()
    }

    /// Dry unit weight γ_dry = (1 − n)·ρs·g/1000 (kN/m³).
    pub fn gamma_dry(&self, g: f64) -> f64 {
        let n = self.porosity.unwrap_or(0.0);
        (1.0 - n) * self.density_solid.unwrap_or(0.0) * g / 1000.0
    }

    /// Unit weight at degree of saturation `s`: ((1 − n)ρs + n·S·ρw)·g/1000 (kN/m³).
    /// Materials without a liquid phase return γ_dry.
    pub fn gamma_at_saturation(&self, s: f64, g: f64) -> f64 {
        if !self.has_water() {
            return self.gamma_dry(g);
        }
        let n = self.porosity.unwrap_or(0.0);
        let rho_w = self.density_liquid.unwrap_or(1000.0);
        self.gamma_dry(g) + n * s.clamp(0.0, 1.0) * rho_w * g / 1000.0
    }

    /// Degree of saturation for an Anura3D-signed pore pressure `pwp`
    /// (negative = compression, positive = suction). 1 without a retention curve.
    pub fn saturation(&self, pwp: f64) -> f64 {
        match &self.retention {
            Some(curve) if self.is_unsaturated() => curve.saturation(pwp),
            _ => 1.0,
        }
    }
}

#[cfg(test)]
mod retention_tests {
    use super::RetentionCurve;

    /// dS/ds against a central difference of S, both curves, and 0 at and
    /// below zero suction.
    #[test]
    fn derivative_matches_a_finite_difference() {
        let curves = [
            RetentionCurve::VanGenuchten {
                s_min: 0.1,
                s_max: 1.0,
                p0: 1.96,
                lambda: 0.63,
            },
            RetentionCurve::Linear { av: 0.05 },
        ];
        for curve in curves {
            for s in [0.1, 0.5, 1.0, 2.0, 5.0, 10.0] {
                let h = 1e-6 * s;
                let fd = (curve.saturation(s + h) - curve.saturation(s - h)) / (2.0 * h);
                let exact = curve.derivative(s);
                assert!(
                    (exact - fd).abs() <= 1e-6 * fd.abs().max(1e-3),
                    "{curve:?} at s = {s}: {exact} vs {fd}"
                );
            }
            assert_eq!(curve.derivative(0.0), 0.0);
            assert_eq!(curve.derivative(-3.0), 0.0);
        }
    }
}
