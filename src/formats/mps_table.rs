//! The per-MP CSV table (`mps.csv`, `inspect --mps`). Spec: `formats/mps-csv.md`.
//!
//! Columns: `id,element,material,local,x,y,z,volume`, then, for a mapped state,
//! the pore pressure, total and effective stresses (Anura3D signs, kPa), the
//! degree of saturation and the mapping diagnostics. Ids are 1-based.

use std::io::Write;

use crate::model::MaterialPoint;

/// Formats a float so that it reads back to the same value (shortest round trip).
pub fn fmt_f64(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    format!("{v}")
}

/// Writes the placement table: one row per MP.
pub fn write_points(w: &mut dyn Write, points: &[MaterialPoint]) -> std::io::Result<()> {
    writeln!(w, "id,element,material,local,x,y,z,volume")?;
    for p in points {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{}",
            p.id,
            p.element + 1,
            p.material,
            p.local,
            fmt_f64(p.position[0]),
            fmt_f64(p.position[1]),
            fmt_f64(p.position[2]),
            fmt_f64(p.volume)
        )?;
    }
    Ok(())
}

/// Mapping diagnostics of one MP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MpDiagnostics {
    pub neighbours: u32,
    pub shepard: f64,
    /// `mapped`, `nearest` or `skipped`.
    pub status: &'static str,
}

/// Header of the mapped-state table.
pub const STATE_HEADER: &str = "id,element,material,local,x,y,z,volume,pwp,sxx,syy,szz,sxy,syz,sxz,esxx,esyy,eszz,esxy,esyz,esxz,saturation,neighbours,shepard,status";

/// Writes the mapped-state table (`mps.csv`): placement, pwp, total and effective
/// stress (Anura3D signs, kPa), saturation and diagnostics.
pub fn write_states(
    w: &mut dyn Write,
    points: &[MaterialPoint],
    states: &[crate::model::MpState],
    diagnostics: &[MpDiagnostics],
) -> std::io::Result<()> {
    writeln!(w, "{STATE_HEADER}")?;
    for ((p, s), d) in points.iter().zip(states).zip(diagnostics) {
        let eff = s.effective();
        let mut row = vec![
            p.id.to_string(),
            (p.element + 1).to_string(),
            p.material.to_string(),
            p.local.to_string(),
        ];
        row.extend(p.position.iter().map(|v| fmt_f64(*v)));
        row.push(fmt_f64(p.volume));
        row.push(fmt_f64(s.pwp));
        row.extend(s.total.iter().map(|v| fmt_f64(*v)));
        row.extend(eff.iter().map(|v| fmt_f64(*v)));
        row.push(fmt_f64(s.saturation));
        row.push(d.neighbours.to_string());
        row.push(fmt_f64(d.shepard));
        row.push(d.status.to_string());
        writeln!(w, "{}", row.join(","))?;
    }
    Ok(())
}

/// Reads a mapped-state table back: (points, states). Positioned errors.
pub fn read_states(
    path: &std::path::Path,
) -> Result<(Vec<MaterialPoint>, Vec<crate::model::MpState>), super::error::FormatError> {
    read_states_with_lines(path).map(|(p, s, _)| (p, s))
}

/// Like [`read_states`], and checks the table against the MPs a model places
/// (`expected`): same count, and row by row the same id, element and position.
/// A mismatch is an error at the row's line.
pub fn read_states_for(
    path: &std::path::Path,
    expected: &[MaterialPoint],
) -> Result<(Vec<MaterialPoint>, Vec<crate::model::MpState>), super::error::FormatError> {
    use super::error::ParseError;
    let (points, states, lines) = read_states_with_lines(path)?;
    if points.len() != expected.len() {
        let line = lines
            .get(expected.len())
            .copied()
            .unwrap_or_else(|| lines.last().map_or(2, |l| l + 1));
        return Err(ParseError::at(
            path,
            line,
            1,
            format!(
                "{} MPs, but the model places {}",
                points.len(),
                expected.len()
            ),
        )
        .into());
    }
    for (k, (a, b)) in points.iter().zip(expected).enumerate() {
        let d = (0..3)
            .map(|c| (a.position[c] - b.position[c]).powi(2))
            .sum::<f64>()
            .sqrt();
        if a.id != b.id
            || a.element != b.element
            || d > 1e-9 * (1.0 + b.position[0].abs() + b.position[1].abs())
        {
            return Err(ParseError::at(
                path,
                lines[k],
                1,
                format!(
                    "MP {} does not match the model's MP {} (element or position differ): the state belongs to another model",
                    a.id, b.id
                ),
            )
            .into());
        }
    }
    Ok((points, states))
}

type StateRows = (Vec<MaterialPoint>, Vec<crate::model::MpState>, Vec<usize>);

/// The rows with the 1-based line of each.
fn read_states_with_lines(path: &std::path::Path) -> Result<StateRows, super::error::FormatError> {
    use super::error::ParseError;
    let text = super::keyword_doc::read_text(path)?;
    let mut lines = text.lines().enumerate();
    let header = lines.next().map(|(_, l)| l.trim()).unwrap_or("");
    if !header.starts_with("id,element,material,local,x,y,z,volume,pwp,sxx") {
        return Err(ParseError::at(
            path,
            1,
            1,
            format!("not an a3d-init MP state table: expected the header `{STATE_HEADER}`"),
        )
        .into());
    }
    let mut points = Vec::new();
    let mut states = Vec::new();
    let mut line_numbers = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 22 {
            return Err(ParseError::at(
                path,
                i + 1,
                line.chars().count() + 1,
                format!("expected at least 22 fields, found {}", f.len()),
            )
            .into());
        }
        // 1-based column of field k: the characters of the fields and commas before it.
        let column =
            |k: usize| -> usize { f[..k].iter().map(|s| s.chars().count() + 1).sum::<usize>() + 1 };
        let num = |k: usize| -> Result<f64, ParseError> {
            f[k].trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    ParseError::at(
                        path,
                        i + 1,
                        column(k),
                        format!(
                            "field {}: expected a finite number, found `{}`",
                            k + 1,
                            f[k]
                        ),
                    )
                })
        };
        let int = |k: usize| -> Result<u32, ParseError> {
            f[k].trim().parse::<u32>().map_err(|_| {
                ParseError::at(
                    path,
                    i + 1,
                    column(k),
                    format!("field {}: expected an integer, found `{}`", k + 1, f[k]),
                )
            })
        };
        points.push(MaterialPoint {
            id: int(0)?,
            element: int(1)?.saturating_sub(1),
            material: int(2)?,
            local: int(3)?,
            position: [num(4)?, num(5)?, num(6)?],
            volume: num(7)?,
        });
        states.push(crate::model::MpState {
            pwp: num(8)?,
            total: [num(9)?, num(10)?, num(11)?, num(12)?, num(13)?, num(14)?],
            saturation: num(21)?,
        });
        line_numbers.push(i + 1);
    }
    Ok((points, states, line_numbers))
}
