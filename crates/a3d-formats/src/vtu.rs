//! VTK XML unstructured grids of vertices (`.vtu`) for ParaView: the MPs with
//! their mapped fields (`mps.vtu`) and the FEM input nodes (`fem.vtu`).
//! Spec: `formats/vtu.md`. One `VTK_VERTEX` cell per point; the arrays are
//! written in binary as raw little-endian appended data (`<AppendedData
//! encoding="raw">`), which ParaView reads at disk speed. [`read`] reads these
//! files back, and also the ASCII files of earlier versions, through the FEM
//! VTU reader's decoders (`fem_vtu`): any encoding, vertex cells only.

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

/// Parses VTU bytes (see [`read`]) with the FEM reader's XML and array
/// decoders (`fem_vtu`): one VTU reader in the crate, whatever the encoding;
/// the cells must be one vertex per point.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<VtuPoints, FormatError> {
    use crate::fem_vtu::{decode::values, xml};
    let doc = xml::parse(path, bytes)?;
    if doc.points.components != 3 {
        return Err(ParseError::new(path, doc.points.at, "points need 3 components").into());
    }
    let coordinates = values(path, bytes, &doc, &doc.points, doc.n_points)?;
    let vertex = doc.n_cells == doc.n_points && {
        let types = values(path, bytes, &doc, &doc.types, doc.n_cells)?;
        let offsets = values(path, bytes, &doc, &doc.offsets, doc.n_cells)?;
        let connectivity = values(path, bytes, &doc, &doc.connectivity, doc.n_cells)?;
        types.iter().all(|&v| v == 1.0)
            && offsets
                .iter()
                .enumerate()
                .all(|(i, &v)| v == (i + 1) as f64)
            && connectivity.iter().enumerate().all(|(i, &v)| v == i as f64)
    };
    if !vertex {
        let message = "cells are not one vertex per point";
        return Err(ParseError::new(path, doc.types.at, message).into());
    }
    let mut arrays = Vec::with_capacity(doc.point_data.len());
    for tag in &doc.point_data {
        arrays.push(PointArray {
            name: tag.name.clone(),
            components: tag.components,
            values: values(path, bytes, &doc, tag, doc.n_points)?,
        });
    }
    Ok(VtuPoints {
        points: coordinates
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        arrays,
    })
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
