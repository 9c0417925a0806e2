//! Blosc chunks, the codec OpenVDB writes leaf and tile values with by default.
//!
//! The format (Blosc 1, as documented in c-blosc's `README_CHUNK_FORMAT.rst`): a 16-byte header
//! (format version, codec version, flags, type size, then the uncompressed size, the block size
//! and the chunk's compressed size as little-endian `u32`s); unless the chunk is a plain copy,
//! one `i32` offset per block follows, and each block is one stream, or one per byte of the type
//! size when the block was split. A stream is an `i32` size and that many bytes of the codec's
//! output, or the block's bytes as they are when the size equals them. A byte-shuffled block holds
//! the first byte of every value, then every second byte, and so on. OpenVDB compresses with
//! LZ4 and byte shuffling (`io/Compression.cc`); zlib streams are read too. Every malformed chunk
//! is an error, never a panic.

use crate::error::{ParseError, ParseResult};

const HEADER: usize = 16;
const DO_SHUFFLE: u8 = 0x01;
const MEMCPYED: u8 = 0x02;
const DO_BITSHUFFLE: u8 = 0x04;
const DONT_SPLIT: u8 = 0x10;

fn bad(detail: impl std::fmt::Display) -> ParseError {
    ParseError::new(format!("invalid blosc chunk: {detail}"))
}

fn le_u32(b: &[u8], at: usize) -> ParseResult<u32> {
    b.get(at..at + 4)
        .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        .ok_or_else(|| bad(format!("it ends at byte {} of {}", b.len(), at + 4)))
}

/// Decompresses one chunk that must hold exactly `expected` bytes.
pub(super) fn decompress(src: &[u8], expected: usize) -> ParseResult<Vec<u8>> {
    if src.len() < HEADER {
        return Err(bad(format!("{} bytes, shorter than its header", src.len())));
    }
    let (flags, typesize) = (src[2], usize::from(src[3]));
    let nbytes = le_u32(src, 4)? as usize;
    let blocksize = le_u32(src, 8)? as usize;
    if nbytes != expected {
        return Err(bad(format!(
            "it holds {nbytes} bytes where {expected} were expected"
        )));
    }
    if flags & DO_BITSHUFFLE != 0 {
        return Err(bad(if flags & DO_SHUFFLE != 0 {
            "a Blosc 2 chunk (extended header), which is not supported"
        } else {
            "bit-shuffled, which is not supported (OpenVDB writes byte-shuffled chunks)"
        }));
    }
    if flags & MEMCPYED != 0 {
        return src
            .get(HEADER..HEADER + nbytes)
            .map(<[u8]>::to_vec)
            .ok_or_else(|| bad("its copied bytes are cut short"));
    }
    if nbytes == 0 {
        return Ok(Vec::new());
    }
    if blocksize == 0 || typesize == 0 {
        return Err(bad(format!("block size {blocksize}, type size {typesize}")));
    }
    let codec = Codec::from_flags(flags)?;
    let nblocks = nbytes.div_ceil(blocksize);
    let mut out = vec![0u8; nbytes];
    let mut block = Vec::new();
    for b in 0..nblocks {
        let start = le_u32(src, HEADER + 4 * b)? as usize;
        let first = b * blocksize;
        let bsize = blocksize.min(nbytes - first);
        let leftover = bsize < blocksize;
        let nstreams = if flags & DONT_SPLIT == 0 && !leftover {
            typesize
        } else {
            1
        };
        block.clear();
        block.resize(bsize, 0);
        read_streams(src, start, nstreams, codec, &mut block)?;
        let dest = &mut out[first..first + bsize];
        if flags & DO_SHUFFLE != 0 && typesize > 1 {
            unshuffle(&block, typesize, dest);
        } else {
            dest.copy_from_slice(&block);
        }
    }
    Ok(out)
}

/// The codecs a chunk's flags can name (bits 5 to 7).
#[derive(Clone, Copy)]
enum Codec {
    Lz4,
    Zlib,
}

impl Codec {
    fn from_flags(flags: u8) -> ParseResult<Self> {
        match flags >> 5 {
            1 => Ok(Self::Lz4),
            3 => Ok(Self::Zlib),
            0 => Err(bad(
                "compressed with BloscLZ, which is not supported (OpenVDB writes LZ4)",
            )),
            4 => Err(bad(
                "compressed with Zstd, which is not supported (OpenVDB writes LZ4)",
            )),
            c => Err(bad(format!("unknown codec {c}"))),
        }
    }

    fn decode(self, input: &[u8], out: &mut [u8]) -> ParseResult<()> {
        let n = match self {
            Self::Lz4 => lz4_flex::block::decompress_into(input, out)
                .map_err(|e| bad(format!("LZ4 stream: {e}")))?,
            Self::Zlib => {
                out.copy_from_slice(&super::inflate(
                    input,
                    out.len(),
                    "a blosc chunk's zlib stream",
                )?);
                out.len()
            }
        };
        if n == out.len() {
            Ok(())
        } else {
            Err(bad(format!(
                "a stream decodes to {n} bytes instead of {}",
                out.len()
            )))
        }
    }
}

/// Decodes the `nstreams` streams of one block, starting at `start`, into `block`.
fn read_streams(
    src: &[u8],
    start: usize,
    nstreams: usize,
    codec: Codec,
    block: &mut [u8],
) -> ParseResult<()> {
    let neblock = block.len() / nstreams;
    if neblock * nstreams != block.len() {
        return Err(bad(format!(
            "a block of {} bytes does not split into {nstreams} streams",
            block.len()
        )));
    }
    let mut at = start;
    for part in block.chunks_exact_mut(neblock) {
        let csize = le_u32(src, at)? as i32;
        at += 4;
        match csize {
            0 => part.fill(0),
            c if c < 0 => {
                // A run of one byte, kept in the size's low byte (Blosc 2 writes these).
                let token = *src.get(at).ok_or_else(|| bad("a run's token is missing"))?;
                at += 1;
                if token & 1 == 0 {
                    return Err(bad(format!("stream token {token:#x} is not supported")));
                }
                part.fill(c.unsigned_abs() as u8);
            }
            c => {
                let n = c as usize;
                let input = src
                    .get(at..at + n)
                    .ok_or_else(|| bad(format!("a {n}-byte stream at offset {at} is cut short")))?;
                at += n;
                if n == neblock {
                    part.copy_from_slice(input);
                } else {
                    codec.decode(input, part)?;
                }
            }
        }
    }
    Ok(())
}

/// Undoes byte shuffling: `src` holds byte 0 of every value, then byte 1 of every value, ...;
/// bytes past the last whole value stay where they are.
fn unshuffle(src: &[u8], typesize: usize, dest: &mut [u8]) {
    let n = src.len() / typesize;
    if n == 0 {
        dest.copy_from_slice(src);
        return;
    }
    for (i, plane) in src[..n * typesize].chunks_exact(n).enumerate() {
        for (j, &byte) in plane.iter().enumerate() {
            dest[j * typesize + i] = byte;
        }
    }
    dest[n * typesize..].copy_from_slice(&src[n * typesize..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chunk by hand: header, one block offset, `streams` as given.
    fn chunk(flags: u8, typesize: u8, nbytes: usize, streams: &[&[u8]]) -> Vec<u8> {
        let mut c = vec![2, 1, flags, typesize];
        c.extend((nbytes as u32).to_le_bytes());
        c.extend((nbytes as u32).to_le_bytes());
        c.extend(0u32.to_le_bytes()); // cbytes: not read
        c.extend(20u32.to_le_bytes()); // the one block starts after the offset table
        for s in streams {
            c.extend((s.len() as u32).to_le_bytes());
            c.extend(*s);
        }
        c
    }

    #[test]
    fn unshuffle_restores_values_byte_by_byte() {
        let values: Vec<u8> = (0..12).collect(); // three 4-byte values
        let shuffled = [0, 4, 8, 1, 5, 9, 2, 6, 10, 3, 7, 11];
        let mut back = [0u8; 12];
        unshuffle(&shuffled, 4, &mut back);
        assert_eq!(back.to_vec(), values);
        // Fewer bytes than one value (a half saved with a float's type size): as they are.
        let mut two = [0u8; 2];
        unshuffle(&[5, 6], 4, &mut two);
        assert_eq!(two, [5, 6]);
    }

    #[test]
    fn split_raw_streams_are_reassembled_and_unshuffled() {
        // Two 4-byte values, split into 4 streams of 2 bytes stored as they are.
        let c = chunk(
            DO_SHUFFLE | (1 << 5),
            4,
            8,
            &[&[1, 5], &[2, 6], &[3, 7], &[4, 8]],
        );
        assert_eq!(
            decompress(&c, 8).expect("decodes"),
            vec![1, 2, 3, 4, 5, 6, 7, 8]
        );
    }

    #[test]
    fn an_lz4_stream_is_decoded() {
        let data: Vec<u8> = (0..200u32).flat_map(|i| (i % 7).to_le_bytes()).collect();
        let packed = lz4_flex::block::compress(&data);
        assert!(packed.len() < data.len());
        let c = chunk(DONT_SPLIT | (1 << 5), 4, data.len(), &[&packed]);
        assert_eq!(decompress(&c, data.len()).expect("decodes"), data);
    }

    #[test]
    fn malformed_chunks_are_errors() {
        let data = [7u8; 64];
        let packed = lz4_flex::block::compress(&data);
        let c = chunk(DONT_SPLIT | (1 << 5), 4, 64, &[&packed]);
        for cut in 0..c.len() {
            assert!(decompress(&c[..cut], 64).is_err(), "cut at {cut}");
        }
        assert!(
            decompress(&c, 65)
                .expect_err("an error")
                .detail
                .contains("65 were expected")
        );
        let mut blosclz = c.clone();
        blosclz[2] = DONT_SPLIT;
        assert!(
            decompress(&blosclz, 64)
                .expect_err("an error")
                .detail
                .contains("BloscLZ")
        );
    }
}
