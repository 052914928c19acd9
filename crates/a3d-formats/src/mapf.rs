//! Anura3D MAPF files (`<project>.MAPF`): the table Anura3D interpolates initial
//! stresses and pore pressures from when `$$MP_STRESS_INITIALIZATION_FROMFILE 1`.
//! Spec: `formats/mapf.md`.
//!
//! a3d-init writes "exact-point mode": one row per MP at its exact position, with a
//! smoothing length so small that each MP sees only its own row, so Anura3D's
//! kernel (and the typo in its inner branch) cannot change the values. Two defects
//! of Anura3D's reader are worked around here: in 3D it stores the `SigXZ` column
//! as τyz and `SigYZ` as τxz, so we write τyz under `SigXZ[kPa]` and τxz under
//! `SigYZ[kPa]`; in 2D it puts τxy into σ'zz, which no column can fix (the report
//! says so).

use std::io::Write;
use std::path::Path;

use super::error::{FormatError, ParseError};
use super::lex;
use super::table_text::{push_f64, write_rows};
use a3d_model::{MaterialPoint, MpState};

/// Column headers, in the order written.
pub fn headers(n_dim: usize) -> &'static [&'static str] {
    if n_dim == 2 {
        &[
            "X[m]",
            "Y[m]",
            "Pwp[kPa]",
            "SigX[kPa]",
            "SigY[kPa]",
            "SigXY[kPa]",
            "SmoothLength[m]",
        ]
    } else {
        &KNOWN[..11]
    }
}

/// The values of one row in header order: positions, pwp and total stresses
/// (Anura3D signs), with the 3D shear labels swapped to cancel Anura3D's swap.
fn row(point: &MaterialPoint, state: &MpState, n_dim: usize, smooth: f64) -> Row {
    let p = point.position;
    let s = state.total;
    if n_dim == 2 {
        Row::new(&[p[0], p[1], state.pwp, s[0], s[1], s[3], smooth])
    } else {
        // Anura3D: component 5 (yz) ← SigXZ column, component 6 (xz) ← SigYZ column.
        Row::new(&[
            p[0], p[1], p[2], state.pwp, s[0], s[1], s[2], s[3], s[4], s[5], smooth,
        ])
    }
}

/// The values of one row without a heap allocation.
struct Row {
    values: [f64; 11],
    len: usize,
}

impl Row {
    fn new(values: &[f64]) -> Row {
        let mut out = Row {
            values: [0.0; 11],
            len: values.len(),
        };
        out.values[..values.len()].copy_from_slice(values);
        out
    }

    fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }
}

/// Writes the MAPF. Every value must be finite (checked by the caller; a
/// non-finite value is refused here too).
pub fn write(
    w: &mut dyn Write,
    points: &[MaterialPoint],
    states: &[MpState],
    n_dim: usize,
    smoothing_length: f64,
) -> std::io::Result<()> {
    writeln!(w, "{}", headers(n_dim).join(" "))?;
    let n = points.len().min(states.len());
    write_rows(w, n, |i, out| {
        let (p, s) = (&points[i], &states[i]);
        let values = row(p, s, n_dim, smoothing_length);
        let values = values.as_slice();
        if values.iter().any(|v| !v.is_finite()) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("MP {} has a non-finite value; refusing to write it", p.id),
            ));
        }
        for (k, &v) in values.iter().enumerate() {
            if k > 0 {
                out.push(b' ');
            }
            push_f64(out, v);
        }
        out.push(b'\n');
        Ok(())
    })
}

/// A MAPF read back: its headers and rows (as written, labels not un-swapped).
#[derive(Debug, Clone, PartialEq)]
pub struct MapfTable {
    pub headers: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl MapfTable {
    /// Column index of `header`.
    pub fn column(&self, header: &str) -> Option<usize> {
        self.headers.iter().position(|h| h == header)
    }
}

/// The headers Anura3D recognises (exact, case-sensitive); the first eleven are
/// the 3D columns a3d-init writes, in order.
const KNOWN: [&str; 13] = [
    "X[m]",
    "Y[m]",
    "Z[m]",
    "Pwp[kPa]",
    "SigX[kPa]",
    "SigY[kPa]",
    "SigZ[kPa]",
    "SigXY[kPa]",
    "SigXZ[kPa]",
    "SigYZ[kPa]",
    "SmoothLength[m]",
    "phi[deg]",
    "cohesion[kPa]",
];

/// Reads a MAPF strictly, as Anura3D would need it: known headers only, a
/// rectangular table of numbers.
pub fn read(path: &Path) -> Result<MapfTable, FormatError> {
    let text = super::keyword_doc::read_text(path)?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header_line)) = lines.next() else {
        return Err(ParseError::at(path, 1, 1, "empty MAPF: expected a header line").into());
    };
    let mut headers = Vec::new();
    for (offset, tok) in lex::tokens(header_line) {
        if !KNOWN.contains(&tok) {
            return Err(ParseError::at(
                path,
                1,
                offset + 1,
                format!(
                    "unknown MAPF column `{tok}` (Anura3D knows: {})",
                    KNOWN.join(" ")
                ),
            )
            .into());
        }
        headers.push(tok.to_string());
    }
    if headers.len() > 39 {
        return Err(ParseError::at(path, 1, 1, "more than 39 columns").into());
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        let mut row = Vec::with_capacity(headers.len());
        for (offset, tok) in lex::tokens(line) {
            let v = lex::parse_real(tok).ok_or_else(|| {
                ParseError::at(
                    path,
                    i + 1,
                    offset + 1,
                    format!("expected a number, found `{tok}`"),
                )
            })?;
            row.push(v);
        }
        if row.len() != headers.len() {
            return Err(ParseError::at(
                path,
                i + 1,
                1,
                format!("expected {} values, found {}", headers.len(), row.len()),
            )
            .into());
        }
        rows.push(row);
    }
    Ok(MapfTable { headers, rows })
}

/// Smoothing length for exact-point mode: 2h below half the minimum distance
/// between any two MPs, i.e. h = min spacing / 5 (so 2h = 0.4 × spacing).
pub fn exact_point_smoothing_length(min_mp_spacing: f64) -> f64 {
    min_mp_spacing / 5.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use a3d_model::MpState;

    fn table(points: &[MaterialPoint], states: &[MpState], dim: usize, threads: usize) -> Vec<u8> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut out = Vec::new();
        pool.install(|| write(&mut out, points, states, dim, 0.01))
            .unwrap();
        out
    }

    #[test]
    fn mapf_keeps_full_precision_for_any_thread_count() {
        let (points, states) = crate::mps_table::tests::sample(20_000, 5);
        for dim in [2, 3] {
            let one = table(&points, &states, dim, 1);
            assert_eq!(one, table(&points, &states, dim, 2));
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("t.MAPF");
            std::fs::write(&path, &one).unwrap();
            let back = read(&path).unwrap();
            assert_eq!(back.rows.len(), points.len());
            for (r, (p, s)) in back.rows.iter().zip(points.iter().zip(&states)) {
                let expected = row(p, s, dim, 0.01);
                let bits = |v: &[f64]| v.iter().map(|x| (x + 0.0).to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(r), bits(expected.as_slice()));
            }
        }
    }

    #[test]
    fn non_finite_value_stops_the_mapf_at_its_row() {
        let (points, mut states) = crate::mps_table::tests::sample(10_000, 6);
        states[7_000].pwp = f64::NAN;
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut out = Vec::new();
            let e = pool
                .install(|| write(&mut out, &points, &states, 3, 0.01))
                .unwrap_err();
            assert!(
                e.to_string().contains("MP 7001 has a non-finite value"),
                "{e}"
            );
        }
    }
}
