//! Anura3D's hydraulic-head file `<project>.HHBF` (CPS `$$HYDRAULIC_HEAD
//! file`): rows of `time head` (s, m), read by the kernel's
//! `ReadHydraulicHeadFromFile` and interpolated linearly in time. Spec:
//! `formats/hhbf.md`.

use std::path::Path;

use super::error::{FormatError, ParseError};
use super::lex;

/// Reads the rows of an HHBF: two numbers per non-blank line (more are
/// ignored, as the kernel's list-directed read ignores them), times strictly
/// increasing; at least one row.
pub fn read(path: &Path) -> Result<Vec<(f64, f64)>, FormatError> {
    let text = super::input::read_text(path)?;
    parse(path, &text)
}

/// [`read`] on text already in memory.
pub fn parse(path: &Path, text: &str) -> Result<Vec<(f64, f64)>, FormatError> {
    let mut rows: Vec<(f64, f64)> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let mut v = [0.0; 2];
        lex::reals(line, &mut v).map_err(|bad| match bad {
            Some(t) => ParseError::at(
                path,
                i + 1,
                t.offset + 1,
                format!("expected a time (s) or a head (m), found `{}`", t.text),
            ),
            None => ParseError::at(path, i + 1, line.len() + 1, "expected `time head` (s, m)"),
        })?;
        if !(v[0].is_finite() && v[1].is_finite()) {
            return Err(
                ParseError::at(path, i + 1, 1, "time and head must be finite numbers").into(),
            );
        }
        if let Some(&(t, _)) = rows.last()
            && v[0] <= t
        {
            return Err(ParseError::at(
                path,
                i + 1,
                1,
                format!("time {} does not follow {t}: times must increase", v[0]),
            )
            .into());
        }
        rows.push((v[0], v[1]));
    }
    if rows.is_empty() {
        return Err(ParseError::at(path, 1, 1, "no `time head` rows").into());
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_read_and_bad_ones_named() {
        let path = Path::new("a.HHBF");
        assert_eq!(
            parse(path, "0 2.0\n\n1.5 1.0\n").unwrap(),
            vec![(0.0, 2.0), (1.5, 1.0)]
        );
        let e = parse(path, "0 2\n1 x\n").unwrap_err().to_string();
        assert!(e.contains("a.HHBF:2:3:") && e.contains("found `x`"), "{e}");
        let e = parse(path, "0 2\n0 1\n").unwrap_err().to_string();
        assert!(
            e.contains("a.HHBF:2:1:") && e.contains("times must increase"),
            "{e}"
        );
        assert!(parse(path, "\n").is_err());
        assert!(
            parse(path, "0\n")
                .unwrap_err()
                .to_string()
                .contains("a.HHBF:1:2:")
        );
    }
}
