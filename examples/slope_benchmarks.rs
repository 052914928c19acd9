//! The limit-equilibrium verification problems of `docs/slope-stability.md`
//! (#31): prints the table of factors against the published ones and draws
//! each critical surface into `docs/slope-stability/`. Deterministic; run
//! `cargo run --release --example slope_benchmarks`. The same problems are
//! asserted in `tests/it/slope_stability.rs`.
#![allow(clippy::print_stdout)]

use std::path::Path;
use std::time::Instant;

use a3d_init::pipeline::io::plot::{self, Overlay};
use a3d_init::slope::{self, Analysis, Interslice, Method, Problem, SearchSettings, Suction};
use a3d_testkit::slopes::{self, Published};
use plotters::style::RGBColor;

fn cases() -> Vec<Published> {
    vec![
        slopes::acads_1a(),
        slopes::acads_1c(),
        slopes::arai_tagyo_3(),
        slopes::acads_3a(),
    ]
}

fn draw(case: &Published, a: &Analysis, path: &Path) {
    // Dots on a raster inside the regions, coloured by material.
    let (x0, x1) = case.domain.x_range();
    let (y0, y1) = (
        case.domain.bottom(),
        case.domain
            .ground()
            .iter()
            .map(|p| p[1])
            .fold(f64::NEG_INFINITY, f64::max),
    );
    let step = (x1 - x0).max(y1 - y0) / 90.0;
    let mut dots = Vec::new();
    let mut y = y0 + 0.5 * step;
    while y < y1 {
        let mut x = x0 + 0.5 * step;
        while x < x1 {
            if let Some(k) = case.domain.region_at(x, y) {
                dots.push((x, y, case.domain.regions()[k].material as f64 + 1.0));
            }
            x += step;
        }
        y += step;
    }
    let line = |p: &[[f64; 2]]| p.iter().map(|q| (q[0], q[1])).collect::<Vec<_>>();
    let overlays = [
        Overlay {
            label: "ground",
            points: line(case.domain.ground()),
            color: RGBColor(0, 0, 0),
            width: 1,
        },
        Overlay {
            label: "best circle",
            points: line(&a.circular.surface),
            color: RGBColor(255, 127, 14),
            width: 2,
        },
        Overlay {
            label: "critical (non-circular)",
            points: line(&a.critical.surface),
            color: RGBColor(214, 39, 40),
            width: 3,
        },
    ];
    plot::field_map_with(
        path,
        &format!(
            "{}: {} circle {:.3}, non-circular {:.3}",
            case.name,
            a.method.name(),
            a.circular.factor,
            a.critical.factor
        ),
        "material",
        &dots,
        &overlays,
    )
    .unwrap();
}

fn main() {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/slope-stability");
    std::fs::create_dir_all(&out).unwrap();
    println!("| problem | method | published | circular | Δ | non-circular | Δ | time |");
    println!("|---|---|---|---|---|---|---|---|");
    for case in cases() {
        let problem = Problem {
            domain: &case.domain,
            materials: &case.materials,
            field: case.field.as_ref(),
            suction: Suction::Bishop,
            n_slices: 40,
            min_depth: 0.0,
            tolerance: 1e-7,
        };
        for (i, &(method, published, source)) in case.published.iter().enumerate() {
            let started = Instant::now();
            let a = slope::analyse(&problem, method, &SearchSettings::default()).unwrap();
            let t = started.elapsed().as_secs_f64();
            let d = |f: f64| format!("{:+.1} %", 100.0 * (f / published - 1.0));
            let shown = if (published * 100.0).fract() == 0.0 {
                format!("{published:.2}")
            } else {
                format!("{published}")
            };
            println!(
                "| {} | {} | {shown} {source} | {:.3} | {} | {:.3} | {} | {t:.2} s |",
                case.name,
                match method {
                    Method::MorgensternPrice(Interslice::HalfSine) =>
                        "Morgenstern–Price (half-sine)",
                    Method::MorgensternPrice(Interslice::Constant) =>
                        "Morgenstern–Price (constant)",
                    Method::Spencer => "Spencer",
                    Method::Bishop => "Bishop",
                    Method::Janbu => "Janbu (f₀)",
                    Method::Ordinary => "ordinary",
                },
                a.circular.factor,
                d(a.circular.factor),
                a.critical.factor,
                d(a.critical.factor)
            );
            if i == 0 || method == slopes::MP {
                let name = if i == 0 {
                    case.file.replace(".svg", "-bishop.svg")
                } else {
                    case.file.to_string()
                };
                draw(&case, &a, &out.join(name));
            }
        }
    }
}
