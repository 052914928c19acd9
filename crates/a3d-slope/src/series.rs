//! A factor of safety over time: the first time it falls to 1 or below,
//! bracketed by two saved times and bisected between them. What the factor
//! at a time between two saved outputs is (how the pore pressures are
//! interpolated) is the caller's: it passes a function of time. No I/O.

/// Where the factor first reaches 1.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Crossing {
    /// The first time found with a factor ≤ 1 (the upper end of the final
    /// bracket; the first saved time when the series starts at or below 1).
    pub time: f64,
    pub factor: f64,
    /// The last time with a factor > 1 and the first with ≤ 1.
    pub bracket: (f64, f64),
    /// The times evaluated by the bisection, with their factors.
    pub bisected: Vec<(f64, f64)>,
}

/// The first crossing of 1 in `saved` ((time, factor), times ascending),
/// refined by bisecting `factor_at` until the bracket is at most `tolerance`
/// wide. `None` when no saved factor is ≤ 1.
pub fn first_crossing<E>(
    saved: &[(f64, f64)],
    tolerance: f64,
    mut factor_at: impl FnMut(f64) -> Result<f64, E>,
) -> Result<Option<Crossing>, E> {
    let Some(k) = saved.iter().position(|&(_, f)| f <= 1.0) else {
        return Ok(None);
    };
    if k == 0 {
        let (t, f) = saved[0];
        return Ok(Some(Crossing {
            time: t,
            factor: f,
            bracket: (t, t),
            bisected: Vec::new(),
        }));
    }
    let (mut lo, mut hi) = (saved[k - 1].0, saved[k].0);
    let mut f_hi = saved[k].1;
    let mut bisected = Vec::new();
    while hi - lo > tolerance && bisected.len() < 60 {
        let mid = 0.5 * (lo + hi);
        let f = factor_at(mid)?;
        bisected.push((mid, f));
        if f > 1.0 {
            lo = mid;
        } else {
            hi = mid;
            f_hi = f;
        }
    }
    Ok(Some(Crossing {
        time: hi,
        factor: f_hi,
        bracket: (lo, hi),
        bisected,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bisects_a_linear_decline_to_the_tolerance() {
        let f = |t: f64| 1.5 - 0.1 * t;
        let saved: Vec<(f64, f64)> = (0..10).map(|t| (t as f64, f(t as f64))).collect();
        let c = first_crossing::<()>(&saved, 1e-3, |t| Ok(f(t)))
            .unwrap()
            .unwrap();
        assert!((c.time - 5.0).abs() <= 1e-3, "{c:?}");
        assert!(c.bracket.1 - c.bracket.0 <= 1e-3);
        assert!(
            first_crossing::<()>(&saved[..3], 1e-3, |t| Ok(f(t)))
                .unwrap()
                .is_none()
        );
    }
}
