//! Slices of a slip surface: widths, base geometry, weights from the regions'
//! unit weights, base strength from the region holding the base point, and
//! the pore pressure there with the chosen suction rule.
//!
//! Slice boundaries: `n` equal steps between the surface's ends, plus every
//! surface vertex and ground vertex in between (so each slice has a straight
//! base and a straight top). The weight is b times the column integral of γ
//! at the slice's mid x, from the base up to the ground; the base point is
//! the middle of the base chord. Slices are returned in the canonical frame
//! the methods use: the mass moves toward −x, slices ordered from the toe
//! (a surface whose toe is on the right is mirrored, x → −x). No I/O.

use super::field::PoreField;
use super::geometry::Domain;
use super::surface::{Reject, Surface};
use super::{SlopeMaterial, Suction};

/// One slice, in the canonical frame (the mass moves toward −x).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Slice {
    /// Mid abscissa (canonical).
    pub x: f64,
    pub width: f64,
    /// Middle of the base chord (canonical x, y).
    pub base: [f64; 2],
    /// Base inclination α (rad): positive where the base rises away from the
    /// toe.
    pub alpha: f64,
    /// Base length b / cos α.
    pub length: f64,
    /// Weight (kN per m run).
    pub weight: f64,
    /// Effective cohesion at the base (with the φᵇ suction term).
    pub cohesion: f64,
    pub tan_phi: f64,
    /// Pore pressure entering the strength, u_eff = χ·u (kPa, + compression).
    pub pore_pressure: f64,
    /// pwp at the base point (kPa, Anura3D sign) and degree of saturation.
    pub pwp: f64,
    pub saturation: f64,
    /// 0-based material slot.
    pub material: usize,
}

/// The slices of one surface with what the methods need besides them.
#[derive(Clone, Debug, PartialEq)]
pub struct SliceSet {
    /// Ordered from the toe (canonical x increasing).
    pub slices: Vec<Slice>,
    /// Canonical x of the slice boundaries (n + 1).
    pub boundaries: Vec<f64>,
    /// Moment axis (canonical).
    pub axis: [f64; 2],
    /// True when the real x is −(canonical x).
    pub mirrored: bool,
    /// Janbu's d/L of the surface.
    pub depth_ratio: f64,
}

impl SliceSet {
    /// Real x of a canonical x.
    pub fn real_x(&self, x: f64) -> f64 {
        if self.mirrored { -x } else { x }
    }
}

/// What slicing needs besides the surface.
pub struct SliceInputs<'a> {
    pub domain: &'a Domain,
    pub materials: &'a [SlopeMaterial],
    pub field: &'a dyn PoreField,
    pub suction: Suction,
    /// Equal steps between the ends.
    pub n_slices: usize,
    /// Smallest admissible depth below the ground (m).
    pub min_depth: f64,
}

/// Slices `surface`.
pub fn slice(surface: &Surface, inputs: &SliceInputs<'_>) -> Result<SliceSet, Reject> {
    let p = &surface.points;
    let (xa, xb) = (p[0][0], p[p.len() - 1][0]);
    let width = xb - xa;
    let (g0, g1) = inputs.domain.x_range();
    if width.is_nan() || width <= 1e-6 * (g1 - g0) {
        return Err(Reject::TooSmall);
    }
    if surface.depth(inputs.domain) < inputs.min_depth {
        return Err(Reject::TooSmall);
    }
    let n = inputs.n_slices.max(1);
    let mut xs: Vec<f64> = (0..=n).map(|i| xa + width * i as f64 / n as f64).collect();
    xs.extend(p.iter().map(|v| v[0]).filter(|&x| x > xa && x < xb));
    xs.extend(
        inputs
            .domain
            .ground()
            .iter()
            .map(|v| v[0])
            .filter(|&x| x > xa && x < xb),
    );
    xs.sort_by(f64::total_cmp);
    let tiny = 1e-9 * width;
    xs.dedup_by(|a, b| (*a - *b).abs() <= tiny);
    // The mass moves from the higher end toward the lower end.
    let mirrored = p[0][1] > p[p.len() - 1][1];
    let sign = if mirrored { -1.0 } else { 1.0 };
    let mut slices = Vec::with_capacity(xs.len());
    for w in xs.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        let b = x1 - x0;
        let (Some(y0), Some(y1)) = (surface_y_right(surface, x0), surface_y_left(surface, x1))
        else {
            return Err(Reject::Shape);
        };
        let xm = 0.5 * (x0 + x1);
        let ym = 0.5 * (y0 + y1);
        let column = inputs.domain.column(xm, ym);
        let Some(region) = column.region else {
            return Err(Reject::LeavesModel);
        };
        let material = inputs.domain.regions()[region].material;
        let Some(strength) = inputs.materials[material].strength else {
            return Err(Reject::Unbreakable);
        };
        let sample = inputs.field.sample(xm, ym);
        let u = -sample.pwp;
        let tan_phi = strength.friction_angle.to_radians().tan();
        let (cohesion, pore_pressure) = match inputs.suction {
            Suction::Bishop => (strength.cohesion, sample.saturation.clamp(0.0, 1.0) * u),
            Suction::Ignored => (strength.cohesion, u.max(0.0)),
            Suction::PhiB(given) => {
                if u >= 0.0 {
                    (strength.cohesion, u)
                } else {
                    let phi_b = given.unwrap_or_else(|| strength.phi_b());
                    (strength.cohesion - u * phi_b.to_radians().tan(), 0.0)
                }
            }
        };
        let alpha_real = (y1 - y0).atan2(b);
        slices.push(Slice {
            x: sign * xm,
            width: b,
            base: [sign * xm, ym],
            alpha: sign * alpha_real,
            length: ((y1 - y0).powi(2) + b * b).sqrt(),
            weight: b * column.weight,
            cohesion,
            tan_phi,
            pore_pressure,
            pwp: sample.pwp,
            saturation: sample.saturation,
            material,
        });
    }
    if mirrored {
        slices.reverse();
    }
    let mut boundaries: Vec<f64> = xs.iter().map(|&x| sign * x).collect();
    if mirrored {
        boundaries.reverse();
    }
    Ok(SliceSet {
        slices,
        boundaries,
        axis: [sign * surface.axis[0], surface.axis[1]],
        mirrored,
        depth_ratio: surface.depth_ratio(),
    })
}

/// Surface y just right of `x` (the lower end of a vertical segment at x is
/// the left end of the next chord).
fn surface_y_right(surface: &Surface, x: f64) -> Option<f64> {
    let p = &surface.points;
    let k = p.partition_point(|v| v[0] <= x);
    if k == 0 {
        return None;
    }
    if k == p.len() {
        return (p[k - 1][0] == x).then_some(p[k - 1][1]);
    }
    let (a, b) = (p[k - 1], p[k]);
    Some(a[1] + (x - a[0]) / (b[0] - a[0]) * (b[1] - a[1]))
}

/// Surface y just left of `x`.
fn surface_y_left(surface: &Surface, x: f64) -> Option<f64> {
    let p = &surface.points;
    let k = p.partition_point(|v| v[0] < x);
    if k == p.len() {
        return None;
    }
    if k == 0 {
        return (p[0][0] == x).then_some(p[0][1]);
    }
    let (a, b) = (p[k - 1], p[k]);
    Some(a[1] + (x - a[0]) / (b[0] - a[0]) * (b[1] - a[1]))
}
