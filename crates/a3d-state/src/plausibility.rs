//! Plausibility of a mapped initial state: signs of a sign or unit error in the
//! FEM pore pressures. Two checks, both warnings (never errors, since suction can
//! be large and water can stand above a model):
//!
//! * a pore pressure whose magnitude exceeds 1.5 × the total vertical stress at
//!   the same MP (+ 10 kPa): compressive ones almost always mean a unit or sign
//!   error, beyond what free water up to the model's top (a reservoir, which
//!   loads the pore water but not the overburden) could add; suctions are
//!   counted apart, and only when they also exceed the hydrostatic suction of a
//!   water table at the model's bottom;
//! * a compressive pore pressure implying a water level above the model's top
//!   (y + |p|/γw above the highest MP by more than 0.5 m + 5 % of the height).
//!
//! Anura3D signs: pwp negative in compression, stresses tension positive.
//! Pure computation; the messages are returned, not printed.

use a3d_model::MpState;

/// One failed check: how many MPs, and the worst few.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Finding {
    pub check: &'static str,
    pub count: usize,
    /// Of `count`, how many are suctions (first check only).
    pub suction: usize,
    /// (1-based MP id, position, pwp, σyy) of the worst MPs, worst first.
    pub worst: Vec<(usize, [f64; 3], f64, f64)>,
    pub message: String,
}

/// Ratio above which |pwp| is implausible against the total vertical stress.
const RATIO: f64 = 1.5;
/// Absolute slack (kPa) so that MPs near the surface with tiny stresses pass.
const SLACK: f64 = 10.0;
const WORST: usize = 3;

fn describe(worst: &[(usize, [f64; 3], f64, f64)], dim: usize) -> String {
    worst
        .iter()
        .map(|(id, p, pwp, syy)| {
            let at = if dim == 3 {
                format!("({:.3}, {:.3}, {:.3})", p[0], p[1], p[2])
            } else {
                format!("({:.3}, {:.3})", p[0], p[1])
            };
            format!("MP {id} at {at}: pwp {pwp:.2} kPa, σyy {syy:.2} kPa")
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Runs both checks. `gamma_w` is the unit weight of water (kN/m³).
/// The [`Finding::worst`] entries of the first [`WORST`] of `sorted`
/// ((score, MP index) pairs, worst first).
fn worst_of(
    sorted: &[(f64, usize)],
    positions: &[[f64; 3]],
    states: &[MpState],
) -> Vec<(usize, [f64; 3], f64, f64)> {
    sorted
        .iter()
        .take(WORST)
        .map(|&(_, i)| (i + 1, positions[i], states[i].pwp, states[i].total[1]))
        .collect()
}

pub fn check(positions: &[[f64; 3]], states: &[MpState], dim: usize, gamma_w: f64) -> Vec<Finding> {
    let mut findings = Vec::new();
    let (lo, hi) = positions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[1]), b.max(p[1]))
        });
    // 1. |pwp| against the total vertical stress. A suction is counted only when it
    // also exceeds the hydrostatic suction of a water table at the model's bottom;
    // a compressive pwp only beyond what water up to the model's top could add.
    let mut bad: Vec<(f64, usize)> = Vec::new();
    let mut suction = 0;
    for (i, s) in states.iter().enumerate() {
        let sv = s.total[1].abs();
        let y = positions[i][1];
        // Water standing above the ground (a reservoir) loads the pore water but
        // not the soil's overburden: compressive pwp may add γw·(top − y).
        let bound = match s.pwp < 0.0 {
            true => RATIO * sv + SLACK + gamma_w * (hi - y).max(0.0),
            false => (RATIO * sv).max(gamma_w * (y - lo)) + SLACK,
        };
        if s.pwp.abs() > bound {
            bad.push((s.pwp.abs() - sv, i));
            if s.pwp > 0.0 {
                suction += 1;
            }
        }
    }
    if !bad.is_empty() {
        // Compressive ones first (they are the likely errors), then by excess.
        bad.sort_by(|a, b| {
            let (ca, cb) = (states[a.1].pwp < 0.0, states[b.1].pwp < 0.0);
            cb.cmp(&ca).then(b.0.total_cmp(&a.0)).then(a.1.cmp(&b.1))
        });
        let worst = worst_of(&bad, positions, states);
        findings.push(Finding {
            check: "pwp-exceeds-vertical-stress",
            count: bad.len(),
            suction,
            message: format!(
                "{} of {} MPs have a pore pressure whose magnitude exceeds {RATIO}× the total vertical stress there (+{SLACK} kPa, + the weight of water up to the model's top for compressive ones): {} compressive, {suction} suction (large suction can be genuine). A sign or unit error? check the FEM sign convention and the FEM units. Worst: {}",
                bad.len(),
                states.len(),
                bad.len() - suction,
                describe(&worst, dim)
            ),
            worst,
        });
    }
    // 2. Compressive pwp implying water above the model's top.
    if hi.is_finite() && gamma_w > 0.0 {
        let tolerance = 0.5 + 0.05 * (hi - lo);
        let mut above: Vec<(f64, usize)> = states
            .iter()
            .enumerate()
            .filter(|(_, s)| s.pwp < 0.0)
            .map(|(i, s)| (positions[i][1] - s.pwp / gamma_w - hi, i))
            .filter(|(h, _)| *h > tolerance)
            .collect();
        if !above.is_empty() {
            above.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            let worst = worst_of(&above, positions, states);
            findings.push(Finding {
                check: "compressive-pwp-above-top",
                count: above.len(),
                suction: 0,
                message: format!(
                    "{} of {} MPs have a compressive pore pressure that puts the water level up to {:.2} m above the model's top (highest MP at y = {hi:.3} m, γw = {gamma_w} kN/m³): unless water stands above the model, a sign error? check the FEM sign convention. Worst: {}",
                    above.len(),
                    states.len(),
                    above[0].0,
                    describe(&worst, dim)
                ),
                worst,
            });
        }
    }
    findings
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10 m column, water table at y = 5, γ = 20, γw = 10.
    fn column(flip: bool, scale: f64) -> (Vec<[f64; 3]>, Vec<MpState>) {
        let mut pos = Vec::new();
        let mut st = Vec::new();
        for k in 0..=20 {
            let y = 0.5 * k as f64;
            let pwp = -10.0 * (5.0 - y) * scale * if flip { -1.0 } else { 1.0 };
            pos.push([1.0, y, 0.0]);
            st.push(MpState {
                pwp,
                total: [0.0, -20.0 * (10.0 - y), 0.0, 0.0, 0.0, 0.0],
                saturation: 1.0,
            });
        }
        (pos, st)
    }

    #[test]
    fn a_hydrostatic_column_passes() {
        let (p, s) = column(false, 1.0);
        assert!(check(&p, &s, 2, 10.0).is_empty());
    }

    #[test]
    fn psf_read_as_kpa_is_flagged_with_the_worst_mps() {
        // psf values read as kPa are about 20.9× too large.
        let (p, s) = column(false, 20.9);
        let f = check(&p, &s, 2, 10.0);
        let first = &f[0];
        assert_eq!(first.check, "pwp-exceeds-vertical-stress");
        assert!(first.count > 5 && first.suction > 0, "{first:?}");
        assert_eq!(
            first.worst[0].0, 1,
            "the deepest MP is the worst compressive one"
        );
        assert!(
            first.message.contains("MP 1 at (1.000, 0.000)"),
            "{}",
            first.message
        );
    }

    #[test]
    fn a_flipped_sign_puts_water_above_the_top() {
        let (p, s) = column(true, 1.0);
        let f = check(&p, &s, 2, 10.0);
        let above = f
            .iter()
            .find(|f| f.check == "compressive-pwp-above-top")
            .expect("flagged");
        assert_eq!(above.worst[0].0, 21, "{above:?}");
        assert!(above.message.contains("above the model's top"));
    }
}
