//! Re-encoding a decoded file: a volume read from a `sparse-bricks` file, handed back with the
//! header it was read with, is written with the same layout, so that encoding what a file
//! decodes to reproduces the file.
//!
//! The band rule cannot be applied again: it reads node values, which quantisation moved, so a
//! node at the band's edge could change side, and the file bricks decoded as background hold the
//! clamp rather than the values the rule saw. Instead the layout is taken from the volume and
//! the header: decoding stores in the volume exactly the grid bricks of the stored file bricks
//! (when the file brick edge is a multiple of the grid's), every other brick takes the
//! background `±clamp` of its side, and the header holds the clamp.

use pgvol_core::{Background, BRICK_EDGE};
use pgvol_field::CoefficientVolume;

use super::bricks::Bricks;
use super::coverage::{Coverage, STORED};
use super::options::EncodeOptions;
use super::stored_band::{every_node, KeptBrick};
use crate::header::PgvHeader;
use crate::sparse_params::{Precision, ENCODING_SPARSE};

/// The layout of a decoded file to write again.
pub(crate) struct Layout {
    /// The file bricks holding a stored brick of the volume, every node needed: no coefficient
    /// is free to move, so quantised values keep their words.
    pub(crate) kept: Vec<KeptBrick>,
    /// The header's clamp, the magnitude of the volume's background.
    pub(crate) clamp: f32,
    /// The precision the file was written in.
    pub(crate) precision: Precision,
}

/// The layout of `volume` when `header` says it was decoded from a `sparse-bricks` file of the
/// brick edge and band `opts` asks for, on its grid, with its background `±clamp`; `None`
/// otherwise (the band rule applies). File bricks must tile the volume's bricks
/// ([`BRICK_EDGE`] divides the edge) for the stored ones to be read off the volume.
pub(crate) fn decoded_layout(
    header: &PgvHeader,
    volume: &CoefficientVolume,
    opts: &EncodeOptions,
    bricks: &Bricks,
    coverage: &Coverage,
) -> Option<Layout> {
    let sp = header.sparse.as_ref()?;
    let same = header.encoding == ENCODING_SPARSE
        && header.grid == volume.grid
        && header.basis == volume.basis
        && sp.brick == opts.brick
        && sp.brick % BRICK_EDGE == 0
        && sp.band == opts.band
        && sp.bricks == bricks.count
        && volume.coeffs.background() == Background::clamp(sp.clamp);
    if !same {
        return None;
    }
    let kept = (0..bricks.total())
        .filter(|&b| coverage.flags(b) & STORED != 0)
        .map(|b| {
            let (_, n) = bricks.extent(b);
            KeptBrick {
                index: b,
                needed: every_node(n[0], n[1] * n[2]),
            }
        })
        .collect();
    Some(Layout {
        kept,
        clamp: sp.clamp,
        precision: sp.precision,
    })
}
