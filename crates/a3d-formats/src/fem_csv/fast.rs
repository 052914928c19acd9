//! The fast path of the data-row pass: a common row (ASCII, no carriage
//! return, quotes only around whole fields, every cell readable) is split and
//! parsed without allocating; any other row goes to
//! [`slow_row`](super::rows::slow_row).

use super::dialect::{Delimiter, parse_number};
use super::schema::{Rows, Schema};

/// `line.trim().is_empty()` without decoding ASCII.
pub(super) fn is_blank(line: &str) -> bool {
    if line.is_ascii() {
        line.bytes().all(is_ascii_space)
    } else {
        line.trim().is_empty()
    }
}

/// The ASCII characters that `char::is_whitespace` accepts.
fn is_ascii_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | 0x0B | 0x0C | b'\r')
}

/// `b[s..e]` without leading and trailing ASCII white space, as a range.
fn trim_range(b: &[u8], mut s: usize, mut e: usize) -> (usize, usize) {
    while s < e && is_ascii_space(b[s]) {
        s += 1;
    }
    while e > s && is_ascii_space(b[e - 1]) {
        e -= 1;
    }
    (s, e)
}

/// A cell seen by the fast path.
enum Cell<'a> {
    /// The row ends before this field.
    Short,
    Empty,
    Text(&'a str),
}

/// A number as [`parse_number`] reads it, without allocating.
fn parse_number_fast(text: &str, decimal_comma: bool) -> Option<f64> {
    let v: f64 = if decimal_comma && text.contains(',') {
        let mut buf = [0u8; 64];
        let b = text.as_bytes();
        if b.len() > buf.len() {
            return parse_number(text, decimal_comma);
        }
        for (o, &c) in buf.iter_mut().zip(b) {
            *o = if c == b',' { b'.' } else { c };
        }
        std::str::from_utf8(&buf[..b.len()]).ok()?.parse().ok()?
    } else {
        text.parse().ok()?
    };
    v.is_finite().then_some(v)
}

/// The common row: ASCII, no carriage return, quotes only around whole fields,
/// every coordinate and id readable, every value readable or empty. Returns
/// false, having stored nothing, for any other row (which
/// [`slow_row`](super::rows::slow_row) reads).
pub(super) fn fast_row(
    schema: &Schema<'_>,
    line: &str,
    line_no: usize,
    ranges: &mut Vec<(usize, usize)>,
    scratch: &mut Vec<f64>,
    rows: &mut Rows,
) -> bool {
    let b = line.as_bytes();
    ranges.clear();
    match schema.delim {
        Delimiter::Byte(d) => {
            // Three vectorised scans (ASCII, `\r`, `"`) and the delimiters by
            // `memchr`: about three times faster than one byte loop.
            if !b.is_ascii() || memchr::memchr(b'\r', b).is_some() {
                return false;
            }
            let mut start = 0;
            for i in memchr::memchr_iter(d, b) {
                ranges.push((start, i));
                start = i + 1;
            }
            ranges.push((start, b.len()));
            if memchr::memchr(b'"', b).is_some() {
                // Only `"…"` spanning a whole field, with no quote inside.
                for r in ranges.iter_mut() {
                    let f = &b[r.0..r.1];
                    if !f.contains(&b'"') {
                        continue;
                    }
                    if f.len() < 2
                        || f[0] != b'"'
                        || f[f.len() - 1] != b'"'
                        || f[1..f.len() - 1].contains(&b'"')
                    {
                        return false;
                    }
                    *r = (r.0 + 1, r.1 - 1);
                }
            }
        }
        Delimiter::Blanks => {
            let mut start: Option<usize> = None;
            for (i, &c) in b.iter().enumerate() {
                if c >= 0x80 || c == b'"' {
                    return false;
                }
                if is_ascii_space(c) {
                    if let Some(s) = start.take() {
                        ranges.push((s, i));
                    }
                } else if start.is_none() {
                    start = Some(i);
                }
            }
            if let Some(s) = start {
                ranges.push((s, b.len()));
            }
        }
    }
    let cell = |k: usize| -> Cell<'_> {
        match ranges.get(k) {
            None => Cell::Short,
            Some(&(s, e)) => {
                let (s, e) = trim_range(b, s, e);
                if s == e {
                    Cell::Empty
                } else {
                    // The line is ASCII: any byte range slices it.
                    Cell::Text(line.get(s..e).unwrap_or_default())
                }
            }
        }
    };
    let mut pos = [0.0; 3];
    for (slot, c) in schema.coords.iter().enumerate() {
        let Some(c) = *c else { continue };
        match cell(c) {
            Cell::Text(t) => match parse_number_fast(t, schema.decimal_comma) {
                Some(v) => pos[slot] = v * schema.factors[c],
                None => return false,
            },
            _ => return false,
        }
    }
    let mut id = None;
    if let Some(c) = schema.node {
        match cell(c) {
            Cell::Text(t) => match t.parse::<i64>() {
                Ok(v) => id = Some(v),
                Err(_) => return false,
            },
            // An empty id is recorded (with its column) by the slow path.
            Cell::Empty => return false,
            Cell::Short => {}
        }
    }
    scratch.clear();
    for &(c, _) in schema.value_cols {
        match cell(c) {
            Cell::Text(t) => match parse_number_fast(t, schema.decimal_comma) {
                Some(v) => scratch.push(v * schema.factors[c]),
                None => return false,
            },
            Cell::Empty | Cell::Short => scratch.push(f64::NAN),
        }
    }
    // Every cell is readable: store the row.
    let end_col = b.len() + 1;
    let n_fields = ranges.len();
    let n_values = schema.value_cols.len();
    for (t, (&(c, _), &v)) in schema.value_cols.iter().zip(scratch.iter()).enumerate() {
        rows.values[t].push(v);
        if v.is_nan() {
            if c >= n_fields {
                rows.short(t, line_no, end_col, n_fields);
            }
        } else {
            rows.has_value[t] = true;
        }
    }
    if let Some(c) = schema.node {
        if id.is_some() {
            rows.has_value[n_values] = true;
        } else if c >= n_fields {
            rows.short(n_values, line_no, end_col, n_fields);
        }
    }
    if let Some(c) = schema.region {
        let text = match cell(c) {
            Cell::Text(t) => {
                rows.has_value[n_values + 1] = true;
                t.to_string()
            }
            Cell::Empty => String::new(),
            Cell::Short => {
                rows.short(n_values + 1, line_no, end_col, n_fields);
                String::new()
            }
        };
        rows.regions.push(text);
    }
    rows.ids.push(id);
    rows.positions.push(pos);
    rows.lines.push(line_no);
    true
}
