//! The whole-table pass behind [`parse_csv`](super::parse_csv): encoding and
//! BOM, dialect, header detection (synonyms or `--columns`), units and signs per
//! column, the data rows (see `rows`), and the checks on the assembled nodes
//! (ragged rows, missing values, duplicate ids and coincident nodes).

use std::path::Path;

use rayon::prelude::*;

use super::dialect::{Delimiter, sniff_delimiter, split_line};
use super::headers::{Field, header_unit, normalise, strip_unit_suffix, synonym, unit_factor};
use super::options::{CsvOptions, check_columns_option};
use super::rows::{Rows, Schema, merge_rows, nth_line_start, parse_chunk, split_chunks};
use super::{ColumnReport, FemReadReport};
use crate::formats::error::{FormatError, ParseError};
use crate::formats::extent::{far_outlier, first_coincident};
use crate::model::{FemNodes, Quantity};

/// [`parse_csv`](super::parse_csv) with data-row chunks of about `chunk_bytes`
/// (tests vary it). Owned bytes are freed as soon as the rows are parsed,
/// before they are joined (the file's text is the largest thing held).
pub(super) fn parse_csv_chunked(
    path: &Path,
    bytes: std::borrow::Cow<'_, [u8]>,
    options: &CsvOptions,
    chunk_bytes: usize,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    check_columns_option(&options.columns).map_err(|m| ParseError::at(path, 1, 1, m))?;
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err(ParseError::at(
            path,
            1,
            1,
            "UTF-16 text: save the table as UTF-8 (or ANSI) CSV",
        )
        .into());
    }
    let (bom, body) = match bytes.as_ref().strip_prefix(&[0xEF, 0xBB, 0xBF]) {
        Some(rest) => (true, rest),
        None => (false, bytes.as_ref()),
    };
    let text = match std::str::from_utf8(body) {
        Ok(t) => std::borrow::Cow::Borrowed(t),
        // Windows-1252 exports: keep ASCII, replace the rest (units like ³ only).
        Err(_) => String::from_utf8_lossy(body),
    };
    if text.trim().is_empty() {
        return Err(ParseError::at(
            path,
            1,
            1,
            "empty file: expected a header line with X and Y (or Node) columns",
        )
        .into());
    }
    // Only the first lines are needed to sniff the dialect and find the header.
    let sample: Vec<&str> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .take(20)
        .collect();
    let delim = sniff_delimiter(&sample);
    let lines: Vec<&str> = text.lines().take(51).collect();
    let decimal_comma = delim != Delimiter::Byte(b',')
        && lines.iter().skip(1).take(50).any(|l| {
            split_line(l, delim)
                .iter()
                .any(|(_, f)| f.contains(',') && f.replace(',', ".").parse::<f64>().is_ok())
        });

    // Header: the first line whose fields map x and y (or node), or the user's names.
    let mut header_idx = None;
    let mut mapping: Vec<Option<Field>> = Vec::new();
    let mut headers: Vec<(usize, String)> = Vec::new();
    for (i, line) in lines.iter().enumerate().take(50) {
        let fields = split_line(line, delim);
        if fields.is_empty() {
            continue;
        }
        let map: Vec<Option<Field>> = fields
            .iter()
            .map(|(_, h)| {
                options
                    .columns
                    .iter()
                    .find(|(_, name)| name == h)
                    .map(|(f, _)| *f)
                    .or_else(|| synonym(&strip_unit_suffix(&normalise(h), h)))
            })
            .collect();
        let has = |f: Field| map.contains(&Some(f));
        if (has(Field::X) && has(Field::Y)) || has(Field::Node) {
            header_idx = Some(i);
            mapping = map;
            headers = fields;
            break;
        }
    }
    let Some(header_idx) = header_idx else {
        let first = split_line(sample.first().copied().unwrap_or(""), delim);
        return Err(ParseError::at(
            path,
            1,
            1,
            format!(
                "no header with X and Y (or Node) columns found; headers seen: {}. Name them with a column mapping (`--columns x=…,y=…`)",
                first.iter().map(|(_, h)| format!("`{h}`")).collect::<Vec<_>>().join(", ")
            ),
        )
        .into());
    };
    for (field, name) in &options.columns {
        if !headers.iter().any(|(_, h)| h == name) {
            return Err(ParseError::at(
                path,
                header_idx + 1,
                1,
                format!(
                    "--columns {}={name}: no such header; headers are {}",
                    field.name(),
                    headers
                        .iter()
                        .map(|(_, h)| format!("`{h}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
            .into());
        }
    }
    // A field mapped twice is ambiguous.
    for (k, f) in mapping.iter().enumerate() {
        if let Some(f) = f
            && let Some(j) = mapping[..k].iter().position(|g| g == &Some(*f))
        {
            return Err(ParseError::at(
                path,
                header_idx + 1,
                headers[k].0,
                format!(
                    "columns `{}` and `{}` both mean {}; choose one with --columns",
                    headers[j].1,
                    headers[k].1,
                    f.name()
                ),
            )
            .into());
        }
    }

    // Units and signs per column.
    let mut columns = Vec::with_capacity(headers.len());
    let mut factors = Vec::with_capacity(headers.len());
    for (k, (col, h)) in headers.iter().enumerate() {
        let field = mapping[k];
        let written = header_unit(h);
        let (unit, factor) = match field {
            Some(f) if f.is_length() || f.is_pressure() => {
                let user = if f.is_length() {
                    &options.units.length
                } else {
                    &options.units.pressure
                };
                let unit = user.clone().or(written.clone());
                match unit {
                    Some(u) => match unit_factor(&u, f.is_length()) {
                        Some(factor) => (Some(u), factor),
                        None => {
                            return Err(ParseError::at(
                                path,
                                header_idx + 1,
                                *col,
                                format!(
                                    "unknown {} unit `{u}` in `{h}` (known: {})",
                                    if f.is_length() { "length" } else { "pressure" },
                                    if f.is_length() {
                                        "m, ft, mm, cm"
                                    } else {
                                        "kPa, Pa, MPa, kN/m², psf, psi"
                                    }
                                ),
                            )
                            .into());
                        }
                    },
                    None => (None, 1.0),
                }
            }
            _ => (None, 1.0),
        };
        let flip = match field {
            Some(Field::Value(Quantity::Pwp)) => options.sign.pwp_sign() < 0.0,
            Some(Field::Value(_)) => options.sign.stress_sign() < 0.0,
            _ => false,
        };
        factors.push(if flip { -factor } else { factor });
        columns.push(ColumnReport {
            header: h.clone(),
            understood_as: field.map_or("ignored".into(), Field::name),
            unit,
            factor,
            sign_flipped: flip,
        });
    }

    let col_of = |f: Field| mapping.iter().position(|m| *m == Some(f));
    let (cx, cy, cz, cnode, cregion) = (
        col_of(Field::X),
        col_of(Field::Y),
        col_of(Field::Z),
        col_of(Field::Node),
        col_of(Field::Region),
    );
    let value_cols: Vec<(usize, Quantity)> = mapping
        .iter()
        .enumerate()
        .filter_map(|(k, m)| match m {
            Some(Field::Value(q)) => Some((k, *q)),
            _ => None,
        })
        .collect();

    let mut nodes = FemNodes {
        dim: if cz.is_some() { 3 } else { 2 },
        ..FemNodes::default()
    };
    let schema = Schema {
        path,
        delim,
        decimal_comma,
        coords: [cx, cy, cz],
        node: cnode,
        region: cregion,
        value_cols: &value_cols,
        factors: &factors,
    };
    // The data rows, in parallel chunks split after a newline; chunks are joined
    // in file order, so the result does not depend on the thread count.
    let body_start = nth_line_start(&text, header_idx + 1);
    let body = &text[body_start..];
    let chunks = split_chunks(body, chunk_bytes.max(1));
    let newlines: Vec<usize> = chunks
        .par_iter()
        .map(|c| c.bytes().filter(|&b| b == b'\n').count())
        .collect();
    let mut first_line = Vec::with_capacity(chunks.len());
    let mut line = header_idx + 2;
    for n in &newlines {
        first_line.push(line);
        line += n;
    }
    crate::progress::READ_FEM.start(body.len() as u64);
    let parts: Vec<Rows> = chunks
        .par_iter()
        .zip(first_line.par_iter().zip(&newlines))
        .map(|(chunk, (&l0, &n))| {
            // A last line without its newline is one more.
            let rows = parse_chunk(&schema, chunk, l0, n + 1);
            crate::progress::READ_FEM.add(chunk.len() as u64);
            rows
        })
        .collect();
    drop(chunks);
    drop(text);
    drop(bytes);
    let merged = merge_rows(parts, value_cols.len());
    if let Some(e) = FormatError::from_list(merged.errors) {
        return Err(e);
    }
    let Rows {
        positions,
        ids,
        mut values,
        regions,
        lines: lines_of,
        has_value,
        first_short,
        first_empty_id,
        ..
    } = merged.rows;
    nodes.positions = positions;
    nodes.ids = ids
        .into_iter()
        .enumerate()
        .map(|(k, id)| id.unwrap_or(k as i64 + 1))
        .collect();
    if nodes.positions.is_empty() {
        return Err(ParseError::at(
            path,
            header_idx + 1,
            1,
            "the table has a header but no data rows",
        )
        .into());
    }
    // A row without a field that other rows fill (fewer fields than the header)
    // is an error at its end; a cell present but empty is not.
    for (t, c) in schema.tracked().into_iter().enumerate() {
        if let (Some(c), Some((line, col, n))) = (c, first_short[t])
            && has_value[t]
        {
            return Err(ParseError::at(
                path,
                line,
                col,
                format!(
                    "the row has {n} field(s) but the header has {}: `{}` is missing (leave the cell empty to mark a value as absent)",
                    headers.len(),
                    headers[c].1
                ),
            )
            .into());
        }
    }
    // Columns absent from every row (ragged GeoStudio rows) are dropped, not zeroed;
    // partly present columns are an error at the first row without a value.
    let mut warnings = Vec::new();
    // The id column likewise: a row without an id would silently take its row
    // number, and with --fem-mesh another node's coordinates.
    let ids_given = has_value[value_cols.len()];
    if let Some(c) = cnode {
        match first_empty_id {
            Some((line, col)) if ids_given => {
                return Err(ParseError::at(
                    path,
                    line,
                    col,
                    format!(
                        "empty node id in `{}`: other rows have ids, so every row needs one",
                        headers[c].1
                    ),
                )
                .into());
            }
            _ if !ids_given && cx.is_some() && cy.is_some() => warnings.push(format!(
                "column `{}` has no values in any row: nodes are numbered by row",
                headers[c].1
            )),
            _ if !ids_given => {
                return Err(ParseError::at(
                    path,
                    header_idx + 1,
                    headers[c].0,
                    format!(
                        "column `{}` has no node ids and the table has no X and Y columns: its rows cannot be joined to mesh nodes",
                        headers[c].1
                    ),
                )
                .into());
            }
            _ => {}
        }
    }
    for (slot, &(c, q)) in value_cols.iter().enumerate() {
        let n_missing = values[slot].iter().filter(|v| v.is_nan()).count();
        if n_missing == 0 {
            nodes.fields.push((q, std::mem::take(&mut values[slot])));
        } else if n_missing == values[slot].len() {
            warnings.push(format!(
                "column `{}` has no values in any row (ragged rows): {} is absent",
                headers[c].1,
                q.name()
            ));
        } else {
            let row = values[slot].iter().position(|v| v.is_nan()).unwrap_or(0);
            return Err(ParseError::at(
                path,
                lines_of[row],
                1,
                format!(
                    "missing value for `{}` ({} of {} rows have none)",
                    headers[c].1,
                    n_missing,
                    values[slot].len()
                ),
            )
            .into());
        }
    }
    if cregion.is_some() {
        nodes.region = Some(regions);
    }
    if cx.is_none() || cy.is_none() {
        if cnode.is_none() {
            return Err(ParseError::at(
                path,
                header_idx + 1,
                1,
                "missing coordinate columns X and Y",
            )
            .into());
        }
        warnings.push(
            "no coordinate columns: coordinates are taken from the mesh given with --fem-mesh (node k = PLY node k − 1)".into(),
        );
    } else {
        check_duplicates(path, &nodes, &lines_of)?;
    }
    let report = FemReadReport {
        path: path.to_path_buf(),
        delimiter: match delim {
            Delimiter::Byte(b'\t') => "tab".into(),
            Delimiter::Byte(b) => (b as char).to_string(),
            Delimiter::Blanks => "blanks".into(),
        },
        decimal_comma,
        bom,
        header_line: header_idx + 1,
        columns,
        nodes: nodes.len(),
        dim: nodes.dim,
        sign: options.sign,
        has_coordinates: cx.is_some() && cy.is_some(),
        vtu: None,
        warnings,
    };
    Ok((nodes, report))
}

/// Duplicate node ids and coincident nodes are errors naming both lines.
fn check_duplicates(path: &Path, nodes: &FemNodes, lines: &[usize]) -> Result<(), FormatError> {
    let mut by_id: Vec<usize> = (0..nodes.len()).collect();
    by_id.par_sort_unstable_by_key(|&i| (nodes.ids[i], i));
    for w in by_id.windows(2) {
        if nodes.ids[w[0]] == nodes.ids[w[1]] {
            return Err(ParseError::at(
                path,
                lines[w[1]],
                1,
                format!(
                    "duplicate node id {} (also on line {})",
                    nodes.ids[w[1]], lines[w[0]]
                ),
            )
            .into());
        }
    }
    if let Some(far) = far_outlier(&nodes.positions) {
        return Err(ParseError::at(path, lines[far.index], 1, far.to_string()).into());
    }
    if let Some((first, second)) = first_coincident(&nodes.positions) {
        let p = nodes.positions[first];
        return Err(ParseError::at(
            path,
            lines[second],
            1,
            format!(
                "duplicate node: same coordinates as line {} ({}, {}, {})",
                lines[first], p[0], p[1], p[2]
            ),
        )
        .into());
    }
    Ok(())
}
