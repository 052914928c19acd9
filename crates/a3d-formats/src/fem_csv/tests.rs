//! Unit tests of the FEM CSV reader: header synonyms, chunking independence,
//! fast path against the field-by-field path, error cuts and positioned errors.

use std::path::Path;

use super::dialect::Delimiter;
use super::fast::fast_row;
use super::headers::strip_unit_suffix;
use super::rows::slow_row;
use super::schema::{Rows, Schema};
use super::table::{Sizes, parse_csv_stream};
use super::*;
use crate::extent::{far_outlier, first_coincident};
use crate::fem::SignConvention;
use a3d_model::{Quantity, StressComponent};

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
        // Greek letters and primes (effective), as tables written by hand
        // or by other programs spell them.
        (
            "σ'xx [kN/m²]",
            Field::Value(Quantity::EffectiveStress(StressComponent::Xx)),
        ),
        (
            "σ′_yy (kPa)",
            Field::Value(Quantity::EffectiveStress(StressComponent::Yy)),
        ),
        (
            "σ_zz'",
            Field::Value(Quantity::EffectiveStress(StressComponent::Zz)),
        ),
        (
            "σxx",
            Field::Value(Quantity::TotalStress(StressComponent::Xx)),
        ),
        (
            "τxy [kPa]",
            Field::Value(Quantity::TotalStress(StressComponent::Xy)),
        ),
        (
            "σ'xy",
            Field::Value(Quantity::TotalStress(StressComponent::Xy)),
        ),
        (
            "Σyz",
            Field::Value(Quantity::TotalStress(StressComponent::Yz)),
        ),
    ] {
        assert_eq!(
            synonym(&strip_unit_suffix(&normalise(header), header)),
            Some(field),
            "{header}"
        );
    }
}

/// Parses `text` read in blocks of `chunk` bytes, parsed in chunks of as
/// many (1 MiB: one block, one chunk for the tables here).
fn parse(text: &str, chunk: usize) -> Result<(FemNodes, FemReadReport), String> {
    parse_bytes(text.as_bytes(), chunk)
}

fn parse_bytes(bytes: &[u8], chunk: usize) -> Result<(FemNodes, FemReadReport), String> {
    let mut reader = bytes;
    let sizes = Sizes {
        block: chunk,
        chunk,
    };
    parse_csv_stream(
        Path::new("t.csv"),
        &mut reader,
        (bytes.len() as u64, u64::MAX),
        &CsvOptions::default(),
        sizes,
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
            let mut fast = Rows::new(&schema, 0);
            let mut slow = Rows::new(&schema, 0);
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
    // Fewer fields than the header while other rows fill the column.
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
            .starts_with("t.csv:1:1: the column mapping gives header `A`"),
        "{e}"
    );
}

/// An empty or blank `Node` cell silently took the row number as its id
/// (with `--fem-mesh`, another node's coordinates). A partly empty id column
/// is an error at the empty cell, from the fast and the field-by-field row
/// paths alike and for any chunking; a wholly empty one numbers rows, with a
/// warning, where the table has coordinates.
#[test]
fn empty_node_id_is_a_positioned_error_not_the_row_number() {
    for (table, expected) in [
        // Fast-path rows around the empty cell.
        (
            "X,Y,Node,PWP\n0,0,1,5\n1,0,,6\n0,1,3,7\n",
            "t.csv:3:5: empty node id in `Node`: other rows have ids",
        ),
        ("X,Y,Node,PWP\n0,0,1,5\n1,0,  ,6\n0,1,3,7\n", "t.csv:3:5: "),
        (
            "X,Y,Node,PWP\n0,0,1,5\n1,0,\"\",6\n0,1,3,7\n",
            "t.csv:3:5: ",
        ),
        // Rows only the field-by-field path reads (non-ASCII, CRLF).
        (
            "X,Y,Node,Region\n0,0,1,sand\n1,0,,argile é\n0,1,3,clay\n",
            "t.csv:3:5: ",
        ),
        ("Node,PWP\r\n1,1\r\n ,2\r\n3,3\r\n", "t.csv:3:1: "),
        // The first row without an id, later rows with.
        ("Node;PWP\n;1\n2;2\n", "t.csv:2:1: "),
    ] {
        for chunk in [1, 4, 1 << 20] {
            let e = parse(table, chunk).unwrap_err();
            assert!(e.starts_with(expected), "{table:?} chunk {chunk}: {e}");
        }
    }
    // Each path on its own: the fast path hands the row over, the slow path
    // records the cell.
    let values = [(3, Quantity::Pwp)];
    let factors = [1.0; 4];
    let schema = Schema {
        path: Path::new("t.csv"),
        delim: Delimiter::Byte(b','),
        decimal_comma: false,
        coords: [Some(0), Some(1), None],
        node: Some(2),
        region: None,
        value_cols: &values,
        factors: &factors,
    };
    for line in ["1,0,,6", "1,0, ,6"] {
        let mut rows = Rows::new(&schema, 0);
        let (mut ranges, mut scratch) = (Vec::new(), Vec::new());
        assert!(!fast_row(
            &schema,
            line,
            3,
            &mut ranges,
            &mut scratch,
            &mut rows
        ));
        assert!(rows.ids.is_empty());
        slow_row(&schema, line, 3, &mut rows);
        assert_eq!(rows.first_empty_id, Some((3, 5)), "{line:?}");
    }
    // No id in any row: rows are numbered, with a warning, when coordinates
    // place them; without coordinates the rows cannot be joined to a mesh.
    let (nodes, report) = parse("X,Y,Node,PWP\n0,0,,1\n1,0,,2\n0,1,,3\n", 4).unwrap();
    assert_eq!(nodes.ids, [1, 2, 3]);
    assert!(
        report.warnings[0].contains("`Node` has no values in any row"),
        "{:?}",
        report.warnings
    );
    let e = parse("Node,PWP\n,1\n,2\n", 4).unwrap_err();
    assert!(
        e.starts_with("t.csv:1:1: column `Node` has no node ids"),
        "{e}"
    );
}

/// Coincident mesh nodes: the duplicate check shared by tables and
/// meshes finds a pair within 1e-9 of the diagonal on every axis and never a
/// false pair on a structured grid (whose columns share an x); a node
/// 10^6 spreads away from the others is found by `far_outlier`.
#[test]
fn first_coincident_finds_pairs_and_only_pairs() {
    let mut grid: Vec<[f64; 3]> = Vec::new();
    for j in 0..300 {
        for i in 0..300 {
            grid.push([i as f64 * 0.5, j as f64 * 0.5, 0.0]);
        }
    }
    assert_eq!(first_coincident(&grid), None);
    // Beside far outliers the pairs are found still (no overflow), but every
    // pair is within 1e-9 of such a diagonal: `far_outlier` refuses these first.
    let mut with_outlier = grid.clone();
    with_outlier.push([1e308, 0.0, 0.0]);
    with_outlier.push([-1e308, -1e308, 1e308]);
    assert_eq!(first_coincident(&with_outlier), Some((0, 1)));
    let far = far_outlier(&with_outlier).unwrap();
    assert_eq!((far.index, far.axis, far.value), (grid.len(), 0, 1e308));
    assert_eq!(far_outlier(&grid), None);
    let mut dup = grid.clone();
    dup.push([10.0 + 1e-12, 20.0, 0.0]);
    assert_eq!(first_coincident(&dup), Some((40 * 300 + 20, grid.len())));
    assert_eq!(first_coincident(&[[1.0; 3]; 2]), Some((0, 1)));
    assert_eq!(first_coincident(&[[1.0; 3]]), None);
}

#[test]
fn blocks_do_not_change_the_result_or_the_error_positions() {
    // A BOM, a preamble of titles and blank lines (CRLF) that makes the
    // head longer than its 51 lines, a Windows-1252 byte in a title and in a row's region, and
    // enough rows to span many blocks; then the same table with a bad value
    // far down.
    let mut good: Vec<u8> = vec![0xEF, 0xBB, 0xBF];
    for k in 0..3 {
        good.extend_from_slice(format!("title-{k}\r\n").as_bytes());
        good.extend_from_slice(&b" \r\n".repeat(8));
    }
    good.extend_from_slice(b"Pr\xfcfung\r\nX (m);Y (m);PWP (kPa);Region\r\n");
    for i in 0..300 {
        let region: &[u8] = if i % 7 == 0 { b"s\xe4nd" } else { b"clay" };
        good.extend_from_slice(format!("{i};{},5;{}e-1;", i % 13, i * 3).as_bytes());
        good.extend_from_slice(region);
        good.extend_from_slice(b"\r\n");
    }
    let whole = parse_bytes(&good, 1 << 20).unwrap();
    assert_eq!(whole.0.len(), 300);
    assert!(whole.1.bom && whole.1.decimal_comma);
    assert_eq!(whole.1.header_line, 29);
    let mut bad = good.clone();
    bad.extend_from_slice(b"300;1;x;clay\r\n301;\xff;2;clay\r\n");
    let whole_bad = parse_bytes(&bad, 1 << 20).unwrap_err();
    assert!(whole_bad.contains("t.csv:330:7"), "{whole_bad}");
    assert!(whole_bad.contains("t.csv:331:5"), "{whole_bad}");
    for block in [1, 2, 3, 7, 64, 1000] {
        let part = parse_bytes(&good, block).unwrap();
        assert_eq!(part.0, whole.0, "block {block}");
        assert_eq!(part.1.warnings, whole.1.warnings, "block {block}");
        assert_eq!(part.1.header_line, whole.1.header_line);
        assert_eq!(
            parse_bytes(&bad, block).unwrap_err(),
            whole_bad,
            "block {block}"
        );
    }
}

#[test]
fn a_blank_or_bom_only_input_is_empty_and_utf16_is_refused() {
    for (bytes, expected) in [
        (&b""[..], "t.csv:1:1: empty file"),
        (&b"\xef\xbb\xbf \r\n\t\n"[..], "t.csv:1:1: empty file"),
        (&b"\xff\xfeX\0,\0Y\0"[..], "t.csv:1:1: UTF-16 text"),
    ] {
        for block in [1, 2, 1 << 20] {
            let e = parse_bytes(bytes, block).unwrap_err();
            assert!(e.starts_with(expected), "{e}");
        }
    }
}

/// A table whose vertical stress reads tensile nearly everywhere is in the
/// other sign convention, most likely: said, with the option that reads it.
#[test]
fn a_tensile_vertical_stress_questions_the_sign_convention() {
    // A PLAXIS-like table: tension positive, σ' and p_water in kN/m².
    let plaxis = "X [m],Y [m],σ'yy [kN/m²],σ'xx [kN/m²],p_water [kN/m²]\n\
                  0,0,-20,-10,-10\n1,0,-20,-10,-10\n0,1,-10,-5,0\n1,1,-10,-5,0\n";
    let (_, report) = parse(plaxis, 1 << 20).unwrap();
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    let w = &report.warnings[0];
    assert!(
        w.contains("vertical effective stress (esyy) is tensile at 4 of 4 loaded nodes")
            && w.contains("--fem-sign tension-positive"),
        "{w}"
    );
    // The same read as tension positive, and a GeoStudio table with one
    // node in tension among compressed ones, raise nothing.
    let options = CsvOptions {
        sign: SignConvention::TensionPositive,
        ..CsvOptions::default()
    };
    let (_, report) = parse_csv(Path::new("t.csv"), plaxis.as_bytes(), &options).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    let geostudio = "X,Y,Y-Total Stress,PWP\n0,0,20,10\n1,0,20,10\n0,1,-1,0\n1,1,10,0\n";
    let (_, report) = parse(geostudio, 1 << 20).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
}
