//! The per-MP CSV table (`mps.csv`, `inspect --mps`). Spec: `formats/mps-csv.md`.
//!
//! Columns: `id,element,material,local,x,y,z,volume`, then, for a mapped state,
//! the pore pressure, total and effective stresses (Anura3D signs, kPa), the
//! degree of saturation and the mapping diagnostics. Ids are 1-based.
//!
//! Each table has a serde row struct (`PlacementRow`, `StateRow`) that the
//! `csv` reader deserialises by position and whose direct writer
//! ([`Row`]) appends what csv + serde would write
//! (tested); numbers go through [`Real`], the
//! shortest round-trip decimals. The chunked, ordered parallel writing lives
//! in [`table_text`](super::table_text).

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::error::{FormatError, ParseError};
use super::table_text::{Real, Row, push_reals, push_u32, write_records};
#[cfg(test)]
use super::table_text::{fmt_f64, push_f64};
use a3d_model::{MaterialPoint, MpState};

/// The writer `csv` + `serde` would use for the tables: no header, no quoting
/// (no field holds a comma, quote or line break), `\n` line endings. The
/// direct writers ([`Row`]) are tested against it (flexible: the test mixes
/// rows of both tables).
#[cfg(test)]
fn csv_writer<W: Write>(out: W) -> csv::Writer<W> {
    csv::WriterBuilder::new()
        .has_headers(false)
        .flexible(true)
        .quote_style(csv::QuoteStyle::Never)
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(out)
}

/// One row of the placement table (`inspect --mps`): the MP's ids (element
/// 1-based), position and volume. The first columns of a [`StateRow`] too.
#[derive(Debug, Serialize, Deserialize)]
struct PlacementRow {
    id: u32,
    element: u32,
    material: u32,
    local: u32,
    x: Real,
    y: Real,
    z: Real,
    volume: Real,
}

impl PlacementRow {
    fn of(p: &MaterialPoint) -> PlacementRow {
        let [x, y, z] = p.position.map(Real);
        PlacementRow {
            id: p.id,
            element: p.element + 1,
            material: p.material,
            local: p.local,
            x,
            y,
            z,
            volume: Real(p.volume),
        }
    }

    fn into_point(self) -> MaterialPoint {
        MaterialPoint {
            id: self.id,
            element: self.element.saturating_sub(1),
            material: self.material,
            local: self.local,
            position: [self.x.0, self.y.0, self.z.0],
            volume: self.volume.0,
        }
    }
}

impl Row for PlacementRow {
    fn push_fields(&self, out: &mut Vec<u8>) {
        for (k, v) in [self.id, self.element, self.material, self.local]
            .into_iter()
            .enumerate()
        {
            if k > 0 {
                out.push(b',');
            }
            push_u32(out, v);
        }
        push_reals(out, &[self.x, self.y, self.z, self.volume]);
    }
}

/// Header of the placement table.
pub const PLACEMENT_HEADER: &str = "id,element,material,local,x,y,z,volume";

/// Writes the placement table: one row per MP.
pub fn write_points(w: &mut dyn Write, points: &[MaterialPoint]) -> std::io::Result<()> {
    writeln!(w, "{PLACEMENT_HEADER}")?;
    write_records(w, points.len(), |i| PlacementRow::of(&points[i]))
}

/// Mapping diagnostics of one MP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MpDiagnostics {
    pub neighbours: u32,
    /// The Shepard ratio Σw·l^dim, where one was computed (written as an
    /// empty cell otherwise).
    pub shepard: Option<f64>,
    /// `mapped`, `nearest` or `skipped`.
    pub status: &'static str,
}

/// Header of the mapped-state table.
pub const STATE_HEADER: &str = "id,element,material,local,x,y,z,volume,pwp,sxx,syy,szz,sxy,syz,sxz,esxx,esyy,eszz,esxy,esyz,esxz,saturation,neighbours,shepard,status";

/// One row of the mapped-state table (`mps.csv`), written by [`write_states`]
/// and read by [`read_states`]: the placement, pwp, total and effective stress
/// (Anura3D signs, kPa), saturation and the mapping diagnostics. The reader
/// needs the columns up to `saturation`; the diagnostics may be missing. The
/// placement is a nested row: `csv` reads and writes it in line, by position.
#[derive(Debug, Serialize, Deserialize)]
struct StateRow<'a> {
    placement: PlacementRow,
    pwp: Real,
    sxx: Real,
    syy: Real,
    szz: Real,
    sxy: Real,
    syz: Real,
    sxz: Real,
    esxx: Real,
    esyy: Real,
    eszz: Real,
    esxy: Real,
    esyz: Real,
    esxz: Real,
    saturation: Real,
    #[serde(default)]
    neighbours: u32,
    #[serde(default)]
    shepard: Option<Real>,
    #[serde(default, borrow)]
    status: &'a str,
}

impl Row for StateRow<'_> {
    fn push_fields(&self, out: &mut Vec<u8>) {
        self.placement.push_fields(out);
        push_reals(out, &[self.pwp]);
        push_reals(out, &self.total());
        push_reals(out, &self.effective());
        push_reals(out, &[self.saturation]);
        out.push(b',');
        push_u32(out, self.neighbours);
        match self.shepard {
            Some(v) => push_reals(out, &[v]),
            None => out.push(b','),
        }
        out.push(b',');
        out.extend_from_slice(self.status.as_bytes());
    }
}

/// Fields a state row needs: every column up to `saturation`.
const STATE_FIELDS_NEEDED: usize = 22;

impl StateRow<'_> {
    fn of(p: &MaterialPoint, s: &MpState, d: &MpDiagnostics) -> StateRow<'static> {
        let [sxx, syy, szz, sxy, syz, sxz] = s.total.map(Real);
        let [esxx, esyy, eszz, esxy, esyz, esxz] = s.effective().map(Real);
        StateRow {
            placement: PlacementRow::of(p),
            pwp: Real(s.pwp),
            sxx,
            syy,
            szz,
            sxy,
            syz,
            sxz,
            esxx,
            esyy,
            eszz,
            esxy,
            esyz,
            esxz,
            saturation: Real(s.saturation),
            neighbours: d.neighbours,
            shepard: d.shepard.map(Real),
            status: d.status,
        }
    }

    /// 0-based field of the first number that is not finite, among the
    /// columns the reader takes (`x` to `saturation`).
    fn first_non_finite(&self) -> Option<usize> {
        let p = &self.placement;
        [p.x, p.y, p.z, p.volume, self.pwp]
            .iter()
            .chain(&self.total())
            .chain(&self.effective())
            .chain([&self.saturation])
            .position(|v| !v.0.is_finite())
            .map(|k| k + 4)
    }

    fn total(&self) -> [Real; 6] {
        [self.sxx, self.syy, self.szz, self.sxy, self.syz, self.sxz]
    }

    fn effective(&self) -> [Real; 6] {
        [
            self.esxx, self.esyy, self.eszz, self.esxy, self.esyz, self.esxz,
        ]
    }

    /// The MP and its state (the effective stresses and diagnostics are
    /// derived data and not read back).
    fn into_model(self) -> (MaterialPoint, MpState) {
        let state = MpState {
            pwp: self.pwp.0,
            total: self.total().map(|v| v.0),
            saturation: self.saturation.0,
        };
        (self.placement.into_point(), state)
    }
}

/// Writes the mapped-state table (`mps.csv`): placement, pwp, total and effective
/// stress (Anura3D signs, kPa), saturation and diagnostics.
pub fn write_states(
    w: &mut dyn Write,
    points: &[MaterialPoint],
    states: &[MpState],
    diagnostics: &[MpDiagnostics],
) -> std::io::Result<()> {
    writeln!(w, "{STATE_HEADER}")?;
    let n = points.len().min(states.len()).min(diagnostics.len());
    write_records(w, n, |i| {
        StateRow::of(&points[i], &states[i], &diagnostics[i])
    })
}

/// A mapped-state table read back whole.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StateTable {
    pub points: Vec<MaterialPoint>,
    pub states: Vec<MpState>,
    /// The mapping diagnostics of each row (zero, empty and empty where the
    /// table has no such columns).
    pub diagnostics: Vec<DiagnosticsRead>,
    /// The 1-based line of each row.
    pub lines: Vec<usize>,
}

/// The diagnostic columns of one row, as read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiagnosticsRead {
    pub neighbours: u32,
    pub shepard: Option<f64>,
    pub status: String,
}

/// Reads a mapped-state table back: (points, states). Positioned errors.
pub fn read_states(path: &Path) -> Result<(Vec<MaterialPoint>, Vec<MpState>), FormatError> {
    read_table(path).map(|t| (t.points, t.states))
}

/// Like [`read_states`], and checks the table against the MPs a model places
/// (`expected`): same count, and row by row the same id, element and position.
/// A mismatch is an error at the row's line.
pub fn read_states_for(
    path: &Path,
    expected: &[MaterialPoint],
) -> Result<(Vec<MaterialPoint>, Vec<MpState>), FormatError> {
    let StateTable {
        points,
        states,
        lines,
        ..
    } = read_table(path)?;
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

/// Reads a mapped-state table back whole (`mps.csv`, `verify/start.csv` of a
/// model whose MPs are all finite). Positioned errors.
pub fn read_table(path: &Path) -> Result<StateTable, FormatError> {
    let text = super::keyword_doc::read_text(path)?;
    let header = text.lines().next().map(str::trim).unwrap_or("");
    if !header.starts_with("id,element,material,local,x,y,z,volume,pwp,sxx") {
        return Err(ParseError::at(
            path,
            1,
            1,
            format!("not an a3d-init MP state table: expected the header `{STATE_HEADER}`"),
        )
        .into());
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut table = StateTable::default();
    let mut record = csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => return Err(csv_error(path, e, None).into()),
        }
        if record.iter().all(str::is_empty) {
            continue;
        }
        let line = record.position().map_or(0, |p| p.line() as usize);
        if record.len() < STATE_FIELDS_NEEDED {
            return Err(ParseError::at(
                path,
                line,
                // Just past the line's last character.
                column(&record, record.len()) - 1,
                format!(
                    "expected at least {STATE_FIELDS_NEEDED} fields, found {}",
                    record.len()
                ),
            )
            .into());
        }
        let row: StateRow = record
            .deserialize(None)
            .map_err(|e| csv_error(path, e, Some(&record)))?;
        if let Some(k) = row.first_non_finite() {
            return Err(field_error(path, line, &record, k, "expected a finite number").into());
        }
        table.diagnostics.push(DiagnosticsRead {
            neighbours: row.neighbours,
            shepard: row.shepard.map(|v| v.0),
            status: row.status.to_string(),
        });
        let (point, state) = row.into_model();
        table.points.push(point);
        table.states.push(state);
        table.lines.push(line);
    }
    Ok(table)
}

/// A csv error as a positioned error: the record's line, and with `record`
/// the field that failed.
fn csv_error(path: &Path, e: csv::Error, record: Option<&csv::StringRecord>) -> ParseError {
    let line = e.position().map_or(0, |p| p.line() as usize);
    let csv::ErrorKind::Deserialize { err, .. } = e.kind() else {
        return ParseError::at(path, line, 1, e.to_string());
    };
    let (Some(k), Some(record)) = (err.field(), record) else {
        return ParseError::at(path, line, 1, err.to_string());
    };
    let expected = match err.kind() {
        csv::DeserializeErrorKind::ParseInt(_) => "expected an integer",
        _ => "expected a finite number",
    };
    field_error(path, line, record, k as usize, expected)
}

/// 1-based column of field `k` (0-based) of `record`: the characters of the
/// fields and commas before it.
fn column(record: &csv::StringRecord, k: usize) -> usize {
    record
        .iter()
        .take(k)
        .map(|s| s.chars().count() + 1)
        .sum::<usize>()
        + 1
}

/// `field N: expected …, found `…`` at field `k` (0-based) of `record`.
fn field_error(
    path: &Path,
    line: usize,
    record: &csv::StringRecord,
    k: usize,
    expected: &str,
) -> ParseError {
    let found = record.get(k).unwrap_or("");
    ParseError::at(
        path,
        line,
        column(record, k),
        format!("field {}: {expected}, found `{found}`", k + 1),
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
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
            (1e16, "1e16"),
            (-1.5e20, "-1.5e20"),
            (1.2345678901234567e300, "1.2345678901234567e300"),
            (123456789012345.6, "123456789012345.6"),
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
                shepard: Some(1.0 / (i as f64 + 3.0)),
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

    /// The direct writers append exactly what csv + serde write for the
    /// same row structs (the reader's view of the columns).
    #[test]
    fn direct_rows_equal_the_csv_serde_rows() {
        let (points, states) = sample(3000, 11);
        let statuses = ["mapped", "nearest", "skipped"];
        let mut direct = Vec::new();
        let mut w = csv_writer(Vec::new());
        for (i, (p, s)) in points.iter().zip(&states).enumerate() {
            let d = MpDiagnostics {
                neighbours: [0, 7, u32::MAX][i % 3],
                shepard: [Some(0.0), Some(1.0 / 3.0), None][i % 3],
                status: statuses[i % 3],
            };
            let row = StateRow::of(p, s, &d);
            row.push_fields(&mut direct);
            direct.push(b'\n');
            w.serialize(row).unwrap();
            let placement = PlacementRow::of(p);
            placement.push_fields(&mut direct);
            direct.push(b'\n');
            w.serialize(placement).unwrap();
        }
        let via_csv = w.into_inner().unwrap();
        assert_eq!(
            String::from_utf8(direct).unwrap(),
            String::from_utf8(via_csv).unwrap()
        );
    }

    #[test]
    fn headers_name_the_row_structs_fields() {
        let (points, states) = sample(1, 1);
        let d = MpDiagnostics {
            neighbours: 1,
            shepard: Some(1.0),
            status: "mapped",
        };
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(PlacementRow::of(&points[0])).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(text.lines().next().unwrap(), PLACEMENT_HEADER);
        // The nested placement has no header of its own: the state header
        // starts with the placement's and has a column per field.
        assert!(STATE_HEADER.starts_with(PLACEMENT_HEADER));
        let mut w = csv_writer(Vec::new());
        w.serialize(StateRow::of(&points[0], &states[0], &d))
            .unwrap();
        let row = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(row.split(',').count(), STATE_HEADER.split(',').count());
    }

    #[test]
    fn reader_skips_blank_lines_and_takes_short_and_long_rows() {
        let (points, states) = sample(3, 2);
        let mut table = states_table(&points, &states, 1);
        let text = String::from_utf8(table.clone()).unwrap();
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        // Row 1 without the diagnostics, row 2 with an extra field, blank lines between.
        lines[1] = lines[1].split(',').take(22).collect::<Vec<_>>().join(",");
        lines[2].push_str(",extra");
        lines.insert(2, String::new());
        lines.insert(3, "   ".into());
        table = lines.join("\n").into_bytes();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mps.csv");
        std::fs::write(&path, &table).unwrap();
        let t = read_table(&path).unwrap();
        assert_eq!(t.points.len(), 3);
        assert_eq!(t.states.len(), 3);
        assert_eq!(t.lines, vec![2, 5, 6]);
        assert_eq!(t.diagnostics[0], DiagnosticsRead::default());
    }

    #[test]
    fn reader_errors_name_line_column_and_field() {
        let good = "id,element,material,local,x,y,z,volume,pwp,sxx,syy,szz,sxy,syz,sxz,esxx,esyy,eszz,esxy,esyz,esxz,saturation\n";
        let row = "1,1,1,1,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,1";
        let cases = [
            (
                "x,1,1,1,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,1",
                "t.csv:2:1: field 1: expected an integer, found `x`",
            ),
            (
                "1,1,1,1,0,0,0,1,NaN,0,0,0,0,0,0,0,0,0,0,0,0,1",
                "t.csv:2:17: field 9: expected a finite number, found `NaN`",
            ),
            (
                "1,1,1,1,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0",
                "t.csv:2:42: expected at least 22 fields, found 21",
            ),
        ];
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        std::fs::write(&path, format!("{good}{row}\n")).unwrap();
        assert_eq!(read_states(&path).unwrap().0.len(), 1);
        for (bad, expected) in cases {
            std::fs::write(&path, format!("{good}{bad}\n")).unwrap();
            let e = read_states(&path).unwrap_err().to_string();
            assert!(e.ends_with(expected), "{e}\nexpected: {expected}");
        }
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
