//! The XML layer of a `.vtu` (VTK XML `UnstructuredGrid`): the file's layout
//! (byte order, header type, compressor), its one piece's counts and the
//! `DataArray` tags of points, cells, point data and cell data, each with where
//! its bytes lie (inline text, or an offset into the appended data). Parsed
//! with roxmltree; the appended data, which may be raw binary and so not XML,
//! are cut off before parsing. Decoding the arrays is [`super::decode`]'s.

use std::ops::Range;
use std::path::Path;

use crate::error::{LineIndex, ParseError, Position};

/// Scalar type of a `DataArray`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "Int8" | "Char" => Scalar::I8,
            "UInt8" | "UnsignedChar" => Scalar::U8,
            "Int16" | "Short" => Scalar::I16,
            "UInt16" | "UnsignedShort" => Scalar::U16,
            "Int32" | "Int" => Scalar::I32,
            "UInt32" | "UnsignedInt" => Scalar::U32,
            "Int64" | "Long" | "LongLong" => Scalar::I64,
            "UInt64" | "UnsignedLong" | "UnsignedLongLong" => Scalar::U64,
            "Float32" | "Float" => Scalar::F32,
            "Float64" | "Double" => Scalar::F64,
            _ => return None,
        })
    }

    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// VTK's name of the type.
    pub fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "Int8",
            Scalar::U8 => "UInt8",
            Scalar::I16 => "Int16",
            Scalar::U16 => "UInt16",
            Scalar::I32 => "Int32",
            Scalar::U32 => "UInt32",
            Scalar::I64 => "Int64",
            Scalar::U64 => "UInt64",
            Scalar::F32 => "Float32",
            Scalar::F64 => "Float64",
        }
    }
}

/// Where an array's values are.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Place {
    /// `format="ascii"`: numbers in this byte range of the file.
    Ascii(Range<usize>),
    /// `format="binary"`: base64 in this byte range of the file.
    Binary(Range<usize>),
    /// `format="appended"`: this offset into the appended data.
    Appended(usize),
}

/// One `DataArray` tag.
#[derive(Clone, Debug)]
pub struct ArrayTag {
    pub name: String,
    pub scalar: Scalar,
    pub components: usize,
    pub place: Place,
    /// The tag's place in the file, for messages.
    pub at: Position,
}

/// How the appended data are encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AppendedEncoding {
    Base64,
    Raw,
}

/// The binary layout shared by the file's arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub big_endian: bool,
    /// Bytes of each header integer: 4 (`UInt32`, VTK's default) or 8 (`UInt64`).
    pub header_bytes: usize,
    /// The `compressor` of the binary blocks.
    pub compressor: Compressor,
}

/// The compressors of VTK's XML writer (ParaView's `CompressorType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compressor {
    /// No `compressor` attribute: each array is one header word and its data.
    None,
    /// `vtkZLibDataCompressor`: zlib streams (VTK's, OGS's and meshio's default).
    Zlib,
    /// `vtkLZ4DataCompressor`: LZ4 blocks without a frame (ParaView's fastest).
    Lz4,
    /// `vtkLZMADataCompressor`: `.xz` streams (ParaView's smallest, meshio's `lzma`).
    Lzma,
}

impl Compressor {
    /// Its name in the report and in messages.
    pub fn name(self) -> &'static str {
        match self {
            Compressor::None => "uncompressed",
            Compressor::Zlib => "zlib",
            Compressor::Lz4 => "LZ4",
            Compressor::Lzma => "LZMA",
        }
    }
}

/// The appended data: encoding and byte range (after the `_` marker).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Appended {
    pub encoding: AppendedEncoding,
    pub data: Range<usize>,
}

/// A parsed `.vtu`: its layout, counts and array tags.
#[derive(Clone, Debug)]
pub struct VtuXml {
    pub layout: Layout,
    pub appended: Option<Appended>,
    pub n_points: usize,
    pub n_cells: usize,
    pub points: ArrayTag,
    pub connectivity: ArrayTag,
    pub offsets: ArrayTag,
    pub types: ArrayTag,
    pub point_data: Vec<ArrayTag>,
    pub cell_data: Vec<ArrayTag>,
    /// A short description of the encodings met (`appended base64, zlib, UInt64 headers`).
    pub encoding: String,
    /// What the file's arrays may still decode to ([`super::decode::values`]
    /// draws on it before it allocates).
    pub budget: Budget,
}

/// Bytes of decoded values (8 per value) the arrays of one file may take in
/// all: [`crate::input::decoded_limit`] of the file's size.
#[derive(Clone, Debug)]
pub struct Budget {
    file_bytes: u64,
    limit: u64,
    left: std::cell::Cell<u64>,
}

impl Budget {
    pub fn of_file(file_bytes: usize) -> Budget {
        let file_bytes = file_bytes as u64;
        let limit = crate::input::decoded_limit(file_bytes);
        Budget {
            file_bytes,
            limit,
            left: std::cell::Cell::new(limit),
        }
    }

    /// Takes `values` values from the budget, or says why not.
    pub fn take(&self, values: usize) -> Result<(), String> {
        let bytes = (values as u64).saturating_mul(8);
        let left = self.left.get();
        if bytes > left {
            return Err(format!(
                "{values} values take {bytes} bytes decoded, past the {} bytes that the arrays of a file of {} bytes may decode to ({}× its size, at least {} MiB; a compression bomb, or a count the file cannot hold?)",
                self.limit,
                self.file_bytes,
                crate::input::ENTRY_EXPANSION,
                crate::input::ENTRY_FLOOR_BYTES >> 20
            ));
        }
        self.left.set(left - bytes);
        Ok(())
    }
}

fn err(path: &Path, at: Position, message: impl Into<String>) -> ParseError {
    ParseError::new(path, at, message)
}

/// Parses the XML of a `.vtu` held in `bytes`.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<VtuXml, ParseError> {
    let appended_at = memchr::memmem::find(bytes, b"<AppendedData");
    let head_end = appended_at.unwrap_or(bytes.len());
    let head = std::str::from_utf8(&bytes[..head_end]).map_err(|e| {
        let valid = e.valid_up_to();
        let text = String::from_utf8_lossy(&bytes[..valid]);
        err(
            path,
            Position::of_byte(&text, valid),
            "the XML is not valid UTF-8 (is this a legacy binary .vtk file?)",
        )
    })?;
    // One index of the line starts: positions of thousands of tags stay linear.
    let lines = LineIndex::new(head);
    let pos = |byte: usize| lines.position(byte);
    // Without the appended data the document lacks its closing tag: add it.
    let mut xml = head.to_string();
    if appended_at.is_some() {
        xml.push_str("</VTKFile>");
    }
    let doc = roxmltree::Document::parse(&xml).map_err(|e| {
        let p = e.pos();
        err(
            path,
            Position::new(p.row as usize, p.col as usize),
            format!("XML: {e}"),
        )
    })?;
    let root = doc.root_element();
    let at = |node: roxmltree::Node| pos(node.range().start.min(head.len()));
    let layout = layout_of(path, root, at(root))?;
    let grid = child(root, "UnstructuredGrid")
        .ok_or_else(|| err(path, at(root), "no <UnstructuredGrid>"))?;
    let pieces: Vec<_> = grid
        .children()
        .filter(|n| n.has_tag_name("Piece"))
        .collect();
    let piece = match pieces.as_slice() {
        [one] => *one,
        [] => return Err(err(path, at(grid), "no <Piece>")),
        [_, second, ..] => {
            return Err(err(
                path,
                at(*second),
                format!(
                    "{} pieces: a3d-init reads one (merge them, e.g. ParaView's Merge Blocks)",
                    pieces.len()
                ),
            ));
        }
    };
    let count = |name: &str| -> Result<usize, ParseError> {
        piece
            .attribute(name)
            .and_then(|v| v.trim().parse().ok())
            .ok_or_else(|| err(path, at(piece), format!("<Piece> without a valid {name}")))
    };
    let n_points = count("NumberOfPoints")?;
    let n_cells = count("NumberOfCells")?;
    let mut formats: Vec<&'static str> = Vec::new();
    let mut tags_of = |parent: Option<roxmltree::Node>| -> Result<Vec<ArrayTag>, ParseError> {
        let Some(parent) = parent else {
            return Ok(Vec::new());
        };
        parent
            .children()
            .filter(|n| n.has_tag_name("DataArray"))
            .map(|n| {
                let tag = array_tag(path, head, n, &pos)?;
                let f = match tag.place {
                    Place::Ascii(_) => "ascii",
                    Place::Binary(_) => "inline binary",
                    Place::Appended(_) => "appended",
                };
                if !formats.contains(&f) {
                    formats.push(f);
                }
                Ok(tag)
            })
            .collect()
    };
    let points = tags_of(child(piece, "Points"))?;
    let cells = tags_of(child(piece, "Cells"))?;
    let point_data = tags_of(child(piece, "PointData"))?;
    let cell_data = tags_of(child(piece, "CellData"))?;
    let points = match points.len() {
        1 => points.into_iter().next().unwrap_or_else(|| unreachable!()),
        n => {
            return Err(err(
                path,
                at(piece),
                format!("<Points> holds {n} arrays; expected one"),
            ));
        }
    };
    if points.components != 3 {
        return Err(err(
            path,
            points.at,
            format!(
                "the points have {} components; expected 3",
                points.components
            ),
        ));
    }
    let cell_array = |name: &str| -> Result<ArrayTag, ParseError> {
        cells
            .iter()
            .find(|t| t.name == name)
            .cloned()
            .ok_or_else(|| err(path, at(piece), format!("<Cells> has no `{name}` array")))
    };
    let (connectivity, offsets, types) = (
        cell_array("connectivity")?,
        cell_array("offsets")?,
        cell_array("types")?,
    );
    let appended = match appended_at {
        None => None,
        Some(start) => Some(appended_section(path, bytes, start)?),
    };
    let uses_appended = [&points, &connectivity, &offsets, &types]
        .into_iter()
        .chain(&point_data)
        .chain(&cell_data)
        .any(|t| matches!(t.place, Place::Appended(_)));
    if uses_appended && appended.is_none() {
        return Err(err(
            path,
            pos(head.len()),
            "arrays are `appended` but the file has no <AppendedData>",
        ));
    }
    let encoding = encoding_text(&formats, appended.as_ref(), &layout);
    Ok(VtuXml {
        layout,
        appended,
        n_points,
        n_cells,
        points,
        connectivity,
        offsets,
        types,
        point_data,
        cell_data,
        encoding,
        budget: Budget::of_file(bytes.len()),
    })
}

/// The `<VTKFile>` root's checks (an UnstructuredGrid, not a parallel
/// piece) and the layout its attributes give: byte order, header size and
/// compression. Errors are at the root's position `root_at`.
fn layout_of(path: &Path, root: roxmltree::Node, root_at: Position) -> Result<Layout, ParseError> {
    if root.tag_name().name() != "VTKFile" {
        return Err(err(path, root_at, "expected a <VTKFile> document"));
    }
    match root.attribute("type") {
        Some("UnstructuredGrid") => {}
        Some("PUnstructuredGrid") => {
            return Err(err(
                path,
                root_at,
                "a parallel .pvtu: give its pieces merged into one .vtu (OGS: pvtu2vtu)",
            ));
        }
        other => {
            return Err(err(
                path,
                root_at,
                format!(
                    "VTKFile type `{}`: a3d-init reads UnstructuredGrid (.vtu)",
                    other.unwrap_or("")
                ),
            ));
        }
    }
    let big_endian = root.attribute("byte_order") == Some("BigEndian");
    let header_bytes = match root.attribute("header_type") {
        None | Some("UInt32") => 4,
        Some("UInt64") => 8,
        Some(other) => {
            return Err(err(
                path,
                root_at,
                format!("header_type `{other}`: expected UInt32 or UInt64"),
            ));
        }
    };
    let compressor = match root.attribute("compressor") {
        None | Some("") => Compressor::None,
        Some("vtkZLibDataCompressor") => Compressor::Zlib,
        Some("vtkLZ4DataCompressor") => Compressor::Lz4,
        Some("vtkLZMADataCompressor") => Compressor::Lzma,
        Some(other) => {
            return Err(err(
                path,
                root_at,
                format!(
                    "compressor `{other}` is not read (vtkZLibDataCompressor, vtkLZ4DataCompressor and vtkLZMADataCompressor are): write the file with one of them or without compression"
                ),
            ));
        }
    };
    Ok(Layout {
        big_endian,
        header_bytes,
        compressor,
    })
}

/// The encoding in words for the report: the array formats, the appended
/// data's encoding, compression, header size and byte order.
fn encoding_text(formats: &[&str], appended: Option<&Appended>, layout: &Layout) -> String {
    let mut encoding = formats.join(" and ");
    if let Some(a) = appended {
        encoding.push_str(match a.encoding {
            AppendedEncoding::Base64 => " (base64)",
            AppendedEncoding::Raw => " (raw)",
        });
    }
    encoding.push_str(", ");
    encoding.push_str(layout.compressor.name());
    encoding.push_str(if layout.header_bytes == 8 {
        ", UInt64 headers"
    } else {
        ", UInt32 headers"
    });
    if layout.big_endian {
        encoding.push_str(", big-endian");
    }
    encoding
}

fn child<'a, 'i>(node: roxmltree::Node<'a, 'i>, name: &str) -> Option<roxmltree::Node<'a, 'i>> {
    node.children().find(|n| n.has_tag_name(name))
}

fn array_tag(
    path: &Path,
    head: &str,
    node: roxmltree::Node,
    pos: &dyn Fn(usize) -> Position,
) -> Result<ArrayTag, ParseError> {
    let at = pos(node.range().start.min(head.len()));
    let name = node.attribute("Name").unwrap_or("").to_string();
    let label = if name.is_empty() {
        "a DataArray".to_string()
    } else {
        format!("array `{name}`")
    };
    let ty = node.attribute("type").unwrap_or("");
    let scalar =
        Scalar::parse(ty).ok_or_else(|| err(path, at, format!("{label}: unknown type `{ty}`")))?;
    let components = match node.attribute("NumberOfComponents") {
        None => 1,
        Some(v) => match v.trim().parse::<usize>() {
            Ok(n) if n >= 1 => n,
            _ => {
                return Err(err(
                    path,
                    at,
                    format!("{label}: NumberOfComponents `{v}` is not a positive integer"),
                ));
            }
        },
    };
    // The values: the array's own text (VTK may add <InformationKey>
    // children after it, whose text is not data), as a byte range of the file.
    let text = || {
        node.children()
            .filter(|c| c.is_text() && c.text().is_some_and(|t| !t.trim().is_empty()))
            .map(|c| c.range())
            .next()
            .unwrap_or(0..0)
    };
    let place = match node.attribute("format").unwrap_or("ascii") {
        "ascii" => Place::Ascii(text()),
        "binary" => Place::Binary(text()),
        "appended" => {
            let offset = node
                .attribute("offset")
                .and_then(|v| v.trim().parse().ok())
                .ok_or_else(|| {
                    err(
                        path,
                        at,
                        format!("{label}: appended without a valid offset"),
                    )
                })?;
            Place::Appended(offset)
        }
        other => {
            return Err(err(
                path,
                at,
                format!("{label}: format `{other}`; expected ascii, binary or appended"),
            ));
        }
    };
    Ok(ArrayTag {
        name,
        scalar,
        components,
        place,
        at,
    })
}

/// The `<AppendedData>` section starting at byte `start`: its encoding and the
/// bytes after its `_` marker.
fn appended_section(path: &Path, bytes: &[u8], start: usize) -> Result<Appended, ParseError> {
    let at = || {
        let head = String::from_utf8_lossy(&bytes[..start]);
        Position::of_byte(&head, head.len())
    };
    let close = memchr::memchr(b'>', &bytes[start..])
        .map(|k| start + k)
        .ok_or_else(|| err(path, at(), "unclosed <AppendedData"))?;
    let tag = String::from_utf8_lossy(&bytes[start..close]);
    let encoding = if tag.contains("encoding=\"raw\"") {
        AppendedEncoding::Raw
    } else if tag.contains("encoding=\"base64\"") {
        AppendedEncoding::Base64
    } else {
        return Err(err(
            path,
            at(),
            "<AppendedData> without encoding=\"raw\" or \"base64\"",
        ));
    };
    let underscore = memchr::memchr(b'_', &bytes[close..])
        .map(|k| close + k)
        .ok_or_else(|| err(path, at(), "no `_` opening the appended data"))?;
    // Raw data may contain any byte: the section ends at the last closing tag.
    let end = memchr::memmem::rfind(bytes, b"</AppendedData>")
        .filter(|&e| e > underscore)
        .unwrap_or(bytes.len());
    Ok(Appended {
        encoding,
        data: underscore + 1..end,
    })
}
