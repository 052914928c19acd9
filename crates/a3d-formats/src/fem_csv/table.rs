//! The whole-table pass behind [`parse_csv`](super::parse_csv): encoding and
//! BOM, dialect, header detection (synonyms or `--columns`), units and signs per
//! column, the data rows (see `rows`), and the checks on the assembled nodes
//! (ragged rows, missing values, duplicate ids and coincident nodes).

use std::path::Path;

use rayon::prelude::*;

use super::dialect::{Delimiter, sniff_delimiter, split_line};
use super::headers::{Field, header_unit, normalise, strip_unit_suffix, synonym, unit_factor};
use super::options::{CsvOptions, check_columns_option};
use super::rows::{Merged, Merger, parse_chunk, split_chunks};
use super::schema::{Rows, Schema};
use super::source::{Source, decode, nth_line_start};
use crate::error::{FormatError, ParseError};
use crate::extent::{far_outlier, first_coincident};
use crate::fem::{ColumnReport, FemReadReport, SignConvention};
use a3d_model::{FemNodes, Quantity};

/// Block and chunk sizes of the data-row pass (tests make them tiny).
#[derive(Clone, Copy)]
pub(super) struct Sizes {
    /// Bytes read per block (see [`super::source`]).
    pub(super) block: usize,
    /// Bytes per chunk parsed in parallel within a block.
    pub(super) chunk: usize,
}

impl Sizes {
    pub(super) const DEFAULT: Sizes = Sizes {
        block: super::source::BLOCK_BYTES,
        chunk: super::rows::CHUNK_BYTES,
    };
}

/// [`parse_csv`](super::parse_csv) on what `reader` gives (`len` bytes
/// expected, for the progress; at most `limit`), read in blocks of whole
/// lines: the text is never held whole, only the head and one block.
///
/// The phases: the encoding ([`encoding`]), the head's dialect ([`sniff`]),
/// the header ([`find_header`]), units and signs per column
/// ([`column_plan`]), the data rows block by block in parallel chunks
/// ([`parse_rows`]), then the checks on what they gave (short rows, ids,
/// missing values, duplicates).
pub(super) fn parse_csv_stream(
    path: &Path,
    reader: &mut dyn std::io::Read,
    (len, limit): (u64, u64),
    options: &CsvOptions,
    sizes: Sizes,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    check_columns_option(&options.columns).map_err(|m| ParseError::at(path, 1, 1, m))?;
    let mut source = Source::new(path, reader, limit, sizes.block);
    let bom = encoding(path, &mut source)?;
    let (head_len, any_text) = source.head()?;
    if !any_text {
        return Err(ParseError::at(
            path,
            1,
            1,
            "empty file: expected a header line with X and Y (or Node) columns",
        )
        .into());
    }
    let (header, delim, decimal_comma) = {
        let head = decode(&source.buf[..head_len]);
        let dialect = sniff(&head);
        (
            find_header(path, &dialect, options)?,
            dialect.delim,
            dialect.decimal_comma,
        )
    };
    let (columns, factors) = column_plan(path, &header, options)?;
    let Header {
        index: header_idx,
        mapping,
        headers,
    } = header;

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
    let body_start = nth_line_start(&source.buf, header_idx + 1);
    source.consume(body_start);
    let merged = parse_rows(&schema, &mut source, header_idx + 2, (len, sizes.chunk))?;
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
    // Collected in place: half the room the optional ids took is spare.
    nodes.ids.shrink_to_fit();
    if nodes.positions.is_empty() {
        return Err(ParseError::at(
            path,
            header_idx + 1,
            1,
            "the table has a header but no data rows",
        )
        .into());
    }
    check_short_rows(path, &schema, &headers, &first_short, &has_value)?;
    // Columns absent from every row (ragged GeoStudio rows) are dropped, not zeroed;
    // partly present columns are an error at the first row without a value.
    let mut warnings = Vec::new();
    let ids_given = has_value[value_cols.len()];
    let coordinates = cx.is_some() && cy.is_some();
    if let Some(c) = cnode {
        let column = IdColumn {
            index: c,
            given: ids_given,
            first_empty: first_empty_id,
        };
        if let Some(warning) = check_ids(path, header_idx, &headers, &column, coordinates)? {
            warnings.push(warning);
        }
    }
    let mut taken = take_values(path, &headers, &value_cols, &mut values, &lines_of)?;
    nodes.fields.append(&mut taken.fields);
    warnings.append(&mut taken.warnings);
    warnings.extend(tensile_vertical_stress(&nodes.fields, options.sign));
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
            "no coordinate columns: coordinates are taken from the FEM mesh (node k = PLY node k − 1)".into(),
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
        has_coordinates: coordinates,
        vtu: None,
        warnings,
    };
    Ok((nodes, report))
}

/// The encoding at the start of the input: UTF-16 refused, a UTF-8 BOM
/// dropped (and said: true). Windows-1252 bytes are replaced as each block
/// is decoded.
fn encoding(path: &Path, source: &mut Source<'_>) -> Result<bool, FormatError> {
    source.fill_to(3)?;
    let bytes = &source.buf;
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err(ParseError::at(
            path,
            1,
            1,
            "UTF-16 text: save the table as UTF-8 (or ANSI) CSV",
        )
        .into());
    }
    let bom = bytes.starts_with(&[0xEF, 0xBB, 0xBF]);
    if bom {
        source.consume(3);
    }
    Ok(bom)
}

/// The dialect, from the first lines: the delimiter, decimal commas, and the
/// lines the header is looked for in.
struct Dialect<'t> {
    /// The first 20 non-blank lines.
    sample: Vec<&'t str>,
    delim: Delimiter,
    /// The first 51 lines.
    lines: Vec<&'t str>,
    decimal_comma: bool,
}

fn sniff(text: &str) -> Dialect<'_> {
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

    Dialect {
        sample,
        delim,
        lines,
        decimal_comma,
    }
}

/// The header line: its 0-based index, its fields (column, text), and what
/// each field means.
struct Header {
    index: usize,
    mapping: Vec<Option<Field>>,
    headers: Vec<(usize, String)>,
}

/// The first line whose fields map x and y (or node), by the synonyms or the
/// user's `--columns`; every `--columns` name must be a header, and no field
/// may be mapped twice.
fn find_header(
    path: &Path,
    dialect: &Dialect<'_>,
    options: &CsvOptions,
) -> Result<Header, FormatError> {
    let Dialect {
        sample,
        delim,
        lines,
        ..
    } = dialect;
    let delim = *delim;
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
                "no header with X and Y (or Node) columns found; headers seen: {}. Name them in the column mapping (x=…, y=…)",
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
                    "the column mapping names {}={name}: no such header; headers are {}",
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
                    "columns `{}` and `{}` both mean {}; choose one with the column mapping",
                    headers[j].1,
                    headers[k].1,
                    f.name()
                ),
            )
            .into());
        }
    }

    Ok(Header {
        index: header_idx,
        mapping,
        headers,
    })
}

/// Units and signs per column: the report of each column and the factor
/// (unit × sign) its values are multiplied by.
fn column_plan(
    path: &Path,
    header: &Header,
    options: &CsvOptions,
) -> Result<(Vec<ColumnReport>, Vec<f64>), FormatError> {
    let Header {
        index: header_idx,
        mapping,
        headers,
    } = header;
    let header_idx = *header_idx;
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

    Ok((columns, factors))
}

/// The data rows, whose first line is `first_line` (1-based), block by
/// block from `source`; each block in parallel chunks split after a newline,
/// merged in file order, so the result does not depend on the thread count
/// or the sizes. Reading stops once the errors are cut. `len`: the input's
/// size (for the progress); `chunk_bytes`: the chunks' size.
fn parse_rows(
    schema: &Schema<'_>,
    source: &mut Source<'_>,
    first_line: usize,
    (len, chunk_bytes): (u64, usize),
) -> Result<Merged, FormatError> {
    let mut merger = Merger::new(schema.value_cols.len());
    let mut line = first_line;
    let (mut bytes_done, mut reserved) = (0u64, false);
    a3d_progress::READ_FEM.start(len);
    while !merger.full() {
        let n = source.next_block()?;
        if n == 0 {
            break;
        }
        let text = decode(&source.buf[..n]);
        let chunks = split_chunks(&text, chunk_bytes.max(1));
        let newlines: Vec<usize> = chunks
            .par_iter()
            .map(|c| memchr::memchr_iter(b'\n', c.as_bytes()).count())
            .collect();
        let mut first_lines = Vec::with_capacity(chunks.len());
        for n in &newlines {
            first_lines.push(line);
            line += n;
        }
        let parts: Vec<Rows> = chunks
            .par_iter()
            .zip(first_lines.par_iter().zip(&newlines))
            // A last line without its newline is one more.
            .map(|(chunk, (&l0, &n))| parse_chunk(schema, chunk, l0, n + 1))
            .collect();
        drop(text);
        if !reserved && !source.at_end() {
            // The rest of the file at this block's rows per byte, a little
            // over: the columns are allocated once, not grown by doubling.
            let rows: usize = parts.iter().map(|p| p.positions.len()).sum();
            let per_byte = rows as f64 / n as f64;
            let left = len.saturating_sub(bytes_done) as f64;
            merger.reserve((left * per_byte * 1.02) as usize + 64);
            reserved = true;
        }
        for part in parts {
            merger.push(part);
        }
        source.consume(n);
        bytes_done += n as u64;
        a3d_progress::READ_FEM.add(n as u64);
    }
    Ok(merger.finish())
}

/// A row without a field that other rows fill (fewer fields than the header)
/// is an error at its end; a cell present but empty is not.
fn check_short_rows(
    path: &Path,
    schema: &Schema<'_>,
    headers: &[(usize, String)],
    first_short: &[Option<(usize, usize, usize)>],
    has_value: &[bool],
) -> Result<(), FormatError> {
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
    Ok(())
}

/// The node-id column: its index, whether any row gives an id, and the first
/// row (line, column) whose id is empty.
struct IdColumn {
    index: usize,
    given: bool,
    first_empty: Option<(usize, usize)>,
}

/// The id column's checks: a row without an id would silently take its row
/// number, and with --fem-mesh another node's coordinates. A warning when no
/// row has an id but the table has coordinates.
fn check_ids(
    path: &Path,
    header_idx: usize,
    headers: &[(usize, String)],
    column: &IdColumn,
    coordinates: bool,
) -> Result<Option<String>, FormatError> {
    let c = column.index;
    match column.first_empty {
        Some((line, col)) if column.given => Err(ParseError::at(
            path,
            line,
            col,
            format!(
                "empty node id in `{}`: other rows have ids, so every row needs one",
                headers[c].1
            ),
        )
        .into()),
        _ if !column.given && coordinates => Ok(Some(format!(
            "column `{}` has no values in any row: nodes are numbered by row",
            headers[c].1
        ))),
        _ if !column.given => Err(ParseError::at(
            path,
            header_idx + 1,
            headers[c].0,
            format!(
                "column `{}` has no node ids and the table has no X and Y columns: its rows cannot be joined to mesh nodes",
                headers[c].1
            ),
        )
        .into()),
        _ => Ok(None),
    }
}

/// A warning where the vertical stress (effective where the file has it,
/// else total) comes out tensile at nine nodes in ten or more, as read in
/// `sign`: ground at rest is in compression, so the file is most likely in
/// the other convention (compression positive for GeoStudio, tension
/// positive for PLAXIS, Anura3D and OGS) and every stress and pore pressure
/// would be read with the wrong sign.
fn tensile_vertical_stress(
    fields: &[(Quantity, Vec<f64>)],
    sign: SignConvention,
) -> Option<String> {
    use a3d_model::StressComponent::Yy;
    let (q, v) = fields
        .iter()
        .find(|(q, _)| *q == Quantity::EffectiveStress(Yy))
        .or_else(|| fields.iter().find(|(q, _)| *q == Quantity::TotalStress(Yy)))?;
    let loaded = v.iter().filter(|x| **x != 0.0).count();
    let tensile = v.iter().filter(|x| **x > 0.0).count();
    if loaded < 3 || 10 * tensile < 9 * loaded {
        return None;
    }
    let (read, other) = match sign {
        SignConvention::GeoStudio => (
            "GeoStudio's signs (compression positive)",
            "`--fem-sign tension-positive` (PLAXIS, Anura3D) or `--fem-sign ogs`",
        ),
        SignConvention::TensionPositive | SignConvention::Ogs => (
            "tension positive",
            "`--fem-sign geostudio` (compression positive)",
        ),
    };
    let kind = match q {
        Quantity::EffectiveStress(_) => "effective",
        _ => "total",
    };
    Some(format!(
        "the vertical {kind} stress ({}) is tensile at {tensile} of {loaded} loaded nodes, read with {read}: ground at rest is in compression, so the file is likely in the other convention; if so, give {other}",
        q.name()
    ))
}

/// The value columns that every row fills, and warnings for those no row
/// fills (dropped, not zeroed).
struct Values {
    fields: Vec<(Quantity, Vec<f64>)>,
    warnings: Vec<String>,
}

/// Takes the value columns out of `values`: whole ones become fields, empty
/// ones warnings, and a partly filled one is an error at its first row
/// without a value.
fn take_values(
    path: &Path,
    headers: &[(usize, String)],
    value_cols: &[(usize, Quantity)],
    values: &mut [Vec<f64>],
    lines_of: &[usize],
) -> Result<Values, FormatError> {
    let mut fields = Vec::new();
    let mut warnings = Vec::new();
    for (slot, &(c, q)) in value_cols.iter().enumerate() {
        let n_missing = values[slot].iter().filter(|v| v.is_nan()).count();
        if n_missing == 0 {
            fields.push((q, std::mem::take(&mut values[slot])));
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
    Ok(Values { fields, warnings })
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
