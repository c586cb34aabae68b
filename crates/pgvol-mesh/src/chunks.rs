//! Writing long arrays of records: chunks encoded to bytes in parallel, written in order, so a
//! file is the same bytes whatever the thread count while the encoding of the next chunks runs
//! beside the writing of the last ones.

use std::io::{self, Write};
use std::ops::Range;
use std::sync::mpsc;

use rayon::prelude::*;

/// Records per chunk: large enough that a chunk's bookkeeping is nothing beside its encoding.
const CHUNK: usize = 1 << 14;
/// Chunks encoded together before they are handed to the writer: a few MB of bytes in flight.
const BATCH: usize = 16;

/// Writes records `0..count` to `w`: `encode(range, bytes)` appends the records of `range` to
/// `bytes`. Batches of chunks are encoded on the thread pool while the caller's thread writes
/// the batch before, and the bytes reach `w` in record order.
pub(crate) fn write_records(
    w: &mut dyn Write,
    count: usize,
    encode: impl Fn(Range<usize>, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    let chunks = count.div_ceil(CHUNK);
    let encode_chunk = |c: usize| {
        let mut bytes = Vec::new();
        encode(c * CHUNK..(c * CHUNK + CHUNK).min(count), &mut bytes);
        bytes
    };
    if chunks <= BATCH {
        let bytes: Vec<Vec<u8>> = (0..chunks).into_par_iter().map(encode_chunk).collect();
        return bytes.iter().try_for_each(|b| w.write_all(b));
    }
    // One batch waits in the channel while the next is encoded: memory stays two batches.
    let (send, receive) = mpsc::sync_channel::<Vec<Vec<u8>>>(1);
    let encode_chunk = &encode_chunk;
    std::thread::scope(move |scope| {
        // Moved in: dropped when the writing stops, so the encoder's next send fails.
        let receive = receive;
        scope.spawn(move || {
            for first in (0..chunks).step_by(BATCH) {
                let batch: Vec<Vec<u8>> = (first..(first + BATCH).min(chunks))
                    .into_par_iter()
                    .map(encode_chunk)
                    .collect();
                // The writer stopped on an error: nothing more is wanted.
                if send.send(batch).is_err() {
                    return;
                }
            }
        });
        for batch in receive.iter() {
            for bytes in &batch {
                w.write_all(bytes)?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records of 1 to 3 bytes, so chunk boundaries fall anywhere in the output.
    fn encode(range: Range<usize>, out: &mut Vec<u8>) {
        for i in range {
            out.extend(std::iter::repeat_n((i % 251) as u8, 1 + i % 3));
        }
    }

    #[test]
    fn bytes_are_those_of_a_sequential_loop() {
        for count in [
            0,
            1,
            CHUNK - 1,
            CHUNK + 1,
            BATCH * CHUNK,
            3 * BATCH * CHUNK + 17,
        ] {
            let mut want = Vec::new();
            encode(0..count, &mut want);
            let mut got = Vec::new();
            write_records(&mut got, count, encode).unwrap();
            assert_eq!(got, want, "{count} records");
        }
    }

    /// A writer that fails after `left` bytes.
    struct Failing {
        left: usize,
    }

    impl Write for Failing {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if buf.len() > self.left {
                return Err(io::Error::other("disk full"));
            }
            self.left -= buf.len();
            Ok(buf.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_write_error_stops_the_encoding_and_is_returned() {
        let mut w = Failing { left: 1000 };
        let err = write_records(&mut w, 4 * BATCH * CHUNK, encode).unwrap_err();
        assert_eq!(err.to_string(), "disk full");
    }
}
