//! The dialect of a table: delimiter sniffing (`,` `;` tab or blanks), splitting
//! a line into positioned fields, and numbers with a decimal point or comma.

/// The sniffed dialect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Delimiter {
    Byte(u8),
    Blanks,
}

/// `sample`: the first 20 non-blank lines.
pub(super) fn sniff_delimiter(sample: &[&str]) -> Delimiter {
    for d in [b'\t', b';', b','] {
        let counts: Vec<usize> = sample
            .iter()
            .map(|l| l.bytes().filter(|&b| b == d).count())
            .collect();
        let rows_with = counts.iter().filter(|&&c| c > 0).count();
        if rows_with * 2 > sample.len() {
            return Delimiter::Byte(d);
        }
    }
    Delimiter::Blanks
}

/// Splits one line into (character column, field) pairs.
pub(super) fn split_line(line: &str, delim: Delimiter) -> Vec<(usize, String)> {
    match delim {
        Delimiter::Blanks => {
            let mut out = Vec::new();
            let mut start: Option<usize> = None;
            for (i, c) in line
                .char_indices()
                .chain(std::iter::once((line.len(), ' ')))
            {
                if c.is_whitespace() {
                    if let Some(s) = start.take() {
                        out.push((
                            line[..s].chars().count() + 1,
                            line[s..i].trim_matches('"').to_string(),
                        ));
                    }
                } else if start.is_none() {
                    start = Some(i);
                }
            }
            out
        }
        Delimiter::Byte(d) => {
            let mut rdr = csv::ReaderBuilder::new()
                .has_headers(false)
                .delimiter(d)
                .flexible(true)
                .from_reader(line.as_bytes());
            let mut record = csv::StringRecord::new();
            if !rdr.read_record(&mut record).unwrap_or(false) {
                return Vec::new();
            }
            // Columns: find each field's start by walking the raw line.
            let mut cols = Vec::with_capacity(record.len());
            let mut col = 1;
            let mut in_quotes = false;
            cols.push(1);
            for c in line.chars() {
                col += 1;
                if c == '"' {
                    in_quotes = !in_quotes;
                } else if c as u32 == d as u32 && !in_quotes {
                    cols.push(col);
                }
            }
            record
                .iter()
                .enumerate()
                .map(|(k, f)| (cols.get(k).copied().unwrap_or(1), f.trim().to_string()))
                .collect()
        }
    }
}

pub(super) fn parse_number(text: &str, decimal_comma: bool) -> Option<f64> {
    let t = text.trim();
    let v: f64 = if decimal_comma {
        t.replace(',', ".").parse().ok()?
    } else {
        t.parse().ok()?
    };
    v.is_finite().then_some(v)
}
