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

/// A lossless CPS (or OPD) document.
#[derive(Debug, Clone)]
pub struct CpsDocument {
    doc: KeywordDocument,
}

impl CpsDocument {
    pub fn read(path: &Path) -> Result<CpsDocument, FormatError> {
        Ok(CpsDocument {
            doc: KeywordDocument::read(path, "$$END", true)?,
        })
    }

    pub fn parse(path: &Path, text: String) -> Result<CpsDocument, FormatError> {
        Ok(CpsDocument {
            doc: KeywordDocument::parse(path, text, "$$END", true)?,
        })
    }

    /// Reads an OPD file (2025 output selection): the CPS layout without a version header.
    pub fn read_opd(path: &Path) -> Result<CpsDocument, FormatError> {
        let text = super::keyword_doc::read_text(path)?;
        Ok(CpsDocument {
            doc: KeywordDocument::parse_with(path, text, "$$END", true, false)?,
        })
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
            .unwrap_or(crate::model::DEFAULT_GRAVITY)
    }

    /// `$$COMPUTATION_METHOD` (`MPM-MIXED` when absent).
    pub fn computation_method(&self) -> String {
        self.get_token("$$COMPUTATION_METHOD", 0)
            .unwrap_or("MPM-MIXED")
            .to_ascii_uppercase()
    }

    /// Local damping factor α when `$$HOMOGENEOUS_LOCAL_DAMPING 1 α` switches it on.
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

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "### Anura3D_2021 ###\n$$k0_procedure\n1\n$$GRAVITY_ACCELERATION\n9.80665\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75\n$$END\n";

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
}
