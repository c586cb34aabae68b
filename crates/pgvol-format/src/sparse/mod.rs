//! The `sparse-bricks` payload encoding: the coefficient grid cut into cubic bricks, only the
//! bricks near the surface stored (quantised, predicted, byte-shuffled, zstd-compressed, each
//! with its own CRC), every other brick reconstructed as a constant `±clamp`.
//!
//! Payload layout (all integers little-endian; see `docs/format.md`):
//! ```text
//! stored bitmap  ceil(B/8) bytes   bit b (byte b/8, LSB first) set: brick b is stored
//! inside bitmap  ceil(B/8) bytes   bit b set: unstored brick b is inside (value −clamp)
//! index          S × 16 bytes      per stored brick, in brick order: offset u64, length u32, crc u32
//! icrc           u32               CRC-32 of the bitmaps and the index
//! data           the brick blobs, back to back in brick order
//! ```
//!
//! Writing: `writer` stores the file bricks holding a coefficient the band needs, which
//! `stored_band` finds from windows of the sparse grid near its stored bricks (`coverage` says
//! per file brick which grid bricks are stored and the sides of the others); `kept_bricks` makes
//! the brick maps, the unstored bricks' sides and clamp; `brick_encoder` encodes the stored
//! bricks at the precision `precision_choice` picks, behind the index of `index`; a volume
//! decoded from such a file keeps that file's layout (`reencode`), and quantisation maps decoded
//! values to their own words (`quantise`), so that writing what a file decodes to gives the file
//! back byte for byte. Memory follows
//! the stored bricks plus a byte per file brick, and so does time, plus a table look-up per grid
//! brick. Reading: `index` checks the layout, `brick_read` and `brick_decoder` decode one stored
//! brick, `payload_read` a whole payload in parallel, `slab_read` one slab of bricks along an
//! axis at a time, `read_brick` a single brick and `info` the header and index alone.

mod brick_decoder;
mod brick_encoder;
mod brick_read;
mod bricks;
mod coverage;
mod free_words;
mod index;
mod info;
mod kept_bricks;
mod options;
pub(crate) mod payload_read;
mod precision_choice;
mod predict;
mod quantise;
mod read_brick;
#[cfg(test)]
mod read_profile;
mod reencode;
mod slab_read;
mod stored_band;
mod streamed;
#[cfg(test)]
mod test_volumes;
mod writer;

pub use crate::sparse_params::{
    Compression, Precision, Predictor, SparseParams, BRICK_RANGE, ENCODING_SPARSE,
};
pub use info::{pgv_info, PgvInfo};
pub use options::{EncodeOptions, EncodeReport};
pub use precision_choice::{basis_weight_bound, AUTO_TOLERANCE};
pub use read_brick::{brick_grid, read_brick, Brick};
pub use slab_read::{CompactBrick, CompactSlab, SlabBricks, SlabReader, SlabSource};
pub use streamed::{StreamError, StreamedPgv};
pub use writer::{encode_pgv_with, sparse_pgv, write_pgv_with, SparsePgv};
