//! The per-MP CSV table (`mps.csv`, `inspect --mps`). Spec: `formats/mps-csv.md`.
//!
//! Columns: `id,element,material,local,x,y,z,volume`, then, for a mapped state,
//! the pore pressure, total and effective stresses (Anura3D signs, kPa), the
//! degree of saturation and the mapping diagnostics. Ids are 1-based.

use std::io::Write;

use rayon::prelude::*;

use crate::model::MaterialPoint;

/// Formats a float so that it reads back to the same value (shortest round trip).
pub fn fmt_f64(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    format!("{v}")
}

/// Appends the shortest decimal that reads back to `v` (ryu): `0` for ±0, no
/// trailing `.0`, an exponent where it is shorter (`1e-7`, `1.5e20`).
pub fn push_f64(out: &mut Vec<u8>, v: f64) {
    if v == 0.0 {
        out.push(b'0');
        return;
    }
    let mut buf = ryu::Buffer::new();
    let s = buf.format(v);
    out.extend_from_slice(s.strip_suffix(".0").unwrap_or(s).as_bytes());
}

/// Appends an integer in decimal.
pub fn push_int(out: &mut Vec<u8>, v: impl itoa::Integer) {
    out.extend_from_slice(itoa::Buffer::new().format(v).as_bytes());
}

/// Rows per formatting chunk of [`write_rows`].
const ROWS_PER_CHUNK: usize = 4096;

/// Writes rows `0..n`, each appended to a buffer by `row`, formatted in
/// parallel chunks and written in order, so the bytes do not depend on the
/// thread count. The first row (in order) whose `row` fails stops the writing
/// with that error, after the rows before it.
pub fn write_rows<F>(w: &mut dyn Write, n: usize, row: F) -> std::io::Result<()>
where
    F: Fn(usize, &mut Vec<u8>) -> std::io::Result<()> + Sync,
{
    // Batches bound the memory held by formatted text.
    let batch = ROWS_PER_CHUNK * 4 * rayon::current_num_threads().max(1);
    let mut start = 0;
    crate::progress::WRITE_TABLE.start(n as u64);
    while start < n {
        let end = (start + batch).min(n);
        crate::progress::WRITE_TABLE.add((end - start) as u64);
        let chunks: Vec<(Vec<u8>, Option<std::io::Error>)> = (start..end)
            .into_par_iter()
            .step_by(ROWS_PER_CHUNK)
            .map(|first| {
                let last = (first + ROWS_PER_CHUNK).min(end);
                let mut buf = Vec::with_capacity((last - first) * 160);
                for i in first..last {
                    if let Err(e) = row(i, &mut buf) {
                        return (buf, Some(e));
                    }
                }
                (buf, None)
            })
            .collect();
        for (buf, error) in chunks {
            w.write_all(&buf)?;
            if let Some(e) = error {
                return Err(e);
            }
        }
        start = end;
    }
    Ok(())
}

/// Writes the placement table: one row per MP.
pub fn write_points(w: &mut dyn Write, points: &[MaterialPoint]) -> std::io::Result<()> {
    writeln!(w, "id,element,material,local,x,y,z,volume")?;
    write_rows(w, points.len(), |i, out| {
        let p = &points[i];
        push_placement(out, p);
        out.push(b'\n');
        Ok(())
    })
}

/// `id,element,material,local,x,y,z,volume` of one MP.
fn push_placement(out: &mut Vec<u8>, p: &MaterialPoint) {
    push_int(out, p.id);
    out.push(b',');
    push_int(out, p.element + 1);
    out.push(b',');
    push_int(out, p.material);
    out.push(b',');
    push_int(out, p.local);
    for v in p.position {
        out.push(b',');
        push_f64(out, v);
    }
    out.push(b',');
    push_f64(out, p.volume);
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
    let n = points.len().min(states.len()).min(diagnostics.len());
    write_rows(w, n, |i, out| {
        let (p, s, d) = (&points[i], &states[i], &diagnostics[i]);
        push_placement(out, p);
        for v in std::iter::once(s.pwp)
            .chain(s.total)
            .chain(s.effective())
            .chain([s.saturation])
        {
            out.push(b',');
            push_f64(out, v);
        }
        out.push(b',');
        push_int(out, d.neighbours);
        out.push(b',');
        push_f64(out, d.shepard);
        out.push(b',');
        out.extend_from_slice(d.status.as_bytes());
        out.push(b'\n');
        Ok(())
    })
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
        if !a.same_as(b) {
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::MpState;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Values across the magnitudes a table meets, and the awkward ones.
    fn awkward(rng: &mut ChaCha8Rng) -> f64 {
        match rng.random_range(0..6) {
            0 => rng.random_range(-1e3..1e3),
            1 => rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-300..300)),
            2 => rng.random_range(-1e6..1e6f64).round(),
            3 => f64::from_bits(rng.random::<u64>() >> 2),
            4 => -0.0,
            _ => 0.1 + 0.2,
        }
    }

    pub(crate) fn sample(n: usize, seed: u64) -> (Vec<MaterialPoint>, Vec<MpState>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut points = Vec::new();
        let mut states = Vec::new();
        for i in 0..n {
            points.push(MaterialPoint {
                id: i as u32 + 1,
                element: i as u32 / 4,
                material: 1 + i as u32 % 3,
                local: 1 + i as u32 % 4,
                position: [awkward(&mut rng), awkward(&mut rng), awkward(&mut rng)],
                volume: rng.random_range(1e-6..1.0),
            });
            states.push(MpState {
                pwp: awkward(&mut rng),
                total: std::array::from_fn(|_| awkward(&mut rng)),
                saturation: rng.random_range(0.0..1.0),
            });
        }
        (points, states)
    }

    #[test]
    fn push_f64_reads_back_to_the_same_value_as_fmt_f64() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..100_000 {
            let v = awkward(&mut rng);
            let mut out = Vec::new();
            push_f64(&mut out, v);
            let text = std::str::from_utf8(&out).unwrap();
            let back: f64 = text.parse().unwrap();
            let old: f64 = fmt_f64(v).parse().unwrap();
            assert_eq!(back.to_bits(), old.to_bits(), "{v:e}: {text}");
            assert!(!text.ends_with(".0"), "{text}");
        }
        for (v, text) in [
            (0.0, "0"),
            (-0.0, "0"),
            (1.0, "1"),
            (-2.5, "-2.5"),
            (1e-7, "1e-7"),
        ] {
            let mut out = Vec::new();
            push_f64(&mut out, v);
            assert_eq!(out, text.as_bytes());
        }
    }

    fn states_table(points: &[MaterialPoint], states: &[MpState], threads: usize) -> Vec<u8> {
        let diagnostics: Vec<MpDiagnostics> = (0..points.len())
            .map(|i| MpDiagnostics {
                neighbours: i as u32 % 70,
                shepard: 1.0 / (i as f64 + 3.0),
                status: "mapped",
            })
            .collect();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut out = Vec::new();
        pool.install(|| write_states(&mut out, points, states, &diagnostics))
            .unwrap();
        out
    }

    #[test]
    fn state_table_is_the_same_for_any_thread_count_and_reads_back() {
        let (points, states) = sample(20_000, 4);
        let one = states_table(&points, &states, 1);
        assert_eq!(one, states_table(&points, &states, 2));
        assert_eq!(one, states_table(&points, &states, 3));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mps.csv");
        std::fs::write(&path, &one).unwrap();
        let (p, s) = read_states(&path).unwrap();
        assert_eq!(p.len(), points.len());
        for ((a, b), (sa, sb)) in p.iter().zip(&points).zip(s.iter().zip(&states)) {
            assert_eq!(
                (a.id, a.element, a.material, a.local),
                (b.id, b.element, b.material, b.local)
            );
            let bits = |v: &[f64]| v.iter().map(|x| (x + 0.0).to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a.position), bits(&b.position));
            assert_eq!(a.volume, b.volume);
            assert_eq!(bits(&[sa.pwp]), bits(&[sb.pwp]));
            assert_eq!(bits(&sa.total), bits(&sb.total));
            assert_eq!(sa.saturation, sb.saturation);
        }
    }
}
