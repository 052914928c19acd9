//! The material parameters a3d-init assumes where the GOM gives none: K0 = 0.5
//! (the geostatic horizontal stress) and ν = 0.3 (σzz of a 2D FEM stress field
//! by plane-strain elasticity). The values live here, once, and
//! [`assumed_defaults`] lists which of them a model's materials rely on, so
//! that a report can name them instead of assuming silently.

use std::fmt;

use a3d_model::Material;

/// A material parameter that has a default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Parameter {
    /// The coefficient of earth pressure at rest (`$$K0_VALUE_SOLID`).
    K0,
    /// Poisson's ratio ν (`$$POISSON_RATIO`).
    PoissonRatio,
}

impl Parameter {
    /// Every parameter with a default.
    pub const ALL: [Parameter; 2] = [Parameter::K0, Parameter::PoissonRatio];

    /// The value assumed where a material gives none.
    pub fn default_value(self) -> f64 {
        match self {
            Parameter::K0 => 0.5,
            Parameter::PoissonRatio => 0.3,
        }
    }

    /// The GOM keyword that gives it.
    pub fn keyword(self) -> &'static str {
        match self {
            Parameter::K0 => "$$K0_VALUE_SOLID",
            Parameter::PoissonRatio => "$$POISSON_RATIO",
        }
    }

    /// Its symbol in messages.
    pub fn symbol(self) -> &'static str {
        match self {
            Parameter::K0 => "K0",
            Parameter::PoissonRatio => "ν",
        }
    }

    /// The material's own value, where the GOM gives one.
    pub fn of(self, material: &Material) -> Option<f64> {
        match self {
            Parameter::K0 => material.k0,
            Parameter::PoissonRatio => material.poisson_ratio,
        }
    }

    /// The value used for `material`: its own, else the default (also for
    /// no material at all).
    pub fn value(self, material: Option<&Material>) -> f64 {
        material
            .and_then(|m| self.of(m))
            .unwrap_or(self.default_value())
    }
}

/// A default assumed for one material.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AssumedDefault {
    /// The material's 1-based index.
    pub material: u32,
    pub name: String,
    pub parameter: Parameter,
    /// The value assumed.
    pub value: f64,
}

impl fmt::Display for AssumedDefault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "material {} `{}` has no {}: {} = {} assumed",
            self.material,
            self.name,
            self.parameter.keyword(),
            self.parameter.symbol(),
            self.value
        )
    }
}

/// The defaults of `parameters` that `materials` rely on, material by
/// material in their order.
pub fn assumed(materials: &[Material], parameters: &[Parameter]) -> Vec<AssumedDefault> {
    materials
        .iter()
        .flat_map(|m| {
            parameters
                .iter()
                .filter(|p| p.of(m).is_none())
                .map(|&p| AssumedDefault {
                    material: m.index,
                    name: m.name.clone(),
                    parameter: p,
                    value: p.default_value(),
                })
        })
        .collect()
}

/// Every default a3d-init assumes for `materials`: K0 and ν wherever the GOM
/// gives none.
pub fn assumed_defaults(materials: &[Material]) -> Vec<AssumedDefault> {
    assumed(materials, &Parameter::ALL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_parameters_are_listed_and_given_their_default() {
        let mut clay = Material::new(1, "clay", "dry_material");
        clay.k0 = Some(0.6);
        let sand = Material::new(2, "sand", "dry_material");
        let found = assumed_defaults(&[clay.clone(), sand.clone()]);
        let listed: Vec<String> = found.iter().map(|d| d.to_string()).collect();
        assert_eq!(
            listed,
            [
                "material 1 `clay` has no $$POISSON_RATIO: ν = 0.3 assumed",
                "material 2 `sand` has no $$K0_VALUE_SOLID: K0 = 0.5 assumed",
                "material 2 `sand` has no $$POISSON_RATIO: ν = 0.3 assumed",
            ]
        );
        assert_eq!(Parameter::K0.value(Some(&clay)), 0.6);
        assert_eq!(Parameter::K0.value(Some(&sand)), 0.5);
        assert_eq!(Parameter::PoissonRatio.value(None), 0.3);
        assert!(assumed(&[clay], &[Parameter::K0]).is_empty());
    }
}
