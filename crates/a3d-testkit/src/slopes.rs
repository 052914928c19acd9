//! The published slope-stability verification problems, one table for
//! the tests (`tests/it/slope_stability.rs`) and the example that draws them
//! (`examples/slope_benchmarks.rs`). Every number's source is in
//! `docs/slope-stability.md` §8.
//!
//! * [`acads_1a`]: ACADS 1(a), the simple homogeneous slope (referee 1.00).
//! * [`acads_1c`]: ACADS 1(c), the three-soil layered slope (referee 1.39),
//!   with the published critical circle.
//! * [`arai_tagyo_3`]: Arai & Tagyo (1985) example 3, a water table
//!   (published 1.138).
//! * [`acads_3a`]: ACADS 3(a), a thin weak layer (referee 1.26 over
//!   non-circular surfaces).
//! * [`fredlund_krahn`]: Fredlund & Krahn (1977), a given circle, dry and
//!   with a piezometric line (four methods published for each).

use a3d_slope::{
    Circle, Domain, Dry, Interslice, Method, PoreField, Region, SlopeMaterial, Strength, WaterTable,
};

/// Morgenstern–Price with the half-sine interslice function, the default.
pub const MP: Method = Method::MorgensternPrice(Interslice::HalfSine);

/// A Mohr–Coulomb material of cohesion `c` (kPa) and friction angle `phi`
/// (degrees).
pub fn material(name: &str, c: f64, phi: f64) -> SlopeMaterial {
    SlopeMaterial {
        name: name.into(),
        strength: Some(Strength {
            cohesion: c,
            friction_angle: phi,
            phi_b: None,
        }),
    }
}

/// A published problem: geometry, strengths, pore pressures and the
/// published factors.
pub struct Published {
    pub name: &'static str,
    /// SVG name under `docs/slope-stability/`.
    pub file: &'static str,
    pub domain: Domain,
    pub materials: Vec<SlopeMaterial>,
    pub field: Box<dyn PoreField>,
    /// (method, published factor, what the number is).
    pub published: Vec<(Method, f64, &'static str)>,
    /// A critical circle the source publishes, with its two ends on the
    /// ground (x of the left and right end).
    pub circle: Option<(Circle, [f64; 2])>,
}

fn region(polygon: Vec<[f64; 2]>, material: usize, unit_weight: f64) -> Region {
    Region {
        polygon,
        material,
        unit_weight,
    }
}

/// ACADS 1(a) (Giam & Donald 1989; Slide2 verification #1; SLOPE/W
/// verification §2.1): ground (20,25)–(30,25)–(50,35)–(70,35), base y = 20,
/// c′ = 3 kPa, φ′ = 19.6°, γ = 20 kN/m³, dry. Referee 1.00 (the rigorous
/// methods' value; the ordinary method lies lower).
pub fn acads_1a() -> Published {
    let domain = Domain::from_polygons(vec![region(
        vec![
            [20.0, 20.0],
            [70.0, 20.0],
            [70.0, 35.0],
            [50.0, 35.0],
            [30.0, 25.0],
            [20.0, 25.0],
        ],
        0,
        20.0,
    )])
    .expect("ACADS 1(a) polygon");
    Published {
        name: "ACADS 1(a) simple slope",
        file: "acads-1a.svg",
        domain,
        materials: vec![material("soil", 3.0, 19.6)],
        field: Box::new(Dry),
        published: vec![
            (Method::Bishop, 1.00, "referee"),
            (Method::Spencer, 1.00, "referee"),
            (MP, 1.00, "referee"),
            (Method::Janbu, 1.00, "referee"),
            (Method::Ordinary, 1.00, "referee"),
        ],
        circle: None,
    }
}

/// ACADS 1(c) (Giam & Donald 1989; Slide2 verification #3; SLOPE/W
/// verification manual, its coordinate-labelled figure): the 1(a) section
/// in three soils, all γ = 19.5 kN/m³, dry. Soil 1 (c′ = 0, φ′ = 38°) above
/// the line (30,25)–(40,27)–(50,29)–(54,31)–(70,31); soil 2 (c′ = 5.3 kPa,
/// φ′ = 23°) between it and (40,27)–(52,24)–(70,24), so it pinches out at
/// (40,27); soil 3 (c′ = 7.2 kPa, φ′ = 20°) below. Referee 1.39 (16 programs'
/// Bishop mean 1.406; Slide2 Bishop 1.405, Spencer 1.375, GLE 1.374;
/// SLOPE/W M–P 1.382). The published critical circle: centre
/// (34.121, 43.254), ends (29.702, 25) and (50.991, 35), hence R = 18.781.
pub fn acads_1c() -> Published {
    let gamma = 19.5;
    let domain = Domain::from_polygons(vec![
        region(
            vec![
                [30.0, 25.0],
                [40.0, 27.0],
                [50.0, 29.0],
                [54.0, 31.0],
                [70.0, 31.0],
                [70.0, 35.0],
                [50.0, 35.0],
            ],
            0,
            gamma,
        ),
        region(
            vec![
                [40.0, 27.0],
                [52.0, 24.0],
                [70.0, 24.0],
                [70.0, 31.0],
                [54.0, 31.0],
                [50.0, 29.0],
            ],
            1,
            gamma,
        ),
        region(
            vec![
                [20.0, 20.0],
                [70.0, 20.0],
                [70.0, 24.0],
                [52.0, 24.0],
                [40.0, 27.0],
                [30.0, 25.0],
                [20.0, 25.0],
            ],
            2,
            gamma,
        ),
    ])
    .expect("ACADS 1(c) polygons");
    Published {
        name: "ACADS 1(c) three-layer slope",
        file: "acads-1c.svg",
        domain,
        materials: vec![
            material("soil 1", 0.0, 38.0),
            material("soil 2", 5.3, 23.0),
            material("soil 3", 7.2, 20.0),
        ],
        field: Box::new(Dry),
        published: vec![
            (Method::Bishop, 1.39, "referee"),
            (Method::Spencer, 1.39, "referee"),
            (MP, 1.39, "referee"),
            (
                Method::MorgensternPrice(Interslice::Constant),
                1.39,
                "referee",
            ),
            (Method::Janbu, 1.357, "Slide2 (Janbu corrected)"),
        ],
        circle: Some((
            Circle {
                xc: 34.121,
                yc: 43.254,
                r: 18.781,
            },
            [29.702, 50.991],
        )),
    }
}

/// Arai & Tagyo (1985) example 3 (Slide2 verification #16): ground
/// (0,15)–(18,15)–(48,35)–(66,35), base y = 0, c′ = 41.65 kPa, φ′ = 15°,
/// γ = 18.82 kN/m³, water table (0,15)–(18,15)–(30,23)–(48,29)–(66,32).
/// Published 1.138 (A&T; the data as tabulated in the Slide2 verification
/// manual).
pub fn arai_tagyo_3() -> Published {
    let domain = Domain::from_polygons(vec![region(
        vec![
            [0.0, 0.0],
            [66.0, 0.0],
            [66.0, 35.0],
            [48.0, 35.0],
            [18.0, 15.0],
            [0.0, 15.0],
        ],
        0,
        18.82,
    )])
    .expect("Arai & Tagyo polygon");
    Published {
        name: "Arai & Tagyo (1985) ex. 3, water table",
        file: "arai-tagyo-3.svg",
        domain,
        materials: vec![material("soil", 41.65, 15.0)],
        field: Box::new(WaterTable {
            line: vec![
                [0.0, 15.0],
                [18.0, 15.0],
                [30.0, 23.0],
                [48.0, 29.0],
                [66.0, 32.0],
            ],
            gamma_w: 9.81,
        }),
        published: vec![
            (Method::Bishop, 1.138, "Arai & Tagyo"),
            (Method::Spencer, 1.138, "Arai & Tagyo (Bishop)"),
        ],
        circle: None,
    }
}

/// Fredlund & Krahn (1977): ground (0,60)–(60,60)–(140,20)–(180,20) ft,
/// base y = 0, c′ = 600 psf, φ′ = 20°, γ = 120 pcf, the circle (120, 90),
/// R = 80; dry, and with the piezometric line (0,40)–(140,20)–(180,20),
/// γw = 62.4 pcf. Returns the section, its material, the circle, the water
/// table and the published factors (ordinary, Bishop, Spencer, M–P with a
/// constant function) dry and with the line.
pub fn fredlund_krahn() -> (Domain, SlopeMaterial, Circle, WaterTable, [[f64; 4]; 2]) {
    let domain = Domain::from_polygons(vec![region(
        vec![
            [0.0, 0.0],
            [180.0, 0.0],
            [180.0, 20.0],
            [140.0, 20.0],
            [60.0, 60.0],
            [0.0, 60.0],
        ],
        0,
        120.0,
    )])
    .expect("Fredlund & Krahn polygon");
    (
        domain,
        material("F&K soil", 600.0, 20.0),
        Circle {
            xc: 120.0,
            yc: 90.0,
            r: 80.0,
        },
        WaterTable {
            line: vec![[0.0, 40.0], [140.0, 20.0], [180.0, 20.0]],
            gamma_w: 62.4,
        },
        [[1.928, 2.080, 2.073, 2.076], [1.693, 1.834, 1.830, 1.832]],
    )
}

/// ACADS 3(a) (Giam & Donald 1989; Slide2 verification #7; SLOPE/W
/// verification §2.7), the weak-layer slope, as transcribed from the SLOPE/W
/// manual's dimensioned figure by the xslope project (one secondary source):
/// ground (20,27.75)–(43,27.75)–(67.5,40)–(84,40), base y = 20; soil 1
/// (c′ = 28.5 kPa, φ′ = 20°) above y = 27 and below y = 26.5, the weak
/// layer (c′ = 0, φ′ = 10°) between; γ = 18.84 kN/m³; the piezometric line
/// at y = 26.5. Referee 1.26, over non-circular surfaces.
pub fn acads_3a() -> Published {
    let gamma = 18.84;
    let band = |y0: f64, y1: f64, m: usize| {
        region(
            vec![[20.0, y0], [84.0, y0], [84.0, y1], [20.0, y1]],
            m,
            gamma,
        )
    };
    let domain = Domain::from_polygons(vec![
        region(
            vec![
                [20.0, 27.0],
                [84.0, 27.0],
                [84.0, 40.0],
                [67.5, 40.0],
                [43.0, 27.75],
                [20.0, 27.75],
            ],
            0,
            gamma,
        ),
        band(26.5, 27.0, 1),
        band(20.0, 26.5, 0),
    ])
    .expect("ACADS 3(a) polygons");
    Published {
        name: "ACADS 3(a) weak layer",
        file: "acads-3a.svg",
        domain,
        materials: vec![
            material("soil 1", 28.5, 20.0),
            material("weak layer", 0.0, 10.0),
        ],
        field: Box::new(WaterTable {
            line: vec![[20.0, 26.5], [84.0, 26.5]],
            gamma_w: 9.81,
        }),
        published: vec![
            (Method::Spencer, 1.26, "referee (non-circular)"),
            (MP, 1.26, "referee (non-circular)"),
        ],
        circle: None,
    }
}
