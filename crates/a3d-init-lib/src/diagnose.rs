//! Diagnostics that explain a FEM file which does not reach the model: the
//! extents (bounding boxes) of the FEM nodes and of the material points, and a
//! hint when the two differ by a length-unit factor (ft, mm, cm, in) or by a
//! constant offset. Pure computation on coordinates; no I/O, no printing.

use std::fmt;

/// An axis-aligned bounding box in `dim` dimensions (z ignored in 2D).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Extent {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    pub dim: usize,
}

impl Extent {
    /// The box of `points`; `None` when there are none.
    pub fn of(points: &[[f64; 3]], dim: usize) -> Option<Extent> {
        let first = points.first()?;
        let mut e = Extent {
            lo: *first,
            hi: *first,
            dim,
        };
        for p in points {
            for (a, v) in p.iter().enumerate() {
                e.lo[a] = e.lo[a].min(*v);
                e.hi[a] = e.hi[a].max(*v);
            }
        }
        Some(e)
    }

    fn size(&self, a: usize) -> f64 {
        self.hi[a] - self.lo[a]
    }

    fn centre(&self, a: usize) -> f64 {
        0.5 * (self.hi[a] + self.lo[a])
    }

    /// True when `p` lies inside the box grown by `margin` on every side.
    pub fn contains(&self, p: &[f64; 3], margin: f64) -> bool {
        (0..self.dim).all(|a| p[a] >= self.lo[a] - margin && p[a] <= self.hi[a] + margin)
    }
}

impl fmt::Display for Extent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names = ["x", "y", "z"];
        let parts: Vec<String> = (0..self.dim)
            .map(|a| format!("{} {:.3} .. {:.3}", names[a], self.lo[a], self.hi[a]))
            .collect();
        write!(f, "{} m", parts.join(", "))
    }
}

/// Length units a FEM export is often in by mistake, with their size in m.
const UNITS: &[(&str, f64)] = &[("ft", 0.3048), ("in", 0.0254), ("cm", 0.01), ("mm", 0.001)];

/// Why the FEM and the model do not overlap, when a simple reason fits: the FEM
/// is larger or smaller by a unit factor, or offset by a constant vector.
pub fn mismatch_hint(fem: &Extent, model: &Extent) -> Option<String> {
    let dim = fem.dim.min(model.dim);
    let axes: Vec<usize> = (0..dim)
        .filter(|&a| fem.size(a) > 0.0 && model.size(a) > 0.0)
        .collect();
    if axes.is_empty() {
        return None;
    }
    let ratios: Vec<f64> = axes.iter().map(|&a| fem.size(a) / model.size(a)).collect();
    let ratio = (ratios.iter().map(|r| r.ln()).sum::<f64>() / ratios.len() as f64).exp();
    let consistent = ratios.iter().all(|r| (r / ratio - 1.0).abs() < 0.15);
    if !consistent {
        return None;
    }
    for (unit, metres) in UNITS {
        let factor = 1.0 / metres;
        if (ratio / factor - 1.0).abs() < 0.12 {
            return Some(format!(
                "the FEM looks {ratio:.2}× larger than the model: is it in {unit}? give the FEM units length={unit}"
            ));
        }
        if (ratio * factor - 1.0).abs() < 0.12 {
            return Some(format!(
                "the FEM looks {:.2}× smaller than the model: is the model in {unit} (Anura3D works in m), or was a length unit given for a FEM file in m?",
                1.0 / ratio
            ));
        }
    }
    if (ratio - 1.0).abs() < 0.05 {
        let offset: Vec<f64> = (0..dim).map(|a| fem.centre(a) - model.centre(a)).collect();
        let scale = axes.iter().map(|&a| model.size(a)).fold(0.0_f64, f64::max);
        if offset.iter().any(|d| d.abs() > 0.05 * scale) {
            let shown: Vec<String> = offset.iter().map(|d| format!("{d:.3}")).collect();
            return Some(format!(
                "the FEM has the model's size but is offset by ({}) m: do the two use different coordinate origins?",
                shown.join(", ")
            ));
        }
    }
    None
}

/// How well the FEM nodes reach the material points.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Reach {
    pub fem: Extent,
    /// The model's mesh (all its nodes).
    pub model: Extent,
    pub mps: Extent,
    /// MPs outside the FEM box grown by the kernel support: no node can reach them.
    pub outside: usize,
    pub total: usize,
    pub hint: Option<String>,
}

impl Reach {
    /// True when no MP, or fewer than half of them, can have a FEM node in reach.
    pub fn is_poor(&self) -> bool {
        self.total > 0 && 2 * self.outside >= self.total
    }

    /// Both extents and the hint, for a message about MPs without FEM nodes.
    pub fn extents(&self) -> String {
        format!(
            "FEM nodes: {}; model mesh: {}{}",
            self.fem,
            self.model,
            self.hint
                .as_deref()
                .map(|h| format!("; {h}"))
                .unwrap_or_default()
        )
    }

    /// The message naming the FEM file(s), both extents and the hint.
    pub fn message(&self, fem_files: &str) -> String {
        format!(
            "{}: the FEM nodes do not reach the model: {} of {} MPs lie outside the FEM's extent (grown by the kernel support), where no FEM node can reach them. FEM nodes: {}; model mesh: {} (MPs: {}){}",
            fem_files,
            self.outside,
            self.total,
            self.fem,
            self.model,
            self.mps,
            self.hint
                .as_deref()
                .map(|h| format!("; {h}"))
                .unwrap_or_default()
        )
    }
}

/// The FEM files as a message names them: `a.csv, b.csv`.
pub fn file_list(paths: &[std::path::PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Compares the FEM nodes with the MPs and the model's mesh nodes (`support` =
/// kernel support radius, m). The unit/offset hint compares the FEM with the mesh.
pub fn reach(
    fem: &[[f64; 3]],
    mesh: &[[f64; 3]],
    mps: &[[f64; 3]],
    dim: usize,
    support: f64,
) -> Option<Reach> {
    let fem_box = Extent::of(fem, dim)?;
    let mp_box = Extent::of(mps, dim)?;
    let mesh_box = Extent::of(mesh, dim).unwrap_or(mp_box);
    let outside = mps.iter().filter(|p| !fem_box.contains(p, support)).count();
    Some(Reach {
        hint: mismatch_hint(&fem_box, &mesh_box),
        fem: fem_box,
        model: mesh_box,
        mps: mp_box,
        outside,
        total: mps.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(x0: f64, y0: f64, w: f64, h: f64) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        for i in 0..=10 {
            for j in 0..=10 {
                out.push([x0 + w * i as f64 / 10.0, y0 + h * j as f64 / 10.0, 0.0]);
            }
        }
        out
    }

    #[test]
    fn feet_millimetres_and_offsets_are_named() {
        let model = grid(0.0, 0.0, 20.0, 10.0);
        let cases = [
            (
                grid(0.0, 0.0, 20.0 / 0.3048, 10.0 / 0.3048),
                "3.28× larger",
                "length=ft",
            ),
            (
                grid(0.0, 0.0, 20_000.0, 10_000.0),
                "1000.00× larger",
                "length=mm",
            ),
            (
                grid(0.0, 0.0, 20.0 * 0.3048, 10.0 * 0.3048),
                "3.28× smaller",
                "in ft",
            ),
            (
                grid(500.0, 100.0, 20.0, 10.0),
                "offset by (500.000, 100.000)",
                "",
            ),
        ];
        for (fem, what, unit) in cases {
            let r = reach(&fem, &model, &model, 2, 0.5).unwrap();
            let hint = r.hint.clone().unwrap_or_default();
            assert!(hint.contains(what) && hint.contains(unit), "{what}: {hint}");
        }
        let far = reach(&grid(500.0, 100.0, 20.0, 10.0), &model, &model, 2, 0.5).unwrap();
        assert!(far.is_poor());
        let m = far.message("seep.csv");
        assert!(m.starts_with("seep.csv: "), "{m}");
        assert!(
            m.contains("x 500.000 .. 520.000, y 100.000 .. 110.000 m"),
            "{m}"
        );
        assert!(m.contains("x 0.000 .. 20.000, y 0.000 .. 10.000 m"), "{m}");
    }

    #[test]
    fn a_covering_fem_is_fine_and_has_no_hint() {
        let model = grid(0.0, 0.0, 20.0, 10.0);
        let r = reach(&grid(-1.0, -1.0, 22.0, 12.0), &model, &model, 2, 0.5).unwrap();
        assert_eq!(r.outside, 0);
        assert!(!r.is_poor());
        assert_eq!(r.hint, None);
        // A FEM covering only a third of the model is no unit error either.
        let part = reach(&grid(0.0, 0.0, 6.0, 10.0), &model, &model, 2, 0.5).unwrap();
        assert!(part.is_poor());
        assert_eq!(part.hint, None);
    }
}
