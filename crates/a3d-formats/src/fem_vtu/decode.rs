//! The values of a `DataArray`, whatever its encoding: ASCII numbers, inline
//! base64 (`format="binary"`), or appended data (base64 or raw), each binary
//! block a header (UInt32 or UInt64 integers) then the data, uncompressed or in
//! zlib, LZ4 or LZMA blocks. Every count is checked against what the piece declares before
//! anything is decompressed, so a damaged or hostile file cannot make us
//! allocate more than the array it claims to hold. Errors give the array's tag
//! position, or a byte offset into the file for the binary data.

use std::io::Read;
use std::path::Path;

use base64::Engine as _;

use super::xml::{AppendedEncoding, ArrayTag, Compressor, Layout, Place, Scalar, VtuXml};
use crate::error::{ParseError, Position};

/// The values of `tag`, which must hold `tuples` tuples of its components,
/// converted to f64 (integers up to 2⁵³ exactly).
pub fn values(
    path: &Path,
    bytes: &[u8],
    xml: &VtuXml,
    tag: &ArrayTag,
    tuples: usize,
) -> Result<Vec<f64>, ParseError> {
    let count = tuples
        .checked_mul(tag.components)
        .ok_or_else(|| too_many(path, tag))?;
    let label = label(tag);
    // Nothing is allocated on a declared count before the file's budget
    // allows it.
    xml.budget
        .take(count)
        .map_err(|why| ParseError::new(path, tag.at, format!("{label}: {why}")))?;
    match &tag.place {
        Place::Ascii(range) => ascii(path, bytes, range.clone(), count, tag),
        Place::Binary(range) => {
            let text: Vec<u8> = bytes[range.clone()]
                .iter()
                .copied()
                .filter(|b| !b.is_ascii_whitespace())
                .collect();
            let mut source = Base64Source::new(&text, range.start);
            block(path, &mut source, xml.layout, tag.scalar, count, &label)
        }
        Place::Appended(offset) => {
            let appended = xml.appended.as_ref().ok_or_else(|| {
                ParseError::new(path, tag.at, format!("{label}: no appended data"))
            })?;
            let start = appended
                .data
                .start
                .checked_add(*offset)
                .filter(|&s| s <= appended.data.end);
            let Some(start) = start else {
                return Err(ParseError::new(
                    path,
                    tag.at,
                    format!("{label}: offset {offset} lies past the end of the appended data"),
                ));
            };
            let data = &bytes[start..appended.data.end];
            match appended.encoding {
                AppendedEncoding::Raw => {
                    let mut source = RawSource { data, at: start };
                    block(path, &mut source, xml.layout, tag.scalar, count, &label)
                }
                AppendedEncoding::Base64 => {
                    let mut source = Base64Source::new(data, start);
                    block(path, &mut source, xml.layout, tag.scalar, count, &label)
                }
            }
        }
    }
}

fn label(tag: &ArrayTag) -> String {
    if tag.name.is_empty() {
        "the points".into()
    } else {
        format!("array `{}`", tag.name)
    }
}

fn too_many(path: &Path, tag: &ArrayTag) -> ParseError {
    ParseError::new(path, tag.at, format!("{}: too many values", label(tag)))
}

fn ascii(
    path: &Path,
    bytes: &[u8],
    range: std::ops::Range<usize>,
    count: usize,
    tag: &ArrayTag,
) -> Result<Vec<f64>, ParseError> {
    let text = std::str::from_utf8(&bytes[range.clone()]).unwrap_or("");
    let mut out = Vec::with_capacity(count.min(text.len() / 2 + 1));
    for (k, token) in text.split_ascii_whitespace().enumerate() {
        if k == count {
            return Err(ParseError::new(
                path,
                tag.at,
                format!("{}: more than the {count} values declared", label(tag)),
            ));
        }
        let v: f64 = token.parse().map_err(|_| {
            let offset = token.as_ptr() as usize - text.as_ptr() as usize + range.start;
            let before = String::from_utf8_lossy(&bytes[..offset]);
            ParseError::new(
                path,
                Position::of_byte(&before, before.len()),
                format!("{}: `{token}` is not a number", label(tag)),
            )
        })?;
        out.push(v);
    }
    if out.len() != count {
        return Err(ParseError::new(
            path,
            tag.at,
            format!(
                "{}: {} values, but the piece declares {count}",
                label(tag),
                out.len()
            ),
        ));
    }
    Ok(out)
}

/// Bytes of one array's binary block, read in order.
trait Source {
    /// The next `n` bytes.
    fn take(&mut self, n: usize) -> Result<Vec<u8>, (usize, String)>;
}

/// Raw appended bytes.
struct RawSource<'a> {
    data: &'a [u8],
    /// File offset of `data[0]`.
    at: usize,
}

impl Source for RawSource<'_> {
    fn take(&mut self, n: usize) -> Result<Vec<u8>, (usize, String)> {
        if n > self.data.len() {
            return Err((
                self.at,
                format!("{n} bytes needed, {} left in the file", self.data.len()),
            ));
        }
        let (head, rest) = self.data.split_at(n);
        self.data = rest;
        self.at += n;
        Ok(head.to_vec())
    }
}

/// Base64 text decoded on demand. Writers encode a block's header and its data
/// either as one stream or as two, each padded: a `=` ends a stream and the
/// next one starts at the following character.
struct Base64Source<'a> {
    text: &'a [u8],
    /// File offset of `text[0]` (for messages).
    at: usize,
    /// Decoded bytes not yet taken.
    pending: Vec<u8>,
}

impl<'a> Base64Source<'a> {
    fn new(text: &'a [u8], at: usize) -> Base64Source<'a> {
        Base64Source {
            text,
            at,
            pending: Vec::new(),
        }
    }

    /// Decodes at least `need` more bytes (or up to a padded end) into `pending`.
    fn decode_more(&mut self, need: usize) -> Result<(), (usize, String)> {
        let quanta = need.div_ceil(3).max(1);
        let mut len = (quanta * 4).min(self.text.len());
        // A padded quantum ends its stream: decode up to it only.
        if let Some(eq) = memchr::memchr(b'=', &self.text[..len]) {
            len = (eq / 4 + 1) * 4;
        }
        if len == 0 || !len.is_multiple_of(4) || len > self.text.len() {
            return Err((
                self.at,
                "the base64 data end before the array does".to_string(),
            ));
        }
        let chunk = &self.text[..len];
        base64::engine::general_purpose::STANDARD
            .decode_vec(chunk, &mut self.pending)
            .map_err(|e| (self.at, format!("invalid base64: {e}")))?;
        self.text = &self.text[len..];
        self.at += len;
        Ok(())
    }
}

impl Source for Base64Source<'_> {
    fn take(&mut self, n: usize) -> Result<Vec<u8>, (usize, String)> {
        while self.pending.len() < n {
            let need = n - self.pending.len();
            self.decode_more(need)?;
        }
        let rest = self.pending.split_off(n);
        Ok(std::mem::replace(&mut self.pending, rest))
    }
}

fn read_uint(bytes: &[u8], layout: Layout) -> u64 {
    let mut buf = [0u8; 8];
    let n = layout.header_bytes;
    if layout.big_endian {
        buf[8 - n..].copy_from_slice(&bytes[..n]);
        u64::from_be_bytes(buf)
    } else {
        buf[..n].copy_from_slice(&bytes[..n]);
        u64::from_le_bytes(buf)
    }
}

/// One array's block: header then data, uncompressed or compressed blocks.
fn block(
    path: &Path,
    source: &mut dyn Source,
    layout: Layout,
    scalar: Scalar,
    count: usize,
    label: &str,
) -> Result<Vec<f64>, ParseError> {
    let fail = |(at, message): (usize, String)| {
        ParseError::new(path, Position::in_binary(at), format!("{label}: {message}"))
    };
    let expected = count
        .checked_mul(scalar.size())
        .ok_or_else(|| fail((0, "too many values".into())))?;
    let h = layout.header_bytes;
    let raw = if layout.compressor == Compressor::None {
        let size = read_uint(&source.take(h).map_err(fail)?, layout);
        if size != expected as u64 {
            return Err(fail((
                0,
                format!(
                    "{size} bytes of data, but {count} {} values are {expected} bytes",
                    scalar.name()
                ),
            )));
        }
        source.take(expected).map_err(fail)?
    } else {
        let first = source.take(3 * h).map_err(fail)?;
        let n_blocks = read_uint(&first, layout);
        let block_size = read_uint(&first[h..], layout);
        let last_size = read_uint(&first[2 * h..], layout);
        let total = if n_blocks == 0 {
            0
        } else {
            let last = if last_size == 0 {
                block_size
            } else {
                last_size
            };
            (n_blocks - 1)
                .checked_mul(block_size)
                .and_then(|t| t.checked_add(last))
                .unwrap_or(u64::MAX)
        };
        if total != expected as u64 || (n_blocks > 0 && block_size == 0) {
            return Err(fail((
                0,
                format!(
                    "compressed header declares {total} bytes ({n_blocks} blocks of {block_size}), but {count} {} values are {expected} bytes",
                    scalar.name()
                ),
            )));
        }
        let sizes = source.take(n_blocks as usize * h).map_err(fail)?;
        // Grown with the data inflated, not reserved on the header's word.
        let mut out = Vec::with_capacity(expected.min(1 << 20));
        for k in 0..n_blocks as usize {
            let csize = read_uint(&sizes[k * h..], layout) as usize;
            let want = if k + 1 == n_blocks as usize {
                total - (n_blocks - 1) * block_size
            } else {
                block_size
            } as usize;
            let compressed = source.take(csize).map_err(fail)?;
            let before = out.len();
            let name = layout.compressor.name();
            inflate(layout.compressor, &compressed, want, &mut out)
                .map_err(|e| fail((0, format!("{name} block {}: {e}", k + 1))))?;
            if out.len() - before != want {
                return Err(fail((
                    0,
                    format!(
                        "{name} block {} holds {} bytes, the header says {want}",
                        k + 1,
                        out.len() - before
                    ),
                )));
            }
        }
        out
    };
    Ok(convert(&raw, scalar, layout.big_endian))
}

/// Appends the block `compressed` to `out`, as inflated by `compressor`:
/// `want` bytes when the block is whole, never more than one byte past
/// them, so that a block that inflates past its header's size is caught
/// without inflating it all (LZ4 is told its size and stops there).
fn inflate(
    compressor: Compressor,
    compressed: &[u8],
    want: usize,
    out: &mut Vec<u8>,
) -> Result<(), String> {
    match compressor {
        Compressor::None => {
            out.extend_from_slice(compressed);
            Ok(())
        }
        Compressor::Zlib => flate2::read::ZlibDecoder::new(compressed)
            .take(want as u64 + 1)
            .read_to_end(out)
            .map(drop)
            .map_err(|e| e.to_string()),
        Compressor::Lz4 => {
            // VTK's LZ4 blocks are bare (no frame): the size comes from the
            // header, and a block that decodes to anything else is refused.
            // The buffer is sized before decoding, so the size is first held
            // against what the block's bytes can give: each byte of an LZ4
            // block adds at most 255 bytes of output.
            let most = compressed.len().saturating_mul(255).saturating_add(64);
            if want > most {
                return Err(format!(
                    "its {} bytes cannot decode to the {want} its header gives (at most {most})",
                    compressed.len()
                ));
            }
            let before = out.len();
            out.resize(before + want, 0);
            let n = lz4_flex::block::decompress_into(compressed, &mut out[before..])
                .map_err(|e| e.to_string())?;
            out.truncate(before + n);
            Ok(())
        }
        Compressor::Lzma => {
            // An `.xz` stream (VTK's `lzma_easy_buffer_encode`, Python's
            // `lzma.compress`), streamed and capped as zlib's is; liblzma
            // refuses a header asking for a dictionary past LZMA_MEMLIMIT.
            let stream = liblzma::stream::Stream::new_stream_decoder(LZMA_MEMLIMIT, 0)
                .map_err(|e| e.to_string())?;
            liblzma::read::XzDecoder::new_stream(compressed, stream)
                .take(want as u64 + 1)
                .read_to_end(out)
                .map(drop)
                .map_err(|e| e.to_string())
        }
    }
}

/// The memory liblzma may take to decode one block: 256 MiB, four times
/// what xz's strongest preset (`-9`, a 64 MiB dictionary) needs.
const LZMA_MEMLIMIT: u64 = 256 << 20;

fn convert(raw: &[u8], scalar: Scalar, big_endian: bool) -> Vec<f64> {
    macro_rules! each {
        ($t:ty) => {
            raw.chunks_exact(std::mem::size_of::<$t>())
                .map(|c| {
                    let b = c.try_into().unwrap_or([0; std::mem::size_of::<$t>()]);
                    (if big_endian {
                        <$t>::from_be_bytes(b)
                    } else {
                        <$t>::from_le_bytes(b)
                    }) as f64
                })
                .collect()
        };
    }
    match scalar {
        Scalar::I8 => each!(i8),
        Scalar::U8 => each!(u8),
        Scalar::I16 => each!(i16),
        Scalar::U16 => each!(u16),
        Scalar::I32 => each!(i32),
        Scalar::U32 => each!(u32),
        Scalar::I64 => each!(i64),
        Scalar::U64 => each!(u64),
        Scalar::F32 => each!(f32),
        Scalar::F64 => each!(f64),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use base64::engine::general_purpose::STANDARD;
    use std::io::Write;

    const LE64: Layout = Layout {
        big_endian: false,
        header_bytes: 8,
        compressor: Compressor::None,
    };

    fn doubles(v: &[f64]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    fn decode(text: &str, layout: Layout, count: usize) -> Result<Vec<f64>, ParseError> {
        let mut source = Base64Source::new(text.as_bytes(), 0);
        block(
            Path::new("t.vtu"),
            &mut source,
            layout,
            Scalar::F64,
            count,
            "array `a`",
        )
    }

    #[test]
    fn uncompressed_base64_as_one_stream_or_two() {
        let v = [1.5, -2.0, 1e-300];
        let data = doubles(&v);
        let header = (data.len() as u64).to_le_bytes();
        let one = STANDARD.encode([header.as_slice(), &data].concat());
        let two = STANDARD.encode(header) + &STANDARD.encode(&data);
        assert_eq!(decode(&one, LE64, 3).unwrap(), v);
        assert_eq!(decode(&two, LE64, 3).unwrap(), v);
    }

    #[test]
    fn zlib_blocks_with_uint32_headers() {
        let v: Vec<f64> = (0..100).map(|i| i as f64 * 0.25).collect();
        let data = doubles(&v);
        // Two blocks of 512 and 288 bytes, as VTK splits them.
        let text = blocks(&data, 512, |chunk| {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(chunk).unwrap();
            z.finish().unwrap()
        });
        let layout = layout(Compressor::Zlib);
        assert_eq!(decode(&text, layout, 100).unwrap(), v);
        // A header declaring more bytes than the array holds is refused before
        // anything is decompressed.
        let e = decode(&text, layout, 99).unwrap_err().to_string();
        assert!(e.contains("declares 800 bytes"), "{e}");
    }

    /// `data` as VTK's compressed blocks of `size` bytes (UInt32 headers),
    /// each compressed by `pack`, in base64.
    fn blocks(data: &[u8], size: usize, pack: impl Fn(&[u8]) -> Vec<u8>) -> String {
        let blobs: Vec<Vec<u8>> = data.chunks(size).map(pack).collect();
        let last = data.len() - (blobs.len() - 1) * size;
        encoded(&blobs, size, last)
    }

    /// Compressed `blobs` under their UInt32 header (count, block size, last
    /// block's size, each blob's size), in base64.
    fn encoded(blobs: &[Vec<u8>], size: usize, last: usize) -> String {
        let mut header = Vec::new();
        for n in [blobs.len(), size, last]
            .into_iter()
            .chain(blobs.iter().map(Vec::len))
        {
            header.extend((n as u32).to_le_bytes());
        }
        STANDARD.encode(&header) + &STANDARD.encode(blobs.concat())
    }

    fn layout(compressor: Compressor) -> Layout {
        Layout {
            big_endian: false,
            header_bytes: 4,
            compressor,
        }
    }

    /// `blob` as the one compressed block of 256 bytes (32 doubles) that a
    /// UInt32 header declares, in base64.
    fn one_block(blob: &[u8]) -> String {
        encoded(&[blob.to_vec()], 256, 256)
    }

    fn xz(data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        liblzma::read::XzEncoder::new(data, 6)
            .read_to_end(&mut out)
            .unwrap();
        out
    }

    #[test]
    fn lz4_and_lzma_blocks_decode_to_the_values() {
        let v: Vec<f64> = (0..100).map(|i| (i as f64).sqrt() - 3.0).collect();
        let data = doubles(&v);
        let lz4 = blocks(&data, 256, lz4_flex::block::compress);
        assert_eq!(decode(&lz4, layout(Compressor::Lz4), 100).unwrap(), v);
        let lzma = blocks(&data, 256, xz);
        assert_eq!(decode(&lzma, layout(Compressor::Lzma), 100).unwrap(), v);
    }

    #[test]
    fn a_block_that_inflates_past_its_header_is_refused_early() {
        // 1 MiB of zeros in one block whose header says 256 bytes: refused
        // without inflating the megabyte.
        let zeros = vec![0u8; 1 << 20];
        for (compressor, blob) in [
            (Compressor::Lz4, lz4_flex::block::compress(&zeros)),
            (Compressor::Lzma, xz(&zeros)),
        ] {
            let e = decode(&one_block(&blob), layout(compressor), 32)
                .unwrap_err()
                .to_string();
            assert!(e.contains(&format!("{} block 1", compressor.name())), "{e}");
        }
        // An LZ4 block of a few bytes whose header claims more than they
        // can give: refused before its buffer is sized.
        let mut header = Vec::new();
        for n in [1u32, 1 << 30, 1 << 30, 4] {
            header.extend(n.to_le_bytes());
        }
        let text = STANDARD.encode(&header) + &STANDARD.encode([0u8; 4]);
        let e = decode(&text, layout(Compressor::Lz4), 1 << 27)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("LZ4 block 1: its 4 bytes cannot decode to the 1073741824"),
            "{e}"
        );
        // A block cut short, and bytes that are no stream at all.
        let data = doubles(&[1.0; 32]);
        for compressor in [Compressor::Lz4, Compressor::Lzma, Compressor::Zlib] {
            for blob in [xz(&data)[..20].to_vec(), vec![0xff; 40]] {
                let e = decode(&one_block(&blob), layout(compressor), 32)
                    .unwrap_err()
                    .to_string();
                assert!(e.contains("block 1"), "{e}");
            }
        }
    }

    #[test]
    fn an_lzma_dictionary_past_the_memory_limit_is_refused() {
        // A valid stream whose block header asks for a 4 GiB dictionary (the
        // LZMA2 property 40), its header's CRC32 mended: refused, nothing
        // allocated for it.
        let data = doubles(&[2.5; 32]);
        let mut blob = xz(&data);
        let at = 12; // the block header follows the 12-byte stream header
        let size = (usize::from(blob[at]) + 1) * 4;
        assert_eq!(
            &blob[at + 2..at + 4],
            &[0x21, 0x01],
            "LZMA2, one property byte"
        );
        blob[at + 4] = 40;
        let mut crc = flate2::Crc::new();
        crc.update(&blob[at..at + size - 4]);
        blob[at + size - 4..at + size].copy_from_slice(&crc.sum().to_le_bytes());
        let e = decode(&one_block(&blob), layout(Compressor::Lzma), 32)
            .unwrap_err()
            .to_string();
        assert!(e.contains("LZMA block 1") && e.contains("emory"), "{e}");
    }

    #[test]
    fn big_endian_raw_values() {
        let mut bytes = 16u64.to_be_bytes().to_vec();
        bytes.extend(3.0f64.to_be_bytes());
        bytes.extend((-0.5f64).to_be_bytes());
        let mut source = RawSource {
            data: &bytes,
            at: 0,
        };
        let layout = Layout {
            big_endian: true,
            ..LE64
        };
        let v = block(Path::new("t.vtu"), &mut source, layout, Scalar::F64, 2, "a").unwrap();
        assert_eq!(v, [3.0, -0.5]);
    }

    #[test]
    fn short_data_give_the_byte_where_they_end() {
        let data = doubles(&[1.0, 2.0]);
        let mut bytes = (data.len() as u64).to_le_bytes().to_vec();
        bytes.extend(&data[..10]);
        let mut source = RawSource {
            data: &bytes,
            at: 1000,
        };
        let e = block(
            Path::new("t.vtu"),
            &mut source,
            LE64,
            Scalar::F64,
            2,
            "array `a`",
        )
        .unwrap_err()
        .to_string();
        assert_eq!(
            e,
            "t.vtu: byte 1008: array `a`: 16 bytes needed, 10 left in the file"
        );
    }
}
