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

fn sniff_delimiter(lines: &[&str]) -> Delimiter {
    let sample: Vec<&str> = lines
        .iter()
        .filter(|l| !l.trim().is_empty())
        .take(20)
        .copied()
        .collect();
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
    let lines: Vec<&str> = text.lines().collect();
    if lines.iter().all(|l| l.trim().is_empty()) {
        return Err(ParseError::at(
            path,
            1,
            1,
            "empty file: expected a header line with X and Y (or Node) columns",
        )
        .into());
    }
    let delim = sniff_delimiter(&lines);
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
        let first = split_line(
            lines
                .iter()
                .find(|l| !l.trim().is_empty())
                .copied()
                .unwrap_or(""),
            delim,
        );
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
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); value_cols.len()];
    let mut regions = Vec::new();
    let mut lines_of = Vec::new();
    let mut errors: Vec<ParseError> = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(header_idx + 1) {
        if line.trim().is_empty() {
            continue;
        }
        let fields = split_line(line, delim);
        let get = |k: usize| fields.get(k).filter(|(_, t)| !t.is_empty());
        let number = |k: usize, what: &str, errors: &mut Vec<ParseError>| -> Option<f64> {
            match get(k) {
                Some((col, text)) => match parse_number(text, decimal_comma) {
                    Some(v) => Some(v),
                    None => {
                        errors.push(ParseError::at(
                            path,
                            i + 1,
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
        for (slot, c, name) in [(0, cx, "x"), (1, cy, "y"), (2, cz, "z")] {
            let Some(c) = c else { continue };
            match number(c, name, &mut errors) {
                Some(v) => pos[slot] = v * factors[c],
                None => {
                    if get(c).is_none() {
                        let at = line.chars().count() + 1;
                        let msg = if slot == 2 {
                            "missing z: some rows are 3D and this one is 2D (mixed 2D/3D rows)"
                                .to_string()
                        } else {
                            format!("missing {name} coordinate")
                        };
                        errors.push(ParseError::at(path, i + 1, at, msg));
                    }
                    ok = false;
                }
            }
        }
        let id = match cnode {
            Some(c) => match get(c) {
                Some((col, text)) => match text.parse::<i64>() {
                    Ok(v) => Some(v),
                    Err(_) => {
                        errors.push(ParseError::at(
                            path,
                            i + 1,
                            *col,
                            format!("expected an integer node id, found `{text}`"),
                        ));
                        ok = false;
                        None
                    }
                },
                None => None,
            },
            None => None,
        };
        for (slot, &(c, q)) in value_cols.iter().enumerate() {
            match number(c, &q.name(), &mut errors) {
                Some(v) => values[slot].push(v * factors[c]),
                None => {
                    if get(c).is_some() {
                        ok = false;
                    }
                    values[slot].push(f64::NAN);
                }
            }
        }
        if errors.len() > 20 {
            break;
        }
        if !ok {
            continue;
        }
        nodes
            .ids
            .push(id.unwrap_or(nodes.positions.len() as i64 + 1));
        nodes.positions.push(pos);
        if let Some(c) = cregion {
            regions.push(get(c).map(|(_, t)| t.clone()).unwrap_or_default());
        }
        lines_of.push(i + 1);
    }
    if let Some(e) = FormatError::from_list(errors) {
        return Err(e);
    }
    if nodes.positions.is_empty() {
        return Err(ParseError::at(
            path,
            header_idx + 1,
            1,
            "the table has a header but no data rows",
        )
        .into());
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
    by_id.sort_by_key(|&i| (nodes.ids[i], i));
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
    order.sort_by(|&a, &b| {
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

/// Parses `x=X (m),y=Y,pwp=PWP` into a column mapping.
pub fn parse_columns_option(s: &str) -> Result<Vec<(Field, String)>, String> {
    s.split(',')
        .filter(|p| !p.trim().is_empty())
        .map(|pair| {
            let (k, v) = pair.split_once('=').ok_or_else(|| format!("`{pair}`: expected field=header"))?;
            let field = Field::from_name(k.trim()).ok_or_else(|| {
                format!("`{k}`: unknown field (known: x y z node region pwp sxx syy szz sxy syz sxz esxx esyy eszz)")
            })?;
            Ok((field, v.trim().to_string()))
        })
        .collect()
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
}
