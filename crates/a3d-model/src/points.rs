//! Material points as Anura3D creates them, and the state a3d-init maps onto them.

/// One material point, in Anura3D's creation order.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MaterialPoint {
    /// 1-based running id, as Anura3D numbers MPs.
    pub id: u32,
    /// 0-based element index (element id − 1).
    pub element: u32,
    /// 1-based material index of the element.
    pub material: u32,
    /// 1-based local point number k within the element's table.
    pub local: u32,
    /// Global position (z = 0 in 2D).
    pub position: [f64; 3],
    /// Integration weight: table weight × det J (m² per metre in 2D plane
    /// strain, m³ in 3D), times the radius x in 2D-axisymmetric models (m³ per
    /// radian).
    pub volume: f64,
}

impl MaterialPoint {
    /// True when `other` is the same MP: same id and element, and a position
    /// equal within 1e-9 of the coordinates' size (a state table written for
    /// this model, read back).
    pub fn same_as(&self, other: &MaterialPoint) -> bool {
        let d = (0..3)
            .map(|k| (self.position[k] - other.position[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        self.id == other.id
            && self.element == other.element
            && d <= 1e-9 * (1.0 + other.position[0].abs() + other.position[1].abs())
    }
}

/// The mapped initial state of one MP, in Anura3D signs (tension positive,
/// pore pressure negative in compression), kPa.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize)]
pub struct MpState {
    /// Pore-water pressure.
    pub pwp: f64,
    /// Total stress xx, yy, zz, xy, yz, xz.
    pub total: [f64; 6],
    /// Degree of saturation used in Bishop's equation.
    pub saturation: f64,
}

impl MpState {
    /// Effective stress by Bishop: σ' = σ − S·p on the normal components.
    pub fn effective(&self) -> [f64; 6] {
        let mut s = self.total;
        for c in s.iter_mut().take(3) {
            *c -= self.saturation * self.pwp;
        }
        s
    }
}
