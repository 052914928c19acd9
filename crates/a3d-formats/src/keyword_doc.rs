//! The lossless layer shared by GOM, CPS and OPD files: a version header, then
//! blocks that each start at a `$$KEYWORD` line, then a terminator (`$$FINISH`
//! or `$$END`) and whatever follows it.
//!
//! The document keeps the original text. Writing an untouched document
//! reproduces it byte for byte (line endings, trailing blanks and all); a block
//! replaced through [`KeywordDocument::replace_block`] is written with the
//! document's own line ending and every other byte stays as it was. Typed views
//! (`gom`, `cps`) sit on top of this layer and never re-render what they did not
//! change.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::error::{FormatError, ParseError, Position};
use super::lex;

/// One `$$KEYWORD` block: its keyword line and the data lines up to the next block.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// The keyword as written, trailing blanks removed (`$$STARTNODES`).
    pub keyword: String,
    /// 0-based index of the keyword line.
    pub line: usize,
    /// 0-based line range of the data lines (after the keyword line).
    pub data: Range<usize>,
}

/// A lossless GOM/CPS/OPD text.
#[derive(Debug, Clone)]
pub struct KeywordDocument {
    path: PathBuf,
    text: String,
    /// Byte range of each line without its line ending, and the end including it.
    lines: Vec<(usize, usize, usize)>,
    version: String,
    blocks: Vec<Block>,
    /// Index into `blocks` of the terminator block.
    terminator: usize,
    /// Replacement data lines for edited blocks, by block index.
    edits: BTreeMap<usize, Vec<String>>,
    /// Blocks inserted just before the terminator (keyword line, then data lines).
    appended: Vec<String>,
    eol: &'static str,
}

impl KeywordDocument {
    /// Parses `text`. `terminator` is `$$FINISH` (GOM) or `$$END` (CPS, OPD);
    /// with `case_insensitive` keywords match in any case (CPS rule).
    pub fn parse(
        path: &Path,
        text: String,
        end_marker: &str,
        case_insensitive: bool,
    ) -> Result<KeywordDocument, FormatError> {
        KeywordDocument::parse_with(path, text, end_marker, case_insensitive, true)
    }

    /// Like [`KeywordDocument::parse`]; with `header_required` false the first line
    /// may already be a keyword (OPD files have no version header).
    pub fn parse_with(
        path: &Path,
        text: String,
        end_marker: &str,
        case_insensitive: bool,
        header_required: bool,
    ) -> Result<KeywordDocument, FormatError> {
        let lines = split_lines(&text);
        let line_str = |i: usize| &text[lines[i].0..lines[i].1];
        if lines.is_empty() || text.trim().is_empty() {
            return Err(ParseError::at(
                path,
                1,
                1,
                "empty file: expected `### Anura3D_<version> ###`",
            )
            .into());
        }
        let version = match lex::header_version(line_str(0)) {
            Some(v) => v.to_string(),
            None if !header_required && line_str(0).starts_with("$$") => String::new(),
            None => {
                return Err(ParseError::at(
                    path,
                    1,
                    1,
                    format!(
                        "expected a version header `### Anura3D_<version> ###` with version one of {}, found `{}`",
                        lex::VERSIONS.join(", "),
                        line_str(0).trim_end()
                    ),
                )
                .into());
            }
        };
        let mut blocks: Vec<Block> = Vec::new();
        let mut terminator_index = None;
        let first = if version.is_empty() { 0 } else { 1 };
        for i in first..lines.len() {
            let line = line_str(i);
            if !line.starts_with("$$") {
                continue;
            }
            let keyword = line.trim_end_matches([' ', '\t']).to_string();
            if let Some(last) = blocks.last_mut() {
                last.data.end = i;
            }
            let is_terminator = if case_insensitive {
                keyword.eq_ignore_ascii_case(end_marker)
            } else {
                keyword == end_marker
            };
            blocks.push(Block {
                keyword,
                line: i,
                data: i + 1..lines.len(),
            });
            if is_terminator {
                terminator_index = Some(blocks.len() - 1);
                break;
            }
        }
        let Some(terminator) = terminator_index else {
            return Err(ParseError::at(
                path,
                lines.len(),
                1,
                format!(
                    "missing `{end_marker}`: the file ends without its end marker (truncated?)"
                ),
            )
            .into());
        };
        // Anura3D stops reading at the end marker: anything after it would be
        // silently ignored, so it is refused (blank lines are fine).
        let end_line = blocks[terminator].line;
        if let Some(i) = (end_line + 1..lines.len()).find(|&i| !line_str(i).trim().is_empty()) {
            return Err(ParseError::at(
                path,
                i + 1,
                1,
                format!(
                    "data after `{}` (line {}): Anura3D stops reading at the end marker; remove it or move it above",
                    blocks[terminator].keyword,
                    end_line + 1
                ),
            )
            .into());
        }
        let eol = if text.contains("\r\n") { "\r\n" } else { "\n" };
        Ok(KeywordDocument {
            path: path.to_path_buf(),
            text,
            lines,
            version,
            blocks,
            terminator,
            edits: BTreeMap::new(),
            appended: Vec::new(),
            eol,
        })
    }

    /// Reads and parses a file.
    pub fn read(
        path: &Path,
        end_marker: &str,
        case_insensitive: bool,
    ) -> Result<KeywordDocument, FormatError> {
        let text = read_text(path)?;
        KeywordDocument::parse(path, text, end_marker, case_insensitive)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The version from line 1, e.g. `2021`.
    pub fn version(&self) -> &str {
        &self.version
    }

    /// Blocks before the terminator, in file order.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks[..self.terminator]
    }

    /// The terminator block (`$$FINISH` / `$$END`).
    pub fn terminator_block(&self) -> &Block {
        &self.blocks[self.terminator]
    }

    /// Text of line `i` (0-based) without its line ending.
    pub fn line(&self, i: usize) -> &str {
        let (a, b, _) = self.lines[i];
        &self.text[a..b]
    }

    /// Number of lines in the file.
    pub fn n_lines(&self) -> usize {
        self.lines.len()
    }

    /// The first block whose keyword equals `keyword` (exactly, or ignoring ASCII
    /// case when `case_insensitive`).
    pub fn find(&self, keyword: &str, case_insensitive: bool) -> Option<usize> {
        self.blocks().iter().position(|b| {
            if case_insensitive {
                b.keyword.eq_ignore_ascii_case(keyword)
            } else {
                b.keyword == keyword
            }
        })
    }

    /// Current data lines of block `index` (edited or original).
    pub fn data_lines(&self, index: usize) -> Vec<&str> {
        match self.edits.get(&index) {
            Some(lines) => lines.iter().map(String::as_str).collect(),
            None => self.blocks[index]
                .data
                .clone()
                .map(|i| self.line(i))
                .collect(),
        }
    }

    /// Replaces the data lines of block `index`. Only this block is re-rendered on write.
    pub fn replace_block(&mut self, index: usize, lines: Vec<String>) {
        self.edits.insert(index, lines);
    }

    /// True when some block was replaced.
    pub fn is_edited(&self) -> bool {
        !self.edits.is_empty() || !self.appended.is_empty()
    }

    /// Inserts a new block just before the terminator. The new block lives in the
    /// edit list, so everything else is written as read.
    pub fn insert_before_terminator(&mut self, keyword: &str, lines: Vec<String>) {
        self.appended.push(keyword.to_string());
        self.appended.extend(lines);
    }

    /// Error position helper: 1-based line `i + 1`, column of `offset` + 1.
    pub fn error_at(&self, line: usize, offset: usize, message: impl Into<String>) -> ParseError {
        let column = self
            .line(line)
            .get(..offset)
            .map_or(offset, |s| s.chars().count())
            + 1;
        ParseError::new(&self.path, Position::new(line + 1, column), message)
    }

    /// Renders the document: byte-identical to the input unless blocks were edited.
    pub fn to_text(&self) -> String {
        if !self.is_edited() {
            return self.text.clone();
        }
        let mut out = String::with_capacity(self.text.len() + 1024);
        let line_full = |i: usize| {
            let (a, _, c) = self.lines[i];
            &self.text[a..c]
        };
        let first_block_line = self.blocks.first().map_or(self.lines.len(), |b| b.line);
        for i in 0..first_block_line {
            out.push_str(line_full(i));
        }
        for (index, block) in self.blocks.iter().enumerate() {
            if index == self.terminator {
                for l in &self.appended {
                    out.push_str(l);
                    out.push_str(self.eol);
                }
                for i in block.line..self.lines.len() {
                    out.push_str(line_full(i));
                }
                break;
            }
            out.push_str(line_full(block.line));
            match self.edits.get(&index) {
                Some(lines) => {
                    for l in lines {
                        out.push_str(l);
                        out.push_str(self.eol);
                    }
                }
                None => {
                    for i in block.data.clone() {
                        out.push_str(line_full(i));
                    }
                }
            }
        }
        out
    }
}

/// Reads a text file, naming the file on I/O errors and the place of invalid
/// UTF-8; non-regular files and oversized files are refused (see [`super::input`]).
pub fn read_text(path: &Path) -> Result<String, FormatError> {
    super::input::read_text(path)
}

/// Splits into lines: (start, end without line ending, end with line ending).
/// A final line without a line ending is kept; `\r\n` and `\n` are both endings.
fn split_lines(text: &str) -> Vec<(usize, usize, usize)> {
    let bytes = text.as_bytes();
    // Counted first (memchr), so the vector is allocated once at its size.
    let count = memchr::memchr_iter(b'\n', bytes).count() + 1;
    let mut lines = Vec::with_capacity(count);
    let mut start = 0;
    for nl in memchr::memchr_iter(b'\n', bytes) {
        let end = if nl > start && bytes[nl - 1] == b'\r' {
            nl - 1
        } else {
            nl
        };
        lines.push((start, end, nl + 1));
        start = nl + 1;
    }
    if start < bytes.len() {
        lines.push((start, bytes.len(), bytes.len()));
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(text: &str) -> Result<KeywordDocument, FormatError> {
        KeywordDocument::parse(Path::new("t.GOM"), text.to_string(), "$$FINISH", false)
    }

    #[test]
    fn untouched_document_round_trips_byte_for_byte() {
        for text in [
            "### Anura3D_2021 ###   \n$$A\n1 2 \n$$FINISH\n",
            "### Anura3D_2025 ###\r\n$$A\r\n1\r\n\r\n$$FINISH\r\n",
            "### Anura3D_2023 ###\n$$FINISH",
            "### Anura3D_2023 ###\n$$A\n$$FINISH\n\n  \n",
        ] {
            assert_eq!(doc(text).unwrap().to_text(), text);
        }
    }

    #[test]
    fn blocks_and_data_lines() {
        let d = doc("### Anura3D_2021 ###\n$$A  \n1\n2\n$$B\n$$FINISH\n").unwrap();
        let kws: Vec<_> = d.blocks().iter().map(|b| b.keyword.as_str()).collect();
        assert_eq!(kws, ["$$A", "$$B"]);
        assert_eq!(d.data_lines(0), ["1", "2"]);
        assert!(d.data_lines(1).is_empty());
    }

    #[test]
    fn editing_rewrites_only_the_edited_block_with_the_file_line_ending() {
        let mut d = doc("### Anura3D_2025 ###\r\n$$A \r\n1\r\n$$B\r\n2  \r\n$$FINISH\r\n").unwrap();
        d.replace_block(0, vec!["9".into()]);
        assert_eq!(
            d.to_text(),
            "### Anura3D_2025 ###\r\n$$A \r\n9\r\n$$B\r\n2  \r\n$$FINISH\r\n"
        );
    }

    #[test]
    fn data_after_the_terminator_is_refused_with_its_line() {
        let e = doc("### Anura3D_2023 ###\n$$A\n$$FINISH\n\ntrailing junk\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.GOM:5:1: data after `$$FINISH` (line 3)"),
            "{e}"
        );
    }

    #[test]
    fn missing_terminator_and_bad_header_are_positioned() {
        let e = doc("### Anura3D_2021 ###\n$$A\n1\n")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "t.GOM:3:1: missing `$$FINISH`: the file ends without its end marker (truncated?)"
        );
        let e = doc("### Anura3D_1999 ###\n$$FINISH\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.GOM:1:1: expected a version header"), "{e}");
    }
}
