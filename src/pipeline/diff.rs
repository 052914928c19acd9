//! `a3d-init diff A B`: a semantic diff of Anura3D inputs and a3d-init outputs —
//! GOM and CPS/OPD block by block and keyword by keyword (numbers within
//! `--rtol/--atol`, the rest as text, block order ignored), MAPF and `mps.csv`
//! column statistics with rows matched by position or id. Folders are compared
//! file by file. Exit code 0 when equal within tolerance, 1 when different, 2 on error.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use serde::Serialize;

use super::Verdict;
use crate::formats::cps::CpsDocument;
use crate::formats::gom::GomDocument;
use crate::formats::keyword_doc::{KeywordDocument, read_text};
use crate::formats::lex;

#[derive(Debug, clap::Args)]
pub struct DiffArgs {
    /// First file or project folder.
    pub a: PathBuf,
    /// Second file or project folder.
    pub b: PathBuf,
    /// Relative tolerance for numbers.
    #[arg(long, default_value_t = 1e-9)]
    pub rtol: f64,
    /// Absolute tolerance for numbers.
    #[arg(long, default_value_t = 1e-12)]
    pub atol: f64,
    /// Match table rows by this id column (e.g. `id` in mps.csv) instead of by position.
    #[arg(long, value_name = "COLUMN")]
    pub by: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
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
    } else if name.ends_with(".csv") {
        "table"
    } else {
        "text"
    }
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
    args: &DiffArgs,
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

/// A table as text cells: headers and rows. Comma-separated files (`mps.csv`,
/// FEM tables) are read with the `csv` reader, one `Vec<String>` per record
/// (the columns are whatever the header names); whitespace-separated ones
/// (MAPF) are split on blanks. Cells are trimmed and blank lines skipped.
struct Table {
    headers: Vec<String>,
    rows: Vec<Vec<String>>,
}

fn read_table(path: &Path) -> anyhow::Result<Table> {
    let text = read_text(path)?;
    let Some(header) = text.lines().find(|l| !l.trim().is_empty()) else {
        bail!("{}: empty table", path.display());
    };
    if !header.contains(',') {
        let mut rows = text
            .lines()
            .map(|l| l.split_whitespace().map(str::to_string).collect::<Vec<_>>())
            .filter(|r| !r.is_empty());
        return Ok(Table {
            headers: rows.next().unwrap_or_default(),
            rows: rows.collect(),
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
    let mut next = || -> anyhow::Result<Option<Vec<String>>> {
        rows.next().transpose().map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            anyhow::anyhow!("{}:{line}:1: {e}", path.display())
        })
    };
    let Some(headers) = next()? else {
        bail!("{}: empty table", path.display());
    };
    let mut table = Table {
        headers,
        rows: Vec::new(),
    };
    while let Some(row) = next()? {
        table.rows.push(row);
    }
    Ok(table)
}

fn diff_tables(a: &Path, b: &Path, args: &DiffArgs, out: &mut FileDiff) -> anyhow::Result<()> {
    let ta = read_table(a)?;
    let tb = read_table(b)?;
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
                .ok_or_else(|| anyhow::anyhow!("{}: no column `{col}`", a.display()))?;
            let ib = tb
                .headers
                .iter()
                .position(|h| h == col)
                .ok_or_else(|| anyhow::anyhow!("{}: no column `{col}`", b.display()))?;
            let index: BTreeMap<&str, usize> = tb
                .rows
                .iter()
                .enumerate()
                .filter_map(|(k, r)| r.get(ib).map(|v| (v.as_str(), k)))
                .collect();
            let mut missing = 0;
            let mut pairs = Vec::new();
            for (k, r) in ta.rows.iter().enumerate() {
                match r.get(ia).and_then(|id| index.get(id.as_str())) {
                    Some(&j) => pairs.push((format!("{col} {}", r[ia]), k, j)),
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
            let (x, y) = (
                ta.rows[*i].get(ca).map(String::as_str).unwrap_or(""),
                tb.rows[*j].get(cb).map(String::as_str).unwrap_or(""),
            );
            match (lex::parse_real(x), lex::parse_real(y)) {
                (Some(u), Some(v)) => {
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

fn diff_files(a: &Path, b: &Path, args: &DiffArgs) -> anyhow::Result<FileDiff> {
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
        _ => {
            if crate::formats::input::read_bytes(a)? != crate::formats::input::read_bytes(b)? {
                out.findings
                    .push("contents differ (compared as bytes)".into());
            }
        }
    }
    out.equal = out.findings.is_empty();
    Ok(out)
}

fn files_of(dir: &Path) -> anyhow::Result<BTreeMap<String, PathBuf>> {
    let mut out = BTreeMap::new();
    for entry in std::fs::read_dir(dir).with_context(|| dir.display().to_string())? {
        let p = entry?.path();
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

pub fn run(args: DiffArgs) -> anyhow::Result<()> {
    let mut diffs = Vec::new();
    let mut notes = Vec::new();
    for path in [&args.a, &args.b] {
        if !path.exists() {
            bail!("{}: no such file or folder", path.display());
        }
    }
    match (args.a.is_dir(), args.b.is_dir()) {
        (true, true) => {
            let (fa, fb) = (files_of(&args.a)?, files_of(&args.b)?);
            for (name, pa) in &fa {
                match fb.get(name) {
                    Some(pb) => diffs.push(diff_files(pa, pb, &args)?),
                    None => notes.push(format!("{name}: only in {}", args.a.display())),
                }
            }
            for name in fb.keys().filter(|n| !fa.contains_key(*n)) {
                notes.push(format!("{name}: only in {}", args.b.display()));
            }
        }
        (false, false) => {
            diffs.push(diff_files(&args.a, &args.b, &args)?);
        }
        (a_is_dir, _) => bail!(
            "{} is a folder and {} a file: compare two files or two folders",
            if a_is_dir { &args.a } else { &args.b }.display(),
            if a_is_dir { &args.b } else { &args.a }.display()
        ),
    }
    let equal = notes.is_empty() && diffs.iter().all(|d| d.equal);
    let mut out = std::io::stdout().lock();
    if args.json {
        #[derive(Serialize)]
        struct Json<'a> {
            equal: bool,
            notes: &'a [String],
            files: &'a [FileDiff],
        }
        serde_json::to_writer_pretty(
            &mut out,
            &Json {
                equal,
                notes: &notes,
                files: &diffs,
            },
        )?;
        writeln!(out)?;
    } else {
        for n in &notes {
            writeln!(out, "{n}")?;
        }
        for d in &diffs {
            if d.equal {
                writeln!(
                    out,
                    "= {} ({}): equal within rtol {} / atol {}",
                    d.b.display(),
                    d.kind,
                    args.rtol,
                    args.atol
                )?;
            } else {
                writeln!(
                    out,
                    "≠ {} vs {} ({}):",
                    d.a.display(),
                    d.b.display(),
                    d.kind
                )?;
                for f in &d.findings {
                    writeln!(out, "    {f}")?;
                }
            }
        }
    }
    if equal {
        Ok(())
    } else {
        Err(Verdict {
            message: "differences found".into(),
            code: 1,
        }
        .into())
    }
}
