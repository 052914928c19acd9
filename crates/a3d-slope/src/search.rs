//! The critical slip surface: circular trial surfaces by entry–exit ranges on
//! the ground or by a grid of centres with tangent radii, evaluated in
//! parallel (rayon; the minimum is taken in trial order, so the result is the
//! same for any thread count); then the best circle refined by a pattern
//! search on its centre and radius; then, from it, a non-circular surface
//! refined by moving the polyline's vertices (the optimisation of the
//! commercial codes): ends along the ground, interior vertices along the
//! circle's radii, step halved when no move lowers the factor. No I/O.

use rayon::prelude::*;

use super::composite;
use super::methods::{Method, Solution, solve};
use super::slices::{SliceInputs, slice};
use super::surface::{Circle, Reject, Surface};

/// How circles are generated.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CircleSearch {
    /// Circles through an entry point and an exit point on the ground, with
    /// half-angles from 6° to 72°. `None` ranges: the whole ground.
    EntryExit {
        entry: Option<(f64, f64)>,
        exit: Option<(f64, f64)>,
    },
    /// Centres on a grid, radii down to tangent elevations. `None`: a grid
    /// above the slope and tangents from near the base to near the crest.
    Grid {
        centres: Option<[f64; 4]>,
        tangents: Option<(f64, f64)>,
    },
}

/// The search's settings.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SearchSettings {
    pub circles: CircleSearch,
    /// About this many trial circles.
    pub trials: usize,
    /// Refine the best circle into a non-circular surface.
    pub refine: bool,
    /// Polyline segments of the non-circular refinement.
    pub segments: usize,
    /// Most surface evaluations of each refinement.
    pub max_refinements: usize,
    /// Surfaces to start from besides the search's own (polylines, left to
    /// right, ends on the ground), e.g. the critical surfaces of the earlier
    /// times of a series: the best of them that can be analysed is refined
    /// with the search's own starts.
    #[serde(skip)]
    pub starts: Vec<Vec<[f64; 2]>>,
}

impl Default for SearchSettings {
    fn default() -> Self {
        SearchSettings {
            circles: CircleSearch::EntryExit {
                entry: None,
                exit: None,
            },
            trials: 5000,
            refine: true,
            segments: 12,
            max_refinements: 1500,
            starts: Vec::new(),
        }
    }
}

/// The outcome of one trial.
#[derive(Clone, Debug)]
pub enum Trial {
    Rejected(Reject),
    NotConverged(&'static str),
    Solved(Box<(Surface, Solution)>),
}

/// Evaluates one surface.
pub fn evaluate(surface: Surface, inputs: &SliceInputs<'_>, method: Method, tol: f64) -> Trial {
    match slice(&surface, inputs) {
        Err(r) => Trial::Rejected(r),
        Ok(set) => {
            let s = solve(&set, method, tol);
            if s.converged {
                Trial::Solved(Box::new((surface, s)))
            } else {
                Trial::NotConverged(s.failure.unwrap_or("did not converge"))
            }
        }
    }
}

/// The trial circles the settings describe, with a description of the
/// search space.
pub fn circles(inputs: &SliceInputs<'_>, settings: &SearchSettings) -> (Vec<Circle>, String) {
    let domain = inputs.domain;
    let ground = domain.ground();
    let (x0, x1) = domain.x_range();
    let ys: Vec<f64> = ground.iter().map(|p| p[1]).collect();
    let (y_low, y_high) = ys
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    let height = (y_high - y_low).max(1e-9 * (x1 - x0));
    let margin = 0.005 * (x1 - x0);
    let trials = settings.trials.max(10);
    match &settings.circles {
        CircleSearch::EntryExit { entry, exit } => {
            let whole = (x0 + margin, x1 - margin);
            let same = entry.is_none() && exit.is_none();
            let (ea, eb) = entry.unwrap_or(whole);
            let (xa, xb) = exit.unwrap_or(whole);
            let n_theta = 10;
            let per_pair = trials as f64 / n_theta as f64;
            let k = if same {
                (2.0 * per_pair).sqrt().ceil() as usize + 1
            } else {
                per_pair.sqrt().ceil() as usize
            }
            .max(2);
            let spread = |a: f64, b: f64| -> Vec<f64> {
                (0..k)
                    .map(|i| a + (b - a) * i as f64 / (k - 1) as f64)
                    .collect()
            };
            let (entries, exits) = (spread(ea, eb), spread(xa, xb));
            let min_width = 0.02 * (x1 - x0);
            let mut out = Vec::new();
            for &xe in &entries {
                for &xx in &exits {
                    let (Some(ye), Some(yx)) = (domain.ground_y(xe), domain.ground_y(xx)) else {
                        continue;
                    };
                    if (xe - xx).abs() < min_width || ye <= yx + 1e-9 * height {
                        continue;
                    }
                    for t in 0..n_theta {
                        let theta = (6.0 + 66.0 * t as f64 / (n_theta - 1) as f64).to_radians();
                        out.push(Circle::through([xe, ye], [xx, yx], theta));
                    }
                }
            }
            let text = format!(
                "entry–exit: {k} entry points over x = {ea:.3}..{eb:.3}, {k} exit points over x = {xa:.3}..{xb:.3}, the entry higher than the exit; {n_theta} circles per pair, half-angles 6°..72°"
            );
            (out, text)
        }
        CircleSearch::Grid { centres, tangents } => {
            let slope: Vec<f64> = ground
                .iter()
                .filter(|p| p[1] > y_low + 0.01 * height && p[1] < y_high - 0.01 * height)
                .map(|p| p[0])
                .collect();
            let (s0, s1) = if slope.is_empty() {
                (x0, x1)
            } else {
                slope
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                        (a.min(x), b.max(x))
                    })
            };
            let w = (s1 - s0).max(height);
            let [cx0, cx1, cy0, cy1] = centres.unwrap_or([
                s0 - 0.25 * w,
                s1 + 0.25 * w,
                y_high + 0.1 * height,
                y_high + 1.5 * w,
            ]);
            let bottom = domain.bottom();
            let (t0, t1) =
                tangents.unwrap_or((bottom + 0.02 * (y_high - bottom), y_high - 0.1 * height));
            let n_r = 10;
            let k = ((trials as f64 / n_r as f64).sqrt().ceil() as usize).max(2);
            let mut out = Vec::new();
            for j in 0..k {
                let yc = cy0 + (cy1 - cy0) * j as f64 / (k - 1) as f64;
                for i in 0..k {
                    let xc = cx0 + (cx1 - cx0) * i as f64 / (k - 1) as f64;
                    for r in 0..n_r {
                        let yt = t0 + (t1 - t0) * r as f64 / (n_r - 1) as f64;
                        out.push(Circle { xc, yc, r: yc - yt });
                    }
                }
            }
            let text = format!(
                "grid and radius: {k} × {k} centres over x = {cx0:.3}..{cx1:.3}, y = {cy0:.3}..{cy1:.3}; {n_r} radii tangent to y = {t0:.3}..{t1:.3}"
            );
            (out, text)
        }
    }
}

/// Counts of what the trials gave.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct TrialCounts {
    pub generated: usize,
    pub solved: usize,
    pub not_converged: usize,
    /// (reason, count), for the reasons that occurred.
    pub rejected: Vec<(String, usize)>,
    /// The first surfaces that did not converge: (circle, reason).
    pub not_converged_examples: Vec<(Circle, String)>,
}

/// Evaluates every circle in parallel; returns up to `keep` best circles
/// (lowest factors first, the first in trial order on a tie, circles within
/// 5 % of R of a better one left out) and the counts.
pub fn best_circles(
    list: &[Circle],
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    n_slices: usize,
    keep: usize,
) -> (Vec<(Surface, Solution)>, TrialCounts) {
    let results: Vec<Trial> = list
        .par_iter()
        .map(|c| match c.trace(inputs.domain, n_slices) {
            Ok(s) => evaluate(s, inputs, method, tol),
            Err(r) => Trial::Rejected(r),
        })
        .collect();
    let mut counts = TrialCounts {
        generated: list.len(),
        ..TrialCounts::default()
    };
    let mut rejected: std::collections::BTreeMap<Reject, usize> = Default::default();
    let mut solved: Vec<(Surface, Solution)> = Vec::new();
    for (c, r) in list.iter().zip(results) {
        match r {
            Trial::Rejected(why) => *rejected.entry(why).or_default() += 1,
            Trial::NotConverged(why) => {
                counts.not_converged += 1;
                if counts.not_converged_examples.len() < 10 {
                    counts.not_converged_examples.push((*c, why.to_string()));
                }
            }
            Trial::Solved(found) => {
                counts.solved += 1;
                solved.push(*found);
            }
        }
    }
    counts.rejected = rejected
        .into_iter()
        .map(|(k, v)| (k.describe().to_string(), v))
        .collect();
    // Stable sort: ties keep trial order.
    solved.sort_by(|a, b| a.1.factor.total_cmp(&b.1.factor));
    let mut best: Vec<(Surface, Solution)> = Vec::new();
    for found in solved {
        if best.len() >= keep {
            break;
        }
        let c = found.0.circle;
        let near = |other: &(Surface, Solution)| match (c, other.0.circle) {
            (Some(a), Some(b)) => {
                let d = (a.xc - b.xc).abs() + (a.yc - b.yc).abs() + (a.r - b.r).abs();
                d < 0.05 * b.r
            }
            _ => false,
        };
        if !best.iter().any(near) {
            best.push(found);
        }
    }
    (best, counts)
}

/// What the composite surfaces came to.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CompositeCounts {
    /// Material interfaces (x-monotone paths) of the section.
    pub interfaces: usize,
    /// Circles clipped: every trial circle that cuts the ground.
    pub circles: usize,
    /// Composite surfaces formed (circles that dip below an interface).
    pub formed: usize,
    pub solved: usize,
    /// The best composite's factor, before its own refinement.
    pub best_factor: Option<f64>,
    /// The best composite's factor after the pattern search on its circle.
    pub refined_factor: Option<f64>,
}

/// How a composite surface is made: a circle held up at an interface
/// lowered by a drop ([`composite::clip`]).
#[derive(Clone, Copy, Debug)]
pub struct CompositeRecipe<'a> {
    pub circle: Circle,
    pub line: &'a [[f64; 2]],
    pub drop: f64,
}

impl CompositeRecipe<'_> {
    /// The composite surface of `circle` clipped as this recipe clips.
    fn surface(
        &self,
        circle: &Circle,
        inputs: &SliceInputs<'_>,
        n_slices: usize,
    ) -> Option<Surface> {
        let traced = circle.trace(inputs.domain, n_slices).ok()?;
        composite::clip(circle, &traced, self.line, self.drop, inputs.domain)
    }
}

/// The best composite surface and how it was made.
pub type BestComposite<'a> = ((Surface, Solution), CompositeRecipe<'a>);

/// Clips every trial circle at each material interface, exactly on it (the
/// strength of the region above) and a hair below (the region below),
/// evaluates the composites in parallel, and returns the best (the first in
/// trial order on a tie) with how it was made, and the counts. Every
/// circle is clipped, not only the best ones: where the layer below an
/// interface is unbreakable, the circles that reach it are rejected and the
/// composites they make are the only surfaces along it.
pub fn best_composite<'a>(
    list: &[Circle],
    lines: &'a [Vec<[f64; 2]>],
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    n_slices: usize,
) -> (Option<BestComposite<'a>>, CompositeCounts) {
    let domain = inputs.domain;
    let height = domain
        .ground()
        .iter()
        .map(|p| p[1])
        .fold(f64::NEG_INFINITY, f64::max)
        - domain.bottom();
    let hair = 1e-4 * height;
    let recipes: Vec<CompositeRecipe<'a>> = list
        .iter()
        .flat_map(|&circle| {
            lines.iter().flat_map(move |line| {
                [-hair, 0.0, hair].map(|drop| CompositeRecipe { circle, line, drop })
            })
        })
        .collect();
    let results: Vec<(bool, Option<(Surface, Solution)>)> = recipes
        .par_iter()
        .map(|r| match r.surface(&r.circle, inputs, n_slices) {
            None => (false, None),
            Some(s) => match evaluate(s, inputs, method, tol) {
                Trial::Solved(found) => (true, Some(*found)),
                _ => (true, None),
            },
        })
        .collect();
    let mut counts = CompositeCounts {
        interfaces: lines.len(),
        circles: list.len(),
        ..CompositeCounts::default()
    };
    let mut best: Option<BestComposite<'a>> = None;
    for (recipe, (formed, found)) in recipes.iter().zip(results) {
        counts.formed += usize::from(formed);
        let Some(found) = found else { continue };
        counts.solved += 1;
        if best.as_ref().is_none_or(|b| found.1.factor < b.0.1.factor) {
            best = Some((found, *recipe));
        }
    }
    counts.best_factor = best.as_ref().map(|b| b.0.1.factor);
    (best, counts)
}

/// A circle as (entry x, exit x, half-angle): the ends of its traced arc on
/// the ground and the half-angle its lower arc subtends; `None` when the
/// circle is not [`Circle::through`] its ends (an arc of more than half a
/// circle).
fn ends_and_angle(circle: &Circle, traced: &Surface) -> Option<[f64; 3]> {
    let (a, b) = (traced.points[0], traced.points[traced.points.len() - 1]);
    let chord = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let theta = (0.5 * chord / circle.r).min(1.0).asin();
    let again = Circle::through(a, b, theta);
    let d =
        (again.xc - circle.xc).abs() + (again.yc - circle.yc).abs() + (again.r - circle.r).abs();
    (d <= 1e-6 * circle.r).then_some([a[0], b[0], theta])
}

/// The circle through the ground at `p[0]` and `p[1]` with half-angle `p[2]`.
fn circle_of(p: &[f64], inputs: &SliceInputs<'_>) -> Option<Circle> {
    let domain = inputs.domain;
    let (ya, yb) = (domain.ground_y(p[0])?, domain.ground_y(p[1])?);
    if !(p[2] > 0.0 && p[2] < std::f64::consts::FRAC_PI_2) || p[0] == p[1] {
        return None;
    }
    Some(Circle::through([p[0], ya], [p[1], yb], p[2]))
}

/// Compass search from `start` (its surface and solution `best`): each
/// coordinate moved by ± its step ([`run_moves`] with runs of one),
/// until the steps are `shrink` × their start or `max_evaluations` are
/// spent. Returns the best, its point, the evaluations and the final step
/// ratio.
fn compass(
    start: Vec<f64>,
    steps: &[f64],
    best: (Surface, Solution),
    shrink: f64,
    max_evaluations: usize,
    score: impl Fn(&[f64]) -> Option<(Surface, Solution)>,
) -> ((Surface, Solution), Vec<f64>, usize, f64) {
    let moves: Vec<(usize, usize)> = (0..steps.len()).map(|k| (k, k + 1)).collect();
    run_moves(start, &moves, steps, shrink, best, max_evaluations, score)
}

/// Pattern search on the circle that makes a composite surface, in (entry x,
/// exit x, half-angle), each trial clipped as the recipe clips. The start
/// stays the answer unless a trial beats it.
pub fn refine_composite(
    start: (Surface, Solution),
    recipe: CompositeRecipe<'_>,
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    n_slices: usize,
    max_evaluations: usize,
) -> (Surface, Solution) {
    let Some(p) = recipe
        .circle
        .trace(inputs.domain, n_slices)
        .ok()
        .and_then(|t| ends_and_angle(&recipe.circle, &t))
    else {
        return start;
    };
    let span = (p[1] - p[0]).abs();
    compass(
        p.to_vec(),
        &[0.05 * span, 0.05 * span, 0.05],
        start,
        1e-4,
        max_evaluations,
        |q| {
            let c = circle_of(q, inputs)?;
            match evaluate(recipe.surface(&c, inputs, n_slices)?, inputs, method, tol) {
                Trial::Solved(found) => Some(*found),
                _ => None,
            }
        },
    )
    .0
}

/// What a refinement did.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Refinement {
    pub evaluations: usize,
    pub start_factor: f64,
    pub end_factor: f64,
    /// Final step over the initial one.
    pub final_step_ratio: f64,
}

/// Pattern search on the circle: first on its ends on the ground and its
/// half-angle (moves that keep the ends on the ground, where the factor is
/// smooth), then on its centre and radius.
pub fn refine_circle(
    start: (Surface, Solution),
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    n_slices: usize,
    max_evaluations: usize,
) -> ((Surface, Solution), Refinement) {
    let start_factor = start.1.factor;
    let Some(circle) = start.0.circle else {
        return (
            start,
            Refinement {
                evaluations: 0,
                start_factor,
                end_factor: start_factor,
                final_step_ratio: 1.0,
            },
        );
    };
    let traced = |c: &Circle| match c.trace(inputs.domain, n_slices) {
        Ok(s) => match evaluate(s, inputs, method, tol) {
            Trial::Solved(found) => Some(*found),
            _ => None,
        },
        Err(_) => None,
    };
    let (mut best, mut evaluations) = (start, 0);
    if let Some(p) = ends_and_angle(&circle, &best.0) {
        let span = (p[1] - p[0]).abs();
        let (found, _, n, _) = compass(
            p.to_vec(),
            &[0.05 * span, 0.05 * span, 0.05],
            best,
            1e-4,
            max_evaluations / 2,
            |q| traced(&circle_of(q, inputs)?),
        );
        best = found;
        evaluations += n;
    }
    let circle = best.0.circle.unwrap_or(circle);
    let step = 0.05 * circle.r;
    let (best, _, n, ratio) = compass(
        vec![circle.xc, circle.yc, circle.r],
        &[step, step, step],
        best,
        1e-4,
        max_evaluations.saturating_sub(evaluations),
        |q| {
            traced(&Circle {
                xc: q[0],
                yc: q[1],
                r: q[2],
            })
        },
    );
    evaluations += n;
    let end_factor = best.1.factor;
    (
        best,
        Refinement {
            evaluations,
            start_factor,
            end_factor,
            final_step_ratio: ratio,
        },
    )
}

/// Moves the vertices of a polyline made from the surface (a circle, a
/// composite or a translational surface) to lower the factor, in rounds
/// that alternate two parametrisations: each round starts again, with the
/// full step, from the polyline the last one ended on, until two rounds in a
/// row gain less than 10⁻⁶ of the factor, or after `rounds`.
pub fn refine_polyline(
    start: &(Surface, Solution),
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    settings: &SearchSettings,
    rounds: usize,
) -> ((Surface, Solution), Refinement) {
    // Even rounds move the depths below the ground ([`depth_round`]), odd
    // rounds the vertices along the axis' radii ([`polyline_round`]): each
    // leaves the other's local minimum.
    let round = |s: &(Surface, Solution), k: usize| {
        if k.is_multiple_of(2) {
            depth_round(s, inputs, method, tol, settings)
        } else {
            polyline_round(s, inputs, method, tol, settings)
        }
    };
    let (mut best, mut total) = round(start, 0);
    let mut stale = 0;
    for k in 1..rounds {
        let mut again = best.clone();
        again.0.circle = None;
        let (found, r) = round(&again, k);
        total.evaluations += r.evaluations;
        total.final_step_ratio = r.final_step_ratio;
        let gain = best.1.factor - found.1.factor;
        if found.1.factor < best.1.factor {
            best = (
                Surface {
                    circle: best.0.circle,
                    ..found.0
                },
                found.1,
            );
        }
        stale = if gain < 1e-6 * best.1.factor {
            stale + 1
        } else {
            0
        };
        if stale == 2 {
            break;
        }
    }
    total.end_factor = best.1.factor;
    (best, total)
}

/// The kinematic limit on the passive end of a refined surface: no segment
/// rises towards the toe (the surface's lower end) more steeply than the
/// Rankine passive wedge, 45° − φ′/2 (φ′ the smallest friction angle of the
/// section's materials), or than the start surface already does. Without it
/// the vertex moves dig a steep spike at the toe, where the base's normal
/// force and the mα factors of Spencer and Morgenstern–Price turn
/// unphysical, and report factors far below the circles'.
#[derive(Clone, Copy, Debug)]
struct Passive {
    /// The toe is the left end.
    toe_left: bool,
    /// tan of the steepest rise allowed.
    tan_limit: f64,
}

impl Passive {
    /// The rule, or the start's steepest rise where that is steeper.
    fn new(start: &Surface, inputs: &SliceInputs<'_>) -> Passive {
        let mut limit = Passive::rule(start, inputs);
        limit.tan_limit = limit.tan_limit.max(limit.steepest(start));
        limit
    }

    /// The rule alone, with the toe at the lower end of `surface`.
    fn rule(surface: &Surface, inputs: &SliceInputs<'_>) -> Passive {
        let phi = inputs
            .materials
            .iter()
            .filter_map(|m| m.strength.as_ref().map(|s| s.friction_angle))
            .fold(f64::INFINITY, f64::min);
        let phi = if phi.is_finite() { phi } else { 0.0 };
        let rule = (45.0 - 0.5 * phi).to_radians().tan();
        let p = &surface.points;
        Passive {
            toe_left: p[0][1] <= p[p.len() - 1][1],
            tan_limit: rule,
        }
    }

    /// The steepest rise towards the toe of the surface's segments (tan).
    fn steepest(&self, s: &Surface) -> f64 {
        s.points
            .windows(2)
            .map(|w| {
                let slope = (w[1][1] - w[0][1]) / (w[1][0] - w[0][0]);
                if self.toe_left { -slope } else { slope }
            })
            .fold(0.0, f64::max)
    }

    fn allows(&self, s: &Surface) -> bool {
        self.steepest(s) <= self.tan_limit * (1.0 + 1e-9)
    }
}

/// [`by_depths`]' parameters of `surface` with `m` segments: its ends' x
/// and its depth below the ground at `m − 1` points equally spaced between
/// them; `None` where the ground or the surface is undefined.
fn depth_params(surface: &Surface, m: usize, domain: &super::geometry::Domain) -> Option<Vec<f64>> {
    let n = surface.points.len();
    let (xa, xb) = (surface.points[0][0], surface.points[n - 1][0]);
    let mut params = vec![xa, xb];
    for i in 1..m {
        let x = xa + (xb - xa) * i as f64 / m as f64;
        params.push(domain.ground_y(x)? - surface.y(x)?);
    }
    Some(params)
}

/// The polyline of [`depth_round`]'s parameters `[xa, xb, d₁, …, d_{m−1}]`
/// (m segments), if admissible; its moment axis `axis`, else the centre of
/// the circle through its ends and deepest vertex.
fn by_depths(
    p: &[f64],
    axis: Option<[f64; 2]>,
    domain: &super::geometry::Domain,
) -> Option<Surface> {
    let (xa, xb) = (p[0], p[1]);
    if xb.partial_cmp(&xa) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let m = p.len() - 1;
    let mut pts = Vec::with_capacity(m + 1);
    pts.push([xa, domain.ground_y(xa)?]);
    for (i, d) in p[2..].iter().enumerate() {
        let x = xa + (xb - xa) * (i + 1) as f64 / m as f64;
        pts.push([x, domain.ground_y(x)? - d]);
    }
    pts.push([xb, domain.ground_y(xb)?]);
    let s = Surface::polyline(domain, pts, axis).ok()?;
    s.admissible(domain).then_some(s)
}

/// A given polyline as a start for [`refine_polyline`]: itself when it can
/// be analysed, else the polyline of `segments` equal steps in x at its
/// depths below the ground (a surface whose kinks keep the λ iteration from
/// closing is often analysable once resampled); `None` when neither is.
pub fn start_from(
    points: &[[f64; 2]],
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    segments: usize,
) -> Option<(Surface, Solution)> {
    let domain = inputs.domain;
    let s = Surface::polyline(domain, points.to_vec(), None).ok()?;
    if let Trial::Solved(found) = evaluate(s.clone(), inputs, method, tol) {
        return Some(*found);
    }
    let params = depth_params(&s, segments.max(3), domain)?;
    match evaluate(by_depths(&params, None, domain)?, inputs, method, tol) {
        Trial::Solved(found) => Some(*found),
        _ => None,
    }
}

/// Translational trial surfaces: for ends on a grid along the ground and a
/// depth from the minimum depth to most of the section's height, the
/// polyline whose interior vertices all lie that depth below the ground (a
/// slab sliding parallel to the ground, as on an infinite slope, or along a
/// layer at that depth). Evaluated in parallel; up to `keep` best of distinct
/// ends (the first in order on a tie) are returned with the number of
/// surfaces tried. The grid
/// is fixed, not drawn from the trial count.
pub fn best_translational(
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    segments: usize,
    keep: usize,
) -> (Vec<(Surface, Solution)>, usize) {
    let domain = inputs.domain;
    let m = segments.max(3);
    let (x0, x1) = domain.x_range();
    let margin = 0.005 * (x1 - x0);
    let top = domain
        .ground()
        .iter()
        .map(|p| p[1])
        .fold(f64::NEG_INFINITY, f64::max);
    let height = top - domain.bottom();
    const ENDS: usize = 24;
    const DEPTHS: usize = 12;
    let xs: Vec<f64> = (0..ENDS)
        .map(|i| x0 + margin + (x1 - x0 - 2.0 * margin) * i as f64 / (ENDS - 1) as f64)
        .collect();
    // Depths from the minimum (or 1 % of the height) to 90 % of the height,
    // spaced geometrically: shallow slabs are the likelier.
    let d0 = inputs.min_depth.max(0.01 * height) * 1.001;
    let d1 = (0.9 * height).max(d0);
    let depths: Vec<f64> = (0..DEPTHS)
        .map(|k| d0 * (d1 / d0).powf(k as f64 / (DEPTHS - 1) as f64))
        .collect();
    let mut params = Vec::new();
    for (i, &xa) in xs.iter().enumerate() {
        for &xb in &xs[i + 1..] {
            for &d in &depths {
                let mut p = vec![xa, xb];
                p.extend(std::iter::repeat_n(d, m - 1));
                params.push(p);
            }
        }
    }
    let found: Vec<Option<(Surface, Solution)>> = params
        .par_iter()
        .map(|p| {
            // The passive rule alone: no start to exempt.
            let s = by_depths(p, None, domain).filter(|s| Passive::rule(s, inputs).allows(s))?;
            match evaluate(s, inputs, method, tol) {
                Trial::Solved(found) => Some(*found),
                _ => None,
            }
        })
        .collect();
    // Stable sort: ties keep grid order. Starts of distinct places: ends
    // more than a grid step apart from a better one's.
    let mut solved: Vec<(Surface, Solution)> = found.into_iter().flatten().collect();
    solved.sort_by(|a, b| a.1.factor.total_cmp(&b.1.factor));
    let step = (x1 - x0 - 2.0 * margin) / (ENDS - 1) as f64;
    let mut best: Vec<(Surface, Solution)> = Vec::new();
    for s in solved {
        if best.len() >= keep {
            break;
        }
        let ends = |t: &Surface| (t.points[0][0], t.points[t.points.len() - 1][0]);
        let (a, b) = ends(&s.0);
        if best.iter().all(|o| {
            let (c, d) = ends(&o.0);
            (a - c).abs() + (b - d).abs() > 1.5 * step
        }) {
            best.push(s);
        }
    }
    (best, params.len())
}

/// The polyline as its ends' x on the ground and each interior vertex's
/// depth below the ground, the vertices equally spaced in x between the
/// ends: moving an end stretches the whole surface, and a surface that
/// follows a layer parallel to the ground keeps its depths (the moves a
/// translational slide along a weak layer needs). Compass moves on each
/// end, each depth, and runs of neighbouring depths together.
fn depth_round(
    start: &(Surface, Solution),
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    settings: &SearchSettings,
) -> ((Surface, Solution), Refinement) {
    let (surface, solution) = start;
    let domain = inputs.domain;
    let m = settings.segments.max(3);
    let Some(params) = depth_params(surface, m, domain) else {
        return (start.clone(), unchanged(solution.factor));
    };
    let (xa, xb) = (params[0], params[1]);
    let axis = Some(surface.axis);
    let passive = Passive::new(surface, inputs);
    let score = |p: &[f64]| -> Option<(Surface, Solution)> {
        let s = by_depths(p, axis, domain).filter(|s| passive.allows(s))?;
        match evaluate(s, inputs, method, tol) {
            Trial::Solved(found) => Some(*found),
            _ => None,
        }
    };
    let Some(first) = score(&params) else {
        return (start.clone(), unchanged(solution.factor));
    };
    let chord = xb - xa;
    // Moves: each end, then runs of depths (all, halves, quarters, … one).
    let mut moves: Vec<(usize, usize)> = vec![(0, 1), (1, 2)];
    moves.extend(nested_runs(2, m + 1, m - 1));
    moves.dedup();
    polish(start, first, params, &moves, chord, settings, score)
}

/// The vertex moves of a refinement round from `first` (the round's first
/// evaluation, at `params`), steps from `chord`/25 to `chord`/2500, and its
/// outcome against `start`.
fn polish(
    start: &(Surface, Solution),
    first: (Surface, Solution),
    params: Vec<f64>,
    moves: &[(usize, usize)],
    chord: f64,
    settings: &SearchSettings,
    score: impl Fn(&[f64]) -> Option<(Surface, Solution)>,
) -> ((Surface, Solution), Refinement) {
    let steps = vec![chord / 25.0; params.len()];
    let (best, _, evaluations, ratio) = run_moves(
        params,
        moves,
        &steps,
        0.01,
        first,
        settings.max_refinements.saturating_sub(1),
        score,
    );
    finish(start, best, evaluations + 1, ratio)
}

/// Runs `(k, k + w)` of neighbouring parameters within `first..end`, of
/// widths `widest`, half that, … down to one, each width's runs
/// overlapping by half.
fn nested_runs(first: usize, end: usize, widest: usize) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut w = widest;
    while w >= 1 {
        let mut k = first;
        while k + w <= end {
            runs.push((k, k + w));
            k += w.div_ceil(2).max(1);
        }
        w /= 2;
    }
    runs
}

/// Pattern moves of runs of parameters: each run shifted by ± its
/// parameters' steps × the ratio, the first move that lowers the factor
/// taken, the ratio halved when none does, until it is `shrink` or
/// `max_evaluations` are spent. Returns the best, its parameters, the
/// evaluations and the final ratio.
fn run_moves(
    mut params: Vec<f64>,
    moves: &[(usize, usize)],
    steps: &[f64],
    shrink: f64,
    first: (Surface, Solution),
    max_evaluations: usize,
    score: impl Fn(&[f64]) -> Option<(Surface, Solution)>,
) -> ((Surface, Solution), Vec<f64>, usize, f64) {
    let mut ratio = 1.0;
    let mut best = first;
    let mut evaluations = 0;
    while ratio > shrink && evaluations < max_evaluations {
        let mut improved = false;
        for &(k0, k1) in moves {
            for sign in [1.0, -1.0] {
                if evaluations >= max_evaluations {
                    break;
                }
                let mut trial = params.clone();
                for (v, step) in trial[k0..k1].iter_mut().zip(&steps[k0..k1]) {
                    *v += sign * ratio * step;
                }
                evaluations += 1;
                if let Some(found) = score(&trial)
                    && found.1.factor < best.1.factor * (1.0 - 1e-12)
                {
                    best = found;
                    params = trial;
                    improved = true;
                    break;
                }
            }
        }
        if !improved {
            ratio *= 0.5;
        }
    }
    (best, params, evaluations, ratio)
}

/// The refinement's outcome: the start when nothing beat it.
fn finish(
    start: &(Surface, Solution),
    best: (Surface, Solution),
    evaluations: usize,
    final_step_ratio: f64,
) -> ((Surface, Solution), Refinement) {
    let best = if start.1.factor <= best.1.factor {
        start.clone()
    } else {
        best
    };
    let end_factor = best.1.factor;
    (
        best,
        Refinement {
            evaluations,
            start_factor: start.1.factor,
            end_factor,
            final_step_ratio,
        },
    )
}

/// A refinement that changed nothing.
fn unchanged(factor: f64) -> Refinement {
    Refinement {
        evaluations: 0,
        start_factor: factor,
        end_factor: factor,
        final_step_ratio: 1.0,
    }
}

/// One round of [`refine_polyline`].
fn polyline_round(
    start: &(Surface, Solution),
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    settings: &SearchSettings,
) -> ((Surface, Solution), Refinement) {
    let (surface, solution) = start;
    let start_factor = solution.factor;
    let circle = surface.circle;
    let [cx, cy] = surface.axis;
    let domain = inputs.domain;
    let passive = Passive::new(surface, inputs);
    let m = settings.segments.max(3);
    let (xa, xb) = (
        surface.points[0][0],
        surface.points[surface.points.len() - 1][0],
    );
    let base: Vec<[f64; 2]> = (0..=m)
        .map(|i| {
            let x = xa + (xb - xa) * i as f64 / m as f64;
            let y = match circle {
                Some(c) => c.lower(x),
                None => surface.y(x).unwrap_or(f64::NAN),
            };
            [x, y]
        })
        .collect();
    // Radial directions of the interior vertices.
    let dirs: Vec<[f64; 2]> = base
        .iter()
        .map(|p| {
            let (dx, dy) = (p[0] - cx, p[1] - cy);
            let l = (dx * dx + dy * dy).sqrt().max(f64::MIN_POSITIVE);
            [dx / l, dy / l]
        })
        .collect();
    let build = |offsets: &[f64]| -> Option<Surface> {
        let mut pts = Vec::with_capacity(m + 1);
        for i in 0..=m {
            if i == 0 || i == m {
                let x = base[i][0] + offsets[i];
                pts.push([x, domain.ground_y(x)?]);
            } else {
                let o = offsets[i];
                pts.push([base[i][0] + o * dirs[i][0], base[i][1] + o * dirs[i][1]]);
            }
        }
        let s = Surface {
            points: pts,
            axis: [cx, cy],
            circle,
        };
        (s.admissible(domain) && passive.allows(&s)).then_some(s)
    };
    let score = |offsets: &[f64]| -> Option<(Surface, Solution)> {
        let s = build(offsets)?;
        match evaluate(s, inputs, method, tol) {
            Trial::Solved(found) => Some(*found),
            _ => None,
        }
    };
    let offsets = vec![0.0; m + 1];
    let Some(best) = score(&offsets) else {
        return (
            start.clone(),
            Refinement {
                evaluations: 1,
                start_factor,
                end_factor: start_factor,
                final_step_ratio: 1.0,
            },
        );
    };
    let last = surface.points[surface.points.len() - 1];
    let chord = ((xb - xa).powi(2) + (last[1] - surface.points[0][1]).powi(2)).sqrt();
    // Moves of runs of neighbouring interior vertices together (half the
    // polyline, a quarter, ... down to one vertex; the ends alone), so that a
    // surface can settle onto a weak layer as a whole rather than through
    // kinks that each raise the factor.
    let mut runs = nested_runs(1, m, (m - 1) / 2);
    runs.push((0, 1));
    runs.push((m, m + 1));
    runs.dedup();
    polish(start, best, offsets, &runs, chord, settings, score)
}
