//! Positioned errors for every reader. A [`ParseError`] prints as
//! `path:line:col: message`, with 1-based line and column, so editors and
//! terminals can jump to the spot.

use std::fmt;
use std::path::{Path, PathBuf};

/// A place in a text file. Line and column count from 1; `byte` from 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Position {
    pub line: usize,
    pub column: usize,
    pub byte: usize,
}

impl Position {
    pub fn new(line: usize, column: usize) -> Position {
        Position {
            line,
            column,
            byte: 0,
        }
    }

    /// A byte offset in a binary file, which has no lines (line and column 0).
    pub fn in_binary(byte: usize) -> Position {
        Position {
            line: 0,
            column: 0,
            byte,
        }
    }

    /// Position of `byte` in `text` (column counted in characters).
    pub fn of_byte(text: &str, byte: usize) -> Position {
        let byte = byte.min(text.len());
        let before = &text.as_bytes()[..byte];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        let column = String::from_utf8_lossy(&before[line_start..])
            .chars()
            .count()
            + 1;
        Position { line, column, byte }
    }
}

/// Line starts of a text, for turning many byte offsets into positions in
/// O(log lines) each ([`Position::of_byte`] scans from the start: quadratic
/// when a reader places thousands of tags).
#[derive(Clone, Debug)]
pub struct LineIndex<'a> {
    text: &'a str,
    /// Byte offset of the start of each line after the first.
    starts: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    pub fn new(text: &'a str) -> LineIndex<'a> {
        let starts = memchr::memchr_iter(b'\n', text.as_bytes())
            .map(|i| i + 1)
            .collect();
        LineIndex { text, starts }
    }

    /// Position of `byte` (column counted in characters), as
    /// [`Position::of_byte`] gives it.
    pub fn position(&self, byte: usize) -> Position {
        let byte = byte.min(self.text.len());
        let lines_before = self.starts.partition_point(|&s| s <= byte);
        let line_start = if lines_before == 0 {
            0
        } else {
            self.starts[lines_before - 1]
        };
        let column = String::from_utf8_lossy(&self.text.as_bytes()[line_start..byte])
            .chars()
            .count()
            + 1;
        Position {
            line: lines_before + 1,
            column,
            byte,
        }
    }
}

/// Longest run of non-blank characters a message repeats whole; longer ones
/// (a 50 MB token in a bad file) are cut to their first
/// [`CLIPPED_HEAD`] and last [`CLIPPED_TAIL`] characters.
pub const MAX_ECHOED_WORD: usize = 120;
/// Characters kept from the start of a clipped word.
pub const CLIPPED_HEAD: usize = 40;
/// Characters kept from the end of a clipped word.
pub const CLIPPED_TAIL: usize = 12;

/// `message` with every run of non-blank characters longer than `max`
/// characters cut in the middle (`head…tail (N characters)`), so that an
/// error never echoes a huge token from its input.
pub fn clip_long_words(message: &str, max: usize) -> std::borrow::Cow<'_, str> {
    let long = |w: &str| w.len() > max && w.chars().count() > max;
    if !message.split_whitespace().any(long) {
        return std::borrow::Cow::Borrowed(message);
    }
    let mut out = String::with_capacity(message.len().min(4 * max));
    let mut rest = message;
    while !rest.is_empty() {
        let blank = rest.len() - rest.trim_start().len();
        out.push_str(&rest[..blank]);
        rest = &rest[blank..];
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let word = &rest[..end];
        if long(word) {
            let n = word.chars().count();
            let head: String = word.chars().take(CLIPPED_HEAD).collect();
            let tail: String = word.chars().skip(n - CLIPPED_TAIL).collect();
            out.push_str(&format!("{head}…{tail} ({n} characters)"));
        } else {
            out.push_str(word);
        }
        rest = &rest[end..];
    }
    std::borrow::Cow::Owned(out)
}

/// A reader error with the file and the place it refers to.
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    pub path: PathBuf,
    pub position: Position,
    pub message: String,
}

impl ParseError {
    /// An error at `position`. A word of the message longer than
    /// [`MAX_ECHOED_WORD`] characters (a token quoted from the input) is cut.
    pub fn new(path: &Path, position: Position, message: impl Into<String>) -> ParseError {
        let message = message.into();
        let message = match clip_long_words(&message, MAX_ECHOED_WORD) {
            std::borrow::Cow::Borrowed(_) => message,
            std::borrow::Cow::Owned(clipped) => clipped,
        };
        ParseError {
            path: path.to_path_buf(),
            position,
            message,
        }
    }

    /// An error at `line`, column `column` (both 1-based).
    pub fn at(path: &Path, line: usize, column: usize, message: impl Into<String>) -> ParseError {
        ParseError::new(path, Position::new(line, column), message)
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.position.line == 0 {
            // Binary files: the place is a byte offset.
            return write!(
                f,
                "{}: byte {}: {}",
                self.path.display(),
                self.position.byte,
                self.message
            );
        }
        write!(
            f,
            "{}:{}:{}: {}",
            self.path.display(),
            self.position.line,
            self.position.column,
            self.message
        )
    }
}

impl std::error::Error for ParseError {}

/// Any failure of a reader or writer: I/O on a named file, or a positioned parse error.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FormatError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Parse(#[from] ParseError),
    /// Several problems found in one pass (e.g. every bad element at once).
    #[error("{}", join_errors(.0))]
    Many(Vec<ParseError>),
    /// A problem that concerns a whole file rather than a place in it.
    #[error("{path}: {message}")]
    File { path: PathBuf, message: String },
}

fn join_errors(errors: &[ParseError]) -> String {
    const SHOWN: usize = 20;
    let mut out: Vec<String> = errors.iter().take(SHOWN).map(|e| e.to_string()).collect();
    if errors.len() > SHOWN {
        out.push(format!("… and {} more", errors.len() - SHOWN));
    }
    out.join("\n")
}

impl FormatError {
    pub fn io(path: &Path, source: std::io::Error) -> FormatError {
        FormatError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// A whole-file error; a word of the message longer than
    /// [`MAX_ECHOED_WORD`] characters is cut, as in [`ParseError::new`].
    pub fn file(path: &Path, message: impl Into<String>) -> FormatError {
        let message = message.into();
        FormatError::File {
            path: path.to_path_buf(),
            message: clip_long_words(&message, MAX_ECHOED_WORD).into_owned(),
        }
    }

    /// Collapses a list of errors: one stays itself, several become `Many`.
    pub fn from_list(mut errors: Vec<ParseError>) -> Option<FormatError> {
        match errors.len() {
            0 => None,
            1 => Some(FormatError::Parse(errors.remove(0))),
            _ => Some(FormatError::Many(errors)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn position_of_byte_counts_lines_and_columns_from_one() {
        let text = "ab\ncde\nf";
        assert_eq!(
            Position::of_byte(text, 0),
            Position {
                line: 1,
                column: 1,
                byte: 0
            }
        );
        assert_eq!(
            Position::of_byte(text, 4),
            Position {
                line: 2,
                column: 2,
                byte: 4
            }
        );
        assert_eq!(
            Position::of_byte(text, 7),
            Position {
                line: 3,
                column: 1,
                byte: 7
            }
        );
    }

    #[test]
    fn parse_error_prints_path_line_column() {
        let e = ParseError::at(Path::new("a/b.GOM"), 12, 3, "expected a number, found `x`");
        assert_eq!(e.to_string(), "a/b.GOM:12:3: expected a number, found `x`");
    }
}
