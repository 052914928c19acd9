//! The data-row pass: the split of the body into chunks parsed in parallel
//! and joined in file order, and the field-by-field path ([`slow_row`]) that reads any row and
//! names the line and column of every error.

use super::dialect::{parse_number, split_line};
use super::fast::{fast_row, is_blank};
use super::schema::{Rows, Schema};
use crate::error::ParseError;

/// Bytes per chunk of the data-row pass (split after the next newline).
pub(super) const CHUNK_BYTES: usize = 1 << 20;

/// The data-row pass stops after a row that brings the errors past this count.
const MAX_ROW_ERRORS: usize = 20;

/// The merged rows and the row errors kept (as many as the serial pass would).
pub(super) struct Merged {
    pub(super) rows: Rows,
    pub(super) errors: Vec<ParseError>,
}

/// Joins chunk results in file order, one chunk at a time (the chunks of
/// one block, then the next block's). Errors are cut as a serial pass
/// would: after the row that brings them past [`MAX_ROW_ERRORS`].
pub(super) struct Merger {
    merged: Merged,
    full: bool,
}

impl Merger {
    pub(super) fn new(n_values: usize) -> Merger {
        Merger {
            merged: Merged {
                rows: Rows {
                    values: vec![Vec::new(); n_values],
                    has_value: vec![false; n_values + 2],
                    first_short: vec![None; n_values + 2],
                    ..Rows::default()
                },
                errors: Vec::new(),
            },
            full: false,
        }
    }

    /// Room for `n` more rows in every column, allocated once rather than
    /// grown by doubling. `n` is an estimate from the file's size, which a
    /// sparse or crafted file can make far larger than its rows: where the
    /// room cannot be had, the columns grow with the rows instead.
    pub(super) fn reserve(&mut self, n: usize) {
        let rows = &mut self.merged.rows;
        let _ = rows.positions.try_reserve_exact(n);
        let _ = rows.ids.try_reserve_exact(n);
        let _ = rows.lines.try_reserve_exact(n);
        for v in &mut rows.values {
            let _ = v.try_reserve_exact(n);
        }
    }

    /// Whether the errors are cut: later rows cannot change the result.
    pub(super) fn full(&self) -> bool {
        self.full
    }

    /// Appends the next chunk's rows, flags and errors.
    pub(super) fn push(&mut self, part: Rows) {
        let Merged { rows, errors } = &mut self.merged;
        rows.positions.extend_from_slice(&part.positions);
        rows.ids.extend_from_slice(&part.ids);
        for (all, v) in rows.values.iter_mut().zip(&part.values) {
            all.extend_from_slice(v);
        }
        rows.regions.extend(part.regions);
        rows.lines.extend_from_slice(&part.lines);
        for (t, h) in part.has_value.iter().enumerate() {
            rows.has_value[t] |= h;
            if rows.first_short[t].is_none() {
                rows.first_short[t] = part.first_short[t];
            }
        }
        if rows.first_empty_id.is_none() {
            rows.first_empty_id = part.first_empty_id;
        }
        for e in part.errors {
            if self.full {
                break;
            }
            if errors.len() > MAX_ROW_ERRORS
                && errors.last().map(|l| l.position.line) != Some(e.position.line)
            {
                self.full = true;
                break;
            }
            errors.push(e);
        }
    }

    /// The rows and errors, the columns without spare room.
    pub(super) fn finish(self) -> Merged {
        let mut merged = self.merged;
        let rows = &mut merged.rows;
        rows.positions.shrink_to_fit();
        rows.ids.shrink_to_fit();
        rows.lines.shrink_to_fit();
        for v in &mut rows.values {
            v.shrink_to_fit();
        }
        merged
    }
}

/// Splits `text` into pieces of about `size` bytes, each ending just after a newline
/// (the last one excepted).
pub(super) fn split_chunks(text: &str, size: usize) -> Vec<&str> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len() / size + 1);
    let mut start = 0;
    while start < bytes.len() {
        let mut end = (start + size).min(bytes.len());
        match bytes[end..].iter().position(|&b| b == b'\n') {
            Some(k) => end += k + 1,
            None => end = bytes.len(),
        }
        out.push(&text[start..end]);
        start = end;
    }
    out
}

/// Parses the rows of one chunk whose first line is `first_line` (1-based)
/// and which holds at most `lines` lines.
pub(super) fn parse_chunk(
    schema: &Schema<'_>,
    chunk: &str,
    first_line: usize,
    lines: usize,
) -> Rows {
    let mut rows = Rows::new(schema, lines);
    let mut ranges: Vec<(usize, usize)> = Vec::with_capacity(32);
    let mut scratch: Vec<f64> = Vec::with_capacity(schema.value_cols.len());
    for (k, line) in chunk.lines().enumerate() {
        let line_no = first_line + k;
        if is_blank(line) {
            continue;
        }
        if !fast_row(schema, line, line_no, &mut ranges, &mut scratch, &mut rows) {
            slow_row(schema, line, line_no, &mut rows);
        }
        if rows.errors.len() > MAX_ROW_ERRORS {
            break;
        }
    }
    rows
}

/// Any row, read field by field with positioned errors.
pub(super) fn slow_row(schema: &Schema<'_>, line: &str, line_no: usize, rows: &mut Rows) {
    let path = schema.path;
    let fields = split_line(line, schema.delim);
    let end_col = line.chars().count() + 1;
    let n_fields = fields.len();
    let n_values = schema.value_cols.len();
    let get = |k: usize| fields.get(k).filter(|(_, t)| !t.is_empty());
    let number = |k: usize, what: &str, errors: &mut Vec<ParseError>| -> Option<f64> {
        match get(k) {
            Some((col, text)) => match parse_number(text, schema.decimal_comma) {
                Some(v) => Some(v),
                None => {
                    errors.push(ParseError::at(
                        path,
                        line_no,
                        *col,
                        format!("expected a number for {what}, found `{text}`"),
                    ));
                    None
                }
            },
            None => None,
        }
    };
    let mut pos = [0.0; 3];
    let mut ok = true;
    for (slot, name) in [(0, "x"), (1, "y"), (2, "z")] {
        let Some(c) = schema.coords[slot] else {
            continue;
        };
        match number(c, name, &mut rows.errors) {
            Some(v) => pos[slot] = v * schema.factors[c],
            None => {
                if get(c).is_none() {
                    let msg = if slot == 2 {
                        "missing z: some rows are 3D and this one is 2D (mixed 2D/3D rows)"
                            .to_string()
                    } else {
                        format!("missing {name} coordinate")
                    };
                    rows.errors
                        .push(ParseError::at(path, line_no, end_col, msg));
                }
                ok = false;
            }
        }
    }
    let id = match schema.node {
        Some(c) => match get(c) {
            Some((col, text)) => match text.parse::<i64>() {
                Ok(v) => {
                    rows.has_value[n_values] = true;
                    Some(v)
                }
                Err(_) => {
                    rows.errors.push(ParseError::at(
                        path,
                        line_no,
                        *col,
                        format!("expected an integer node id, found `{text}`"),
                    ));
                    ok = false;
                    None
                }
            },
            None => {
                match fields.get(c) {
                    // Present but empty: an error when other rows have ids.
                    Some((col, _)) => {
                        if rows.first_empty_id.is_none() {
                            rows.first_empty_id = Some((line_no, *col));
                        }
                    }
                    None => rows.short(n_values, line_no, end_col, n_fields),
                }
                None
            }
        },
        None => None,
    };
    for (slot, &(c, q)) in schema.value_cols.iter().enumerate() {
        match number(c, &q.name(), &mut rows.errors) {
            Some(v) => {
                rows.has_value[slot] = true;
                rows.values[slot].push(v * schema.factors[c]);
            }
            None => {
                if get(c).is_some() {
                    ok = false;
                } else if c >= n_fields {
                    rows.short(slot, line_no, end_col, n_fields);
                }
                rows.values[slot].push(f64::NAN);
            }
        }
    }
    if !ok {
        return;
    }
    if let Some(c) = schema.region {
        match get(c) {
            Some((_, t)) => {
                rows.has_value[n_values + 1] = true;
                rows.regions.push(t.clone());
            }
            None => {
                if c >= n_fields {
                    rows.short(n_values + 1, line_no, end_col, n_fields);
                }
                rows.regions.push(String::new());
            }
        }
    }
    rows.ids.push(id);
    rows.positions.push(pos);
    rows.lines.push(line_no);
}
