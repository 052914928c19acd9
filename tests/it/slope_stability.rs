//! Limit equilibrium (`a3d_init::slope`) against closed forms and published
//! results (#31): the infinite slope, dry and with seepage parallel to the
//! surface; a Bishop factor computed by hand for a given circle; and the
//! slope-stability verification problems that commercial programs are checked
//! against (ACADS, Giam & Donald 1989; Fredlund & Krahn 1977; Arai & Tagyo
//! 1985). Sources of every number are in `docs/slope-stability.md`.

use a3d_init::slope::{
    self, CircleSearch, Domain, Dry, Interslice, Method, PoreField, PoreSample, Problem, Region,
    SearchSettings, SlopeMaterial, Suction, Surface, WaterTable,
};
use a3d_testkit::slopes::{self, MP, Published, material};

fn problem<'a>(
    domain: &'a Domain,
    materials: &'a [SlopeMaterial],
    field: &'a dyn PoreField,
) -> Problem<'a> {
    Problem {
        domain,
        materials,
        field,
        suction: Suction::Bishop,
        n_slices: 40,
        min_depth: 0.0,
        tolerance: 1e-7,
    }
}

// ---------------------------------------------------------------------------
// Closed forms.

/// A band of thickness `t` (vertical) under a uniform slope of angle β,
/// 100 m long.
fn infinite_slope(beta_deg: f64, t: f64, gamma: f64) -> Domain {
    let tan = beta_deg.to_radians().tan();
    let l = 100.0;
    Domain::from_polygons(vec![Region {
        polygon: vec![[0.0, l * tan], [0.0, l * tan - t], [l, -t], [l, 0.0]],
        material: 0,
        unit_weight: gamma,
    }])
    .unwrap()
}

/// A surface at vertical depth `d` parallel to the ground from x = 10 to 90,
/// with vertical ends.
fn parallel_surface(domain: &Domain, d: f64) -> Surface {
    let g = |x: f64| domain.ground_y(x).unwrap();
    Surface::polyline(
        domain,
        vec![
            [10.0, g(10.0)],
            [10.0, g(10.0) - d],
            [90.0, g(90.0) - d],
            [90.0, g(90.0)],
        ],
        None,
    )
    .unwrap()
}

/// Seepage parallel to the surface with the water table at the ground:
/// u = γw·z·cos²β at vertical depth z.
struct ParallelSeepage {
    beta: f64,
    gamma_w: f64,
    top: f64,
}

impl PoreField for ParallelSeepage {
    fn sample(&self, x: f64, y: f64) -> PoreSample {
        let z = (self.top - x * self.beta.tan()) - y;
        PoreSample {
            pwp: -self.gamma_w * z.max(0.0) * self.beta.cos().powi(2),
            saturation: 1.0,
        }
    }
}

#[test]
fn infinite_slope_dry_every_method_within_half_a_percent() {
    let (beta, phi) = (25.0_f64, 35.0_f64);
    let domain = infinite_slope(beta, 8.0, 19.0);
    let materials = [material("sand", 0.0, phi)];
    let p = problem(&domain, &materials, &Dry);
    let surface = parallel_surface(&domain, 1.0);
    let exact = phi.to_radians().tan() / beta.to_radians().tan();
    for method in Method::ALL {
        let (_, s) = slope::evaluate_surface(&p, method, &surface).unwrap();
        assert!(s.converged, "{method:?}");
        let err = (s.factor - exact).abs() / exact;
        assert!(err < 0.005, "{method:?}: {} vs {exact} ({err:e})", s.factor);
    }
}

#[test]
fn infinite_slope_with_parallel_seepage_every_method_within_half_a_percent() {
    let (beta, phi, gamma, gamma_w) = (20.0_f64, 33.0_f64, 20.0, 9.81);
    let domain = infinite_slope(beta, 8.0, gamma);
    let materials = [material("sand", 0.0, phi)];
    let field = ParallelSeepage {
        beta: beta.to_radians(),
        gamma_w,
        top: 100.0 * beta.to_radians().tan(),
    };
    let p = problem(&domain, &materials, &field);
    let surface = parallel_surface(&domain, 1.0);
    let exact = (gamma - gamma_w) / gamma * phi.to_radians().tan() / beta.to_radians().tan();
    for method in Method::ALL {
        let (_, s) = slope::evaluate_surface(&p, method, &surface).unwrap();
        let err = (s.factor - exact).abs() / exact;
        assert!(err < 0.005, "{method:?}: {} vs {exact} ({err:e})", s.factor);
    }
}

/// Bishop's simplified method by hand: slices of equal width between the
/// circle's ground crossings (both on a planar face, so no extra slice
/// boundary), weight γ·b·(ground − base) at the slice middle, chord bases,
/// and the fixed point F = Σ[c·b + W·tan φ]/m_α / Σ W·sin α.
#[test]
fn bishop_factor_matches_a_hand_computation() {
    let (c, phi, gamma) = (8.0, 28.0_f64, 18.5);
    let domain = infinite_slope(30.0, 40.0, gamma);
    let materials = [material("clay", c, phi)];
    let p = Problem {
        n_slices: 25,
        ..problem(&domain, &materials, &Dry)
    };
    let circle = slope::Circle {
        xc: 45.0,
        yc: 52.0,
        r: 30.0,
    };
    let surface = circle.trace(&domain, 25).unwrap();
    let (_, s) = slope::evaluate_surface(&p, Method::Bishop, &surface).unwrap();

    // The hand computation.
    let tan30 = 30f64.to_radians().tan();
    let ground = |x: f64| 100.0 * tan30 - x * tan30;
    let arc = |x: f64| circle.yc - (circle.r * circle.r - (x - circle.xc).powi(2)).sqrt();
    // Crossings of y = ground(x) with the lower arc, by bisection.
    let crossing = |mut a: f64, mut b: f64| {
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if (ground(a) - arc(a)) * (ground(m) - arc(m)) <= 0.0 {
                b = m;
            } else {
                a = m;
            }
        }
        0.5 * (a + b)
    };
    let xa = crossing(circle.xc - circle.r + 1e-9, circle.xc);
    let xb = crossing(circle.xc, circle.xc + circle.r - 1e-9);
    let n = 25;
    let b = (xb - xa) / n as f64;
    let tan_phi = phi.to_radians().tan();
    let mut rows = Vec::new();
    for i in 0..n {
        let (x0, x1) = (xa + i as f64 * b, xa + (i + 1) as f64 * b);
        let (y0, y1) = (arc(x0), arc(x1));
        let xm = 0.5 * (x0 + x1);
        let w = gamma * b * (ground(xm) - 0.5 * (y0 + y1));
        // The mass moves toward +x (the toe is on the right): α is measured
        // positive where the base falls toward the toe.
        let alpha = -((y1 - y0) / b).atan();
        // The base is the chord: its shear acts at the distance of the chord
        // from the centre, R·cos(δ/2) with δ the angle the chord subtends.
        let chord = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
        let arm = (circle.r * circle.r - 0.25 * chord * chord).sqrt();
        rows.push((w, alpha, arm));
    }
    // Moments about the centre: Σ S·arm = Σ W·arm·sin α, with
    // S = (c·b + W·tan φ)/m_α for Bishop's N.
    let mut f = 1.0_f64;
    for _ in 0..200 {
        let resisting: f64 = rows
            .iter()
            .map(|&(w, a, r)| r * (c * b + w * tan_phi) / (a.cos() + a.sin() * tan_phi / f))
            .sum();
        let driving: f64 = rows.iter().map(|&(w, a, r)| r * w * a.sin()).sum();
        f = resisting / driving;
    }
    assert!(
        (s.factor - f).abs() < 1e-6 * f,
        "engine {} vs hand {f}",
        s.factor
    );
}

// ---------------------------------------------------------------------------
// Published verification problems.

fn published_problem(p: &Published) -> Problem<'_> {
    problem(&p.domain, &p.materials, p.field.as_ref())
}

fn search(p: &Problem<'_>, method: Method) -> slope::Analysis {
    slope::analyse(p, method, &SearchSettings::default()).unwrap()
}

fn within(what: &str, got: f64, referee: f64, tolerance: f64) {
    let err = (got - referee) / referee;
    assert!(
        err.abs() <= tolerance,
        "{what}: {got:.4} against the referee {referee} ({:+.2} %)",
        100.0 * err
    );
}

/// The circular search of `method` within 2 % of `referee`; the non-circular
/// refinement only lowers the factor, and by under 5 %.
#[track_caller]
fn circular_near_the_referee(name: &str, p: &Problem<'_>, method: Method, referee: f64) {
    let a = search(p, method);
    within(
        &format!("{name} {method:?} circular"),
        a.circular.factor,
        referee,
        0.02,
    );
    assert!(a.critical.factor <= a.circular.factor + 1e-12);
    assert!(
        a.circular.factor - a.critical.factor < 0.05 * a.circular.factor,
        "{name} {method:?}: non-circular {:.4} vs circular {:.4}",
        a.critical.factor,
        a.circular.factor
    );
}

#[test]
fn acads_1a_simple_slope_within_two_percent_of_the_referee() {
    let acads = slopes::acads_1a();
    let p = published_problem(&acads);
    for method in [MP, Method::Spencer, Method::Bishop] {
        circular_near_the_referee("ACADS 1(a)", &p, method, 1.00);
    }
}

/// A layered infinite slope: a band of soil 1 (γ₁, thickness t₁ measured
/// vertically) over soil 2 (γ₂), both parallel to the ground; a surface
/// parallel to the ground at vertical depth d > t₁ lies in soil 2, whose
/// strength alone acts on it, under the weight of both. Per unit horizontal
/// width W = γ₁t₁ + γ₂(d − t₁); on the base σ = W cos²β, τ = W sin β cos β,
/// so F = c₂/(W sin β cos β) + tan φ₂/tan β.
#[test]
fn layered_infinite_slope_every_method_within_half_a_percent() {
    let (beta, t1, d) = (22.0_f64, 2.0, 3.5);
    let (gamma1, gamma2) = (17.0, 21.0);
    let (c2, phi2) = (4.0, 26.0_f64);
    let tan = beta.to_radians().tan();
    let l = 100.0;
    let ground = |x: f64| (l - x) * tan;
    let domain = Domain::from_polygons(vec![
        Region {
            polygon: vec![
                [0.0, ground(0.0)],
                [0.0, ground(0.0) - t1],
                [l, -t1],
                [l, 0.0],
            ],
            material: 0,
            unit_weight: gamma1,
        },
        Region {
            polygon: vec![
                [0.0, ground(0.0) - t1],
                [0.0, ground(0.0) - 8.0],
                [l, -8.0],
                [l, -t1],
            ],
            material: 1,
            unit_weight: gamma2,
        },
    ])
    .unwrap();
    // Soil 1 is much stronger: were its strength used at the base, the
    // factor would be far off.
    let materials = [material("upper", 30.0, 40.0), material("lower", c2, phi2)];
    let p = problem(&domain, &materials, &Dry);
    let surface = parallel_surface(&domain, d);
    let w = gamma1 * t1 + gamma2 * (d - t1);
    let (sb, cb) = beta.to_radians().sin_cos();
    let exact = c2 / (w * sb * cb) + phi2.to_radians().tan() / tan;
    for method in Method::ALL {
        let (_, s) = slope::evaluate_surface(&p, method, &surface).unwrap();
        assert!(s.converged, "{method:?}");
        // Janbu's empirical correction f₀ = 1 + b₁(d/L − 1.4(d/L)²) raises a
        // c–φ soil's factor by 2 % at d/L = 3.5/80: the closed form is the
        // uncorrected factor's.
        let factor = match method {
            Method::Janbu => {
                let f0 = s.janbu_f0.unwrap();
                assert!((s.factor - f0 * s.force_factor.unwrap()).abs() < 1e-12);
                s.force_factor.unwrap()
            }
            _ => s.factor,
        };
        let err = (factor - exact).abs() / exact;
        assert!(err < 0.005, "{method:?}: {factor} vs {exact} ({err:e})");
    }
}

/// Fredlund & Krahn (1977), the circle given (`testkit::slopes`): their
/// four methods' factors, dry and with the piezometric line, within 1 %.
#[test]
fn fredlund_krahn_circle_dry_and_with_a_water_table_within_one_percent() {
    let (domain, soil, circle, water, published) = slopes::fredlund_krahn();
    let materials = [soil];
    let surface = circle.trace(&domain, 40).unwrap();
    let cases: [(&dyn PoreField, [f64; 4]); 2] = [(&Dry, published[0]), (&water, published[1])];
    for (field, published) in cases {
        let p = problem(&domain, &materials, field);
        let methods = [
            Method::Ordinary,
            Method::Bishop,
            Method::Spencer,
            Method::MorgensternPrice(Interslice::Constant),
        ];
        for (method, reference) in methods.into_iter().zip(published) {
            let (_, s) = slope::evaluate_surface(&p, method, &surface).unwrap();
            within(&format!("F&K {method:?}"), s.factor, reference, 0.01);
        }
    }
}

/// Arai & Tagyo (1985) example 3 (`testkit::slopes`; the data as tabulated
/// in the Slide2 verification manual, not re-checked against the paper
/// here): the test holds the circular Bishop search to 3 % of the published
/// 1.138 (it finds 1.115).
#[test]
fn arai_tagyo_water_table_slope_near_the_published_factor() {
    let arai = slopes::arai_tagyo_3();
    let p = published_problem(&arai);
    let bishop = search(&p, Method::Bishop).circular.factor;
    within("Arai & Tagyo 3 Bishop circular", bishop, 1.138, 0.03);
    // The rigorous methods over circles agree with Bishop's to a percent or
    // two. (A sign change of the residual at a pole of the slice recursion,
    // taken for a root, once gave Spencer 0.910 and half-sine M–P 0.432
    // here.)
    for method in [
        MP,
        Method::MorgensternPrice(Interslice::Constant),
        Method::Spencer,
    ] {
        let f = search(&p, method).circular.factor;
        assert!(
            (f / bishop - 1.0).abs() < 0.02,
            "{method:?}: {f:.4} against Bishop {bishop:.4}"
        );
    }
}

/// ACADS 1(c), the layered slope (`testkit::slopes`: three soils, referee
/// 1.39). First the geometry: the published critical circle must leave the
/// ground where the source says (29.702 and 50.991), and on it Bishop's,
/// Spencer's and Morgenstern–Price's factors must be Slide2's (1.405, 1.375,
/// GLE 1.374) within 1 %. Then the circular searches of the rigorous methods
/// and Bishop's within 2 % of the referee; Janbu's simplified (with f₀) lies
/// lower by nature and is held to Slide2's corrected Janbu, 1.357, within
/// 2 %. The non-circular refinement may only lower the factor, by under 5 %.
#[test]
fn acads_1c_layered_slope_within_two_percent_of_the_referee() {
    let acads = slopes::acads_1c();
    let p = published_problem(&acads);
    let (circle, ends) = acads.circle.unwrap();
    let traced = circle.trace(&acads.domain, 40).unwrap();
    let (first, last) = (traced.points[0], traced.points[traced.points.len() - 1]);
    assert!(
        (first[0] - ends[0]).abs() < 2e-3,
        "{first:?} vs {}",
        ends[0]
    );
    assert!((last[0] - ends[1]).abs() < 2e-3, "{last:?} vs {}", ends[1]);
    for (method, slide2) in [
        (Method::Bishop, 1.405),
        (Method::Spencer, 1.375),
        (MP, 1.374),
    ] {
        let (_, s) = slope::evaluate_surface(&p, method, &traced).unwrap();
        within(
            &format!("ACADS 1(c) {method:?} on the published circle"),
            s.factor,
            slide2,
            0.01,
        );
    }
    for method in [
        Method::Bishop,
        Method::Spencer,
        MP,
        Method::MorgensternPrice(Interslice::Constant),
    ] {
        circular_near_the_referee("ACADS 1(c)", &p, method, 1.39);
    }
    let janbu = search(&p, Method::Janbu).circular.factor;
    within("ACADS 1(c) Janbu circular", janbu, 1.357, 0.02);
}

/// ACADS 3(a), a 0.5 m weak layer (`testkit::slopes`; the data from one
/// secondary source): no circle finds the block that slides along the
/// layer (the best circle stays above 1.5), the composite surfaces do. The
/// critical surface runs in the layer (y from 26.5 to 27) over more than
/// 10 m (a block; a circle touches it at a point), and its factor lies
/// from 6 % below to 4 % above the referee's 1.26. Below: the search is
/// free where the ACADS entrants mostly fixed a block; it finds 1.198 (MP,
/// #39) with a passive wedge rising at 32° (the rule allows 40°) and an
/// active scarp steepening to 56° (Rankine's 45° + φ′/2 is 59°).
#[test]
fn acads_3a_weak_layer_block_is_found_by_the_composite_surfaces() {
    let acads = slopes::acads_3a();
    let p = published_problem(&acads);
    for method in [MP, Method::Spencer] {
        let a = search(&p, method);
        assert!(
            a.circular.factor > 1.45,
            "{method:?}: {}",
            a.circular.factor
        );
        assert!(a.search.composites.interfaces == 2 && a.search.composites.solved > 0);
        let err = a.critical.factor / 1.26 - 1.0;
        assert!(
            (-0.06..=0.04).contains(&err),
            "ACADS 3(a) {method:?} non-circular: {:.4} against the referee 1.26 ({:+.2} %)",
            a.critical.factor,
            100.0 * err
        );
        let s = &a.critical.surface;
        let along: f64 = s
            .windows(2)
            .filter(|w| w.iter().all(|p| (26.45..27.0).contains(&p[1])))
            .map(|w| w[1][0] - w[0][0])
            .sum();
        let length = s[s.len() - 1][0] - s[0][0];
        assert!(
            along > 10.0,
            "{method:?}: {along:.1} m of {length:.1} m along the layer"
        );
    }
}

#[test]
fn grid_search_finds_the_entry_exit_minimum_on_acads_1a() {
    let acads = slopes::acads_1a();
    let p = published_problem(&acads);
    let grid = slope::analyse(
        &p,
        Method::Bishop,
        &SearchSettings {
            circles: CircleSearch::Grid {
                centres: None,
                tangents: None,
            },
            refine: false,
            ..SearchSettings::default()
        },
    )
    .unwrap();
    within("ACADS 1(a) grid Bishop", grid.circular.factor, 1.00, 0.02);
}

/// Water above the ground is named, not silently analysed: the ACADS 1(a)
/// section under a level water table 1 m above its crest warns (the most,
/// about 108 kPa, at the toe); the same table 1 m below the toe does not.
#[test]
fn ponding_above_the_ground_is_warned_of() {
    let domain = slopes::acads_1a().domain;
    let table = |y: f64| WaterTable {
        line: vec![[20.0, y], [70.0, y]],
        gamma_w: 9.81,
    };
    let warning = a3d_init::pipeline::stability::slope::ponding(&domain, &table(36.0)).unwrap();
    assert!(warning.contains("ponding"), "{warning}");
    assert!(a3d_init::pipeline::stability::slope::ponding(&domain, &table(24.0)).is_none());
    assert!(a3d_init::pipeline::stability::slope::ponding(&domain, &Dry).is_none());
}
