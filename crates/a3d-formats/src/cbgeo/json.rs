//! The CB-Geo run file (`mpm.json`) as text with spans: what a3d-init reads
//! from it, each value with its place for errors, and the one edit `map`
//! makes (a member of `"mesh"` set or added) with every other byte kept.
//!
//! Parsed strictly (no comments, trailing commas or bare names: nlohmann's
//! defaults, which CB-Geo uses) by `jsonc-parser`, which keeps byte ranges and
//! limits nesting, so a crafted file cannot overflow the stack.

use std::path::Path;

use jsonc_parser::ast::{Array, Object, ObjectProp, Value};
use jsonc_parser::common::Ranged;
use jsonc_parser::{CollectOptions, ParseOptions};

use crate::error::{ParseError, Position};

/// Parses `text` strictly; the error is positioned.
pub fn parse<'a>(path: &Path, text: &'a str) -> Result<Object<'a>, ParseError> {
    let options = ParseOptions {
        allow_comments: false,
        allow_loose_object_property_names: false,
        allow_trailing_commas: false,
        allow_missing_commas: false,
        allow_single_quoted_strings: false,
        allow_hexadecimal_numbers: false,
        allow_unary_plus_numbers: false,
        allow_bare_decimal_point_numbers: false,
        allow_non_finite_numbers: false,
        allow_extended_string_escapes: false,
    };
    let parsed =
        jsonc_parser::parse_to_ast(text, &CollectOptions::default(), &options).map_err(|e| {
            ParseError::new(
                path,
                Position::of_byte(text, e.range().start),
                format!("not valid JSON: {}", e.kind()),
            )
        })?;
    match parsed.value {
        Some(Value::Object(o)) => Ok(o),
        Some(other) => Err(ParseError::new(
            path,
            Position::of_byte(text, other.start()),
            "a CB-Geo run file is one JSON object; this is not an object",
        )),
        None => Err(ParseError::at(
            path,
            1,
            1,
            "empty file: a CB-Geo run file is one JSON object",
        )),
    }
}

/// Reading typed values out of the AST with positioned errors.
pub struct Reader<'t> {
    pub path: &'t Path,
    pub text: &'t str,
}

impl Reader<'_> {
    /// An error at byte `at`.
    pub fn error(&self, at: usize, message: impl Into<String>) -> ParseError {
        ParseError::new(self.path, Position::of_byte(self.text, at), message)
    }

    /// The member `name` of `object`, which must be there.
    pub fn member<'o, 'a>(
        &self,
        object: &'o Object<'a>,
        name: &str,
        context: &str,
    ) -> Result<&'o ObjectProp<'a>, ParseError> {
        object
            .get(name)
            .ok_or_else(|| self.error(object.range.start, format!("{context} has no \"{name}\"")))
    }

    /// `name` as an object.
    pub fn object<'o, 'a>(
        &self,
        object: &'o Object<'a>,
        name: &str,
        context: &str,
    ) -> Result<&'o Object<'a>, ParseError> {
        let prop = self.member(object, name, context)?;
        match &prop.value {
            Value::Object(o) => Ok(o),
            v => Err(self.error(v.start(), format!("\"{name}\" must be an object"))),
        }
    }

    /// `name` as an array, when present.
    pub fn array<'o, 'a>(
        &self,
        object: &'o Object<'a>,
        name: &str,
    ) -> Result<Option<&'o Array<'a>>, ParseError> {
        match object.get(name).map(|p| &p.value) {
            None => Ok(None),
            Some(Value::Array(a)) => Ok(Some(a)),
            Some(v) => Err(self.error(v.start(), format!("\"{name}\" must be an array"))),
        }
    }

    /// `name` as a string, when present.
    pub fn string(&self, object: &Object<'_>, name: &str) -> Result<Option<String>, ParseError> {
        match object.get(name).map(|p| &p.value) {
            None => Ok(None),
            Some(Value::StringLit(s)) => Ok(Some(s.value.to_string())),
            Some(v) => Err(self.error(v.start(), format!("\"{name}\" must be a string"))),
        }
    }

    /// `name` as a string that must be there.
    pub fn required_string(
        &self,
        object: &Object<'_>,
        name: &str,
        context: &str,
    ) -> Result<String, ParseError> {
        self.string(object, name)?
            .ok_or_else(|| self.error(object.range.start, format!("{context} has no \"{name}\"")))
    }

    /// A value as a finite number.
    pub fn number_value(&self, value: &Value<'_>, what: &str) -> Result<f64, ParseError> {
        match value {
            Value::NumberLit(n) => n
                .value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    self.error(
                        n.range.start,
                        format!("{what} `{}` is out of range", n.value),
                    )
                }),
            v => Err(self.error(v.start(), format!("{what} must be a number"))),
        }
    }

    /// `name` as a number, when present.
    pub fn number(&self, object: &Object<'_>, name: &str) -> Result<Option<f64>, ParseError> {
        object
            .get(name)
            .map(|p| self.number_value(&p.value, &format!("\"{name}\"")))
            .transpose()
    }

    /// A value as an integer (a JSON number without fraction or exponent).
    pub fn int_value(&self, value: &Value<'_>, what: &str) -> Result<i64, ParseError> {
        match value {
            Value::NumberLit(n) => n.value.parse::<i64>().map_err(|_| {
                self.error(
                    n.range.start,
                    format!("{what} must be an integer, not `{}`", n.value),
                )
            }),
            v => Err(self.error(v.start(), format!("{what} must be an integer"))),
        }
    }

    /// `name` as an integer, when present.
    pub fn int(&self, object: &Object<'_>, name: &str) -> Result<Option<i64>, ParseError> {
        object
            .get(name)
            .map(|p| self.int_value(&p.value, &format!("\"{name}\"")))
            .transpose()
    }

    /// `name` as an integer ≥ 0, when present.
    pub fn uint(&self, object: &Object<'_>, name: &str) -> Result<Option<u32>, ParseError> {
        match object.get(name) {
            None => Ok(None),
            Some(p) => {
                let v = self.int_value(&p.value, &format!("\"{name}\""))?;
                u32::try_from(v).map(Some).map_err(|_| {
                    self.error(
                        p.value.start(),
                        format!("\"{name}\" must be an integer from 0 to {}", u32::MAX),
                    )
                })
            }
        }
    }

    /// `name` as an array of numbers, when present.
    pub fn numbers(&self, object: &Object<'_>, name: &str) -> Result<Option<Vec<f64>>, ParseError> {
        let Some(a) = self.array(object, name)? else {
            return Ok(None);
        };
        a.elements
            .iter()
            .map(|v| self.number_value(v, &format!("an entry of \"{name}\"")))
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }
}

/// The text of a JSON string literal holding `s`.
pub fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// `text` with member `name` of the object spanning `object` set to the JSON
/// `value`: the old value's bytes replaced when the member is there, else a
/// new last member on a line of its own, indented as the one before it.
/// Every other byte stays as it was.
pub fn set_member(text: &str, object: &Object<'_>, name: &str, value: &str) -> String {
    if let Some(prop) = object.get(name) {
        let r = prop.value.range();
        return format!("{}{}{}", &text[..r.start], value, &text[r.end..]);
    }
    let (at, indent, lead) = match object.properties.last() {
        Some(last) => {
            let start = last.range.start;
            let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
            let indent: String = text[line_start..start]
                .chars()
                .take_while(|c| *c == ' ' || *c == '\t')
                .collect();
            (last.range.end, indent, ",")
        }
        None => {
            // `{}`: inside the braces, one level deeper than the brace's line.
            let open = object.range.start;
            let line_start = text[..open].rfind('\n').map_or(0, |i| i + 1);
            let base: String = text[line_start..open]
                .chars()
                .take_while(|c| *c == ' ' || *c == '\t')
                .collect();
            (open + 1, format!("{base}\t"), "")
        }
    };
    let newline = if text.contains("\r\n") { "\r\n" } else { "\n" };
    let mut out = String::with_capacity(text.len() + name.len() + value.len() + 16);
    out.push_str(&text[..at]);
    out.push_str(lead);
    out.push_str(newline);
    out.push_str(&indent);
    out.push_str(&quote(name));
    out.push_str(": ");
    out.push_str(value);
    if object.properties.is_empty() {
        out.push_str(newline);
    }
    out.push_str(&text[at..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_member_replaces_a_value_or_adds_a_last_member_and_keeps_every_other_byte() {
        let p = Path::new("mpm.json");
        let text = "{\n\t\"mesh\": {\n\t\t\"mesh\": \"mesh.txt\",\n\t\t\"particles_stresses\": \"old.txt\"\n\t},\n\t\"x\": 1\n}";
        let root = parse(p, text).unwrap();
        let mesh = match &root.get("mesh").unwrap().value {
            Value::Object(o) => o,
            _ => unreachable!(),
        };
        let replaced = set_member(text, mesh, "particles_stresses", "\"new.txt\"");
        assert_eq!(replaced, text.replace("old.txt", "new.txt"));
        let added = set_member(
            text,
            mesh,
            "particles_pore_pressures",
            "{\"type\": \"file\"}",
        );
        assert_eq!(
            added,
            text.replace(
                "\"old.txt\"",
                "\"old.txt\",\n\t\t\"particles_pore_pressures\": {\"type\": \"file\"}"
            )
        );
        // The result is JSON again.
        parse(p, &added).unwrap();
    }

    #[test]
    fn bad_json_is_refused_with_its_place_and_deep_nesting_does_not_overflow() {
        let p = Path::new("mpm.json");
        let e = parse(p, "{\n  \"a\": 1,\n}").unwrap_err();
        assert_eq!((e.position.line, e.position.column), (2, 9), "{e}");
        let deep = format!("{{\"a\": {}{}}}", "[".repeat(100_000), "]".repeat(100_000));
        assert!(parse(p, &deep).is_err());
        assert!(
            parse(p, "[1]")
                .unwrap_err()
                .message
                .contains("not an object")
        );
        let r = Reader {
            path: p,
            text: "{\"n\": 1.5}",
        };
        let o = parse(p, r.text).unwrap();
        assert!(r.int(&o, "n").unwrap_err().message.contains("integer"));
        assert_eq!(quote("a\"b\\"), "\"a\\\"b\\\\\"");
    }
}
