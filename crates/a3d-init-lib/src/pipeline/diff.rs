//! `diff` as a library call: a semantic diff of Anura3D inputs and a3d-init
//! outputs — GOM and CPS/OPD block by block and keyword by keyword (numbers
//! within the tolerances, the rest as text, block order ignored), MAPF and
//! `mps.csv` column statistics with rows matched by position or id. Folders are
//! compared file by file. The MAPF and `mps.csv` are read by the same readers
//! `verify` uses ([`crate::formats::mapf::read`],
//! [`crate::formats::mps_table::read_table`]); other CSV tables as text cells.
//! A CB-Geo project's particle stresses and pore pressures are tables by the
//! readers of [`crate::formats::cbgeo::text`], its run file (and any JSON) is
//! compared value by value, numbers within the tolerances.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::PipelineError;
use crate::formats::cps::CpsDocument;
use crate::formats::gom::GomDocument;
use crate::formats::keyword_doc::{KeywordDocument, read_text};
use crate::formats::{lex, mapf, mps_table};

/// Tolerances and row matching of a diff.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffOptions {
    /// Relative tolerance for numbers.
    pub rtol: f64,
    /// Absolute tolerance for numbers.
    pub atol: f64,
    /// Match table rows by this id column (e.g. `id` in mps.csv) instead of
    /// by position.
    pub by: Option<String>,
}

impl Default for DiffOptions {
    fn default() -> Self {
        DiffOptions {
            rtol: 1e-9,
            atol: 1e-12,
            by: None,
        }
    }
}

/// The comparison of one pair of files.
#[derive(Debug, Serialize, Default)]
pub struct FileDiff {
    /// The first file.
    pub a: PathBuf,
    /// The second file.
    pub b: PathBuf,
    /// How the pair was compared, from the first file's name: `gom`, `cps`,
    /// `opd`, `mapf`, `table` (a CSV) or `text`.
    pub kind: &'static str,
    /// Equal within `--rtol`/`--atol`.
    pub equal: bool,
    /// Human-readable findings, most important first.
    pub findings: Vec<String>,
    /// Column statistics of a MAPF or CSV table (empty for other kinds).
    pub columns: Vec<ColumnStats>,
}

/// How one column of two tables differs, over the matched rows.
#[derive(Debug, Serialize, Clone)]
pub struct ColumnStats {
    /// The column's header.
    pub column: String,
    /// Largest |a − b|.
    pub max_abs: f64,
    /// Mean |a − b|.
    pub mean_abs: f64,
    /// Root mean square of a − b.
    pub rms: f64,
    /// Rows whose difference is over the tolerance.
    pub over_tolerance: usize,
    /// (row or id, a, b) of the worst rows.
    pub worst: Vec<(String, f64, f64)>,
}

fn kind_of(path: &Path) -> &'static str {
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    if name.contains(".GOM") || name.ends_with("-2.dat") {
        "gom"
    } else if name.contains(".CPS_") {
        "cps"
    } else if name.contains(".OPD_") {
        "opd"
    } else if name.ends_with(".MAPF") {
        "mapf"
    } else if name.ends_with(".txt") && name.contains("stresses") {
        "cbgeo-stresses"
    } else if name.ends_with(".txt") && name.contains("pore-pressure") {
        "cbgeo-pore-pressures"
    } else if name.ends_with(".txt") {
        // A CB-Geo mesh, particle coordinates, constraints: compared as bytes.
        "cbgeo-file"
    } else if name.ends_with(".json") && name != "report.json" {
        "json"
    } else if name.ends_with(".csv") {
        "table"
    } else {
        "text"
    }
}

fn no_column(path: &Path, column: &str) -> PipelineError {
    PipelineError::Option(format!(
        "{}: no column `{column}` to match rows by",
        path.display()
    ))
}

fn close(a: f64, b: f64, rtol: f64, atol: f64) -> bool {
    (a - b).abs() <= atol + rtol * a.abs().max(b.abs())
}

/// Blocks keyed by (keyword, occurrence) so that reordering does not matter.
fn keyed_blocks(doc: &KeywordDocument, fold_case: bool) -> BTreeMap<(String, usize), Vec<String>> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeMap::new();
    for (i, block) in doc.blocks().iter().enumerate() {
        let key = if fold_case {
            block.keyword.to_ascii_uppercase()
        } else {
            block.keyword.clone()
        };
        let n = seen.entry(key.clone()).or_insert(0);
        let lines: Vec<String> = doc
            .data_lines(i)
            .into_iter()
            .map(|l| l.trim().to_string())
            .filter(|l| !l.is_empty())
            .collect();
        out.insert((key, *n), lines);
        *n += 1;
    }
    out
}

fn diff_documents(
    a: &KeywordDocument,
    b: &KeywordDocument,
    fold_case: bool,
    args: &DiffOptions,
    out: &mut FileDiff,
) {
    if a.version() != b.version() {
        out.findings
            .push(format!("version: {} → {}", a.version(), b.version()));
    }
    let ka = keyed_blocks(a, fold_case);
    let kb = keyed_blocks(b, fold_case);
    for (key, la) in &ka {
        let label = if key.1 > 0 {
            format!("{} (#{})", key.0, key.1 + 1)
        } else {
            key.0.clone()
        };
        let Some(lb) = kb.get(key) else {
            out.findings.push(format!("{label}: only in A"));
            continue;
        };
        if la.len() != lb.len() {
            out.findings
                .push(format!("{label}: {} → {} data lines", la.len(), lb.len()));
        }
        let (mut text_changes, mut num_changes, mut worst) = (0usize, 0usize, 0.0f64);
        let mut first: Option<String> = None;
        for (x, y) in la.iter().zip(lb) {
            let tx: Vec<&str> = lex::tokens(x).map(|t| t.1).collect();
            let ty: Vec<&str> = lex::tokens(y).map(|t| t.1).collect();
            let mut line_differs = tx.len() != ty.len();
            for (p, q) in tx.iter().zip(&ty) {
                match (lex::parse_real(p), lex::parse_real(q)) {
                    (Some(u), Some(v)) if !close(u, v, args.rtol, args.atol) => {
                        num_changes += 1;
                        worst = worst.max((u - v).abs());
                        line_differs = true;
                    }
                    // Numbers within tolerance are equal, however they are written.
                    (Some(_), Some(_)) => {}
                    _ if p != q => {
                        text_changes += 1;
                        line_differs = true;
                    }
                    _ => {}
                }
            }
            if line_differs && first.is_none() {
                first = Some(format!("`{x}` → `{y}`"));
            }
        }
        if text_changes + num_changes > 0 {
            out.findings.push(format!(
                "{label}: {num_changes} number(s) beyond tolerance (max |Δ| = {worst:.6e}), {text_changes} text change(s); first: {}",
                first.unwrap_or_default()
            ));
        }
    }
    for key in kb.keys() {
        if !ka.contains_key(key) {
            let label = if key.1 > 0 {
                format!("{} (#{})", key.0, key.1 + 1)
            } else {
                key.0.clone()
            };
            out.findings.push(format!("{label}: only in B"));
        }
    }
}

/// A table's cell: a number, or text where a reader keeps text.
#[derive(Clone, Debug, PartialEq)]
enum Cell {
    Num(f64),
    Text(String),
}

impl Cell {
    fn text(cell: &str) -> Cell {
        lex::parse_real(cell).map_or_else(|| Cell::Text(cell.to_string()), Cell::Num)
    }

    fn label(&self) -> String {
        match self {
            Cell::Num(v) => v.to_string(),
            Cell::Text(t) => t.clone(),
        }
    }
}

/// A table: headers and rows of cells.
struct Table {
    headers: Vec<String>,
    rows: Vec<Vec<Cell>>,
}

/// A MAPF, through the reader `verify` uses.
fn read_mapf(path: &Path) -> Result<Table, PipelineError> {
    let table = mapf::read(path)?;
    Ok(Table {
        headers: table.headers,
        rows: table
            .rows
            .into_iter()
            .map(|r| r.into_iter().map(Cell::Num).collect())
            .collect(),
    })
}

/// An `mps.csv`, through the reader `verify` uses: every column it reads (the
/// effective stresses are derived from these and not read back).
fn read_mps(path: &Path) -> Result<Table, PipelineError> {
    let t = mps_table::read_table(path)?;
    let headers = "id,element,material,local,x,y,z,volume,pwp,sxx,syy,szz,sxy,syz,sxz,saturation,neighbours,shepard,status";
    let rows = t
        .points
        .iter()
        .zip(&t.states)
        .zip(&t.diagnostics)
        .map(|((p, s), d)| {
            let mut row: Vec<Cell> = [p.id, p.element + 1, p.material, p.local]
                .into_iter()
                .map(|v| Cell::Num(f64::from(v)))
                .collect();
            row.extend(
                p.position
                    .iter()
                    .chain([&p.volume, &s.pwp])
                    .map(|&v| Cell::Num(v)),
            );
            row.extend(s.total.iter().chain([&s.saturation]).map(|&v| Cell::Num(v)));
            row.push(Cell::Num(f64::from(d.neighbours)));
            row.push(
                d.shepard
                    .map_or_else(|| Cell::Text(String::new()), Cell::Num),
            );
            row.push(Cell::Text(d.status.clone()));
            row
        })
        .collect();
    Ok(Table {
        headers: headers.split(',').map(str::to_string).collect(),
        rows,
    })
}

/// Any other table as text cells: comma-separated files are read with the
/// `csv` reader, one record per row (the columns are whatever the header
/// names); whitespace-separated ones are split on blanks. Cells are trimmed
/// and blank lines skipped.
fn read_text_table(path: &Path) -> Result<Table, PipelineError> {
    let empty = || PipelineError::Input(format!("{}: empty table", path.display()));
    let text = read_text(path)?;
    let Some(header) = text.lines().find(|l| !l.trim().is_empty()) else {
        return Err(empty());
    };
    let cells = |r: Vec<String>| r.iter().map(|c| Cell::text(c)).collect();
    if !header.contains(',') {
        let mut rows = text
            .lines()
            .map(|l| l.split_whitespace().map(str::to_string).collect::<Vec<_>>())
            .filter(|r| !r.is_empty());
        return Ok(Table {
            headers: rows.next().unwrap_or_default(),
            rows: rows.map(cells).collect(),
        });
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut rows = reader.deserialize::<Vec<String>>().filter(|row| {
        row.as_ref()
            .map_or(true, |cells| cells.iter().any(|c| !c.is_empty()))
    });
    let mut next = || -> Result<Option<Vec<String>>, PipelineError> {
        rows.next().transpose().map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            PipelineError::Positioned(format!("{}:{line}:1: {e}", path.display()))
        })
    };
    let Some(headers) = next()? else {
        return Err(empty());
    };
    let mut table = Table {
        headers,
        rows: Vec::new(),
    };
    while let Some(row) = next()? {
        table.rows.push(cells(row));
    }
    Ok(table)
}

/// A CB-Geo particle stresses file (`sxx … sxz` per particle) or pore
/// pressure file (`id p`), through the readers `map`'s files are tested with.
fn read_cbgeo(path: &Path, kind: &str) -> Result<Table, PipelineError> {
    use crate::formats::cbgeo::text;
    let t = read_text(path)?;
    let parse = |e| crate::formats::FormatError::from(e);
    if kind == "cbgeo-stresses" {
        let rows = text::read_stresses(path, &t).map_err(parse)?;
        Ok(Table {
            headers: ["sxx", "syy", "szz", "sxy", "syz", "sxz"]
                .map(String::from)
                .to_vec(),
            rows: rows
                .iter()
                .map(|r| r.iter().map(|&v| Cell::Num(v)).collect())
                .collect(),
        })
    } else {
        let rows = text::read_id_values(path, &t).map_err(parse)?;
        Ok(Table {
            headers: vec!["id".into(), "p".into()],
            rows: rows
                .iter()
                .map(|&(id, v)| vec![Cell::Num(id as f64), Cell::Num(v)])
                .collect(),
        })
    }
}

/// The places where two JSON values differ (`mesh.particles_stresses`,
/// `materials[0].density: 2000 → 2100`), numbers within the tolerances; at
/// most `room` of them.
fn json_differences(
    path: &str,
    a: &serde_json::Value,
    b: &serde_json::Value,
    args: &DiffOptions,
    out: &mut Vec<String>,
) {
    use serde_json::Value;
    const ROOM: usize = 50;
    if out.len() >= ROOM {
        return;
    }
    let at = |p: &str| {
        if p.is_empty() {
            "(the whole file)".to_string()
        } else {
            p.to_string()
        }
    };
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            for (k, va) in x {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                match y.get(k) {
                    Some(vb) => json_differences(&p, va, vb, args, out),
                    None => out.push(format!("{p}: only in the first")),
                }
            }
            for k in y.keys().filter(|k| !x.contains_key(*k)) {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                out.push(format!("{p}: only in the second"));
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (i, (va, vb)) in x.iter().zip(y).enumerate() {
                json_differences(&format!("{path}[{i}]"), va, vb, args, out);
            }
        }
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
            );
            if !close(x, y, args.rtol, args.atol) {
                out.push(format!("{}: {x} → {y}", at(path)));
            }
        }
        _ if a != b => out.push(format!("{}: {a} → {b}", at(path))),
        _ => {}
    }
}

/// Two JSON files compared value by value.
fn diff_json(
    a: &Path,
    b: &Path,
    args: &DiffOptions,
    out: &mut FileDiff,
) -> Result<(), PipelineError> {
    let value = |p: &Path| -> Result<serde_json::Value, PipelineError> {
        let t = read_text(p)?;
        // The positioned reader first, so that a bad file gets its place.
        crate::formats::cbgeo::json::parse(p, &t).map_err(crate::formats::FormatError::from)?;
        serde_json::from_str(&t).map_err(|e| {
            PipelineError::Positioned(format!("{}:{}:{}: {e}", p.display(), e.line(), e.column()))
        })
    };
    json_differences("", &value(a)?, &value(b)?, args, &mut out.findings);
    Ok(())
}

/// The table at `path`, by the reader its kind takes.
fn read_table(path: &Path, kind: &str) -> Result<Table, PipelineError> {
    if kind == "mapf" {
        read_mapf(path)
    } else if kind.starts_with("cbgeo-") {
        read_cbgeo(path, kind)
    } else if path.file_name().is_some_and(|n| n == "mps.csv") {
        read_mps(path)
    } else {
        read_text_table(path)
    }
}

fn diff_tables(
    a: &Path,
    b: &Path,
    args: &DiffOptions,
    out: &mut FileDiff,
) -> Result<(), PipelineError> {
    let ta = read_table(a, out.kind)?;
    let tb = read_table(b, out.kind)?;
    if ta.headers != tb.headers {
        out.findings.push(format!(
            "columns: [{}] → [{}]",
            ta.headers.join(" "),
            tb.headers.join(" ")
        ));
    }
    if ta.rows.len() != tb.rows.len() {
        out.findings
            .push(format!("rows: {} → {}", ta.rows.len(), tb.rows.len()));
    }
    // Row pairing: by position, or by an id column.
    let pairs: Vec<(String, usize, usize)> = match &args.by {
        Some(col) => {
            let ia = ta
                .headers
                .iter()
                .position(|h| h == col)
                .ok_or_else(|| no_column(a, col))?;
            let ib = tb
                .headers
                .iter()
                .position(|h| h == col)
                .ok_or_else(|| no_column(b, col))?;
            let index: BTreeMap<String, usize> = tb
                .rows
                .iter()
                .enumerate()
                .filter_map(|(k, r)| r.get(ib).map(|v| (v.label(), k)))
                .collect();
            let mut missing = 0;
            let mut pairs = Vec::new();
            for (k, r) in ta.rows.iter().enumerate() {
                match r.get(ia).and_then(|id| index.get(&id.label())) {
                    Some(&j) => pairs.push((format!("{col} {}", r[ia].label()), k, j)),
                    None => missing += 1,
                }
            }
            if missing > 0 {
                out.findings
                    .push(format!("{missing} row(s) of A have no `{col}` match in B"));
            }
            pairs
        }
        None => (0..ta.rows.len().min(tb.rows.len()))
            .map(|k| (format!("row {}", k + 1), k, k))
            .collect(),
    };
    for (ca, name) in ta.headers.iter().enumerate() {
        let Some(cb) = tb.headers.iter().position(|h| h == name) else {
            continue;
        };
        let mut stats = ColumnStats {
            column: name.clone(),
            max_abs: 0.0,
            mean_abs: 0.0,
            rms: 0.0,
            over_tolerance: 0,
            worst: Vec::new(),
        };
        let mut diffs: Vec<(f64, String, f64, f64)> = Vec::new();
        let mut text_changes = 0;
        for (label, i, j) in &pairs {
            let none = Cell::Text(String::new());
            let (x, y) = (
                ta.rows[*i].get(ca).unwrap_or(&none),
                tb.rows[*j].get(cb).unwrap_or(&none),
            );
            match (x, y) {
                (&Cell::Num(u), &Cell::Num(v)) => {
                    let d = (u - v).abs();
                    stats.max_abs = stats.max_abs.max(d);
                    stats.mean_abs += d;
                    stats.rms += d * d;
                    if !close(u, v, args.rtol, args.atol) {
                        stats.over_tolerance += 1;
                        diffs.push((d, label.clone(), u, v));
                    }
                }
                _ if x != y => text_changes += 1,
                _ => {}
            }
        }
        let n = pairs.len().max(1) as f64;
        stats.mean_abs /= n;
        stats.rms = (stats.rms / n).sqrt();
        diffs.sort_by(|p, q| q.0.total_cmp(&p.0).then(p.1.cmp(&q.1)));
        stats.worst = diffs
            .iter()
            .take(5)
            .map(|(_, l, u, v)| (l.clone(), *u, *v))
            .collect();
        if stats.over_tolerance > 0 {
            out.findings.push(format!(
                "{name}: {} value(s) beyond tolerance, max |Δ| = {:.6e}, mean {:.3e}, RMS {:.3e}; worst: {}",
                stats.over_tolerance,
                stats.max_abs,
                stats.mean_abs,
                stats.rms,
                stats.worst.iter().map(|(l, u, v)| format!("{l}: {u} → {v}")).collect::<Vec<_>>().join(", ")
            ));
        }
        if text_changes > 0 {
            out.findings
                .push(format!("{name}: {text_changes} text value(s) differ"));
        }
        out.columns.push(stats);
    }
    Ok(())
}

fn diff_files(a: &Path, b: &Path, args: &DiffOptions) -> Result<FileDiff, PipelineError> {
    let kind = kind_of(a);
    let mut out = FileDiff {
        a: a.to_path_buf(),
        b: b.to_path_buf(),
        kind,
        ..FileDiff::default()
    };
    match kind {
        "gom" => {
            let (da, db) = (GomDocument::read(a)?, GomDocument::read(b)?);
            // Counts first: a mesh change is summarised, not dumped.
            if let (Ok((ma, _)), Ok((mb, _))) = (da.model(), db.model())
                && (ma.mesh.n_nodes() != mb.mesh.n_nodes()
                    || ma.mesh.n_elements() != mb.mesh.n_elements())
            {
                out.findings.push(format!(
                    "mesh: {} nodes / {} elements → {} nodes / {} elements",
                    ma.mesh.n_nodes(),
                    ma.mesh.n_elements(),
                    mb.mesh.n_nodes(),
                    mb.mesh.n_elements()
                ));
            }
            diff_documents(da.document(), db.document(), false, args, &mut out);
        }
        "cps" | "opd" => {
            let read = if kind == "cps" {
                CpsDocument::read
            } else {
                CpsDocument::read_opd
            };
            diff_documents(
                read(a)?.document(),
                read(b)?.document(),
                true,
                args,
                &mut out,
            );
        }
        "mapf" | "table" => diff_tables(a, b, args, &mut out)?,
        // Named like CB-Geo's particle files: tables when they read as such,
        // else compared as bytes (a model's own `*pore-pressure*.txt` of
        // another layout is not an error).
        "cbgeo-stresses" | "cbgeo-pore-pressures" => {
            if diff_tables(a, b, args, &mut out).is_err() {
                out.kind = "text";
                out.findings.clear();
                diff_bytes(a, b, &mut out)?;
            }
        }
        "json" => diff_json(a, b, args, &mut out)?,
        _ => diff_bytes(a, b, &mut out)?,
    }
    out.equal = out.findings.is_empty();
    Ok(out)
}

fn diff_bytes(a: &Path, b: &Path, out: &mut FileDiff) -> Result<(), PipelineError> {
    if crate::formats::input::read_bytes(a)? != crate::formats::input::read_bytes(b)? {
        out.findings
            .push("contents differ (compared as bytes)".into());
    }
    Ok(())
}

fn files_of(dir: &Path) -> Result<BTreeMap<String, PathBuf>, PipelineError> {
    let listing = |e: std::io::Error| PipelineError::Input(format!("{}: {e}", dir.display()));
    let mut out = BTreeMap::new();
    for entry in std::fs::read_dir(dir).map_err(listing)? {
        let p = entry.map_err(listing)?.path();
        if p.is_file() {
            let name = p
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            if kind_of(&p) != "text" {
                out.insert(name, p);
            }
        }
    }
    Ok(out)
}

/// The comparison of two files or two folders.
#[derive(Debug, Serialize, Default)]
pub struct DiffReport {
    /// Equal within the tolerances, and the same files in both folders.
    pub equal: bool,
    /// Files only in one of two folders.
    pub notes: Vec<String>,
    /// One comparison per pair of files.
    pub files: Vec<FileDiff>,
}

/// Compares two files, or two folders file by file (the files both hold; a
/// file only in one is a note). Differences are in the report, not errors.
pub fn diff(a: &Path, b: &Path, options: &DiffOptions) -> Result<DiffReport, PipelineError> {
    let mut files = Vec::new();
    let mut notes = Vec::new();
    for path in [a, b] {
        // The reason itself where it is not a missing path (a symlink loop,
        // a folder it may not read).
        match std::fs::metadata(path) {
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(PipelineError::Input(format!(
                    "{}: no such file or folder",
                    path.display()
                )));
            }
            Err(e) => {
                return Err(PipelineError::Input(format!("{}: {e}", path.display())));
            }
        }
    }
    match (a.is_dir(), b.is_dir()) {
        (true, true) => {
            let (fa, fb) = (files_of(a)?, files_of(b)?);
            for (name, pa) in &fa {
                match fb.get(name) {
                    Some(pb) => files.push(diff_files(pa, pb, options)?),
                    None => notes.push(format!("{name}: only in {}", a.display())),
                }
            }
            for name in fb.keys().filter(|n| !fa.contains_key(*n)) {
                notes.push(format!("{name}: only in {}", b.display()));
            }
        }
        (false, false) => files.push(diff_files(a, b, options)?),
        (a_is_dir, _) => {
            return Err(PipelineError::Input(format!(
                "{} is a folder and {} a file: compare two files or two folders",
                if a_is_dir { a } else { b }.display(),
                if a_is_dir { b } else { a }.display()
            )));
        }
    }
    Ok(DiffReport {
        equal: notes.is_empty() && files.iter().all(|d| d.equal),
        notes,
        files,
    })
}
