//! nom helpers shared by the Anura3D text readers: Fortran list-directed data
//! lines (tokens separated by blanks, tabs or commas; reals may use a `D`
//! exponent) and the `### Anura3D_<version> ###` header; and the
//! `key=value,…` splitting of option values.
//!
//! Parsers here work on one line at a time and report the 0-based byte offset of
//! the offending token so the caller can build a `path:line:col` error.

use nom::branch::alt;
use nom::bytes::complete::{tag, take_while, take_while1};
use nom::character::complete::{char, digit1, one_of};
use nom::combinator::{opt, recognize};
use nom::sequence::{delimited, pair};
use nom::{IResult, Parser};

/// Versions the Anura3D readers accept on line 1 of a GOM or CPS.
pub const VERSIONS: [&str; 6] = ["2019.2", "2021", "2022", "2023", "2024", "2025"];

fn is_separator(c: char) -> bool {
    c == ' ' || c == '\t' || c == ','
}

/// Skips separators (blanks, tabs, commas).
fn separators(input: &str) -> IResult<&str, &str> {
    take_while(is_separator)(input)
}

/// One token: a run of non-separator characters.
fn token(input: &str) -> IResult<&str, &str> {
    take_while1(|c: char| !is_separator(c))(input)
}

/// A Fortran real: optional sign, digits with an optional fraction (or a
/// fraction alone), optional exponent introduced by e, E, d or D.
fn fortran_real(input: &str) -> IResult<&str, &str> {
    recognize((
        opt(one_of("+-")),
        alt((
            recognize((digit1, opt(pair(char('.'), opt(digit1))))),
            recognize(pair(char('.'), digit1)),
        )),
        opt((one_of("eEdD"), opt(one_of("+-")), digit1)),
    ))
    .parse(input)
}

/// A data-line token that failed to parse: its byte offset in the line and text.
#[derive(Debug, Clone, PartialEq)]
pub struct BadToken<'a> {
    pub offset: usize,
    pub text: &'a str,
}

/// Splits a data line into tokens with their byte offsets.
pub fn tokens(line: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = line;
    std::iter::from_fn(move || {
        let (after_sep, _) = separators(rest).ok()?;
        let (after, tok) = token(after_sep).ok()?;
        let offset = line.len() - after_sep.len();
        rest = after;
        Some((offset, tok))
    })
}

/// The hot-path twin of [`tokens`] for the big data blocks: the same
/// separators, scanned byte by byte (a test checks both agree).
struct FastTokens<'a> {
    line: &'a str,
    pos: usize,
}

impl<'a> Iterator for FastTokens<'a> {
    type Item = (usize, &'a str);
    #[inline]
    fn next(&mut self) -> Option<(usize, &'a str)> {
        let b = self.line.as_bytes();
        let mut i = self.pos;
        while i < b.len() && matches!(b[i], b' ' | b'\t' | b',') {
            i += 1;
        }
        if i >= b.len() {
            self.pos = i;
            return None;
        }
        let start = i;
        while i < b.len() && !matches!(b[i], b' ' | b'\t' | b',') {
            i += 1;
        }
        self.pos = i;
        Some((start, &self.line[start..i]))
    }
}

/// Parses a whole token as a real number.
pub fn parse_real(tok: &str) -> Option<f64> {
    // Fast path: plain decimal tokens go straight to the standard parser, which
    // accepts exactly the forms `fortran_real` recognises except `inf`/`nan`
    // (excluded by the byte check) and the `d` exponent (handled below).
    let b = tok.as_bytes();
    if !b.is_empty()
        && b[0] != b'e'
        && b[0] != b'E'
        && b.iter()
            .all(|&c| c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'+' | b'e' | b'E'))
        && b.iter().any(u8::is_ascii_digit)
        && let Ok(v) = tok.parse::<f64>()
    {
        // Out-of-range tokens such as `1e400` parse as infinity: refused.
        return v.is_finite().then_some(v);
    }
    match fortran_real(tok) {
        Ok(("", text)) => {
            let v: f64 = if text.contains(['d', 'D']) {
                text.replace(['d', 'D'], "e").parse().ok()?
            } else {
                text.parse().ok()?
            };
            v.is_finite().then_some(v)
        }
        _ => None,
    }
}

/// Parses a whole token as a non-negative integer (Fortran allows a leading `+`).
pub fn parse_uint(tok: &str) -> Option<u64> {
    let digits = tok.strip_prefix('+').unwrap_or(tok);
    if digits.is_empty() || digits.len() > 18 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some(
        digits
            .bytes()
            .fold(0u64, |acc, b| acc * 10 + u64::from(b - b'0')),
    )
}

/// Parses a whole token as a signed integer.
pub fn parse_int(tok: &str) -> Option<i64> {
    match tok.strip_prefix('-') {
        Some(rest) if !rest.starts_with(['+', '-']) => parse_uint(rest).map(|v| -(v as i64)),
        _ => parse_uint(tok).map(|v| v as i64),
    }
}

/// Reads `n` reals from the start of `line`; extra tokens are ignored, as in
/// Fortran list-directed input. On failure returns the offending token, or
/// `None` when the line has fewer than `n` tokens.
pub fn reals<'a>(line: &'a str, out: &mut [f64]) -> Result<(), Option<BadToken<'a>>> {
    let mut it = FastTokens { line, pos: 0 };
    for slot in out.iter_mut() {
        let (offset, text) = it.next().ok_or(None)?;
        *slot = parse_real(text).ok_or(Some(BadToken { offset, text }))?;
    }
    Ok(())
}

/// Reads `n` unsigned integers from the start of `line`, like [`reals`].
pub fn uints<'a>(line: &'a str, out: &mut [u64]) -> Result<(), Option<BadToken<'a>>> {
    if uints_plain(line.as_bytes(), out) {
        return Ok(());
    }
    uints_tokens(line, out)
}

/// The common case of [`uints`] in one pass: each number is 1 to 18 digits
/// ended by a separator or the line's end. False (with `out` partly written)
/// for anything else, which [`uints_tokens`] then reads or refuses.
fn uints_plain(b: &[u8], out: &mut [u64]) -> bool {
    let separator = |c: u8| matches!(c, b' ' | b'\t' | b',');
    let mut i = 0;
    for slot in out.iter_mut() {
        while i < b.len() && separator(b[i]) {
            i += 1;
        }
        let start = i;
        let mut value = 0u64;
        while i < b.len() && b[i].is_ascii_digit() {
            value = value * 10 + u64::from(b[i] - b'0');
            i += 1;
        }
        if i == start || i - start > 18 || (i < b.len() && !separator(b[i])) {
            return false;
        }
        *slot = value;
    }
    true
}

/// [`uints`] token by token, with the offending token on failure.
fn uints_tokens<'a>(line: &'a str, out: &mut [u64]) -> Result<(), Option<BadToken<'a>>> {
    let mut it = FastTokens { line, pos: 0 };
    for slot in out.iter_mut() {
        let (offset, text) = it.next().ok_or(None)?;
        *slot = parse_uint(text).ok_or(Some(BadToken { offset, text }))?;
    }
    Ok(())
}

/// Parses the version header `### Anura3D_<version> ###` (trailing blanks allowed,
/// leading blanks not). Returns the version string.
pub fn header_version(line: &str) -> Option<&str> {
    let line = line.trim_end_matches([' ', '\t']);
    let parsed: IResult<&str, &str> = delimited(
        tag("### Anura3D_"),
        take_while1(|c: char| c.is_ascii_alphanumeric() || c == '.'),
        tag(" ###"),
    )
    .parse(line);
    match parsed {
        Ok(("", v)) if VERSIONS.contains(&v) => Some(v),
        _ => None,
    }
}

/// Splits an option value `key=value,key=value` into trimmed pairs (empty
/// pairs skipped); `expected` names the form in the error (`field=header`).
pub fn key_value_pairs<'a>(s: &'a str, expected: &str) -> Result<Vec<(&'a str, &'a str)>, String> {
    s.split(',')
        .filter(|p| !p.trim().is_empty())
        .map(|pair| {
            pair.split_once('=')
                .map(|(k, v)| (k.trim(), v.trim()))
                .ok_or_else(|| format!("`{pair}`: expected {expected}"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one-pass reader gives what the token reader gives, wherever it
    /// accepts a line; on the rest `uints` answers as the token reader.
    #[test]
    fn plain_uints_agree_with_the_token_reader() {
        let alphabet = [
            b'0', b'1', b'9', b'5', b' ', b'\t', b',', b'+', b'-', b'x', b'.',
        ];
        let mut k = 7u64;
        let mut plain_lines = 0;
        for _ in 0..200_000 {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let len = (k >> 58) as usize;
            let mut line = String::new();
            let mut r = k;
            for _ in 0..len {
                r = r
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                line.push(alphabet[(r >> 33) as usize % alphabet.len()] as char);
            }
            let n = 1 + (k >> 50) as usize % 3;
            let (mut a, mut b) = (vec![0u64; n], vec![0u64; n]);
            let tokens = uints_tokens(&line, &mut b).map_err(|e| e.map(|t| (t.offset, t.text)));
            if uints_plain(line.as_bytes(), &mut a) {
                plain_lines += 1;
                assert_eq!(tokens, Ok(()), "{line:?}");
                assert_eq!(a, b, "{line:?}");
            }
            let whole = uints(&line, &mut a).map_err(|e| e.map(|t| (t.offset, t.text)));
            assert_eq!(whole, tokens, "{line:?}");
            if whole.is_ok() {
                assert_eq!(a, b, "{line:?}");
            }
        }
        assert!(plain_lines > 1000, "{plain_lines}");
        let mut long = [0u64; 1];
        assert!(!uints_plain(b"1234567890123456789", &mut long));
        assert_eq!(uints(" 12,\t34", &mut [0, 0][..]).map_err(|_| ()), Ok(()));
    }

    #[test]
    fn reals_accept_fortran_forms() {
        for (text, value) in [
            ("1", 1.0),
            ("-2.5", -2.5),
            ("+.5", 0.5),
            ("3.", 3.0),
            ("1e-3", 1e-3),
            ("1.0D+2", 100.0),
            ("2d0", 2.0),
            ("-0.0", -0.0),
        ] {
            assert_eq!(parse_real(text), Some(value), "{text}");
        }
        for bad in [
            "", "x", "1.2.3", "1e", "--1", "nan", "inf", "1,0", "1e400", "-1D999",
        ] {
            assert_eq!(parse_real(bad), None, "{bad}");
        }
    }

    #[test]
    fn tokens_split_on_blanks_tabs_and_commas() {
        for line in [
            "  1\t2,3 ,4  ",
            "",
            "   ",
            "a",
            ",,x,, y\t\tz",
            "1.0 2.0 3.0",
        ] {
            let nom: Vec<_> = tokens(line).collect();
            let fast: Vec<_> = FastTokens { line, pos: 0 }.collect();
            assert_eq!(nom, fast, "{line:?}");
        }
        let toks: Vec<_> = tokens("  1\t2,3 ,4  ").collect();
        assert_eq!(toks, vec![(2, "1"), (4, "2"), (6, "3"), (9, "4")]);
    }

    #[test]
    fn reals_report_the_bad_token() {
        let mut out = [0.0; 3];
        assert_eq!(
            reals("1.0 abc 3", &mut out),
            Err(Some(BadToken {
                offset: 4,
                text: "abc"
            }))
        );
        assert_eq!(reals("1.0 2", &mut out), Err(None));
        assert_eq!(reals("1 2 3 extra", &mut out), Ok(()));
    }

    #[test]
    fn header_versions() {
        assert_eq!(header_version("### Anura3D_2021 ###        "), Some("2021"));
        assert_eq!(header_version("### Anura3D_2019.2 ###"), Some("2019.2"));
        assert_eq!(header_version(" ### Anura3D_2021 ###"), None);
        assert_eq!(header_version("### Anura3D_2020 ###"), None);
        assert_eq!(header_version("### Anura3D_2021 ### x"), None);
    }
}
