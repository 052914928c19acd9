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
    /// Circles clipped.
    pub circles: usize,
    /// Composite surfaces formed (circles that dip below an interface).
    pub formed: usize,
    pub solved: usize,
    /// The best composite's factor, before the vertex moves.
    pub best_factor: Option<f64>,
}

/// Clips each seed circle at each material interface, exactly on it (the
/// strength of the region above) and a hair below (the region below),
/// evaluates the composites in parallel, and returns the best (the first in
/// order on a tie) with the counts.
pub fn best_composite(
    seeds: &[&(Surface, Solution)],
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
) -> (Option<(Surface, Solution)>, CompositeCounts) {
    let domain = inputs.domain;
    let lines = composite::interfaces(domain);
    let height = domain
        .ground()
        .iter()
        .map(|p| p[1])
        .fold(f64::NEG_INFINITY, f64::max)
        - domain.bottom();
    let hair = 1e-4 * height;
    let mut surfaces = Vec::new();
    for (s, _) in seeds.iter().copied() {
        let Some(c) = s.circle else { continue };
        for line in &lines {
            for drop in [0.0, hair] {
                if let Some(clipped) = composite::clip(&c, s, line, drop, domain) {
                    surfaces.push(clipped);
                }
            }
        }
    }
    let formed = surfaces.len();
    let solved: Vec<Option<(Surface, Solution)>> = surfaces
        .into_par_iter()
        .map(|s| match evaluate(s, inputs, method, tol) {
            Trial::Solved(found) => Some(*found),
            _ => None,
        })
        .collect();
    let mut count = 0;
    let mut best: Option<(Surface, Solution)> = None;
    for found in solved.into_iter().flatten() {
        count += 1;
        if best.as_ref().is_none_or(|b| found.1.factor < b.1.factor) {
            best = Some(found);
        }
    }
    let counts = CompositeCounts {
        interfaces: lines.len(),
        circles: seeds.len(),
        formed,
        solved: count,
        best_factor: best.as_ref().map(|b| b.1.factor),
    };
    (best, counts)
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

/// Pattern search on the circle's centre and radius.
pub fn refine_circle(
    start: (Surface, Solution),
    inputs: &SliceInputs<'_>,
    method: Method,
    tol: f64,
    n_slices: usize,
    max_evaluations: usize,
) -> ((Surface, Solution), Refinement) {
    let Some(circle) = start.0.circle else {
        let f = start.1.factor;
        return (
            start,
            Refinement {
                evaluations: 0,
                start_factor: f,
                end_factor: f,
                final_step_ratio: 1.0,
            },
        );
    };
    let start_factor = start.1.factor;
    let mut best = start;
    let mut current = circle;
    let step0 = 0.05 * circle.r;
    let mut step = step0;
    let mut evaluations = 0;
    while step > 1e-4 * circle.r && evaluations < max_evaluations {
        let mut improved = false;
        for k in 0..6 {
            let mut c = current;
            let d = if k % 2 == 0 { step } else { -step };
            match k / 2 {
                0 => c.xc += d,
                1 => c.yc += d,
                _ => c.r += d,
            }
            evaluations += 1;
            let trial = match c.trace(inputs.domain, n_slices) {
                Ok(s) => evaluate(s, inputs, method, tol),
                Err(r) => Trial::Rejected(r),
            };
            if let Trial::Solved(found) = trial
                && found.1.factor < best.1.factor * (1.0 - 1e-12)
            {
                best = *found;
                current = c;
                improved = true;
            }
        }
        if !improved {
            step *= 0.5;
        }
    }
    let end_factor = best.1.factor;
    (
        best,
        Refinement {
            evaluations,
            start_factor,
            end_factor,
            final_step_ratio: step / step0,
        },
    )
}

/// Moves the vertices of a polyline made from the surface (a circle, or a
/// composite surface with the circle's centre as its axis) to lower the
/// factor.
pub fn refine_polyline(
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
        s.admissible(domain).then_some(s)
    };
    let score = |offsets: &[f64]| -> Option<(Surface, Solution)> {
        let s = build(offsets)?;
        match evaluate(s, inputs, method, tol) {
            Trial::Solved(found) => Some(*found),
            _ => None,
        }
    };
    let mut offsets = vec![0.0; m + 1];
    let Some(mut best) = score(&offsets) else {
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
    let step0 = chord / 25.0;
    let mut step = step0;
    let mut evaluations = 1;
    // Moves of runs of neighbouring interior vertices together (half the
    // polyline, a quarter, ... down to one vertex; the ends alone), so that a
    // surface can settle onto a weak layer as a whole rather than through
    // kinks that each raise the factor.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut w = (m - 1) / 2;
    while w >= 1 {
        let mut k = 1;
        while k + w <= m {
            runs.push((k, k + w));
            k += w.div_ceil(2).max(1);
        }
        w /= 2;
    }
    runs.push((0, 1));
    runs.push((m, m + 1));
    runs.dedup();
    while step > chord / 2500.0 && evaluations < settings.max_refinements {
        let mut improved = false;
        for &(k0, k1) in &runs {
            for d in [step, -step] {
                if evaluations >= settings.max_refinements {
                    break;
                }
                let mut trial = offsets.clone();
                for o in &mut trial[k0..k1] {
                    *o += d;
                }
                evaluations += 1;
                if let Some(found) = score(&trial)
                    && found.1.factor < best.1.factor * (1.0 - 1e-12)
                {
                    best = found;
                    offsets = trial;
                    improved = true;
                    break;
                }
            }
        }
        if !improved {
            step *= 0.5;
        }
    }
    // A start better than every polyline stays the answer.
    if solution.factor <= best.1.factor {
        best = start.clone();
    }
    let end_factor = best.1.factor;
    (
        best,
        Refinement {
            evaluations,
            start_factor,
            end_factor,
            final_step_ratio: step / step0,
        },
    )
}
