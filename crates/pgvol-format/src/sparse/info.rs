//! What a `.pgv` file holds, from its header and index alone.

use std::path::Path;

use super::index::layout;
use crate::container::parse_container;
use crate::error::FormatError;
use crate::header::PgvHeader;
use crate::sparse_params::{Precision, ENCODING_SPARSE};

/// What [`pgv_info`] finds from the header and index alone.
#[derive(Clone, Debug, PartialEq)]
pub struct PgvInfo {
    pub header: PgvHeader,
    /// The format version: 1 (header first) or 2 (index and header last, `sparse-bricks`).
    pub version: u32,
    /// `None` for `dense-f32`.
    pub bricks_total: Option<usize>,
    pub bricks_stored: Option<usize>,
    pub precision: Precision,
    /// As in [`EncodeReport`](super::EncodeReport); for `dense-f32` the index is empty and
    /// the payload is the coefficients.
    pub bytes_header: usize,
    pub bytes_index: usize,
    pub bytes_payload: usize,
}

/// Header, brick counts, precision and bytes per part, from the header and index alone.
pub fn pgv_info(bytes: &[u8], path: &Path) -> Result<PgvInfo, FormatError> {
    let c = parse_container(bytes, path, false)?;
    let framing = bytes.len() - c.payload.len() - c.index.map_or(0, <[u8]>::len);
    if c.header.encoding != ENCODING_SPARSE {
        return Ok(PgvInfo {
            version: c.version(),
            header: c.header,
            bricks_total: None,
            bricks_stored: None,
            precision: Precision::F32,
            bytes_header: framing,
            bytes_index: 0,
            bytes_payload: c.payload.len(),
        });
    }
    let l = layout(&c.header, c.index, c.payload, path)?;
    Ok(PgvInfo {
        version: c.version(),
        bricks_total: Some(l.bricks.total()),
        bricks_stored: Some(l.sp.stored),
        precision: l.sp.precision,
        bytes_header: framing,
        bytes_index: l.index_bytes,
        bytes_payload: l.data.len() as usize,
        header: c.header,
    })
}
