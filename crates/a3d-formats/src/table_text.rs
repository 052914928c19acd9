//! The text of numeric tables (mps.csv, the MAPF): numbers as the shortest
//! decimals that read back to them, and rows formatted in parallel chunks and
//! written in order, so that the bytes do not depend on the thread count.

use std::io::Write;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Formats a float so that it reads back to the same value (shortest round trip).
pub fn fmt_f64(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    format!("{v}")
}

/// The shortest decimal that reads back to `v` (`zmij`, Schubfach: the same
/// digits as ryu at about twice its speed), formatted in `buf`: `0` for ±0, no
/// trailing `.0`, an exponent where it is shorter (`1e-7`, `1.5e20`; zmij's
/// `e+20` loses its `+`, as ryu wrote it).
fn shortest(v: f64, buf: &mut zmij::Buffer) -> std::borrow::Cow<'_, str> {
    if v == 0.0 {
        return "0".into();
    }
    let s = buf.format(v);
    let s = s.strip_suffix(".0").unwrap_or(s);
    if s.as_bytes().contains(&b'+') {
        s.replacen("e+", "e", 1).into()
    } else {
        s.into()
    }
}

/// Appends the shortest decimal that reads back to `v` (see `shortest`).
pub fn push_f64(out: &mut Vec<u8>, v: f64) {
    out.extend_from_slice(shortest(v, &mut zmij::Buffer::new()).as_bytes());
}

/// Rows per formatting chunk of [`write_rows`] and [`write_records`].
const ROWS_PER_CHUNK: usize = 4096;

/// Writes rows `0..n` in parallel chunks: `chunk` formats the rows of one
/// range into a buffer (with the error that stopped it, if any), and the
/// buffers are written in order, so the bytes do not depend on the thread
/// count. The first failing chunk (in order) stops the writing with its error,
/// after the rows before it. Rows go in batches, and the next batch is
/// formatted by the pool while this thread writes the last one.
fn write_chunks<F>(w: &mut dyn Write, n: usize, chunk: F) -> std::io::Result<()>
where
    F: Fn(std::ops::Range<usize>) -> (Vec<u8>, Option<std::io::Error>) + Sync,
{
    type Batch = Vec<(Vec<u8>, Option<std::io::Error>)>;
    // Batches bound the memory held by formatted text (two at a time).
    let batch = ROWS_PER_CHUNK * 4 * rayon::current_num_threads().max(1);
    let format = |start: usize| -> Batch {
        let end = (start + batch).min(n);
        a3d_progress::WRITE_TABLE.add((end - start) as u64);
        (start..end)
            .into_par_iter()
            .step_by(ROWS_PER_CHUNK)
            .map(|first| chunk(first..(first + ROWS_PER_CHUNK).min(end)))
            .collect()
    };
    let write = |w: &mut dyn Write, chunks: Batch| -> std::io::Result<()> {
        for (buf, error) in chunks {
            w.write_all(&buf)?;
            if let Some(e) = error {
                return Err(e);
            }
        }
        Ok(())
    };
    a3d_progress::WRITE_TABLE.start(n as u64);
    let mut pending = format(0);
    let mut start = batch;
    while start < n {
        let mut next = None;
        let written = rayon::in_place_scope(|scope| {
            scope.spawn(|_| next = Some(format(start)));
            write(w, std::mem::take(&mut pending))
        });
        written?;
        pending = next.unwrap_or_default();
        start += batch;
    }
    write(w, pending)
}

/// Writes rows `0..n`, each appended to a buffer by `row`, formatted in
/// parallel chunks and written in order (see `write_chunks`). The first row
/// (in order) whose `row` fails stops the writing with that error, after the
/// rows before it.
pub fn write_rows<F>(w: &mut dyn Write, n: usize, row: F) -> std::io::Result<()>
where
    F: Fn(usize, &mut Vec<u8>) -> std::io::Result<()> + Sync,
{
    write_chunks(w, n, |rows| {
        let mut buf = Vec::with_capacity(rows.len() * 160);
        for i in rows {
            if let Err(e) = row(i, &mut buf) {
                return (buf, Some(e));
            }
        }
        (buf, None)
    })
}

/// A table row with a direct writer that appends exactly what `csv` +
/// `serde` write for it (no header, no quoting, `\n` ending); a test holds
/// the two equal. The row struct stays the one definition of the columns
/// (the reader deserialises it), the direct writer skips csv's buffering and
/// per-field checks, which cost a third of the time of writing mps.csv.
pub trait Row: Serialize {
    /// Appends the row's fields, comma-separated, without the line ending.
    fn push_fields(&self, out: &mut Vec<u8>);
}

/// Writes records `0..n` as CSV rows without a header, one row struct each
/// ([`Row`]), in parallel chunks written in order (see `write_chunks`).
pub fn write_records<R, F>(w: &mut dyn Write, n: usize, row: F) -> std::io::Result<()>
where
    R: Row,
    F: Fn(usize) -> R + Sync,
{
    write_rows(w, n, |i, buf| {
        row(i).push_fields(buf);
        buf.push(b'\n');
        Ok(())
    })
}

/// Appends the unsigned integer `v`.
pub(super) fn push_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(itoa::Buffer::new().format(v).as_bytes());
}

/// Appends each of `values` after a comma.
pub(super) fn push_reals(out: &mut Vec<u8>, values: &[Real]) {
    for v in values {
        out.push(b',');
        push_f64(out, v.0);
    }
}

/// A number in a table: written as the shortest decimal that reads back to it
/// ([`push_f64`]), read back as a finite number.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Real(pub f64);

impl Serialize for Real {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&shortest(self.0, &mut zmij::Buffer::new()))
    }
}

impl<'de> Deserialize<'de> for Real {
    /// Any number; the readers refuse the non-finite ones where they know the
    /// field (see `StateRow::first_non_finite`).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Real, D::Error> {
        f64::deserialize(d).map(Real)
    }
}
