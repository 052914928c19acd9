//! FEM node results as a3d-init holds them after reading and converting:
//! SI units (m, kPa) and Anura3D signs, whatever the source used.

/// Stress tensor component, in Anura3D's order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum StressComponent {
    Xx,
    Yy,
    Zz,
    Xy,
    Yz,
    Xz,
}

impl StressComponent {
    pub const ALL: [StressComponent; 6] = [
        StressComponent::Xx,
        StressComponent::Yy,
        StressComponent::Zz,
        StressComponent::Xy,
        StressComponent::Yz,
        StressComponent::Xz,
    ];

    /// Position in a `[f64; 6]` tensor.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Short name: `xx`, `yy`, …
    pub fn suffix(self) -> &'static str {
        ["xx", "yy", "zz", "xy", "yz", "xz"][self as usize]
    }

    /// Normal components are xx, yy and zz.
    pub fn is_normal(self) -> bool {
        self.index() < 3
    }
}

/// A physical quantity carried by a FEM node column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum Quantity {
    /// Pore-water pressure (kPa, Anura3D sign: negative in compression).
    Pwp,
    /// Total stress component (kPa, tension positive).
    TotalStress(StressComponent),
    /// Effective stress component (kPa, tension positive).
    EffectiveStress(StressComponent),
}

impl Quantity {
    /// Stable name used in tables, reports and `--field`: `pwp`, `sxx`, `esxx`, …
    pub fn name(self) -> String {
        match self {
            Quantity::Pwp => "pwp".to_string(),
            Quantity::TotalStress(c) => format!("s{}", c.suffix()),
            Quantity::EffectiveStress(c) => format!("es{}", c.suffix()),
        }
    }

    /// Inverse of [`Quantity::name`].
    pub fn from_name(s: &str) -> Option<Quantity> {
        if s == "pwp" {
            return Some(Quantity::Pwp);
        }
        for c in StressComponent::ALL {
            if s == format!("s{}", c.suffix()) {
                return Some(Quantity::TotalStress(c));
            }
            if s == format!("es{}", c.suffix()) {
                return Some(Quantity::EffectiveStress(c));
            }
        }
        None
    }
}

/// A cloud of FEM nodes with field values, ready to be mapped.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct FemNodes {
    /// 2 or 3.
    pub dim: usize,
    /// Node ids (from the file, or 1..=n when the file has none).
    pub ids: Vec<i64>,
    /// Coordinates in m; z = 0 in 2D.
    pub positions: Vec<[f64; 3]>,
    /// Optional region / material label per node.
    pub region: Option<Vec<String>>,
    /// Field columns, each with one value per node.
    pub fields: Vec<(Quantity, Vec<f64>)>,
}

impl FemNodes {
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The values of `q`, when present.
    pub fn field(&self, q: Quantity) -> Option<&[f64]> {
        self.fields
            .iter()
            .find(|(k, _)| *k == q)
            .map(|(_, v)| v.as_slice())
    }

    /// True when all six (3D) or the four in-plane (2D) total stress components exist.
    pub fn has_total_stress(&self) -> bool {
        let needed: &[StressComponent] = if self.dim == 3 {
            &StressComponent::ALL
        } else {
            &[
                StressComponent::Xx,
                StressComponent::Yy,
                StressComponent::Xy,
            ]
        };
        needed
            .iter()
            .all(|&c| self.field(Quantity::TotalStress(c)).is_some())
    }
}
