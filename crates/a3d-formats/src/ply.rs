//! A small, strict reader for the binary little-endian PLY meshes GeoStudio keeps
//! in `.gsz` archives (`Mesh.ply`). Spec: `formats/ply.md`.
//!
//! Only what a3d-init needs: the ASCII header, then the elements before `node`
//! (skipped by their declared sizes), then `node` with x, y, z as doubles. Header
//! errors give line and column; binary errors give the byte offset.

use std::path::Path;

use super::error::{FormatError, ParseError, Position};

/// Node coordinates and, per element, its 0-based node indices.
pub type PlyMesh = (Vec<[f64; 3]>, Vec<Vec<u32>>);

#[derive(Debug, Clone)]
struct Property {
    /// Scalar type, or for a list the (count type, item type).
    kind: PropKind,
    name: String,
    /// The header line that declares it, as written, and its 1-based number.
    text: String,
    line: usize,
}

#[derive(Debug, Clone)]
enum PropKind {
    Scalar(usize),
    List(usize, usize),
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
    /// 1-based header line of its `element` declaration.
    line: usize,
}

fn type_size(t: &str) -> Option<usize> {
    Some(match t {
        "char" | "uchar" | "int8" | "uint8" => 1,
        "short" | "ushort" | "int16" | "uint16" => 2,
        "int" | "uint" | "float" | "int32" | "uint32" | "float32" => 4,
        "double" | "float64" => 8,
        _ => return None,
    })
}

fn read_uint(bytes: &[u8], size: usize) -> u64 {
    let mut v = 0u64;
    for (k, b) in bytes.iter().take(size).enumerate() {
        v |= u64::from(*b) << (8 * k);
    }
    v
}

/// Bytes of one row of `el` without its list items.
fn min_row_size(el: &Element) -> usize {
    el.properties
        .iter()
        .map(|p| match p.kind {
            PropKind::Scalar(s) => s,
            PropKind::List(c, _) => c,
        })
        .sum()
}

/// The offset after the `el.count` rows of `el` starting at `offset`, or `None`
/// when they do not fit in `bytes`. The declared count is checked against the
/// bytes left before any loop, so a huge count costs nothing.
fn skip_element(bytes: &[u8], mut offset: usize, el: &Element) -> Option<usize> {
    let row = min_row_size(el);
    if row == 0 {
        // Rows without properties take no bytes, whatever their count.
        return Some(offset);
    }
    if el.count > bytes.len().saturating_sub(offset) / row {
        return None;
    }
    if el
        .properties
        .iter()
        .all(|p| matches!(p.kind, PropKind::Scalar(_)))
    {
        return Some(offset + el.count * row);
    }
    for _ in 0..el.count {
        for p in &el.properties {
            match p.kind {
                PropKind::Scalar(s) => offset = offset.checked_add(s)?,
                PropKind::List(c, t) => {
                    if offset.checked_add(c)? > bytes.len() {
                        return None;
                    }
                    let n = usize::try_from(read_uint(&bytes[offset..], c)).ok()?;
                    offset = offset.checked_add(c)?.checked_add(n.checked_mul(t)?)?;
                }
            }
        }
        if offset > bytes.len() {
            return None;
        }
    }
    Some(offset)
}

/// Reads the `id` lists of the `el` rows starting at `offset` into `cells`
/// (0-based node indices, from GeoStudio's 1-based ids, each checked against
/// the `n_nodes` nodes); returns the offset after the rows.
fn read_cells(
    path: &Path,
    bytes: &[u8],
    mut offset: usize,
    el: &Element,
    n_nodes: usize,
    cells: &mut Vec<Vec<u32>>,
) -> Result<usize, FormatError> {
    let truncated = |offset: usize| -> FormatError {
        ParseError::new(
            path,
            Position::in_binary(offset),
            format!(
                "truncated PLY: the data ends at byte {} inside {}",
                bytes.len(),
                el.name
            ),
        )
        .into()
    };
    if el.count > bytes.len().saturating_sub(offset) / min_row_size(el).max(1) {
        return Err(truncated(offset));
    }
    for _ in 0..el.count {
        for p in &el.properties {
            match p.kind {
                PropKind::Scalar(sz) => {
                    offset = offset.saturating_add(sz);
                    if offset > bytes.len() {
                        return Err(truncated(offset));
                    }
                }
                PropKind::List(c, t) => {
                    if offset.saturating_add(c) > bytes.len() {
                        return Err(truncated(offset));
                    }
                    let n = usize::try_from(read_uint(&bytes[offset..], c)).unwrap_or(usize::MAX);
                    offset += c;
                    if n.saturating_mul(t) > bytes.len() - offset {
                        return Err(truncated(offset));
                    }
                    if p.name == "id" {
                        // GeoStudio numbers element nodes from 1.
                        let ids: Vec<u32> = (0..n)
                            .map(|k| read_uint(&bytes[offset + k * t..], t) as u32)
                            .collect();
                        if let Some(bad) = ids.iter().find(|&&id| id == 0 || id as usize > n_nodes)
                        {
                            return Err(ParseError::new(
                                path,
                                Position::in_binary(offset),
                                format!(
                                    "element {} refers to node {bad}, outside 1..={n_nodes}",
                                    cells.len() + 1,
                                ),
                            )
                            .into());
                        }
                        cells.push(ids.into_iter().map(|id| id - 1).collect());
                    }
                    offset += n * t;
                }
            }
        }
    }
    Ok(offset)
}

/// Reads the node coordinates of a GeoStudio PLY mesh.
pub fn read_ply_nodes(path: &Path) -> Result<Vec<[f64; 3]>, FormatError> {
    let bytes = super::input::read_bytes(path)?;
    parse_ply_nodes(path, &bytes)
}

/// Parses PLY bytes (see [`read_ply_nodes`]).
pub fn parse_ply_nodes(path: &Path, bytes: &[u8]) -> Result<Vec<[f64; 3]>, FormatError> {
    parse_ply(path, bytes, false).map(|(nodes, _)| nodes)
}

/// Reads nodes and the node lists of the `element` element (converted from
/// GeoStudio's 1-based ids to 0-based indices).
pub fn read_ply_mesh(path: &Path) -> Result<PlyMesh, FormatError> {
    let bytes = super::input::read_bytes(path)?;
    parse_ply_mesh(path, &bytes)
}

/// Parses PLY bytes (see [`read_ply_mesh`]).
pub fn parse_ply_mesh(path: &Path, bytes: &[u8]) -> Result<PlyMesh, FormatError> {
    parse_ply(path, bytes, true)
}

/// The PLY header: its elements with their properties, and the offset of
/// the data after `end_header`. Only `binary_little_endian 1.0` is read.
fn parse_header(path: &Path, bytes: &[u8]) -> Result<(Vec<Element>, usize), FormatError> {
    let at = |line: usize, col: usize, msg: String| -> FormatError {
        ParseError::at(path, line, col, msg).into()
    };
    let end_marker = b"end_header\n";
    let header_end = bytes
        .windows(end_marker.len())
        .position(|w| w == end_marker)
        .map(|p| p + end_marker.len())
        .ok_or_else(|| at(1, 1, "not a PLY file: no `end_header` line".into()))?;
    let header = std::str::from_utf8(&bytes[..header_end])
        .map_err(|_| at(1, 1, "PLY header is not ASCII text".into()))?;
    let mut lines = header.lines().enumerate();
    match lines.next() {
        Some((_, "ply")) => {}
        _ => {
            return Err(at(
                1,
                1,
                "not a PLY file: the first line must be `ply`".into(),
            ));
        }
    }
    let mut elements: Vec<Element> = Vec::new();
    let mut format_ok = false;
    for (i, line) in lines {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["format", "binary_little_endian", "1.0"] => format_ok = true,
            ["format", other, ..] => {
                return Err(at(
                    i + 1,
                    8,
                    format!(
                        "unsupported PLY format `{other}`: a3d-init reads binary_little_endian 1.0"
                    ),
                ));
            }
            ["comment", ..] | ["obj_info", ..] | ["end_header"] => {}
            ["element", name, count] => {
                let count = count.parse().map_err(|_| {
                    at(
                        i + 1,
                        10 + name.len(),
                        format!("bad element count `{count}`"),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    line: i + 1,
                });
            }
            ["property", "list", ct, it, name] => {
                let (c, t) = (type_size(ct), type_size(it));
                let (Some(c), Some(t)) = (c, t) else {
                    return Err(at(i + 1, 15, format!("unknown PLY list type `{ct} {it}`")));
                };
                let el = elements
                    .last_mut()
                    .ok_or_else(|| at(i + 1, 1, "property before any element".into()))?;
                el.properties.push(Property {
                    kind: PropKind::List(c, t),
                    name: name.to_string(),
                    text: line.trim().to_string(),
                    line: i + 1,
                });
            }
            ["property", t, name] => {
                let size =
                    type_size(t).ok_or_else(|| at(i + 1, 10, format!("unknown PLY type `{t}`")))?;
                let el = elements
                    .last_mut()
                    .ok_or_else(|| at(i + 1, 1, "property before any element".into()))?;
                el.properties.push(Property {
                    kind: PropKind::Scalar(size),
                    name: name.to_string(),
                    text: line.trim().to_string(),
                    line: i + 1,
                });
            }
            // GeoStudio writes `property int` with no name in its `precision` element.
            ["property", t] if type_size(t).is_some() => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| at(i + 1, 1, "property before any element".into()))?;
                el.properties.push(Property {
                    kind: PropKind::Scalar(type_size(t).unwrap_or(4)),
                    name: String::new(),
                    text: line.trim().to_string(),
                    line: i + 1,
                });
            }
            [] => {}
            _ => return Err(at(i + 1, 1, format!("unexpected PLY header line `{line}`"))),
        }
    }
    if !format_ok {
        return Err(at(2, 1, "missing `format binary_little_endian 1.0`".into()));
    }
    Ok((elements, header_end))
}

/// The `node` element must be `double x, y, z`, no more and no less.
fn check_node_element(path: &Path, node: &Element) -> Result<(), FormatError> {
    // The first property that is not the expected `double x|y|z`, at its line
    // (or the element's line when properties are missing).
    let wrong =
        ["x", "y", "z"]
            .iter()
            .enumerate()
            .find_map(|(k, want)| match node.properties.get(k) {
                Some(p) if p.name == *want && matches!(p.kind, PropKind::Scalar(8)) => None,
                Some(p) => Some((p.line, format!("property {} is `{}`", k + 1, p.text))),
                None => Some((
                    node.line,
                    format!("it has {} properties", node.properties.len()),
                )),
            });
    let extra = node
        .properties
        .get(3)
        .map(|p| (p.line, format!("property 4 (`{}`) is one too many", p.text)));
    if let Some((line, what)) = wrong.or(extra) {
        return Err(ParseError::at(
            path,
            line,
            1,
            format!("the PLY `node` element must be `double x, y, z`: {what}"),
        )
        .into());
    }
    Ok(())
}

fn parse_ply(path: &Path, bytes: &[u8], with_elements: bool) -> Result<PlyMesh, FormatError> {
    let (elements, header_end) = parse_header(path, bytes)?;
    let node_index = elements
        .iter()
        .position(|e| e.name == "node")
        .ok_or_else(|| {
            FormatError::from(ParseError::at(path, 1, 1, "the PLY has no `node` element"))
        })?;
    let node = &elements[node_index];
    check_node_element(path, node)?;
    // Skip the elements before `node` by their sizes.
    let mut offset = header_end;
    let truncated = |offset: usize, what: &str| -> FormatError {
        ParseError::new(
            path,
            Position::in_binary(offset),
            format!(
                "truncated PLY: the data ends at byte {} inside {what}",
                bytes.len()
            ),
        )
        .into()
    };
    for el in &elements[..node_index] {
        offset = skip_element(bytes, offset, el).ok_or_else(|| truncated(offset, &el.name))?;
    }
    let need = node.count.saturating_mul(24);
    if offset.saturating_add(need) > bytes.len() {
        return Err(ParseError::new(
            path,
            Position::in_binary(offset),
            format!(
                "truncated PLY: {} nodes need {need} bytes from byte {offset}, but only {} remain ({} whole nodes)",
                node.count,
                bytes.len().saturating_sub(offset),
                bytes.len().saturating_sub(offset) / 24
            ),
        )
        .into());
    }
    let mut nodes = Vec::with_capacity(node.count);
    for k in 0..node.count {
        let base = offset + 24 * k;
        let mut p = [0.0; 3];
        for (c, slot) in p.iter_mut().enumerate() {
            let mut b = [0u8; 8];
            b.copy_from_slice(&bytes[base + 8 * c..base + 8 * c + 8]);
            *slot = f64::from_le_bytes(b);
        }
        if p.iter().any(|v| !v.is_finite()) {
            return Err(ParseError::new(
                path,
                Position::in_binary(base),
                format!("node {} has a non-finite coordinate", k + 1),
            )
            .into());
        }
        nodes.push(p);
    }
    // Every element after `node` is walked, read or skipped, and the data
    // must end with the last one: a count that does not match the data (a
    // `node` count one too large reads a node from the element block) is an
    // error whatever is asked for.
    let mut offset = offset + need;
    let mut cells = Vec::new();
    let mut cells_read = false;
    for el in &elements[node_index + 1..] {
        if with_elements && !cells_read && el.name == "element" {
            offset = read_cells(path, bytes, offset, el, nodes.len(), &mut cells)?;
            cells_read = true;
        } else {
            offset = skip_element(bytes, offset, el).ok_or_else(|| truncated(offset, &el.name))?;
        }
    }
    if offset != bytes.len() {
        return Err(ParseError::new(
            path,
            Position::in_binary(offset),
            format!(
                "{} bytes after the last element `{}`: the header's counts do not match the data",
                bytes.len() - offset,
                elements.last().map_or("node", |e| e.name.as_str())
            ),
        )
        .into());
    }
    Ok((nodes, cells))
}
