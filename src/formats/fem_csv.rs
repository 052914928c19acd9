//! FEM node tables: GeoStudio-style CSV exports in their many dialects, and the
//! `node.csv` that GeoStudio keeps inside a `.gsz` (with coordinates from the
//! sibling `Mesh.ply`). Spec: `formats/geostudio-csv.md`.
//!
//! The reader sniffs the dialect (BOM, delimiter `,` `;` tab or blanks, decimal
//! comma, preamble lines), matches headers loosely through a synonym table,
//! converts units given in the header to m and kPa, and converts signs to
//! Anura3D's (tension positive, pwp negative in compression) when the source is
//! GeoStudio. Every conversion is recorded in [`FemReadReport`]. Errors name the
//! file, line and column.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::error::{FormatError, ParseError};
use crate::model::{FemNodes, Quantity, StressComponent};

/// What a column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Field {
    X,
    Y,
    Z,
    Node,
    Region,
    Value(Quantity),
}

impl Field {
    /// Name used by `--columns` and reports: x, y, z, node, region, pwp, sxx, …, esxx, …
    pub fn name(self) -> String {
        match self {
            Field::X => "x".into(),
            Field::Y => "y".into(),
            Field::Z => "z".into(),
            Field::Node => "node".into(),
            Field::Region => "region".into(),
            Field::Value(q) => q.name(),
        }
    }

    pub fn from_name(s: &str) -> Option<Field> {
        match s {
            "x" => Some(Field::X),
            "y" => Some(Field::Y),
            "z" => Some(Field::Z),
            "node" | "id" => Some(Field::Node),
            "region" | "material" => Some(Field::Region),
            other => Quantity::from_name(other).map(Field::Value),
        }
    }

    fn is_pressure(self) -> bool {
        matches!(self, Field::Value(_))
    }

    fn is_length(self) -> bool {
        matches!(self, Field::X | Field::Y | Field::Z)
    }
}

/// Sign convention of the source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, Default)]
pub enum SignConvention {
    /// Compression positive, pwp positive below the water table: every stress and
    /// the pwp are negated.
    #[default]
    GeoStudio,
    /// Already Anura3D's convention: kept.
    TensionPositive,
}

/// Unit overrides (`--fem-units length=ft,pressure=psf`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UnitOverride {
    pub length: Option<String>,
    pub pressure: Option<String>,
}

/// Options of the reader.
#[derive(Clone, Debug, Default)]
pub struct CsvOptions {
    /// Explicit field → header mapping; wins over the synonym table.
    pub columns: Vec<(Field, String)>,
    pub units: UnitOverride,
    pub sign: SignConvention,
}

/// How one column was understood.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ColumnReport {
    pub header: String,
    /// Field name, or "ignored".
    pub understood_as: String,
    pub unit: Option<String>,
    pub factor: f64,
    pub sign_flipped: bool,
}

/// What the reader did, for `inspect --fem` and `report.json`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FemReadReport {
    pub path: PathBuf,
    pub delimiter: String,
    pub decimal_comma: bool,
    pub bom: bool,
    /// 1-based line of the header.
    pub header_line: usize,
    pub columns: Vec<ColumnReport>,
    pub nodes: usize,
    pub dim: usize,
    pub sign: SignConvention,
    /// False for a GeoStudio `node.csv` (coordinates live in the mesh PLY).
    pub has_coordinates: bool,
    pub warnings: Vec<String>,
}

/// Normalises a header for matching: drops units in () or [], lower-cases and
/// keeps letters and digits only.
pub fn normalise(header: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in header.chars() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth = (depth as i32 - 1).max(0) as usize,
            c if depth == 0 && c.is_alphanumeric() && c.is_ascii() => {
                out.push(c.to_ascii_lowercase())
            }
            _ => {}
        }
    }
    out
}

/// The unit written in a header: inside () or [], or an `_unit` suffix.
fn header_unit(header: &str) -> Option<String> {
    if let Some(start) = header.find(['(', '[']) {
        let rest = &header[start + 1..];
        if let Some(end) = rest.find([')', ']']) {
            return Some(rest[..end].trim().to_string());
        }
    }
    let (_, suffix) = header.rsplit_once('_')?;
    let s = suffix.to_ascii_lowercase();
    (["m", "ft", "mm", "cm", "kpa", "pa", "mpa", "psf", "psi"].contains(&s.as_str()))
        .then(|| suffix.to_string())
}

fn strip_unit_suffix(normalised: &str, header: &str) -> String {
    match header.rsplit_once('_') {
        Some((_, suffix)) if header_unit(header).as_deref() == Some(suffix) => normalised
            .trim_end_matches(&suffix.to_ascii_lowercase())
            .to_string(),
        _ => normalised.to_string(),
    }
}

/// The field a normalised header stands for.
pub fn synonym(n: &str) -> Option<Field> {
    use StressComponent::*;
    let t = |c| Some(Field::Value(Quantity::TotalStress(c)));
    let e = |c| Some(Field::Value(Quantity::EffectiveStress(c)));
    match n {
        "x" | "xcoordinate" | "xcoord" | "xm" | "pointsx" | "points0" => Some(Field::X),
        "y" | "ycoordinate" | "ycoord" | "ym" | "pointsy" | "points1" | "elevation" => {
            Some(Field::Y)
        }
        "z" | "zcoordinate" | "zcoord" | "zm" | "pointsz" | "points2" => Some(Field::Z),
        "node" | "nodenum" | "nodeid" | "nodenumber" | "id" | "nodeno" => Some(Field::Node),
        "material" | "region" | "materialid" | "soil" | "materialname" | "zone" | "regionid" => {
            Some(Field::Region)
        }
        "porewaterpressure"
        | "pwp"
        | "porepressure"
        | "waterpressure"
        | "u"
        | "pwater"
        | "porewaterpressurekpa" => Some(Field::Value(Quantity::Pwp)),
        "xtotalstress" | "sigmax" | "sigx" | "sxx" | "sigxxt" | "sigmaxx" | "totalstressx"
        | "sigxx" | "s11" => t(Xx),
        "ytotalstress" | "sigmay" | "sigy" | "syy" | "sigyyt" | "sigmayy" | "totalstressy"
        | "sigyy" | "s22" => t(Yy),
        "ztotalstress" | "sigmaz" | "sigz" | "szz" | "sigzzt" | "sigmazz" | "totalstressz"
        | "sigzz" | "s33" => t(Zz),
        "xyshearstress" | "tauxy" | "sxy" | "sigxy" | "sigmaxy" | "shearstressxy" | "xyshear"
        | "s12" | "yxshearstress" => t(Xy),
        "yzshearstress" | "tauyz" | "syz" | "sigyz" | "sigmayz" | "shearstressyz" | "s23"
        | "zyshearstress" => t(Yz),
        "xzshearstress" | "tauxz" | "sxz" | "sigxz" | "sigmaxz" | "shearstressxz"
        | "zxshearstress" | "tauzx" | "s13" => t(Xz),
        "xeffectivestress" | "sigxxe" | "esxx" | "effectivestressx" | "sigmaxeff"
        | "sigmaxprime" => e(Xx),
        "yeffectivestress" | "sigyye" | "esyy" | "effectivestressy" | "sigmayeff"
        | "sigmayprime" => e(Yy),
        "zeffectivestress" | "sigzze" | "eszz" | "effectivestressz" | "sigmazeff"
        | "sigmazprime" => e(Zz),
        _ => None,
    }
}

/// Factor from a header unit to kPa (pressure) or m (length).
fn unit_factor(unit: &str, length: bool) -> Option<f64> {
    let u: String = unit
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect::<String>()
        .to_ascii_lowercase();
    if length {
        match u.as_str() {
            "m" => Some(1.0),
            "ft" | "feet" => Some(0.3048),
            "mm" => Some(1e-3),
            "cm" => Some(1e-2),
            _ => None,
        }
    } else {
        match u.as_str() {
            "kpa" | "kn/m2" | "kn/m²" | "kn/m^2" => Some(1.0),
            "pa" | "n/m2" | "n/m²" => Some(1e-3),
            "mpa" => Some(1e3),
            "psf" | "lbf/ft2" | "lb/ft2" => Some(0.047880258980335),
            "psi" | "lbf/in2" => Some(6.894757293168361),
            _ => None,
        }
    }
}

/// The sniffed dialect.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Delimiter {
    Byte(u8),
    Blanks,
}

/// `sample`: the first 20 non-blank lines.
fn sniff_delimiter(sample: &[&str]) -> Delimiter {
    for d in [b'\t', b';', b','] {
        let counts: Vec<usize> = sample
            .iter()
            .map(|l| l.bytes().filter(|&b| b == d).count())
            .collect();
        let rows_with = counts.iter().filter(|&&c| c > 0).count();
        if rows_with * 2 > sample.len() {
            return Delimiter::Byte(d);
        }
    }
    Delimiter::Blanks
}

/// Splits one line into (character column, field) pairs.
fn split_line(line: &str, delim: Delimiter) -> Vec<(usize, String)> {
    match delim {
        Delimiter::Blanks => {
            let mut out = Vec::new();
            let mut start: Option<usize> = None;
            for (i, c) in line
                .char_indices()
                .chain(std::iter::once((line.len(), ' ')))
            {
                if c.is_whitespace() {
                    if let Some(s) = start.take() {
                        out.push((
                            line[..s].chars().count() + 1,
                            line[s..i].trim_matches('"').to_string(),
                        ));
                    }
                } else if start.is_none() {
                    start = Some(i);
                }
            }
            out
        }
        Delimiter::Byte(d) => {
            let mut rdr = csv::ReaderBuilder::new()
                .has_headers(false)
                .delimiter(d)
                .flexible(true)
                .from_reader(line.as_bytes());
            let mut record = csv::StringRecord::new();
            if !rdr.read_record(&mut record).unwrap_or(false) {
                return Vec::new();
            }
            // Columns: find each field's start by walking the raw line.
            let mut cols = Vec::with_capacity(record.len());
            let mut col = 1;
            let mut in_quotes = false;
            cols.push(1);
            for c in line.chars() {
                col += 1;
                if c == '"' {
                    in_quotes = !in_quotes;
                } else if c as u32 == d as u32 && !in_quotes {
                    cols.push(col);
                }
            }
            record
                .iter()
                .enumerate()
                .map(|(k, f)| (cols.get(k).copied().unwrap_or(1), f.trim().to_string()))
                .collect()
        }
    }
}

fn parse_number(text: &str, decimal_comma: bool) -> Option<f64> {
    let t = text.trim();
    let v: f64 = if decimal_comma {
        t.replace(',', ".").parse().ok()?
    } else {
        t.parse().ok()?
    };
    v.is_finite().then_some(v)
}

/// Bytes per chunk of the data-row pass (split after the next newline).
const CHUNK_BYTES: usize = 1 << 20;

/// The data-row pass stops after a row that brings the errors past this count.
const MAX_ROW_ERRORS: usize = 20;

/// What the data-row pass needs to know about the table.
struct Schema<'a> {
    path: &'a Path,
    delim: Delimiter,
    decimal_comma: bool,
    /// Column of x, y, z.
    coords: [Option<usize>; 3],
    node: Option<usize>,
    region: Option<usize>,
    value_cols: &'a [(usize, Quantity)],
    /// Unit factor × sign per column.
    factors: &'a [f64],
}

impl Schema<'_> {
    /// The columns whose missing fields are tracked: the values, then node, then region.
    fn tracked(&self) -> Vec<Option<usize>> {
        let mut out: Vec<Option<usize>> = self.value_cols.iter().map(|(c, _)| Some(*c)).collect();
        out.push(self.node);
        out.push(self.region);
        out
    }
}

/// Data rows read from one chunk (or from the whole body once merged).
#[derive(Default)]
struct Rows {
    positions: Vec<[f64; 3]>,
    /// The id column's value, when the row has one.
    ids: Vec<Option<i64>>,
    /// One vector per value column with a value (NaN when absent) for every row.
    values: Vec<Vec<f64>>,
    regions: Vec<String>,
    /// 1-based line of each row.
    lines: Vec<usize>,
    /// Per tracked column ([`Schema::tracked`]): some row has a value.
    has_value: Vec<bool>,
    /// Per tracked column: the first row that lacks the field, as (line,
    /// column past its end, fields in the row).
    first_short: Vec<Option<(usize, usize, usize)>>,
    errors: Vec<ParseError>,
}

impl Rows {
    fn new(schema: &Schema<'_>) -> Rows {
        let n_tracked = schema.value_cols.len() + 2;
        Rows {
            values: vec![Vec::new(); schema.value_cols.len()],
            has_value: vec![false; n_tracked],
            first_short: vec![None; n_tracked],
            ..Rows::default()
        }
    }

    fn short(&mut self, t: usize, line: usize, col: usize, n_fields: usize) {
        if self.first_short[t].is_none() {
            self.first_short[t] = Some((line, col, n_fields));
        }
    }
}

/// The merged rows and the row errors kept (as many as the serial pass would).
struct Merged {
    rows: Rows,
    errors: Vec<ParseError>,
}

/// Joins chunk results in file order. Errors are cut as a serial pass would:
/// after the row that brings them past [`MAX_ROW_ERRORS`].
fn merge_rows(parts: Vec<Rows>, n_values: usize) -> Merged {
    let n: usize = parts.iter().map(|p| p.positions.len()).sum();
    let n_rows: usize = parts
        .iter()
        .map(|p| p.values.first().map_or(0, Vec::len))
        .sum();
    let mut rows = Rows {
        positions: Vec::with_capacity(n),
        ids: Vec::with_capacity(n),
        values: vec![Vec::with_capacity(n_rows); n_values],
        lines: Vec::with_capacity(n),
        has_value: vec![false; n_values + 2],
        first_short: vec![None; n_values + 2],
        ..Rows::default()
    };
    let mut errors: Vec<ParseError> = Vec::new();
    let mut full = false;
    for part in parts {
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
        for e in part.errors {
            if full {
                break;
            }
            if errors.len() > MAX_ROW_ERRORS
                && errors.last().map(|l| l.position.line) != Some(e.position.line)
            {
                full = true;
                break;
            }
            errors.push(e);
        }
    }
    Merged { rows, errors }
}

/// Byte offset of 0-based line `k` of `text` (its length when there are fewer lines).
fn nth_line_start(text: &str, k: usize) -> usize {
    if k == 0 {
        return 0;
    }
    text.bytes()
        .enumerate()
        .filter(|&(_, b)| b == b'\n')
        .nth(k - 1)
        .map_or(text.len(), |(i, _)| i + 1)
}

/// Splits `text` into pieces of about `size` bytes, each ending just after a newline
/// (the last one excepted).
fn split_chunks(text: &str, size: usize) -> Vec<&str> {
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

/// Parses the rows of one chunk whose first line is `first_line` (1-based).
fn parse_chunk(schema: &Schema<'_>, chunk: &str, first_line: usize) -> Rows {
    let mut rows = Rows::new(schema);
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

/// `line.trim().is_empty()` without decoding ASCII.
fn is_blank(line: &str) -> bool {
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
/// false, having stored nothing, for any other row (which [`slow_row`] reads).
fn fast_row(
    schema: &Schema<'_>,
    line: &str,
    line_no: usize,
    ranges: &mut Vec<(usize, usize)>,
    scratch: &mut Vec<f64>,
    rows: &mut Rows,
) -> bool {
    let b = line.as_bytes();
    ranges.clear();
    let mut quotes = false;
    match schema.delim {
        Delimiter::Byte(d) => {
            let mut start = 0;
            for (i, &c) in b.iter().enumerate() {
                if c == d {
                    ranges.push((start, i));
                    start = i + 1;
                } else if c >= 0x80 || c == b'\r' {
                    return false;
                } else if c == b'"' {
                    quotes = true;
                }
            }
            ranges.push((start, b.len()));
            if quotes {
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
            Cell::Empty | Cell::Short => {}
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

/// Any row, read field by field with positioned errors.
fn slow_row(schema: &Schema<'_>, line: &str, line_no: usize, rows: &mut Rows) {
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
                if c >= n_fields {
                    rows.short(n_values, line_no, end_col, n_fields);
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

/// Reads a node table. `path` names the file in errors.
pub fn read_csv(
    path: &Path,
    options: &CsvOptions,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    let bytes = super::input::read_bytes(path)?;
    parse_csv(path, &bytes, options)
}

/// Parses node-table bytes (see [`read_csv`]).
pub fn parse_csv(
    path: &Path,
    bytes: &[u8],
    options: &CsvOptions,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    parse_csv_chunked(path, bytes, options, CHUNK_BYTES)
}

/// [`parse_csv`] with data-row chunks of about `chunk_bytes` (tests vary it).
fn parse_csv_chunked(
    path: &Path,
    bytes: &[u8],
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
    let (bom, body) = match bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]) {
        Some(rest) => (true, rest),
        None => (false, bytes),
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
                "no header with X and Y (or Node) columns found; headers seen: {}. Name them with --columns x=…,y=…",
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
        let flip =
            matches!(field, Some(Field::Value(_))) && options.sign == SignConvention::GeoStudio;
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
        .zip(first_line.par_iter())
        .map(|(chunk, &l0)| {
            let rows = parse_chunk(&schema, chunk, l0);
            crate::progress::READ_FEM.add(chunk.len() as u64);
            rows
        })
        .collect();
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
    // is an error at its end; a cell present but empty is not (#15).
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
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &nodes.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diag = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2))
        .sqrt()
        .max(1e-300);
    let tol = 1e-9 * diag;
    let mut order: Vec<usize> = (0..nodes.len()).collect();
    order.par_sort_unstable_by(|&a, &b| {
        nodes.positions[a][0]
            .total_cmp(&nodes.positions[b][0])
            .then(a.cmp(&b))
    });
    for (k, &a) in order.iter().enumerate() {
        for &b in &order[k + 1..] {
            let (pa, pb) = (nodes.positions[a], nodes.positions[b]);
            if pb[0] - pa[0] > tol {
                break;
            }
            if (pa[1] - pb[1]).abs() <= tol && (pa[2] - pb[2]).abs() <= tol {
                let (first, second) = (a.min(b), a.max(b));
                return Err(ParseError::at(
                    path,
                    lines[second],
                    1,
                    format!(
                        "duplicate node: same coordinates as line {} ({}, {}, {})",
                        lines[first], pa[0], pa[1], pa[2]
                    ),
                )
                .into());
            }
        }
    }
    Ok(())
}

/// Parses `x=X (m),y=Y,pwp=PWP` into a column mapping. A field given twice, or a
/// header given to two fields, is an error (#15).
pub fn parse_columns_option(s: &str) -> Result<Vec<(Field, String)>, String> {
    let columns = s
        .split(',')
        .filter(|p| !p.trim().is_empty())
        .map(|pair| {
            let (k, v) = pair.split_once('=').ok_or_else(|| format!("`{pair}`: expected field=header"))?;
            let field = Field::from_name(k.trim()).ok_or_else(|| {
                format!("`{k}`: unknown field (known: x y z node region pwp sxx syy szz sxy syz sxz esxx esyy eszz)")
            })?;
            Ok((field, v.trim().to_string()))
        })
        .collect::<Result<Vec<_>, String>>()?;
    check_columns_option(&columns)?;
    Ok(columns)
}

/// Refuses a column mapping that names a field twice or a header twice.
fn check_columns_option(columns: &[(Field, String)]) -> Result<(), String> {
    for (k, (field, header)) in columns.iter().enumerate() {
        for (other_field, other_header) in &columns[..k] {
            if other_field == field {
                return Err(format!(
                    "--columns gives {} twice (`{other_header}` and `{header}`): name one header per field",
                    field.name()
                ));
            }
            if other_header == header {
                return Err(format!(
                    "--columns gives header `{header}` to both {} and {}: a column holds one field",
                    other_field.name(),
                    field.name()
                ));
            }
        }
    }
    Ok(())
}

/// Parses `length=ft,pressure=psf`.
pub fn parse_units_option(s: &str) -> Result<UnitOverride, String> {
    let mut out = UnitOverride::default();
    for pair in s.split(',').filter(|p| !p.trim().is_empty()) {
        let (k, v) = pair
            .split_once('=')
            .ok_or_else(|| format!("`{pair}`: expected length=… or pressure=…"))?;
        match k.trim() {
            "length" if unit_factor(v, true).is_some() => out.length = Some(v.trim().into()),
            "pressure" if unit_factor(v, false).is_some() => out.pressure = Some(v.trim().into()),
            "length" | "pressure" => return Err(format!("unknown unit `{v}` for {k}")),
            other => return Err(format!("`{other}`: expected length or pressure")),
        }
    }
    Ok(out)
}

/// Gives a GeoStudio `node.csv` its coordinates from the mesh PLY: node id k is
/// PLY node k − 1. 2D when every z is 0.
pub fn attach_mesh(
    nodes: &mut FemNodes,
    csv_path: &Path,
    mesh: &[[f64; 3]],
) -> Result<(), FormatError> {
    for (i, id) in nodes.ids.iter().enumerate() {
        let k = *id;
        if k < 1 || k as usize > mesh.len() {
            return Err(FormatError::file(
                csv_path,
                format!(
                    "node {k} (row {}) has no coordinates: the mesh has {} nodes",
                    i + 1,
                    mesh.len()
                ),
            ));
        }
        nodes.positions[i] = mesh[k as usize - 1];
    }
    nodes.dim = if nodes.positions.iter().all(|p| p[2] == 0.0) {
        2
    } else {
        3
    };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_normalise_to_synonyms() {
        for (header, field) in [
            ("X", Field::X),
            ("X (m)", Field::X),
            ("X-Coordinate", Field::X),
            ("x_ft", Field::X),
            ("Pore-Water Pressure (kPa)", Field::Value(Quantity::Pwp)),
            ("PoreWaterPressure", Field::Value(Quantity::Pwp)),
            ("PWP", Field::Value(Quantity::Pwp)),
            (
                "XTotalStress",
                Field::Value(Quantity::TotalStress(StressComponent::Xx)),
            ),
            (
                "Y-Total Stress",
                Field::Value(Quantity::TotalStress(StressComponent::Yy)),
            ),
            (
                "XYShearStress",
                Field::Value(Quantity::TotalStress(StressComponent::Xy)),
            ),
            (
                "Sigma X",
                Field::Value(Quantity::TotalStress(StressComponent::Xx)),
            ),
            (
                "X-Effective Stress",
                Field::Value(Quantity::EffectiveStress(StressComponent::Xx)),
            ),
            ("Node", Field::Node),
            ("Material ID", Field::Region),
        ] {
            assert_eq!(
                synonym(&strip_unit_suffix(&normalise(header), header)),
                Some(field),
                "{header}"
            );
        }
    }

    fn parse(text: &str, chunk: usize) -> Result<(FemNodes, FemReadReport), String> {
        parse_csv_chunked(
            Path::new("t.csv"),
            text.as_bytes(),
            &CsvOptions::default(),
            chunk,
        )
        .map_err(|e| e.to_string())
    }

    /// Tables in several dialects, with quirks the fast path hands to the
    /// field-by-field path (quotes, non-ASCII, blank lines, decimal commas, CRLF).
    const TABLES: &[&str] = &[
        "X,Y,PWP,Region\n0,0,1.5,sand\n1,0,2.5,clay\n\n0,1,\"3.5\",\"sa,nd\"\n1,1, 4 ,\n",
        "title\r\nX (m);Y (m);Sxx (kPa)\r\n0,5;0;1,25\r\n1;0;2\r\n0;1,5;3e2\r\n",
        "X\tY\tZ\tNode\n0\t0\t0\t7\n1\t0\t0\t8\n0\t1\t0\t9\n0\t0\t1\t10\n",
        "  X   Y   PWP\n 0  0  1\n 1  0  2\n \"0\" 1 3\n 1 1 4\n",
        "X,Y,PWP\n0,0,1\n1,0,2\n0,1,3\n1,1,4\u{a0}\n",
        "Node,PoreWaterPressure,XTotalStress,YTotalStress\r\n1,78.4\r\n2,74.0\r\n3,70.5\r\n",
    ];

    #[test]
    fn chunk_size_does_not_change_the_result() {
        for table in TABLES {
            let whole = parse(table, 1 << 20);
            for chunk in [1, 2, 5, 17] {
                let part = parse(table, chunk);
                match (&whole, &part) {
                    (Ok((a, ra)), Ok((b, rb))) => {
                        assert_eq!(a, b, "{table:?} chunk {chunk}");
                        assert_eq!(ra.warnings, rb.warnings);
                    }
                    (a, b) => assert_eq!(a.as_ref().err(), b.as_ref().err(), "{table:?}"),
                }
            }
        }
    }

    #[test]
    fn fast_rows_equal_field_by_field_rows() {
        // Every line the fast path accepts must read the same through `slow_row`.
        let values = [
            (2, Quantity::Pwp),
            (3, Quantity::TotalStress(StressComponent::Xx)),
        ];
        let factors = [1.0, 0.3048, -1.0, -2.0, 1.0, 1.0];
        for (delim, decimal_comma, lines) in [
            (
                Delimiter::Byte(b','),
                false,
                &[
                    "1,2,3,4,5,r",
                    " 1 , 2 ,3,,5,",
                    "\"1\",2,\"\",4,5,\"a b\"",
                    "1,2,3",
                    "1,2",
                    "-1e3,+.5,5.,1E-300,7,x",
                ][..],
            ),
            (
                Delimiter::Byte(b';'),
                true,
                &["1,5;2;3,25;4;5;r", "1;2;;4,0", "1;2"][..],
            ),
            (
                Delimiter::Blanks,
                false,
                &["1 2 3 4 5 r", "1\t2  3", "1 2"][..],
            ),
        ] {
            let schema = Schema {
                path: Path::new("t.csv"),
                delim,
                decimal_comma,
                coords: [Some(0), Some(1), None],
                node: Some(4),
                region: Some(5),
                value_cols: &values,
                factors: &factors,
            };
            for line in lines {
                let mut fast = Rows::new(&schema);
                let mut slow = Rows::new(&schema);
                let mut ranges = Vec::new();
                let mut scratch = Vec::new();
                assert!(
                    fast_row(&schema, line, 3, &mut ranges, &mut scratch, &mut fast),
                    "{line:?}"
                );
                slow_row(&schema, line, 3, &mut slow);
                assert!(slow.errors.is_empty(), "{line:?}: {:?}", slow.errors);
                assert_eq!(fast.positions, slow.positions, "{line:?}");
                assert_eq!(fast.ids, slow.ids, "{line:?}");
                assert_eq!(fast.regions, slow.regions, "{line:?}");
                assert_eq!(fast.lines, slow.lines, "{line:?}");
                assert_eq!(fast.has_value, slow.has_value, "{line:?}");
                assert_eq!(fast.first_short, slow.first_short, "{line:?}");
                for (a, b) in fast.values.iter().zip(&slow.values) {
                    let bits = |v: &Vec<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(a), bits(b), "{line:?}");
                }
            }
        }
    }

    #[test]
    fn error_list_is_cut_as_a_serial_pass_would() {
        // 30 bad rows with two errors each: the list stops after the row that
        // brings it past 20, whatever the chunking.
        let mut text = String::from("X,Y,PWP\n");
        for _ in 0..30 {
            text.push_str("a,0,b\n");
        }
        let whole = parse(&text, 1 << 20).unwrap_err();
        assert_eq!(whole.lines().count(), 21, "{whole}");
        assert!(whole.ends_with("… and 2 more"), "{whole}");
        for chunk in [1, 3, 50] {
            assert_eq!(parse(&text, chunk).unwrap_err(), whole);
        }
    }

    #[test]
    fn row_missing_its_last_field_is_a_positioned_error() {
        // #15: fewer fields than the header while other rows fill the column.
        for (table, expected) in [
            (
                "X,Y,PWP\n0,0,1\n1,0\n0,1,3\n",
                "t.csv:3:4: the row has 2 field(s) but the header has 3: `PWP` is missing",
            ),
            (
                "X,Y,Node\n0,0,1\n1,0,2\n0,1\n",
                "t.csv:4:4: the row has 2 field(s) but the header has 3: `Node` is missing",
            ),
            (
                "X;Y;Material\n0;0;sand\n1;0;sand\n0;1\n",
                "t.csv:4:4: the row has 2 field(s) but the header has 3: `Material` is missing",
            ),
        ] {
            let e = parse(table, 4).unwrap_err();
            assert!(e.starts_with(expected), "{e}");
        }
        // A cell present but empty is not a missing field: partly empty is the
        // old error, wholly empty or wholly absent (GeoStudio's ragged rows) drops
        // the column with a warning.
        let e = parse("X,Y,PWP\n0,0,1\n1,0,\n0,1,3\n", 4).unwrap_err();
        assert!(e.starts_with("t.csv:3:1: missing value for `PWP`"), "{e}");
        for table in ["X,Y,PWP\n0,0,\n1,0,\n0,1,\n", "X,Y,PWP\n0,0\n1,0\n0,1\n"] {
            let (nodes, report) = parse(table, 4).unwrap();
            assert!(nodes.fields.is_empty());
            assert!(report.warnings[0].contains("has no values in any row"));
        }
    }

    #[test]
    fn duplicate_column_assignments_are_errors() {
        let e = parse_columns_option("x=A,x=B").unwrap_err();
        assert!(e.contains("gives x twice"), "{e}");
        let e = parse_columns_option("x=A,y=A").unwrap_err();
        assert!(e.contains("header `A` to both x and y"), "{e}");
        let options = CsvOptions {
            columns: vec![(Field::X, "A".into()), (Field::Y, "A".into())],
            ..CsvOptions::default()
        };
        let e = parse_csv(Path::new("t.csv"), b"A,B\n0,0\n", &options).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("t.csv:1:1: --columns gives header `A`"),
            "{e}"
        );
    }
}
