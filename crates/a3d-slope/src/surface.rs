//! Slip surfaces: circles and polylines, and where they run below the ground.
//!
//! Every surface is analysed as a polyline from its left end to its right
//! end, both on the ground, x non-decreasing (vertical end segments are
//! allowed; they carry no slice). A circle becomes the chords of its lower arc
//! between the two ground crossings around its lowest point, with vertices at
//! equal x steps. The moment axis is the circle's centre, or for a polyline
//! the centre of the circle it was refined from (else the circle through its
//! ends and its deepest vertex). No I/O.

use super::geometry::{Domain, polyline_y};

/// A circle: centre and radius.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Circle {
    pub xc: f64,
    pub yc: f64,
    pub r: f64,
}

/// A slip surface ready to be sliced.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    /// Left end to right end, both on the ground.
    pub points: Vec<[f64; 2]>,
    /// Moment axis.
    pub axis: [f64; 2],
    /// The circle it is (or was refined from).
    pub circle: Option<Circle>,
}

/// Why a trial surface cannot be analysed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum Reject {
    /// It does not cut the ground twice below its centre.
    MissesGround,
    /// It leaves the section through a side or the base, or a base point lies
    /// outside every region.
    LeavesModel,
    /// A slice base lies in a material without Mohr–Coulomb strength.
    Unbreakable,
    /// Shallower than the minimum depth, or narrower than the minimum width.
    TooSmall,
    /// Not a valid polyline (x decreasing, above the ground, not concave up).
    Shape,
}

impl Reject {
    pub fn describe(self) -> &'static str {
        match self {
            Reject::MissesGround => "does not cut the ground twice below its centre",
            Reject::LeavesModel => "leaves the section (side, base, or a hole)",
            Reject::Unbreakable => "passes through a material without Mohr–Coulomb strength",
            Reject::TooSmall => "shallower than the minimum depth or too narrow",
            Reject::Shape => "not an admissible polyline",
        }
    }
}

impl Circle {
    /// The circle through `a` and `b` whose lower arc between them subtends
    /// 2θ (centre above the chord); θ in (0, π/2).
    pub fn through(a: [f64; 2], b: [f64; 2], theta: f64) -> Circle {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let c = (dx * dx + dy * dy).sqrt();
        // Upward normal of the chord.
        let (mut nx, mut ny) = (-dy / c, dx / c);
        if ny < 0.0 {
            (nx, ny) = (-nx, -ny);
        }
        let offset = 0.5 * c / theta.tan();
        Circle {
            xc: 0.5 * (a[0] + b[0]) + nx * offset,
            yc: 0.5 * (a[1] + b[1]) + ny * offset,
            r: 0.5 * c / theta.sin(),
        }
    }

    /// y of the lower arc at `x` (inside |x − xc| ≤ r).
    pub fn lower(&self, x: f64) -> f64 {
        let d = x - self.xc;
        self.yc - (self.r * self.r - d * d).max(0.0).sqrt()
    }

    /// The chords of the lower arc below the ground, `n` of equal width.
    pub fn trace(&self, domain: &Domain, n: usize) -> Result<Surface, Reject> {
        if !(self.r > 0.0 && self.r.is_finite() && self.xc.is_finite() && self.yc.is_finite()) {
            return Err(Reject::MissesGround);
        }
        let ground = domain.ground();
        // Crossings of the lower arc with the ground segments.
        let mut xs = Vec::new();
        for w in ground.windows(2) {
            let (p, q) = (w[0], w[1]);
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            let (fx, fy) = (p[0] - self.xc, p[1] - self.yc);
            let a = dx * dx + dy * dy;
            if a == 0.0 {
                continue;
            }
            let b = 2.0 * (fx * dx + fy * dy);
            let c = fx * fx + fy * fy - self.r * self.r;
            let disc = b * b - 4.0 * a * c;
            if disc < 0.0 {
                continue;
            }
            let sq = disc.sqrt();
            for t in [(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)] {
                if (0.0..=1.0).contains(&t) {
                    let y = p[1] + t * dy;
                    if y < self.yc {
                        xs.push(p[0] + t * dx);
                    }
                }
            }
        }
        xs.sort_by(f64::total_cmp);
        xs.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * self.r);
        // The interval around the arc's lowest point where the arc is below ground.
        let below = |x: f64| domain.ground_y(x).is_some_and(|g| g > self.lower(x));
        let k = xs.partition_point(|&x| x <= self.xc);
        if !below(self.xc) {
            return Err(Reject::MissesGround);
        }
        if k == 0 || k == xs.len() {
            // Below the ground at its lowest point but without a crossing on
            // one side: it runs out through a side of the section.
            return Err(Reject::LeavesModel);
        }
        let (xa, xb) = (xs[k - 1], xs[k]);
        let (g0, g1) = domain.x_range();
        let margin = 1e-9 * (g1 - g0);
        if xa <= g0 + margin || xb >= g1 - margin {
            return Err(Reject::LeavesModel);
        }
        let mut points = Vec::with_capacity(n + 1);
        for i in 0..=n {
            let x = xa + (xb - xa) * i as f64 / n as f64;
            points.push([x, self.lower(x)]);
        }
        Ok(Surface {
            points,
            axis: [self.xc, self.yc],
            circle: Some(*self),
        })
    }
}

impl Surface {
    /// A polyline surface. Its ends are moved onto the ground when within
    /// 1e-6 of the section's size; the axis is `axis` or, without it, the
    /// centre of the circle through the ends and the deepest vertex.
    pub fn polyline(
        domain: &Domain,
        points: Vec<[f64; 2]>,
        axis: Option<[f64; 2]>,
    ) -> Result<Surface, Reject> {
        if points.len() < 2 || points.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Reject::Shape);
        }
        if points.windows(2).any(|w| w[1][0] < w[0][0]) {
            return Err(Reject::Shape);
        }
        let (g0, g1) = domain.x_range();
        let tol = 1e-6 * (g1 - g0);
        let mut points = points;
        for k in [0, points.len() - 1] {
            let x = points[k][0];
            let g = domain.ground_y(x).ok_or(Reject::LeavesModel)?;
            if (points[k][1] - g).abs() > tol {
                return Err(Reject::Shape);
            }
            points[k][1] = g;
        }
        let axis = axis.unwrap_or_else(|| default_axis(&points));
        Ok(Surface {
            points,
            axis,
            circle: None,
        })
    }

    /// y of the surface at `x` (the lower value at a vertical step).
    pub fn y(&self, x: f64) -> Option<f64> {
        let n = self.points.len();
        if !(x >= self.points[0][0] && x <= self.points[n - 1][0]) {
            return None;
        }
        let k = self.points.partition_point(|p| p[0] < x);
        if k == 0 {
            return Some(self.points[0][1].min(self.points[1][1]));
        }
        if k == n {
            return Some(self.points[n - 1][1]);
        }
        let (a, b) = (self.points[k - 1], self.points[k]);
        if b[0] == x {
            return Some(
                self.points[k..]
                    .iter()
                    .take_while(|p| p[0] == x)
                    .map(|p| p[1])
                    .fold(b[1], f64::min),
            );
        }
        Some(a[1] + (x - a[0]) / (b[0] - a[0]) * (b[1] - a[1]))
    }

    /// Largest vertical depth below the ground over the vertices.
    pub fn depth(&self, domain: &Domain) -> f64 {
        self.points
            .iter()
            .filter_map(|p| domain.ground_y(p[0]).map(|g| g - p[1]))
            .fold(0.0, f64::max)
    }

    /// Janbu's d/L: the largest distance of the surface from the chord
    /// joining its ends over the chord's length.
    pub fn depth_ratio(&self) -> f64 {
        let (a, b) = (self.points[0], self.points[self.points.len() - 1]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l = (dx * dx + dy * dy).sqrt();
        if l == 0.0 {
            return 0.0;
        }
        let d = self
            .points
            .iter()
            .map(|p| ((p[0] - a[0]) * dy - (p[1] - a[1]) * dx).abs() / l)
            .fold(0.0, f64::max);
        d / l
    }

    /// True when every interior vertex is below the ground, x increases and
    /// the slopes do not decrease (concave up), as the vertex-moving
    /// refinement requires.
    pub fn admissible(&self, domain: &Domain) -> bool {
        let p = &self.points;
        if p.windows(2).any(|w| w[1][0] <= w[0][0]) {
            return false;
        }
        if p[1..p.len() - 1]
            .iter()
            .any(|v| domain.ground_y(v[0]).is_none_or(|g| v[1] >= g))
        {
            return false;
        }
        let slopes: Vec<f64> = p
            .windows(2)
            .map(|w| (w[1][1] - w[0][1]) / (w[1][0] - w[0][0]))
            .collect();
        slopes.windows(2).all(|s| s[1] >= s[0] - 1e-12)
    }
}

/// The centre of the circle through the ends and the vertex farthest below
/// their chord, when it lies above the chord; else a point one chord length
/// above the chord's middle.
fn default_axis(points: &[[f64; 2]]) -> [f64; 2] {
    let (a, b) = (points[0], points[points.len() - 1]);
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l = (dx * dx + dy * dy).sqrt().max(f64::MIN_POSITIVE);
    // Signed distance below the chord (positive below for a left-to-right chord).
    let below = |p: &[f64; 2]| ((p[0] - a[0]) * dy - (p[1] - a[1]) * dx) / l;
    let deepest = points
        .iter()
        .copied()
        .max_by(|p, q| below(p).total_cmp(&below(q)))
        .unwrap_or(a);
    let fallback = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]) + l];
    match circumcentre(a, deepest, b) {
        Some(c) if below(&c) < 0.0 && below(&deepest) > 0.0 => c,
        _ => fallback,
    }
}

fn circumcentre(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> Option<[f64; 2]> {
    let d = 2.0 * (a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]));
    let scale = (b[0] - a[0]).abs() + (c[0] - a[0]).abs() + (b[1] - a[1]).abs();
    if d.abs() <= 1e-9 * scale * scale {
        return None;
    }
    let sq = |p: [f64; 2]| p[0] * p[0] + p[1] * p[1];
    Some([
        (sq(a) * (b[1] - c[1]) + sq(b) * (c[1] - a[1]) + sq(c) * (a[1] - b[1])) / d,
        (sq(a) * (c[0] - b[0]) + sq(b) * (a[0] - c[0]) + sq(c) * (b[0] - a[0])) / d,
    ])
}

/// y of the ground or surface `line` at `x`, for callers outside this module.
pub fn line_y(line: &[[f64; 2]], x: f64) -> Option<f64> {
    polyline_y(line, x)
}

#[cfg(test)]
mod tests {
    use super::super::geometry::Region;
    use super::*;

    fn block() -> Domain {
        Domain::from_polygons(vec![Region {
            polygon: vec![[0.0, 0.0], [20.0, 0.0], [20.0, 10.0], [0.0, 10.0]],
            material: 0,
            unit_weight: 20.0,
        }])
        .unwrap()
    }

    #[test]
    fn circle_through_two_points_subtends_twice_theta() {
        let c = Circle::through([2.0, 10.0], [8.0, 10.0], 30f64.to_radians());
        assert!((c.xc - 5.0).abs() < 1e-12);
        assert!((c.r - 6.0).abs() < 1e-12);
        assert!(((c.yc - 10.0) - 3.0 * 3f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn circle_trace_ends_on_the_ground() {
        let c = Circle {
            xc: 10.0,
            yc: 12.0,
            r: 5.0,
        };
        let s = c.trace(&block(), 10).unwrap();
        assert!((s.points[0][0] - (10.0 - 21f64.sqrt())).abs() < 1e-9);
        assert!((s.points[10][1] - 10.0).abs() < 1e-9);
        assert!((s.depth(&block()) - 3.0).abs() < 1e-12);
        // A circle reaching the side leaves the model.
        let wide = Circle {
            xc: 10.0,
            yc: 12.0,
            r: 11.0,
        };
        assert_eq!(wide.trace(&block(), 10), Err(Reject::LeavesModel));
        let high = Circle {
            xc: 10.0,
            yc: 20.0,
            r: 5.0,
        };
        assert_eq!(high.trace(&block(), 10), Err(Reject::MissesGround));
    }
}
