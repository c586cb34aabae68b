//! Reading one brick of a `sparse-bricks` file on its own: the header, the index and that brick.

use std::path::Path;

use pgvol_field::Grid;

use super::brick_read::{background, BrickReader};
use super::index::{bit, layout};
use crate::container::parse_container;
use crate::error::{err, FormatError};
use crate::sparse_params::ENCODING_SPARSE;

/// One brick read on its own by [`read_brick`].
#[derive(Clone, Debug, PartialEq)]
pub struct Brick {
    /// Brick coordinates.
    pub coords: [usize; 3],
    /// Grid node of the brick's first coefficient.
    pub first_node: [usize; 3],
    /// Nodes per axis (smaller than the brick edge at the far faces of the grid).
    pub dims: [usize; 3],
    /// False for a background brick, whose coefficients are all `±clamp`.
    pub stored: bool,
    /// x fastest within the brick.
    pub coeffs: Vec<f32>,
}

/// Decodes one brick of a `sparse-bricks` file, reading the header, the index and that brick
/// only (the payload-wide CRC is not computed; the index and brick CRCs are).
pub fn read_brick(bytes: &[u8], path: &Path, coords: [usize; 3]) -> Result<Brick, FormatError> {
    let c = parse_container(bytes, path, false)?;
    if c.header.encoding != ENCODING_SPARSE {
        return Err(err(
            path,
            format!(
                "single bricks can be read only from the {ENCODING_SPARSE} encoding, not '{}'",
                c.header.encoding
            ),
        ));
    }
    let l = layout(&c.header, c.index, c.payload, path)?;
    if (0..3).any(|a| coords[a] >= l.bricks.count[a]) {
        return Err(err(
            path,
            format!(
                "brick {coords:?} is outside the {:?} bricks of the grid",
                l.bricks.count
            ),
        ));
    }
    let b = coords[0] + l.bricks.count[0] * (coords[1] + l.bricks.count[1] * coords[2]);
    let (first_node, dims) = l.bricks.extent(b);
    let stored = bit(l.stored, b);
    let coeffs = if stored {
        // The entry's position is the number of stored bricks before this one.
        let full: usize = l.stored[..b / 8]
            .iter()
            .map(|x| x.count_ones() as usize)
            .sum();
        let e = full + (l.stored[b / 8] & ((1u8 << (b % 8)) - 1)).count_ones() as usize;
        let mut coeffs = vec![0.0; dims.iter().product()];
        BrickReader::default().decode(&l, b, e, path, &mut coeffs)?;
        coeffs
    } else {
        vec![background(&l, b); dims.iter().product()]
    };
    Ok(Brick {
        coords,
        first_node,
        dims,
        stored,
        coeffs,
    })
}

/// The grid a brick of `g` covers, for callers that evaluate bricks on their own.
pub fn brick_grid(g: &Grid, brick: &Brick) -> Grid {
    Grid {
        origin: g.point(
            brick.first_node[0],
            brick.first_node[1],
            brick.first_node[2],
        ),
        spacing: g.spacing,
        dims: brick.dims,
        offset: g.offset,
    }
}
