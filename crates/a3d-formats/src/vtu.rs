//! VTK XML unstructured grids of vertices (`.vtu`) for ParaView: the MPs with
//! their mapped fields (`mps.vtu`) and the FEM input nodes (`fem.vtu`).
//! Spec: `formats/vtu.md`. One `VTK_VERTEX` cell per point; the arrays are
//! written in binary as raw little-endian appended data (`<AppendedData
//! encoding="raw">`), which ParaView reads at disk speed. [`read`] reads these
//! files back, and also the ASCII files of earlier versions; it understands the
//! subset we write, not every VTU.

use std::io::Write;
use std::path::Path;

use super::error::{FormatError, ParseError};

/// A named point-data array: 1 (scalar), 3 (vector) or 9 (tensor) components.
#[derive(Clone, Debug, PartialEq)]
pub struct PointArray {
    pub name: String,
    pub components: usize,
    pub values: Vec<f64>,
}

/// Bytes converted per write call.
const BLOCK: usize = 1 << 16;

/// Writes `n` little-endian items produced by `item` as one appended block:
/// its byte count (UInt64), then the bytes.
fn write_block<const N: usize>(
    w: &mut dyn Write,
    n: usize,
    item: impl Fn(usize) -> [u8; N],
) -> std::io::Result<()> {
    w.write_all(&((n * N) as u64).to_le_bytes())?;
    let mut buf = Vec::with_capacity(BLOCK);
    for i in 0..n {
        buf.extend_from_slice(&item(i));
        if buf.len() + N > BLOCK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    w.write_all(&buf)
}

/// A point-data array computed while it is written, so that no copy of the
/// values is held: `fill(i, out)` writes the `components` values of point `i`.
pub struct ArrayFn<'a> {
    pub name: String,
    pub components: usize,
    pub fill: Box<FillFn<'a>>,
}

/// `fill(i, out)` of an [`ArrayFn`].
pub type FillFn<'a> = dyn Fn(usize, &mut [f64]) + Sync + 'a;

impl<'a> ArrayFn<'a> {
    /// A scalar array with value `f(i)` at point `i`.
    pub fn scalar(name: impl Into<String>, f: impl Fn(usize) -> f64 + Sync + 'a) -> ArrayFn<'a> {
        ArrayFn {
            name: name.into(),
            components: 1,
            fill: Box::new(move |i, out: &mut [f64]| out[0] = f(i)),
        }
    }
}

/// Writes points with their point-data arrays (binary, appended raw).
pub fn write_points(
    w: &mut dyn Write,
    points: &[[f64; 3]],
    arrays: &[PointArray],
) -> std::io::Result<()> {
    let n = points.len();
    for a in arrays {
        if a.values.len() != n * a.components.max(1) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "array `{}` has {} values for {n} points × {} components",
                    a.name,
                    a.values.len(),
                    a.components
                ),
            ));
        }
    }
    let fns: Vec<ArrayFn<'_>> = arrays
        .iter()
        .map(|a| {
            let c = a.components.max(1);
            ArrayFn {
                name: a.name.clone(),
                components: a.components,
                fill: Box::new(move |i: usize, out: &mut [f64]| {
                    out.copy_from_slice(&a.values[i * c..(i + 1) * c])
                }) as Box<FillFn<'_>>,
            }
        })
        .collect();
    write_points_with(w, n, &|i| points[i], &fns)
}

/// Writes `n` points, given by `point(i)`, with arrays computed while writing
/// (see [`ArrayFn`]). The bytes equal [`write_points`]' for the same values.
pub fn write_points_with(
    w: &mut dyn Write,
    n: usize,
    point: &(dyn Fn(usize) -> [f64; 3] + Sync),
    arrays: &[ArrayFn<'_>],
) -> std::io::Result<()> {
    // Offsets of each block in the appended section (8-byte header + data).
    let mut offset = 0usize;
    let mut next = |bytes: usize| {
        let at = offset;
        offset += 8 + bytes;
        at
    };
    let mut head = String::new();
    head.push_str("<?xml version=\"1.0\"?>\n");
    head.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    head.push_str("<UnstructuredGrid>\n");
    head.push_str(&format!(
        "<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">\n"
    ));
    head.push_str("<PointData>\n");
    for a in arrays {
        head.push_str(&format!(
            "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{}\"/>\n",
            xml_escape(&a.name),
            a.components,
            next(n * a.components.max(1) * 8)
        ));
    }
    head.push_str("</PointData>\n<Points>\n");
    head.push_str(&format!(
        "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"{}\"/>\n",
        next(n * 24)
    ));
    head.push_str("</Points>\n<Cells>\n");
    head.push_str(&format!(
        "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"{}\"/>\n",
        next(n * 8)
    ));
    head.push_str(&format!(
        "<DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"{}\"/>\n",
        next(n * 8)
    ));
    head.push_str(&format!(
        "<DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{}\"/>\n",
        next(n)
    ));
    head.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n");
    head.push_str("<AppendedData encoding=\"raw\">\n_");
    w.write_all(head.as_bytes())?;
    for a in arrays {
        let c = a.components.max(1);
        let mut row = vec![0.0; c];
        w.write_all(&((n * c * 8) as u64).to_le_bytes())?;
        let mut buf = Vec::with_capacity(BLOCK + 8 * c);
        for i in 0..n {
            (a.fill)(i, &mut row);
            for v in &row {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            if buf.len() >= BLOCK {
                w.write_all(&buf)?;
                buf.clear();
            }
        }
        w.write_all(&buf)?;
    }
    write_block(w, n * 3, |i| point(i / 3)[i % 3].to_le_bytes())?;
    write_block(w, n, |i| (i as i64).to_le_bytes())?;
    write_block(w, n, |i| (i as i64 + 1).to_le_bytes())?;
    write_block(w, n, |_| [1u8])?;
    w.write_all(b"\n</AppendedData>\n</VTKFile>\n")
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('"', "&quot;")
}

/// Expands a 6-component stress (xx, yy, zz, xy, yz, xz) into a row-major 3×3 tensor.
pub fn tensor9(s: &[f64; 6]) -> [f64; 9] {
    [s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2]]
}

/// A point cloud read back from a VTU we wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct VtuPoints {
    pub points: Vec<[f64; 3]>,
    pub arrays: Vec<PointArray>,
}

/// Reads a `.vtu` written by [`write_points`] (binary appended raw) or by earlier
/// versions (ASCII). Checks the vertex cells.
pub fn read(path: &Path) -> Result<VtuPoints, FormatError> {
    let bytes = super::input::read_bytes(path)?;
    parse(path, &bytes)
}

/// One `<DataArray …>` tag: its attributes and where its data lie.
struct Tag {
    attrs: Vec<(String, String)>,
    /// Byte range of the ASCII text between the tags (ASCII arrays).
    text: Option<(usize, usize)>,
    /// Byte offset of the tag (for error positions).
    at: usize,
}

impl Tag {
    fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }
}

/// Parses VTU bytes (see [`read`]).
pub fn parse(path: &Path, bytes: &[u8]) -> Result<VtuPoints, FormatError> {
    // The XML part ends where the appended data start (after `_`).
    let appended_tag = find(bytes, b"<AppendedData", 0);
    let (xml_end, data_start) = match appended_tag {
        Some(at) => {
            let underscore = find(bytes, b"_", at)
                .ok_or_else(|| err(path, bytes, at, "no `_` opening the appended data"))?;
            (at, underscore + 1)
        }
        None => (bytes.len(), bytes.len()),
    };
    let xml = &bytes[..xml_end];
    if let Some(at) = appended_tag {
        let head = String::from_utf8_lossy(&bytes[at..data_start]);
        if !head.contains("encoding=\"raw\"") {
            return Err(err(path, bytes, at, "only raw appended data are supported").into());
        }
    }
    let text = String::from_utf8_lossy(xml);
    if !text.contains("header_type=\"UInt64\"") && appended_tag.is_some() {
        return Err(err(path, bytes, 0, "expected header_type=\"UInt64\"").into());
    }
    let n_points: usize = attr_after(&text, "<Piece", "NumberOfPoints")
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| err(path, bytes, 0, "no <Piece NumberOfPoints=…>"))?;
    let mut tags = Vec::new();
    let mut pos = 0;
    while let Some(at) = text[pos..].find("<DataArray").map(|k| k + pos) {
        let close = text[at..]
            .find('>')
            .map(|k| k + at)
            .ok_or_else(|| err(path, bytes, at, "unclosed <DataArray"))?;
        let inner = &text[at + "<DataArray".len()..close];
        let self_closing = inner.ends_with('/');
        let attrs = parse_attrs(inner.trim_end_matches('/'));
        let data = if self_closing {
            pos = close + 1;
            None
        } else {
            let end = text[close..]
                .find("</DataArray>")
                .map(|k| k + close)
                .ok_or_else(|| err(path, bytes, at, "no </DataArray>"))?;
            pos = end;
            Some((close + 1, end))
        };
        tags.push(Tag {
            attrs,
            text: data,
            at,
        });
    }
    let points_at = text.find("<Points>");
    let cells_at = text.find("<Cells>");
    let mut out = VtuPoints {
        points: Vec::new(),
        arrays: Vec::new(),
    };
    for tag in &tags {
        let ty = tag.attr("type").unwrap_or("");
        let values: Vec<f64> = match (tag.attr("format"), tag.text) {
            (Some("appended"), _) => {
                let offset: usize = tag
                    .attr("offset")
                    .and_then(|v| v.parse().ok())
                    .ok_or_else(|| err(path, bytes, tag.at, "appended array without offset"))?;
                let start = data_start + offset;
                let header = bytes
                    .get(start..start + 8)
                    .ok_or_else(|| err(path, bytes, tag.at, "offset past the end of the file"))?;
                let len = u64::from_le_bytes(header.try_into().unwrap_or([0; 8])) as usize;
                let body = bytes.get(start + 8..start + 8 + len).ok_or_else(|| {
                    err(path, bytes, tag.at, "array runs past the end of the file")
                })?;
                decode(ty, body).ok_or_else(|| err(path, bytes, tag.at, "unknown array type"))?
            }
            (Some("ascii"), Some((s, e))) => text[s..e]
                .split_ascii_whitespace()
                .map(|t| t.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| err(path, bytes, tag.at, "expected numbers"))?,
            _ => return Err(err(path, bytes, tag.at, "unsupported DataArray format").into()),
        };
        let components: usize = tag
            .attr("NumberOfComponents")
            .and_then(|v| v.parse().ok())
            .unwrap_or(1);
        if values.len() != n_points * components {
            return Err(err(
                path,
                bytes,
                tag.at,
                &format!(
                    "expected {} values ({n_points} points × {components}), found {}",
                    n_points * components,
                    values.len()
                ),
            )
            .into());
        }
        let in_points =
            points_at.is_some_and(|p| tag.at > p) && cells_at.is_none_or(|c| tag.at < c);
        let in_cells = cells_at.is_some_and(|c| tag.at > c);
        if in_points {
            out.points = values.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        } else if in_cells {
            let ok = match tag.attr("Name") {
                Some("connectivity") => values.iter().enumerate().all(|(i, &v)| v == i as f64),
                Some("offsets") => values.iter().enumerate().all(|(i, &v)| v == (i + 1) as f64),
                Some("types") => values.iter().all(|&v| v == 1.0),
                _ => true,
            };
            if !ok {
                return Err(err(path, bytes, tag.at, "cells are not one vertex per point").into());
            }
        } else {
            out.arrays.push(PointArray {
                name: tag.attr("Name").unwrap_or("").to_string(),
                components,
                values,
            });
        }
    }
    if out.points.len() != n_points {
        return Err(err(path, bytes, 0, "no <Points> array").into());
    }
    Ok(out)
}

fn decode(ty: &str, body: &[u8]) -> Option<Vec<f64>> {
    match ty {
        "Float64" => Some(
            body.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect(),
        ),
        "Int64" => Some(
            body.chunks_exact(8)
                .map(|c| i64::from_le_bytes(c.try_into().unwrap_or([0; 8])) as f64)
                .collect(),
        ),
        "UInt8" => Some(body.iter().map(|&b| b as f64).collect()),
        _ => None,
    }
}

fn find(hay: &[u8], needle: &[u8], from: usize) -> Option<usize> {
    hay.get(from..)?
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|k| k + from)
}

fn parse_attrs(s: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = s;
    while let Some(eq) = rest.find("=\"") {
        let key = rest[..eq].trim().to_string();
        let after = &rest[eq + 2..];
        let Some(end) = after.find('"') else { break };
        let value = after[..end]
            .replace("&quot;", "\"")
            .replace("&lt;", "<")
            .replace("&amp;", "&");
        out.push((key, value));
        rest = &after[end + 1..];
    }
    out
}

fn attr_after(text: &str, tag: &str, name: &str) -> Option<String> {
    let at = text.find(tag)?;
    let close = text[at..].find('>')? + at;
    parse_attrs(&text[at + tag.len()..close])
        .into_iter()
        .find(|(k, _)| k == name)
        .map(|(_, v)| v)
}

fn err(path: &Path, bytes: &[u8], at: usize, message: &str) -> ParseError {
    let head = String::from_utf8_lossy(&bytes[..at.min(bytes.len())]);
    ParseError::new(
        path,
        super::error::Position::of_byte(&head, head.len()),
        message,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(n: usize) -> (Vec<[f64; 3]>, Vec<PointArray>) {
        let points: Vec<[f64; 3]> = (0..n)
            .map(|i| [i as f64 * 0.1, -(i as f64) / 3.0, 1e-300 * i as f64])
            .collect();
        let arrays = vec![
            PointArray {
                name: "pwp".into(),
                components: 1,
                values: (0..n).map(|i| (i as f64).sqrt() - 7.25).collect(),
            },
            PointArray {
                name: "total_stress".into(),
                components: 9,
                values: (0..9 * n)
                    .map(|i| f64::from_bits(0x3ff0_0000_0000_0000 + i as u64))
                    .collect(),
            },
        ];
        (points, arrays)
    }

    #[test]
    fn binary_vtu_reads_back_bit_for_bit() {
        for n in [0, 1, 5, 10_000] {
            let (points, arrays) = sample(n);
            let mut bytes = Vec::new();
            write_points(&mut bytes, &points, &arrays).unwrap();
            let back = parse(Path::new("t.vtu"), &bytes).unwrap();
            assert_eq!(back.points, points);
            assert_eq!(back.arrays, arrays);
        }
    }

    #[test]
    fn ascii_vtu_of_earlier_versions_reads() {
        let text = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"2\" NumberOfCells=\"2\">\n<PointData>\n<DataArray type=\"Float64\" Name=\"pwp\" NumberOfComponents=\"1\" format=\"ascii\">\n-1.5\n2\n</DataArray>\n</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n0 0 0\n1 2 3\n</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n0\n1\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n1\n2\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n1\n1\n</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
        let back = parse(Path::new("t.vtu"), text.as_bytes()).unwrap();
        assert_eq!(back.points, vec![[0.0; 3], [1.0, 2.0, 3.0]]);
        assert_eq!(back.arrays[0].values, vec![-1.5, 2.0]);
    }

    #[test]
    fn truncated_vtu_is_an_error() {
        let (points, arrays) = sample(10);
        let mut bytes = Vec::new();
        write_points(&mut bytes, &points, &arrays).unwrap();
        bytes.truncate(bytes.len() - 100);
        let e = parse(Path::new("t.vtu"), &bytes).unwrap_err().to_string();
        assert!(e.starts_with("t.vtu:"), "{e}");
    }
}
