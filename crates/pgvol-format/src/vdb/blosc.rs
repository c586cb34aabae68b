//! Blosc1 frames as OpenVDB writes them: a 16-byte header, a table of block offsets, then per
//! block one or `typesize` compressed streams ("splits"), each an LZ4 block, unshuffled by
//! byte afterwards. Only the LZ4 codec and byte shuffle are read: OpenVDB asks for nothing
//! else. Every size is checked against the frame and the expected length before use.

/// Bytes in a Blosc1 header.
pub const HEADER_BYTES: usize = 16;
/// The newest Blosc1 frame format.
const FORMAT_VERSION: u8 = 2;
/// Header flags.
const DOSHUFFLE: u8 = 0x1;
const MEMCPYED: u8 = 0x2;
const DOBITSHUFFLE: u8 = 0x4;
const DONT_SPLIT: u8 = 0x10;
/// Codec number (flags bits 5-7) of LZ4 and LZ4HC, which share one block format.
const LZ4_FORMAT: u8 = 1;
/// Blosc splits a block into `typesize` streams only for types of at most this many bytes
/// and blocks of at least `MIN_SPLIT_ELEMENTS` elements (the rule older frames follow, which
/// carry no flag).
const MAX_SPLITS: usize = 16;
const MIN_SPLIT_ELEMENTS: usize = 128;

/// The bytes of the Blosc1 frame `src`, which must decompress to exactly `expected` bytes.
pub fn decompress(src: &[u8], expected: usize) -> Result<Vec<u8>, String> {
    if src.len() < HEADER_BYTES {
        return Err(format!(
            "a Blosc frame of {} bytes is shorter than its {HEADER_BYTES}-byte header",
            src.len()
        ));
    }
    let version = src[0];
    let flags = src[2];
    let typesize = usize::from(src[3]);
    let nbytes = u32_at(src, 4) as usize;
    let blocksize = u32_at(src, 8) as usize;
    let cbytes = u32_at(src, 12) as usize;
    if version == 0 || version > FORMAT_VERSION {
        return Err(format!(
            "Blosc frame format {version} is not Blosc1 (formats 1 and 2 are read)"
        ));
    }
    if nbytes != expected {
        return Err(format!(
            "the Blosc frame holds {nbytes} bytes where {expected} were expected"
        ));
    }
    if cbytes > src.len() || cbytes < HEADER_BYTES {
        return Err(format!(
            "the Blosc frame says {cbytes} bytes, which is not between its header's \
             {HEADER_BYTES} and the {} there are",
            src.len()
        ));
    }
    let src = &src[..cbytes];
    if flags & MEMCPYED != 0 {
        let body = &src[HEADER_BYTES..];
        if body.len() < nbytes {
            return Err(format!(
                "the uncompressed Blosc frame holds {} of its {nbytes} bytes",
                body.len()
            ));
        }
        return Ok(body[..nbytes].to_vec());
    }
    if flags & DOBITSHUFFLE != 0 {
        return Err("Blosc bit shuffle is not read (OpenVDB writes byte shuffle)".into());
    }
    let codec = flags >> 5;
    if codec != LZ4_FORMAT {
        return Err(format!(
            "Blosc codec {codec} ({}) is not read: OpenVDB writes LZ4 (codec 1)",
            codec_name(codec)
        ));
    }
    if nbytes == 0 {
        return Ok(Vec::new());
    }
    if blocksize == 0 || typesize == 0 {
        return Err(format!(
            "the Blosc frame has a block size of {blocksize} and a type size of {typesize}"
        ));
    }
    let blocks = nbytes.div_ceil(blocksize);
    let starts_end = HEADER_BYTES + 4 * blocks;
    if starts_end > src.len() {
        return Err(format!(
            "the Blosc frame's {blocks} block offsets do not fit in its {} bytes",
            src.len()
        ));
    }
    let shuffled = flags & DOSHUFFLE != 0 && typesize > 1;
    let mut out = vec![0u8; nbytes];
    let mut scratch = Vec::new();
    for (b, block_out) in out.chunks_mut(blocksize).enumerate() {
        let start = u32_at(src, HEADER_BYTES + 4 * b) as usize;
        if start < starts_end || start > src.len() {
            return Err(format!(
                "Blosc block {b} starts at byte {start}, outside the frame's data ({starts_end} to {})",
                src.len()
            ));
        }
        let leftover = block_out.len() < blocksize;
        let splits = if flags & DONT_SPLIT == 0
            && typesize <= MAX_SPLITS
            && blocksize / typesize >= MIN_SPLIT_ELEMENTS
            && !leftover
        {
            typesize
        } else {
            1
        };
        let target: &mut [u8] = if shuffled {
            scratch.clear();
            scratch.resize(block_out.len(), 0);
            &mut scratch
        } else {
            block_out
        };
        decode_block(&src[start..], target, splits, b)?;
        if shuffled {
            unshuffle(typesize, &scratch, block_out);
        }
    }
    Ok(out)
}

/// One block: `splits` streams, each a 4-byte compressed length and an LZ4 block (or the
/// raw bytes when the length equals the stream's size), filling `out` exactly.
fn decode_block(mut src: &[u8], out: &mut [u8], splits: usize, block: usize) -> Result<(), String> {
    let each = out.len() / splits;
    if each * splits != out.len() {
        return Err(format!(
            "Blosc block {block} of {} bytes does not divide into {splits} streams",
            out.len()
        ));
    }
    for (s, part) in out.chunks_mut(each).enumerate() {
        if src.len() < 4 {
            return Err(format!(
                "Blosc block {block} ends before stream {s}'s length"
            ));
        }
        let n = i32::from_le_bytes([src[0], src[1], src[2], src[3]]);
        src = &src[4..];
        let n = usize::try_from(n)
            .ok()
            .filter(|&n| n <= src.len())
            .ok_or_else(|| {
                format!(
                    "Blosc block {block} stream {s} claims {n} bytes, {} remain",
                    src.len()
                )
            })?;
        let (data, rest) = src.split_at(n);
        src = rest;
        if n == part.len() {
            part.copy_from_slice(data);
            continue;
        }
        let got = lz4_flex::block::decompress_into(data, part)
            .map_err(|e| format!("Blosc block {block} stream {s} is not valid LZ4: {e}"))?;
        if got != part.len() {
            return Err(format!(
                "Blosc block {block} stream {s} decompressed to {got} bytes, not {}",
                part.len()
            ));
        }
    }
    Ok(())
}

/// Byte unshuffle: the shuffled block holds byte 0 of every element, then byte 1, ...; bytes
/// past the last whole element are stored as they are.
fn unshuffle(typesize: usize, src: &[u8], out: &mut [u8]) {
    let elements = src.len() / typesize;
    for (j, plane) in src.chunks_exact(elements.max(1)).take(typesize).enumerate() {
        if elements == 0 {
            break;
        }
        for (i, &byte) in plane.iter().enumerate() {
            out[i * typesize + j] = byte;
        }
    }
    let whole = elements * typesize;
    out[whole..].copy_from_slice(&src[whole..]);
}

fn codec_name(codec: u8) -> &'static str {
    match codec {
        0 => "BloscLZ",
        1 => "LZ4",
        2 => "Snappy",
        3 => "zlib",
        4 => "Zstandard",
        _ => "unknown",
    }
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame of `data` stored raw (the memcpy flag).
    fn memcpy_frame(data: &[u8]) -> Vec<u8> {
        let mut f = vec![2, 1, MEMCPYED | DOSHUFFLE, 4];
        f.extend((data.len() as u32).to_le_bytes());
        f.extend((data.len() as u32).to_le_bytes());
        f.extend(((HEADER_BYTES + data.len()) as u32).to_le_bytes());
        f.extend(data);
        f
    }

    /// A one-block frame of `data` shuffled by `typesize` and compressed as one LZ4 stream.
    fn lz4_frame(data: &[u8], typesize: usize) -> Vec<u8> {
        let elements = data.len() / typesize;
        let mut shuffled = vec![0u8; data.len()];
        for i in 0..elements {
            for j in 0..typesize {
                shuffled[j * elements + i] = data[i * typesize + j];
            }
        }
        shuffled[elements * typesize..].copy_from_slice(&data[elements * typesize..]);
        let packed = lz4_flex::block::compress(&shuffled);
        let mut f = vec![
            2,
            1,
            DOSHUFFLE | DONT_SPLIT | (LZ4_FORMAT << 5),
            typesize as u8,
        ];
        f.extend((data.len() as u32).to_le_bytes());
        f.extend((data.len() as u32).to_le_bytes());
        let total = HEADER_BYTES + 4 + 4 + packed.len();
        f.extend((total as u32).to_le_bytes());
        f.extend(((HEADER_BYTES + 4) as u32).to_le_bytes());
        f.extend((packed.len() as i32).to_le_bytes());
        f.extend(packed);
        f
    }

    #[test]
    fn memcpy_frames_give_their_bytes() {
        let data: Vec<u8> = (0..40).collect();
        assert_eq!(decompress(&memcpy_frame(&data), 40).unwrap(), data);
    }

    #[test]
    fn shuffled_lz4_frames_round_trip_with_a_ragged_tail() {
        let data: Vec<u8> = (0..1027u32).map(|i| (i * 7 % 251) as u8).collect();
        assert_eq!(decompress(&lz4_frame(&data, 4), 1027).unwrap(), data);
    }

    #[test]
    fn wrong_sizes_truncation_and_bad_streams_are_errors() {
        let data = vec![3u8; 512];
        let f = lz4_frame(&data, 4);
        assert!(decompress(&f, 511).unwrap_err().contains("expected"));
        for cut in [0, 10, HEADER_BYTES, HEADER_BYTES + 5, f.len() - 1] {
            assert!(decompress(&f[..cut], 512).is_err(), "cut at {cut}");
        }
        let mut bad = f.clone();
        let last = bad.len() - 1;
        bad[last] ^= 0xff;
        bad.truncate(last);
        assert!(decompress(&bad, 512).is_err());
        // A frame size shorter than the header itself.
        let mut short = f.clone();
        short[12..16].copy_from_slice(&3u32.to_le_bytes());
        assert!(decompress(&short, 512).unwrap_err().contains("not between"));
        let mut zstd = f.clone();
        zstd[2] = (zstd[2] & 0x1f) | (4 << 5);
        assert!(decompress(&zstd, 512).unwrap_err().contains("Zstandard"));
    }

    /// A header for one block of `n` bytes.
    fn header(flags: u8, typesize: u8, n: usize, total: usize) -> Vec<u8> {
        let mut f = vec![2, 1, flags, typesize];
        f.extend((n as u32).to_le_bytes());
        f.extend((n as u32).to_le_bytes());
        f.extend((total as u32).to_le_bytes());
        f.extend(((HEADER_BYTES + 4) as u32).to_le_bytes());
        f
    }

    /// An LZ4 block written by hand: one literal, a 19-byte match at offset 1 (a run, the
    /// match overlapping its own output, its length continued in an extra byte), then the five
    /// literals the format requires at the end.
    #[test]
    fn a_hand_written_lz4_stream_with_an_overlapping_match_decodes() {
        let stream = [0x1f, b'a', 1, 0, 0, 0x50, b'b', b'b', b'b', b'b', b'b'];
        let want: Vec<u8> = [vec![b'a'; 20], vec![b'b'; 5]].concat();
        let flags = DONT_SPLIT | (LZ4_FORMAT << 5);
        let mut f = header(flags, 1, want.len(), HEADER_BYTES + 8 + stream.len());
        f.extend((stream.len() as i32).to_le_bytes());
        f.extend(stream);
        assert_eq!(decompress(&f, want.len()).unwrap(), want);
        // The same stream claiming a longer output is refused.
        let mut long = header(flags, 1, 26, HEADER_BYTES + 8 + stream.len());
        long.extend((stream.len() as i32).to_le_bytes());
        long.extend(stream);
        assert!(decompress(&long, 26).is_err());
        // An offset reaching before the output's start is refused.
        let mut reach = header(flags, 1, 25, HEADER_BYTES + 8 + stream.len());
        reach.extend((stream.len() as i32).to_le_bytes());
        reach.extend([0x1f, b'a', 2, 0, 0, 0x50, b'b', b'b', b'b', b'b', b'b']);
        assert!(decompress(&reach, 25).is_err());
    }

    /// Frames without the no-split flag split blocks of at least 128 elements into one stream
    /// per byte of the type (here stored, a stream as long as its share), then unshuffle.
    #[test]
    fn split_blocks_are_read_stream_by_stream() {
        let n = 512;
        let want: Vec<u8> = (0..n).map(|i| (i % 256) as u8 ^ (i / 256) as u8).collect();
        let mut shuffled = vec![0u8; n];
        for i in 0..n / 4 {
            for j in 0..4 {
                shuffled[j * (n / 4) + i] = want[i * 4 + j];
            }
        }
        let mut f = header(
            DOSHUFFLE | (LZ4_FORMAT << 5),
            4,
            n,
            HEADER_BYTES + 4 + 4 * (4 + n / 4),
        );
        for part in shuffled.chunks(n / 4) {
            f.extend(((n / 4) as i32).to_le_bytes());
            f.extend(part);
        }
        assert_eq!(decompress(&f, n).unwrap(), want);
    }
}
