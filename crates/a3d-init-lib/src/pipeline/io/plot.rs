//! SVG plots (plotters): line charts with axis titles and units, and scatter
//! plots with a 1:1 line. Written by `calibrate`, `verify`, `run`, `fos` and `demo`.

use std::path::Path;

use crate::pipeline::PipelineError;
use plotters::prelude::*;

/// One series of a line chart.
pub struct Series<'a> {
    pub label: &'a str,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
    /// Draw markers instead of a line.
    pub markers: bool,
}

fn bounds(series: &[Series<'_>]) -> ((f64, f64), (f64, f64)) {
    let mut x = (f64::INFINITY, f64::NEG_INFINITY);
    let mut y = (f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for &(a, b) in &s.points {
            if a.is_finite() && b.is_finite() {
                x = (x.0.min(a), x.1.max(a));
                y = (y.0.min(b), y.1.max(b));
            }
        }
    }
    let pad = |r: (f64, f64)| {
        if !r.0.is_finite() {
            return (0.0, 1.0);
        }
        let d = (r.1 - r.0).abs().max(1e-12 * r.0.abs().max(1.0));
        if !(0.1 * d + r.1.abs().max(r.0.abs())).is_finite() {
            // Values near the end of the f64 range: no room for padding.
            return (r.0.max(-1e307), r.1.min(1e307));
        }
        (r.0 - 0.05 * d, r.1 + 0.05 * d)
    };
    (pad(x), pad(y))
}

/// Writes a line chart to `path` (SVG, 900 × 560).
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    log_y: bool,
) -> Result<(), PipelineError> {
    let ((x0, x1), (y0, y1)) = bounds(series);
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).ok();
    let draw = || -> Result<(), Box<dyn std::error::Error + '_>> {
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80);
        // Log scale drawn as log10 of the values on a linear axis, labelled 1e±n.
        let (drawn, (lo, hi)) = if log_y {
            let logged: Vec<Vec<(f64, f64)>> = series
                .iter()
                .map(|s| {
                    s.points
                        .iter()
                        .filter(|p| p.1 > 0.0 && p.1.is_finite() && p.0.is_finite())
                        .map(|p| (p.0, p.1.log10()))
                        .collect()
                })
                .collect();
            let (lo, hi) = logged
                .iter()
                .flatten()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                    (a.min(p.1), b.max(p.1))
                });
            let range = if lo.is_finite() {
                (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
            } else {
                (-1.0, 1.0)
            };
            (logged, range)
        } else {
            let points = series.iter().map(|s| s.points.clone()).collect();
            (points, (y0, y1))
        };
        let mut chart = builder.build_cartesian_2d(x0..x1, lo..hi)?;
        let log_label = |v: &f64| format!("1e{:.0}", v);
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(x_label)
            .y_desc(y_label)
            .label_style(("sans-serif", 15));
        if log_y {
            mesh.y_labels(((hi - lo) as usize).saturating_add(1).min(12))
                .y_label_formatter(&log_label);
        }
        mesh.draw()?;
        for (s, pts) in series.iter().zip(drawn) {
            let c = s.color;
            if s.markers {
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?
                    .label(s.label)
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
            } else {
                chart
                    .draw_series(LineSeries::new(pts, c.stroke_width(2)))?
                    .label(s.label)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    });
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| PipelineError::Output(format!("drawing {}: {e}", path.display())))
}

/// Predicted against observed, with the 1:1 line.
pub fn scatter_1to1(
    path: &Path,
    title: &str,
    unit: &str,
    pairs: &[(f64, f64)],
) -> Result<(), PipelineError> {
    let (lo, hi) = pairs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0.min(p.1)), b.max(p.0.max(p.1)))
        });
    let line = Series {
        label: "1:1",
        points: vec![(lo, lo), (hi, hi)],
        color: RGBColor(120, 120, 120),
        markers: false,
    };
    let dots = Series {
        label: "nodes",
        points: pairs.to_vec(),
        color: RGBColor(31, 119, 180),
        markers: true,
    };
    line_chart(
        path,
        title,
        &format!("observed ({unit})"),
        &format!("predicted ({unit})"),
        &[dots, line],
        false,
    )
}

/// Viridis-like colour for t in [0, 1].
fn colour(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = t.clamp(0.0, 1.0) * 4.0;
    let k = (t.floor() as usize).min(3);
    let f = t - k as f64;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A field over the MPs: one dot per point coloured by value, with axes in m and
/// a labelled colour bar.
pub fn field_map(
    path: &Path,
    title: &str,
    label: &str,
    points: &[(f64, f64, f64)],
) -> Result<(), PipelineError> {
    field_map_with(path, title, label, points, &[])
}

/// A polyline drawn over a field map (a slip surface, the ground).
pub struct Overlay<'a> {
    pub label: &'a str,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
    /// Stroke width in pixels.
    pub width: u32,
}

/// [`field_map`] with polylines drawn over the dots, and their legend.
pub fn field_map_with(
    path: &Path,
    title: &str,
    label: &str,
    points: &[(f64, f64, f64)],
    overlays: &[Overlay<'_>],
) -> Result<(), PipelineError> {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let (mut v0, mut v1) = (f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y, v) in points {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
        v0 = v0.min(v);
        v1 = v1.max(v);
    }
    for &(x, y) in overlays.iter().flat_map(|o| o.points.iter()) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !v0.is_finite() {
        (v0, v1) = (0.0, 1.0);
    }
    if v1 - v0 < 1e-12 {
        v1 = v0 + 1.0;
    }
    let (pad_x, pad_y) = (0.03 * (x1 - x0).max(1e-9), 0.05 * (y1 - y0).max(1e-9));
    let root = SVGBackend::new(path, (1000, 620)).into_drawing_area();
    root.fill(&WHITE).ok();
    let draw = || -> Result<(), Box<dyn std::error::Error + '_>> {
        let (main, bar) = root.split_horizontally(860);
        let mut chart = ChartBuilder::on(&main)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(56)
            .build_cartesian_2d((x0 - pad_x)..(x1 + pad_x), (y0 - pad_y)..(y1 + pad_y))?;
        chart
            .configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .label_style(("sans-serif", 15))
            .draw()?;
        chart.draw_series(
            points
                .iter()
                .map(|&(x, y, v)| Circle::new((x, y), 2, colour((v - v0) / (v1 - v0)).filled())),
        )?;
        for o in overlays {
            let style = o.color.stroke_width(o.width);
            chart
                .draw_series(LineSeries::new(o.points.clone(), style))?
                .label(o.label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        }
        if !overlays.is_empty() {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .draw()?;
        }
        let mut cb = ChartBuilder::on(&bar)
            .margin_top(60)
            .margin_bottom(60)
            .margin_right(10)
            .y_label_area_size(70)
            .caption(label, ("sans-serif", 14))
            .build_cartesian_2d(0.0..1.0, v0..v1)?;
        cb.configure_mesh()
            .disable_x_mesh()
            .disable_x_axis()
            .disable_y_mesh()
            .label_style(("sans-serif", 13))
            .draw()?;
        let steps = 64;
        cb.draw_series((0..steps).map(|k| {
            let a = v0 + (v1 - v0) * k as f64 / steps as f64;
            let b = v0 + (v1 - v0) * (k + 1) as f64 / steps as f64;
            Rectangle::new(
                [(0.0, a), (1.0, b)],
                colour((k as f64 + 0.5) / steps as f64).filled(),
            )
        }))?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| PipelineError::Output(format!("drawing {}: {e}", path.display())))
}
