//! Anura3D CPS files (calculation parameters) and the OPD output-selection files
//! of 2025 projects, which share the layout. Spec: `formats/cps.md`.
//!
//! Lossless like the GOM: untouched files are written back byte for byte. Keywords
//! match without regard to ASCII case (Anura3D upper-cases them before matching).
//! [`CpsDocument::set`] replaces one keyword's value lines or inserts the keyword
//! before `$$END`; nothing else is re-rendered.

use std::path::Path;

use super::error::FormatError;
use super::keyword_doc::KeywordDocument;
use super::lex;
use a3d_model::loads::{Multiplier, MultiplierKind};

/// The load multipliers the runner applies (GOM loads × these).
pub const MULTIPLIERS: [&str; 5] = [
    "$$GRAVITY_LOAD",
    "$$SOLID_TRACTION",
    "$$SOLID_TRACTION_B",
    "$$LIQUID_PRESSURE",
    "$$LIQUID_PRESSURE_B",
];

/// A lossless CPS (or OPD) document.
#[derive(Debug, Clone)]
pub struct CpsDocument {
    doc: KeywordDocument,
}

impl CpsDocument {
    pub fn read(path: &Path) -> Result<CpsDocument, FormatError> {
        CpsDocument {
            doc: KeywordDocument::read(path, "$$END", true)?,
        }
        .validated()
    }

    pub fn parse(path: &Path, text: String) -> Result<CpsDocument, FormatError> {
        CpsDocument {
            doc: KeywordDocument::parse(path, text, "$$END", true)?,
        }
        .validated()
    }

    /// Reads an OPD file (2025 output selection): the CPS layout without a version header.
    pub fn read_opd(path: &Path) -> Result<CpsDocument, FormatError> {
        let text = super::keyword_doc::read_text(path)?;
        CpsDocument {
            doc: KeywordDocument::parse_with(path, text, "$$END", true, false)?,
        }
        .validated()
    }

    /// Refuses values Anura3D cannot read as numbers: NaN, infinities and reals
    /// out of the double range anywhere, and a typed value a3d-init uses
    /// (gravity, Courant number, local damping) that is not a finite number in
    /// its range. Every problem is reported, each at its line and column.
    fn validated(self) -> Result<CpsDocument, FormatError> {
        let mut errors = Vec::new();
        for b in 0..self.doc.blocks().len() {
            let block = &self.doc.blocks()[b];
            for i in block.data.clone() {
                let line = self.doc.line(i);
                for (offset, tok) in lex::tokens(line) {
                    if is_non_finite(tok) {
                        errors.push(self.doc.error_at(
                            i,
                            offset,
                            format!("{}: `{tok}` is not a finite number", block.keyword),
                        ));
                    }
                }
            }
        }
        for (keyword, index, lo, hi) in [
            ("$$GRAVITY_ACCELERATION", 0, 0.0, 1e4),
            ("$$COURANT_NUMBER", 0, 0.0, 10.0),
        ] {
            self.check_range(keyword, index, lo, hi, &mut errors);
        }
        if self.get_token("$$HOMOGENEOUS_LOCAL_DAMPING", 0) == Some("1") {
            self.check_range("$$HOMOGENEOUS_LOCAL_DAMPING", 1, 0.0, 1.0, &mut errors);
        }
        for keyword in MULTIPLIERS {
            self.check_multiplier(keyword, &mut errors);
        }
        match FormatError::from_list(errors) {
            Some(e) => Err(e),
            None => Ok(self),
        }
    }

    /// The value tokens of block `b`, in order: (0-based line, byte offset,
    /// text).
    fn value_tokens(&self, b: usize) -> impl Iterator<Item = (usize, usize, &str)> {
        self.doc.blocks()[b]
            .data
            .clone()
            .flat_map(|i| lex::tokens(self.doc.line(i)).map(move |(o, t)| (i, o, t)))
    }

    /// A load multiplier, when present, is `type realised final` with a type
    /// the kernel takes (`linear`, `step` or `off`, as written) and two
    /// numbers; Anura3D stops on anything else.
    fn check_multiplier(&self, keyword: &str, errors: &mut Vec<super::error::ParseError>) {
        let Some(b) = self.doc.find(keyword, true) else {
            return;
        };
        let block = &self.doc.blocks()[b];
        let mut tokens = self.value_tokens(b);
        match tokens.next() {
            Some((_, _, "linear" | "step" | "off")) => {}
            Some((i, o, tok)) => errors.push(self.doc.error_at(
                i,
                o,
                format!("{keyword}: load type `{tok}` must be `linear`, `step` or `off`"),
            )),
            None => {
                errors.push(self.doc.error_at(
                    block.line,
                    0,
                    format!("{keyword}: expected `type realised final`, found nothing"),
                ));
                return;
            }
        }
        for what in ["realised", "final"] {
            match tokens.next() {
                Some((i, o, tok)) => {
                    if lex::parse_real(tok).is_none() && !is_non_finite(tok) {
                        errors.push(self.doc.error_at(
                            i,
                            o,
                            format!("{keyword}: expected the {what} multiplier, found `{tok}`"),
                        ));
                    }
                }
                None => errors.push(self.doc.error_at(
                    block.line,
                    0,
                    format!("{keyword}: the {what} multiplier is missing (`type realised final`)"),
                )),
            }
        }
    }

    /// The load multiplier `keyword` (`$$SOLID_TRACTION`, …; checked when
    /// the CPS was read), or the kernel's default `step 0 1` when absent.
    pub fn multiplier(&self, keyword: &str) -> Multiplier {
        let Some(kind) = self.get_token(keyword, 0) else {
            return Multiplier::default();
        };
        let kind = match kind {
            "linear" => MultiplierKind::Linear,
            "off" => MultiplierKind::Off,
            _ => MultiplierKind::Step,
        };
        let value = |i| self.get_real(keyword, i).unwrap_or(0.0);
        if kind == MultiplierKind::Off {
            return Multiplier {
                kind,
                realised: 0.0,
                final_value: 0.0,
            };
        }
        Multiplier {
            kind,
            realised: value(1),
            final_value: value(2),
        }
    }

    /// The 1-based line of `keyword`, when present.
    pub fn keyword_line(&self, keyword: &str) -> Option<usize> {
        self.doc
            .find(keyword, true)
            .map(|b| self.doc.blocks()[b].line + 1)
    }

    /// `$$NUMBER_OF_LOADSTEPS` (at least 1; 1 when absent) and
    /// `$$TIME_PER_LOADSTEP` (s; the kernel's 0.5 when absent).
    pub fn load_steps(&self) -> (usize, f64) {
        let n = self
            .get_real("$$NUMBER_OF_LOADSTEPS", 0)
            .filter(|v| v.is_finite() && *v >= 1.0)
            .map_or(1, |v| v as usize);
        let t = self
            .get_real("$$TIME_PER_LOADSTEP", 0)
            .filter(|v| v.is_finite() && *v > 0.0)
            .unwrap_or(0.5);
        (n, t)
    }

    /// Token `index` of `keyword`, when the keyword is present, must be a real in `lo..=hi`.
    fn check_range(
        &self,
        keyword: &str,
        index: usize,
        lo: f64,
        hi: f64,
        errors: &mut Vec<super::error::ParseError>,
    ) {
        let Some(b) = self.doc.find(keyword, true) else {
            return;
        };
        let block = &self.doc.blocks()[b];
        let found = self.value_tokens(b).nth(index);
        match found {
            Some((i, o, tok)) => match lex::parse_real(tok) {
                Some(v) if (lo..=hi).contains(&v) => {}
                Some(_) => errors.push(self.doc.error_at(
                    i,
                    o,
                    format!("{keyword}: {tok} is out of range {lo}..={hi}"),
                )),
                None if is_non_finite(tok) => {}
                None => errors.push(self.doc.error_at(
                    i,
                    o,
                    format!("{keyword}: expected a number, found `{tok}`"),
                )),
            },
            None => errors.push(self.doc.error_at(
                block.line,
                0,
                format!("{keyword}: value {} is missing", index + 1),
            )),
        }
    }

    /// `$$GRAVITY_VECTOR`, when present, must be (0, −1) in 2D (a third value
    /// is ignored, as Anura3D reads only `n_dim` values) or (0, −1, 0) in 3D,
    /// each component within 1e-6. Anura3D multiplies the vector by
    /// `$$GRAVITY_ACCELERATION` as written (it refuses components outside
    /// [−1, 1] and a length above 1.01, so `0 -9.81` is not a vector it reads,
    /// and `0 -0.5` would halve the body forces while the unit weights keep
    /// g); a3d-init's geostatic stress and runner take gravity as −g·ŷ. Every
    /// other vector is an error at its value's line and column.
    pub fn check_gravity_vector(&self, n_dim: usize) -> Result<(), FormatError> {
        const KEYWORD: &str = "$$GRAVITY_VECTOR";
        let Some(b) = self.doc.find(KEYWORD, true) else {
            return Ok(());
        };
        let block = &self.doc.blocks()[b];
        let expected = [0.0, -1.0, 0.0];
        let wanted = if n_dim == 3 { "0 -1 0" } else { "0 -1" };
        let mut tokens = self.value_tokens(b);
        let mut errors = Vec::new();
        for (k, want) in expected.iter().enumerate().take(n_dim) {
            match tokens.next() {
                Some((i, o, tok)) => match lex::parse_real(tok) {
                    Some(v) if (v - want).abs() <= 1e-6 => {}
                    _ => errors.push(self.doc.error_at(
                        i,
                        o,
                        format!(
                            "{KEYWORD}: component {} is {tok}, but a3d-init needs gravity along −y, `{wanted}` (its geostatic stress and runner take gravity as −g·ŷ; Anura3D scales this vector by $$GRAVITY_ACCELERATION as written)",
                            k + 1
                        ),
                    )),
                },
                None => errors.push(self.doc.error_at(
                    block.line,
                    0,
                    format!(
                        "{KEYWORD}: value {} is missing ({n_dim}D needs `{wanted}`)",
                        k + 1
                    ),
                )),
            }
        }
        match FormatError::from_list(errors) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The MP ids of `$$OUTPUT_NUMBER_OF_MATERIAL_POINTS` n and
    /// `$$OUTPUT_MATERIAL_POINTS` (the MPs whose history Anura3D writes to
    /// `<project>.PAR_<id>`): the first n values, each a positive integer;
    /// none when n is absent or ≤ 0 (the kernel then reads one dummy value).
    /// A bad count or id, a missing id or one above `n_points` is an error at
    /// its line and column.
    pub fn output_material_points(&self, n_points: usize) -> Result<Vec<u32>, FormatError> {
        const COUNT: &str = "$$OUTPUT_NUMBER_OF_MATERIAL_POINTS";
        const IDS: &str = "$$OUTPUT_MATERIAL_POINTS";
        let Some(b) = self.doc.find(COUNT, true) else {
            return Ok(Vec::new());
        };
        let block_line = self.doc.blocks()[b].line;
        let integer = |tok: &str| tok.parse::<i64>().ok();
        let n = match self.value_tokens(b).next() {
            Some((i, o, tok)) => integer(tok).ok_or_else(|| {
                self.doc
                    .error_at(i, o, format!("{COUNT}: expected an integer, found `{tok}`"))
            })?,
            None => {
                return Err(self
                    .doc
                    .error_at(block_line, 0, format!("{COUNT}: the count is missing"))
                    .into());
            }
        };
        if n <= 0 {
            return Ok(Vec::new());
        }
        let Some(ids) = self.doc.find(IDS, true) else {
            return Err(self
                .doc
                .error_at(
                    block_line,
                    0,
                    format!("{COUNT} is {n} but there is no {IDS} block"),
                )
                .into());
        };
        let ids_line = self.doc.blocks()[ids].line;
        let mut tokens = self.value_tokens(ids);
        let mut out = Vec::new();
        for k in 0..n {
            let Some((i, o, tok)) = tokens.next() else {
                return Err(self
                    .doc
                    .error_at(
                        ids_line,
                        0,
                        format!("{IDS}: {COUNT} is {n} but only {k} ids follow"),
                    )
                    .into());
            };
            match integer(tok) {
                Some(id) if id >= 1 && (id as u64) <= n_points as u64 => out.push(id as u32),
                Some(id) => {
                    return Err(self
                        .doc
                        .error_at(i, o, format!("{IDS}: MP {id} does not exist (the model has {n_points} MPs, ids 1..={n_points})"))
                        .into());
                }
                None => {
                    return Err(self
                        .doc
                        .error_at(i, o, format!("{IDS}: expected an MP id, found `{tok}`"))
                        .into());
                }
            }
        }
        Ok(out)
    }

    pub fn document(&self) -> &KeywordDocument {
        &self.doc
    }

    pub fn version(&self) -> &str {
        self.doc.version()
    }

    /// True for a `### Anura3D_2025 ###` file: staged names (GOM_stage, OPD_stage).
    pub fn is_staged(&self) -> bool {
        self.version() == "2025"
    }

    /// The value lines of `keyword` (trimmed, blank lines dropped), when present.
    pub fn get(&self, keyword: &str) -> Option<Vec<&str>> {
        let b = self.doc.find(keyword, true)?;
        Some(
            self.doc
                .data_lines(b)
                .into_iter()
                .map(str::trim)
                .filter(|l| !l.is_empty())
                .collect(),
        )
    }

    /// The first token of `keyword`'s value, when present.
    pub fn get_token(&self, keyword: &str, index: usize) -> Option<&str> {
        let b = self.doc.find(keyword, true)?;
        let lines = self.doc.data_lines(b);
        lines
            .into_iter()
            .flat_map(|l| lex::tokens(l).map(|(_, t)| t))
            .nth(index)
    }

    /// A real value: token `index` of `keyword`'s value lines.
    pub fn get_real(&self, keyword: &str, index: usize) -> Option<f64> {
        self.get_token(keyword, index).and_then(lex::parse_real)
    }

    /// `$$STAGE` (0 when absent, as in Anura3D).
    pub fn stage(&self) -> u32 {
        self.get_token("$$STAGE", 0)
            .and_then(lex::parse_uint)
            .map_or(0, |v| v as u32)
    }

    /// `$$GRAVITY_ACCELERATION` (9.81 when absent, as in Anura3D).
    pub fn gravity(&self) -> f64 {
        self.get_real("$$GRAVITY_ACCELERATION", 0)
            .unwrap_or(a3d_model::DEFAULT_GRAVITY)
    }

    /// `$$SUBMERGED_CALCULATION 1 n`: buoyant weights in a one-phase analysis
    /// (off when absent).
    pub fn submerged_calculation(&self) -> bool {
        self.get_real("$$SUBMERGED_CALCULATION", 0) == Some(1.0)
    }

    /// `$$COMPUTATION_METHOD` (`MPM-MIXED` when absent).
    pub fn computation_method(&self) -> String {
        self.get_token("$$COMPUTATION_METHOD", 0)
            .unwrap_or("MPM-MIXED")
            .to_ascii_uppercase()
    }

    /// Local damping factor α when `$$HOMOGENEOUS_LOCAL_DAMPING 1 α` switches it on.
    /// `$$HOMOGENEOUS_LOCAL_DAMPING` as Anura3D applies it: α when switched
    /// on, 0 when switched off, `None` when the CPS does not say.
    pub fn local_damping_setting(&self) -> Option<f64> {
        match self.get_token("$$HOMOGENEOUS_LOCAL_DAMPING", 0) {
            Some("0") => Some(0.0),
            _ => self.local_damping(),
        }
    }

    pub fn local_damping(&self) -> Option<f64> {
        match self.get_token("$$HOMOGENEOUS_LOCAL_DAMPING", 0) {
            Some("1") => self.get_real("$$HOMOGENEOUS_LOCAL_DAMPING", 1),
            _ => None,
        }
    }

    /// Sets `keyword`'s value to `lines`, replacing the existing value lines or
    /// inserting the keyword just before `$$END`. Returns the previous value.
    pub fn set(&mut self, keyword: &str, lines: &[&str]) -> Option<Vec<String>> {
        let lines: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
        match self.doc.find(keyword, true) {
            Some(b) => {
                let old = self
                    .doc
                    .data_lines(b)
                    .into_iter()
                    .map(str::to_string)
                    .collect();
                self.doc.replace_block(b, lines);
                Some(old)
            }
            None => {
                self.doc.insert_before_terminator(keyword, lines);
                None
            }
        }
    }

    pub fn to_text(&self) -> String {
        self.doc.to_text()
    }
}

/// A token meant as a number that is not finite: `NaN`, `Inf`, `-Infinity`, or a
/// real whose exponent overflows (`1e400`, `1D999`).
fn is_non_finite(tok: &str) -> bool {
    let t = tok.trim_start_matches(['+', '-']).to_ascii_lowercase();
    if matches!(t.as_str(), "nan" | "inf" | "infinity") {
        return true;
    }
    let b = t.as_bytes();
    !b.is_empty()
        && (b[0].is_ascii_digit() || b[0] == b'.')
        && b.iter()
            .all(|&c| c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'+' | b'e' | b'd'))
        && lex::parse_real(tok).is_none()
        && t.replace('d', "e")
            .parse::<f64>()
            .is_ok_and(|v| !v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "### Anura3D_2021 ###\n$$k0_procedure\n1\n$$GRAVITY_ACCELERATION\n9.80665\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75\n$$END\n";

    #[test]
    fn monitored_mps_are_read_and_bad_ones_refused_at_their_place() {
        let read = |body: &str| {
            let text = format!("### Anura3D_2023 ###\n{body}$$END\n");
            CpsDocument::parse(Path::new("a.CPS_001"), text)
                .unwrap()
                .output_material_points(100)
                .map_err(|e| e.to_string())
        };
        let ids = "$$OUTPUT_MATERIAL_POINTS\n7\n100\n";
        assert_eq!(
            read(&format!("$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n2\n{ids}")),
            Ok(vec![7, 100])
        );
        assert_eq!(
            read(&format!("$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n1\n{ids}")),
            Ok(vec![7])
        );
        assert_eq!(
            read("$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n0\n$$OUTPUT_MATERIAL_POINTS\n-1\n"),
            Ok(vec![])
        );
        assert_eq!(read(""), Ok(vec![]));
        for (body, expected) in [
            (
                format!("$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n3\n{ids}"),
                "a.CPS_001:4:1: $$OUTPUT_MATERIAL_POINTS: $$OUTPUT_NUMBER_OF_MATERIAL_POINTS is 3 but only 2 ids follow",
            ),
            (
                "$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n1\n$$OUTPUT_MATERIAL_POINTS\n101\n".into(),
                "a.CPS_001:5:1: $$OUTPUT_MATERIAL_POINTS: MP 101 does not exist (the model has 100 MPs, ids 1..=100)",
            ),
            (
                "$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\ntwo\n".into(),
                "a.CPS_001:3:1: $$OUTPUT_NUMBER_OF_MATERIAL_POINTS: expected an integer, found `two`",
            ),
            (
                "$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n1\n".into(),
                "a.CPS_001:2:1: $$OUTPUT_NUMBER_OF_MATERIAL_POINTS is 1 but there is no $$OUTPUT_MATERIAL_POINTS block",
            ),
        ] {
            assert_eq!(read(&body), Err(expected.to_string()), "{body}");
        }
    }

    #[test]
    fn non_finite_values_are_refused_at_their_place() {
        for (text, expected) in [
            (
                "### Anura3D_2021 ###\n$$GRAVITY_ACCELERATION\nNaN\n$$END\n",
                "a.CPS_001:3:1: $$GRAVITY_ACCELERATION: `NaN` is not a finite number",
            ),
            (
                "### Anura3D_2021 ###\n$$TIME_PER_LOADSTEP\n  1e400\n$$END\n",
                "a.CPS_001:3:3: $$TIME_PER_LOADSTEP: `1e400` is not a finite number",
            ),
            (
                "### Anura3D_2021 ###\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 -inf\n$$END\n",
                "a.CPS_001:3:3: $$HOMOGENEOUS_LOCAL_DAMPING: `-inf` is not a finite number",
            ),
            (
                "### Anura3D_2021 ###\n$$GRAVITY_ACCELERATION\n1e308\n$$END\n",
                "a.CPS_001:3:1: $$GRAVITY_ACCELERATION: 1e308 is out of range",
            ),
            (
                "### Anura3D_2021 ###\n$$GRAVITY_ACCELERATION\nfast\n$$END\n",
                "a.CPS_001:3:1: $$GRAVITY_ACCELERATION: expected a number, found `fast`",
            ),
        ] {
            let e = CpsDocument::parse(Path::new("a.CPS_001"), text.to_string())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with(expected), "{e}");
        }
    }

    #[test]
    fn get_is_case_insensitive_and_set_touches_one_keyword() {
        let mut cps = CpsDocument::parse(Path::new("a.CPS_001"), TEXT.to_string()).unwrap();
        assert_eq!(cps.get("$$K0_PROCEDURE"), Some(vec!["1"]));
        assert_eq!(cps.gravity(), 9.80665);
        assert_eq!(cps.local_damping(), Some(0.75));
        assert_eq!(
            cps.set("$$K0_PROCEDURE", &["0"]),
            Some(vec!["1".to_string()])
        );
        assert_eq!(cps.set("$$MP_STRESS_INITIALIZATION_FROMFILE", &["1"]), None);
        assert_eq!(
            cps.to_text(),
            "### Anura3D_2021 ###\n$$k0_procedure\n0\n$$GRAVITY_ACCELERATION\n9.80665\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75\n$$MP_STRESS_INITIALIZATION_FROMFILE\n1\n$$END\n"
        );
    }
    /// A `$$GRAVITY_VECTOR` not along −y was accepted (map computed −y
    /// geostatic stress, verify ran with −y gravity): refused at its value.
    #[test]
    fn gravity_vector_not_along_minus_y_is_refused_at_its_value() {
        let cps = |v: &str| {
            CpsDocument::parse(
                Path::new("a.CPS_001"),
                format!("### Anura3D_2021 ###\n$$GRAVITY_VECTOR\n{v}\n$$END\n"),
            )
            .unwrap()
        };
        for (v, dim) in [
            ("0.0 -1.0", 2),
            ("0 -1", 2),
            ("0.0 -1.0 0.0", 2),
            ("0 -1 0.5", 2),
            ("0.000000000000000E+000  -1.00000000000000", 2),
            ("0.0 -1.0 0.0", 3),
        ] {
            assert!(cps(v).check_gravity_vector(dim).is_ok(), "{v} {dim}D");
        }
        assert!(cps("x").check_gravity_vector(2).is_err());
        for (v, dim, expected) in [
            (
                "1.0 0.0",
                2,
                "a.CPS_001:3:1: $$GRAVITY_VECTOR: component 1 is 1.0",
            ),
            (
                "0.0 0.0",
                2,
                "a.CPS_001:3:5: $$GRAVITY_VECTOR: component 2 is 0.0",
            ),
            (
                "0 -9.81",
                2,
                "a.CPS_001:3:3: $$GRAVITY_VECTOR: component 2 is -9.81",
            ),
            ("0 -0.5", 2, "a.CPS_001:3:3: "),
            (
                "0 -1 0.5",
                3,
                "a.CPS_001:3:6: $$GRAVITY_VECTOR: component 3 is 0.5",
            ),
            (
                "0 -1",
                3,
                "a.CPS_001:2:1: $$GRAVITY_VECTOR: value 3 is missing (3D needs `0 -1 0`)",
            ),
        ] {
            let e = cps(v).check_gravity_vector(dim).unwrap_err().to_string();
            assert!(e.starts_with(expected), "{v} {dim}D: {e}");
        }
    }
}
