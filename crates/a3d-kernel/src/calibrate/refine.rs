//! Deterministic golden-section refinement of a bracketed minimum.

/// Result of [`golden_section`].
#[derive(Clone, Debug, PartialEq)]
pub struct Refined {
    pub x: f64,
    pub value: f64,
    pub trace: Vec<(f64, f64)>,
}

/// Golden-section search for a minimum of `f` on [a, b], stopping when the
/// bracket is narrower than `tol` or after `max_iter` steps. Returns the best
/// point evaluated (including both ends).
pub fn golden_section(
    f: impl Fn(f64) -> f64,
    a: f64,
    b: f64,
    tol: f64,
    max_iter: usize,
) -> Refined {
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (a.min(b), a.max(b));
    let mut trace = Vec::new();
    let eval = |x: f64, trace: &mut Vec<(f64, f64)>| {
        let v = f(x);
        trace.push((x, v));
        v
    };
    // Both ends are candidates too.
    eval(a, &mut trace);
    eval(b, &mut trace);
    let mut c = b - ratio * (b - a);
    let mut d = a + ratio * (b - a);
    let mut fc = eval(c, &mut trace);
    let mut fd = eval(d, &mut trace);
    for _ in 0..max_iter {
        if (b - a).abs() < tol {
            break;
        }
        if fc <= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - ratio * (b - a);
            fc = eval(c, &mut trace);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + ratio * (b - a);
            fd = eval(d, &mut trace);
        }
    }
    let (x, value) =
        trace.iter().copied().fold(
            (a, f64::INFINITY),
            |best, s| if s.1 < best.1 { s } else { best },
        );
    Refined { x, value, trace }
}
