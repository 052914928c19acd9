//! The methods of slices on one set of slices (canonical frame: the mass moves
//! toward −x, slices from the toe; see `docs/slope-stability.md` for the
//! equations and their sources).
//!
//! One sweep carries the interslice forces across the slices for a trial
//! factor F and interslice scale λ (X = λ·f(x)·E, Morgenstern & Price 1965):
//! each slice's vertical equilibrium gives its base normal force N, its
//! horizontal equilibrium the next E. The sweep returns the last E (force
//! equilibrium of the whole mass when zero) and the moment of the external
//! forces about the axis (moment equilibrium when zero). Then
//!
//! * F_f(λ) is the root in F of the force residual, F_m(λ) of the moment one;
//! * Morgenstern–Price (constant or half-sine f) and Spencer (f = 1) find λ
//!   with F_f(λ) = F_m(λ) (the general limit-equilibrium picture of Fredlund &
//!   Krahn 1977);
//! * Bishop's simplified method is F_m(0), Janbu's simplified F_f(0) times
//!   his correction f₀ = 1 + b₁·(d/L − 1.4·(d/L)²);
//! * the ordinary method (Fellenius) takes N = W cos α − u·l, no interslice
//!   forces, moments about the axis.
//!
//! Every root is bracketed and found by Brent's method to the relative
//! tolerance asked; a solution that cannot be bracketed, or that would need a
//! slice with m_α = cos α + sin α·tan φ/F below [`M_ALPHA_FLOOR`], is
//! returned with `converged: false` and its reason. No I/O.

use super::slices::SliceSet;

/// The smallest m_α a solution may use: below it the base normal force of
/// Bishop-type methods is meaningless (it changes sign at m_α = 0).
pub const M_ALPHA_FLOOR: f64 = 0.05;

/// The interslice force function f(x) of Morgenstern–Price.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Interslice {
    /// f = 1 (Spencer's parallel interslice forces).
    Constant,
    /// f = sin(π·(x − x_left)/(x_right − x_left)).
    HalfSine,
}

/// A method of slices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    MorgensternPrice(Interslice),
    Spencer,
    Bishop,
    Janbu,
    Ordinary,
}

impl Method {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Method::MorgensternPrice(_) => "morgenstern-price",
            Method::Spencer => "spencer",
            Method::Bishop => "bishop",
            Method::Janbu => "janbu",
            Method::Ordinary => "ordinary",
        }
    }

    /// The interslice function, for the methods that have one.
    pub fn interslice(self) -> Option<Interslice> {
        match self {
            Method::MorgensternPrice(f) => Some(f),
            Method::Spencer => Some(Interslice::Constant),
            _ => None,
        }
    }

    /// Every method, Morgenstern–Price with both functions.
    pub const ALL: [Method; 6] = [
        Method::MorgensternPrice(Interslice::HalfSine),
        Method::MorgensternPrice(Interslice::Constant),
        Method::Spencer,
        Method::Bishop,
        Method::Janbu,
        Method::Ordinary,
    ];
}

/// The factor of one surface by one method.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Solution {
    /// The factor of safety (for Janbu the corrected one).
    pub factor: f64,
    /// F_f at the final λ (Janbu: uncorrected).
    pub force_factor: Option<f64>,
    /// F_m at the final λ.
    pub moment_factor: Option<f64>,
    /// λ of X = λ f(x) E.
    pub lambda: Option<f64>,
    /// Janbu's correction factor f₀.
    pub janbu_f0: Option<f64>,
    /// Sweeps over the slices.
    pub iterations: usize,
    pub converged: bool,
    /// Why it did not converge.
    pub failure: Option<&'static str>,
    /// Smallest m_α over the slices at the factor.
    pub min_m_alpha: f64,
}

impl Solution {
    fn failed(reason: &'static str, iterations: usize) -> Solution {
        Solution {
            factor: f64::NAN,
            force_factor: None,
            moment_factor: None,
            lambda: None,
            janbu_f0: None,
            iterations,
            converged: false,
            failure: Some(reason),
            min_m_alpha: f64::NAN,
        }
    }
}

/// One slice's constants for the sweeps.
#[derive(Clone, Copy)]
struct Row {
    sin: f64,
    cos: f64,
    tan_phi: f64,
    /// (c − u·tan φ)·l.
    k: f64,
    weight: f64,
    /// Arms of the base shear and normal forces about the axis.
    arm_shear: f64,
    arm_normal: f64,
    /// W times the horizontal arm of the weight.
    weight_moment: f64,
    /// f at the slice's right boundary (the last one at the right end).
    f_right: f64,
}

/// Per-slice constants of a set.
struct Prepared {
    rows: Vec<Row>,
    /// Σ W, to scale the residuals.
    scale: f64,
    /// The smallest F at which every m_α ≥ the floor.
    f_floor: f64,
}

impl Prepared {
    fn new(set: &SliceSet, interslice: Interslice) -> Prepared {
        let [ox, oy] = set.axis;
        let n = set.slices.len();
        let (left, right) = (set.boundaries[0], set.boundaries[n]);
        let f = |x: f64| match interslice {
            Interslice::Constant => 1.0,
            Interslice::HalfSine => (std::f64::consts::PI * (x - left) / (right - left))
                .sin()
                .max(0.0),
        };
        let mut p = Prepared {
            rows: Vec::with_capacity(n),
            scale: 0.0,
            f_floor: 0.0,
        };
        for (i, s) in set.slices.iter().enumerate() {
            let (sin, cos) = s.alpha.sin_cos();
            let (dx, dy) = (s.base[0] - ox, s.base[1] - oy);
            let t = s.tan_phi;
            p.rows.push(Row {
                sin,
                cos,
                tan_phi: t,
                k: (s.cohesion - s.pore_pressure * t) * s.length,
                weight: s.weight,
                arm_shear: dx * sin - dy * cos,
                arm_normal: dx * cos + dy * sin,
                weight_moment: s.weight * (s.x - ox),
                f_right: f(set.boundaries[i + 1]),
            });
            p.scale += s.weight.abs();
            if sin * t < 0.0 {
                let room = cos - M_ALPHA_FLOOR;
                p.f_floor = if room > 0.0 {
                    p.f_floor.max(-sin * t / room)
                } else {
                    f64::INFINITY
                };
            } else if cos < M_ALPHA_FLOOR && sin * t == 0.0 {
                p.f_floor = f64::INFINITY;
            }
        }
        p.scale = p.scale.max(f64::MIN_POSITIVE);
        p
    }

    /// One sweep at (F, λ): the last E and the moment residual, both over Σ W.
    fn sweep(&self, factor: f64, lambda: f64) -> (f64, f64) {
        let inv = 1.0 / factor;
        let (mut e_prev, mut x_prev) = (0.0, 0.0);
        let mut moment = 0.0;
        for r in &self.rows {
            let im = 1.0 / (r.cos + r.sin * r.tan_phi * inv);
            let a = r.weight - x_prev - r.sin * r.k * inv;
            let d = r.tan_phi * r.cos * inv - r.sin;
            let lf = lambda * r.f_right;
            let e = (e_prev + r.k * r.cos * inv + d * a * im) / (1.0 - d * lf * im);
            let x = lf * e;
            let normal = (a + x) * im;
            let shear = (r.k + normal * r.tan_phi) * inv;
            moment += shear * r.arm_shear + normal * r.arm_normal - r.weight_moment;
            e_prev = e;
            x_prev = x;
        }
        (e_prev / self.scale, moment / self.scale)
    }

    fn min_m_alpha(&self, factor: f64) -> f64 {
        self.rows
            .iter()
            .map(|r| r.cos + r.sin * r.tan_phi / factor)
            .fold(f64::INFINITY, f64::min)
    }
}

/// Which equilibrium a root is taken of.
#[derive(Clone, Copy)]
enum Equation {
    Force,
    Moment,
}

/// The root in F of one residual at λ; `None` when it cannot be bracketed
/// above the m_α floor.
fn factor_root(
    p: &Prepared,
    equation: Equation,
    lambda: f64,
    guess: f64,
    tolerance: f64,
    sweeps: &mut usize,
) -> Option<f64> {
    let g = |f: f64, sweeps: &mut usize| {
        *sweeps += 1;
        let (force, moment) = p.sweep(f, lambda);
        let r = match equation {
            Equation::Force => force,
            Equation::Moment => moment,
        };
        r.is_finite().then_some(r)
    };
    let floor = (p.f_floor * (1.0 + 1e-12)).max(1e-6);
    if !floor.is_finite() {
        return None;
    }
    // Bracket: geometric steps up and down from the guess, alternately,
    // until the residual changes sign (it need not fall as F grows: about an
    // axis that is not a circle's centre a non-circular surface's moment
    // residual can rise).
    let start = guess.max(floor);
    let g0 = g(start, sweeps)?;
    if g0 == 0.0 {
        return Some(start);
    }
    let (mut up, mut g_up) = (start, g0);
    let (mut down, mut g_down) = (start, g0);
    let mut bracket = None;
    for _ in 0..40 {
        if up < 1e4 {
            let next = up * 1.6;
            let gn = g(next, sweeps)?;
            if gn * g_up <= 0.0 {
                bracket = Some((up, g_up, next, gn));
                break;
            }
            (up, g_up) = (next, gn);
        }
        if down > floor {
            let next = (down / 1.6).max(floor);
            if let Some(gn) = g(next, sweeps) {
                if gn * g_down <= 0.0 {
                    bracket = Some((next, gn, down, g_down));
                    break;
                }
                (down, g_down) = (next, gn);
            } else {
                down = floor;
            }
        } else if up >= 1e4 {
            break;
        }
    }
    let (a, ga, b, gb) = bracket?;
    let root = brent(a, ga, b, gb, tolerance, |f| g(f, sweeps))?;
    // A sign change can be a pole (the sweep's E divides by 1 − d·λf/m_α,
    // which passes zero): a root leaves a small residual, a pole a large one.
    (g(root, sweeps)?.abs() <= ROOT_RESIDUAL).then_some(root)
}

/// The largest residual (over Σ W) accepted at a root in F.
const ROOT_RESIDUAL: f64 = 1e-6;

/// Brent's method on a bracket [a, b] with g(a)·g(b) ≤ 0.
fn brent(
    mut a: f64,
    mut fa: f64,
    mut b: f64,
    mut fb: f64,
    tolerance: f64,
    mut g: impl FnMut(f64) -> Option<f64>,
) -> Option<f64> {
    if fa == 0.0 {
        return Some(a);
    }
    if fb == 0.0 {
        return Some(b);
    }
    if fa.abs() < fb.abs() {
        std::mem::swap(&mut a, &mut b);
        std::mem::swap(&mut fa, &mut fb);
    }
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..100 {
        if fb * fc > 0.0 {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 0.5 * tolerance * b.abs().max(1e-12);
        let m = 0.5 * (c - b);
        if m.abs() <= tol || fb == 0.0 {
            return Some(b);
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut pp, mut q);
            if a == c {
                pp = 2.0 * m * s;
                q = 1.0 - s;
            } else {
                let qa = fa / fc;
                let r = fb / fc;
                pp = s * (2.0 * m * qa * (qa - r) - (b - a) * (r - 1.0));
                q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if pp > 0.0 {
                q = -q;
            } else {
                pp = -pp;
            }
            if 2.0 * pp < (3.0 * m * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = pp / q;
            } else {
                d = m;
                e = m;
            }
        } else {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(m) };
        fb = g(b)?;
    }
    None
}

/// The factor of `set` by `method`, to the relative `tolerance`.
pub fn solve(set: &SliceSet, method: Method, tolerance: f64) -> Solution {
    if set.slices.is_empty() {
        return Solution::failed("no slices", 0);
    }
    let interslice = method.interslice().unwrap_or(Interslice::Constant);
    let p = Prepared::new(set, interslice);
    let mut sweeps = 0;
    let finish = |mut s: Solution, p: &Prepared| {
        s.min_m_alpha = p.min_m_alpha(s.factor);
        s
    };
    match method {
        Method::Ordinary => finish(ordinary(set, &p), &p),
        Method::Bishop => {
            match factor_root(&p, Equation::Moment, 0.0, 1.0, tolerance, &mut sweeps) {
                Some(f) => finish(
                    Solution {
                        factor: f,
                        moment_factor: Some(f),
                        ..converged(sweeps)
                    },
                    &p,
                ),
                None => Solution::failed("no moment-equilibrium root above the m_α floor", sweeps),
            }
        }
        Method::Janbu => match factor_root(&p, Equation::Force, 0.0, 1.0, tolerance, &mut sweeps) {
            Some(f) => {
                let f0 = janbu_f0(set);
                finish(
                    Solution {
                        factor: f * f0,
                        force_factor: Some(f),
                        janbu_f0: Some(f0),
                        ..converged(sweeps)
                    },
                    &p,
                )
            }
            None => Solution::failed("no force-equilibrium root above the m_α floor", sweeps),
        },
        Method::MorgensternPrice(_) | Method::Spencer => finish(lambda_solve(&p, tolerance), &p),
    }
}

/// A converged solution's frame; the caller fills in what it found.
fn converged(iterations: usize) -> Solution {
    Solution {
        converged: true,
        failure: None,
        ..Solution::failed("", iterations)
    }
}

/// The ordinary method: N = W cos α − u·l, moments about the axis.
fn ordinary(set: &SliceSet, p: &Prepared) -> Solution {
    let (mut resisting, mut driving) = (0.0, 0.0);
    for (i, s) in set.slices.iter().enumerate() {
        let normal = s.weight * s.alpha.cos();
        let effective = normal - s.pore_pressure * s.length;
        let r = &p.rows[i];
        resisting += (s.cohesion * s.length + effective * s.tan_phi) * r.arm_shear;
        driving += r.weight_moment - normal * r.arm_normal;
    }
    let f = resisting / driving;
    if !(f.is_finite() && f > 0.0) {
        return Solution::failed("the driving moment is not positive", 1);
    }
    Solution {
        factor: f,
        moment_factor: Some(f),
        ..converged(1)
    }
}

/// Janbu's correction factor for the set's d/L and its strength terms.
fn janbu_f0(set: &SliceSet) -> f64 {
    let any_c = set.slices.iter().any(|s| s.cohesion > 0.0);
    let any_phi = set.slices.iter().any(|s| s.tan_phi > 0.0);
    let b1 = match (any_c, any_phi) {
        (true, false) => 0.69,
        (false, true) => 0.31,
        _ => 0.50,
    };
    let r = set.depth_ratio;
    1.0 + b1 * (r - 1.4 * r * r)
}

/// Morgenstern–Price / Spencer: λ with F_f(λ) = F_m(λ).
fn lambda_solve(p: &Prepared, tolerance: f64) -> Solution {
    let mut sweeps = 0;
    let inner = tolerance * 1e-2;
    let mut guess = 1.0;
    let pair = |lambda: f64, sweeps: &mut usize, guess: &mut f64| -> Option<(f64, f64)> {
        let fm = factor_root(p, Equation::Moment, lambda, *guess, inner, sweeps)?;
        let ff = factor_root(p, Equation::Force, lambda, fm, inner, sweeps)?;
        *guess = fm;
        Some((fm, ff))
    };
    let done = |lambda: f64, fm: f64, ff: f64, sweeps: usize| Solution {
        factor: 0.5 * (fm + ff),
        force_factor: Some(ff),
        moment_factor: Some(fm),
        lambda: Some(lambda),
        ..converged(sweeps)
    };
    // The root nearest λ = 0: a secant walk from 0 with steps of at most
    // LAMBDA_STEP inside |λ| ≤ LAMBDA_MAX, then a march outward from 0;
    // farther roots of F_m(λ) = F_f(λ) are the spurious ones (they need
    // tensile interslice forces or m_α near zero).
    let Some((fm0, ff0)) = pair(0.0, &mut sweeps, &mut guess) else {
        return Solution::failed("no moment or force root at λ = 0", sweeps);
    };
    let close = |fm: f64, ff: f64| (fm - ff).abs() <= tolerance * fm.abs();
    if close(fm0, ff0) {
        return done(0.0, fm0, ff0, sweeps);
    }
    let mut h = |lambda: f64, sweeps: &mut usize| -> Option<(f64, f64, f64)> {
        pair(lambda, sweeps, &mut guess).map(|(fm, ff)| (fm - ff, fm, ff))
    };
    let mut bracket = None;
    let (mut l0, mut h0) = (0.0, fm0 - ff0);
    let mut l1 = 0.1_f64.copysign(h0);
    for _ in 0..30 {
        let Some((h1, fm, ff)) = h(l1, &mut sweeps) else {
            break;
        };
        if close(fm, ff) {
            return done(l1, fm, ff, sweeps);
        }
        if h0 * h1 < 0.0 {
            bracket = Some((l0, h0, l1, h1));
            break;
        }
        if h1 == h0 {
            break;
        }
        let step = (-h1 * (l1 - l0) / (h1 - h0)).clamp(-LAMBDA_STEP, LAMBDA_STEP);
        let next = l1 + step;
        if next.abs() > LAMBDA_MAX {
            break;
        }
        (l0, h0, l1) = (l1, h1, next);
    }
    if bracket.is_none() {
        // March outward from 0, nearer λ first.
        let mut last = [(0.0, fm0 - ff0); 2];
        let mut k = 1;
        'march: while k as f64 * 0.1 <= LAMBDA_MAX + 1e-9 {
            for (side, sign) in [1.0, -1.0].into_iter().enumerate() {
                let lambda = sign * k as f64 * 0.1;
                if let Some((hl, fm, ff)) = h(lambda, &mut sweeps) {
                    if close(fm, ff) {
                        return done(lambda, fm, ff, sweeps);
                    }
                    let (lp, hp) = last[side];
                    if hp * hl < 0.0 {
                        bracket = Some((lp, hp, lambda, hl));
                        break 'march;
                    }
                    last[side] = (lambda, hl);
                }
            }
            k += 1;
        }
    }
    let Some((a, ha, b, hb)) = bracket else {
        return Solution::failed(
            "no λ with equal force and moment factors within |λ| ≤ 3",
            sweeps,
        );
    };
    let root = brent(a, ha, b, hb, 1e-10, |l| h(l, &mut sweeps).map(|v| v.0));
    match root.and_then(|l| pair(l, &mut sweeps, &mut guess).map(|(fm, ff)| (l, fm, ff))) {
        Some((l, fm, ff)) if (fm - ff).abs() <= 10.0 * tolerance * fm.abs() => {
            done(l, fm, ff, sweeps)
        }
        _ => Solution::failed("the λ iteration did not close", sweeps),
    }
}

/// Largest |λ| searched, and the largest secant step.
const LAMBDA_MAX: f64 = 3.0;
const LAMBDA_STEP: f64 = 0.25;

#[cfg(test)]
mod tests {
    use super::super::slices::Slice;
    use super::*;

    /// Slices of a surface parallel to a uniform slope (an infinite slope cut
    /// into equal slices with vertical, force-free ends).
    fn parallel(beta_deg: f64, c: f64, phi_deg: f64, u: f64) -> SliceSet {
        let beta = beta_deg.to_radians();
        let n = 20;
        let b = 1.0;
        let slices = (0..n)
            .map(|i| {
                let x = (i as f64 + 0.5) * b;
                Slice {
                    x,
                    width: b,
                    base: [x, x * beta.tan()],
                    alpha: beta,
                    length: b / beta.cos(),
                    weight: 20.0 * 2.0 * b,
                    cohesion: c,
                    tan_phi: phi_deg.to_radians().tan(),
                    pore_pressure: u,
                    pwp: -u,
                    saturation: 1.0,
                    material: 0,
                }
            })
            .collect();
        SliceSet {
            slices,
            boundaries: (0..=n).map(|i| i as f64 * b).collect(),
            axis: [10.0, 40.0],
            mirrored: false,
            depth_ratio: 0.0,
        }
    }

    #[test]
    fn every_method_gives_tan_phi_over_tan_beta_on_a_parallel_surface() {
        let set = parallel(25.0, 0.0, 35.0, 0.0);
        let exact = 35f64.to_radians().tan() / 25f64.to_radians().tan();
        for method in Method::ALL {
            let s = solve(&set, method, 1e-9);
            assert!(s.converged, "{method:?}: {s:?}");
            assert!(
                (s.factor - exact).abs() < 1e-6 * exact,
                "{method:?}: {} vs {exact}",
                s.factor
            );
        }
    }
}
