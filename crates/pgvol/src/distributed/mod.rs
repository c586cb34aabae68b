//! Jobs in parts for a distributed engine (the Python package's `pgvol.distributed` runs them
//! on Dask): each part is a slab of the grid that a worker computes alone from global inputs
//! (the mesh, the options, or the coefficient bricks around the slab), so a part can run
//! anywhere, any number of times, and the assembled result is the single-process one.
//!
//! - encode: [`plan_encode`] cuts the grid into slabs of fitting groups along z; an
//!   [`EncodeJob`] (built once per process) samples and fits one slab
//!   ([`EncodeJob::encode_part`]), reading the distances of the two bricks around it that the
//!   local fit's halo needs; [`assemble_encode`] builds the file from the slabs' coefficient
//!   bricks, bit for bit the file of [`encode`](crate::encode()), and [`write_encode_parts`]
//!   writes that file as the parts arrive, holding a window of slabs.
//! - decode: [`plan_decode`] cuts the cells into slabs along z; [`decode_part_bricks`] gives
//!   the coefficient bricks around one, [`decode_part`] its triangles, and [`weld_parts`]
//!   merges the seams.
//! - slice: [`plan_slice`] cuts the layers into ranges; [`slice_part_bricks`] and
//!   [`slice_part`] compute one range, and [`sharpen_layers`] puts the corners of a file's
//!   sharp section back into the concatenated ranges.
//!
//! Bricks travel as [`Slab`] bytes: the grid, basis, sides of absent bricks as runs, and the
//! stored bricks, compressed with zstd.

mod decode_parts;
mod encode_parts;
mod file_parts;
mod slab;
mod split;
mod stream_parts;
mod tiling;

pub use decode_parts::{
    decode_part, decode_part_bricks, plan_decode, plan_slice, sharpen_layers, slice_part,
    slice_part_bricks, weld_parts, PART_HALO_BRICKS,
};
pub use encode_parts::{
    assemble_encode, part_encode_bytes, plan_encode, plan_encode_bytes, EncodeJob, EncodePlan,
    EncodedPart, GroupBox, JOB_BYTES_PER_TRIANGLE,
};
pub use file_parts::{
    decode_file_part, decode_file_part_bricks, plan_decode_file, plan_slice_file,
    sharpen_file_layers, slice_file_part, slice_file_part_bricks,
};
pub use slab::Slab;
pub use split::split;
pub use stream_parts::{write_encode_parts, write_encode_parts_to, PartsWritten};
