//! Reading a `sparse-bricks` payload one slab of file bricks at a time (the bricks sharing one
//! coordinate along an axis), so a caller walking along the axis holds a window of the volume
//! instead of all of it. Each slab is cut into the sparse grid's bricks as the whole read does.

use std::path::{Path, PathBuf};

use pgvol_core::sparse::BrickValues;
use pgvol_core::{Background, BRICK_EDGE};
use rayon::prelude::*;

use super::brick_read::{check_all_bricks, BrickReader};
use super::index::{bit, layout, Layout};
use super::payload_read::{cut_into_grid_bricks, grid_bricks_of};
use crate::container::parse_container;
use crate::error::FormatError;
use crate::header::PgvHeader;
use crate::sparse_params::ENCODING_SPARSE;

/// A checked `sparse-bricks` file, read slab by slab.
pub struct SlabReader<'a> {
    header: PgvHeader,
    layout: Layout<'a>,
    path: PathBuf,
    /// Per row of file bricks along x: the index entry of its first stored brick.
    row_entries: Vec<usize>,
}

/// The sparse grid's bricks within one slab of file bricks.
#[derive(Default)]
pub struct SlabBricks {
    /// Stored bricks with their coordinates, in file brick order.
    pub stored: Vec<([usize; 3], Box<BrickValues>)>,
    /// Coordinates of the absent bricks that are inside.
    pub inside: Vec<[usize; 3]>,
}

impl<'a> SlabReader<'a> {
    /// Checks the container (both CRCs) and the brick index of `bytes`. `Ok(None)` for a valid
    /// file that is not read by slabs: another encoding, or file bricks that are not whole
    /// numbers of the grid's bricks.
    pub fn open(bytes: &'a [u8], path: &Path) -> Result<Option<Self>, FormatError> {
        let c = parse_container(bytes, path, true)?;
        if c.header.encoding != ENCODING_SPARSE {
            return Ok(None);
        }
        let layout = layout(&c.header, c.index, c.payload, path)?;
        if c.index.is_some() {
            check_all_bricks(&layout, path)?;
        }
        if layout.bricks.edge % BRICK_EDGE != 0 {
            return Ok(None);
        }
        let [cx, cy, cz] = layout.bricks.count;
        let mut row_entries = Vec::with_capacity(cy * cz);
        let mut seen = 0;
        for row in 0..cy * cz {
            row_entries.push(seen);
            seen += (row * cx..(row + 1) * cx)
                .filter(|&b| bit(layout.stored, b))
                .count();
        }
        Ok(Some(SlabReader {
            header: c.header,
            layout,
            path: path.to_path_buf(),
            row_entries,
        }))
    }

    pub fn header(&self) -> &PgvHeader {
        &self.header
    }

    /// The value of absent bricks by side.
    pub fn background(&self) -> Background {
        Background::clamp(self.layout.sp.clamp)
    }

    /// File bricks per axis.
    pub fn brick_counts(&self) -> [usize; 3] {
        self.layout.bricks.count
    }

    /// The sparse grid's bricks per file brick edge.
    pub fn grid_bricks_per_slab(&self) -> usize {
        self.layout.bricks.edge / BRICK_EDGE
    }

    /// The index entry of stored file brick `b`: the stored bricks before it.
    fn entry(&self, b: usize) -> usize {
        let cx = self.layout.bricks.count[0];
        let row = b / cx;
        self.row_entries[row]
            + (row * cx..b)
                .filter(|&x| bit(self.layout.stored, x))
                .count()
    }

    /// The bricks of the file bricks whose coordinate along `axis` is `slab`; stored ones are
    /// decoded in parallel. Nothing for a slab past the grid.
    pub fn slab(&self, axis: usize, slab: usize) -> Result<SlabBricks, FormatError> {
        let l = &self.layout;
        let count = l.bricks.count;
        if axis > 2 || slab >= count[axis] {
            return Ok(SlabBricks::default());
        }
        let [p, q] = [(axis + 1) % 3, (axis + 2) % 3];
        let mut stored = Vec::new();
        let mut out = SlabBricks::default();
        for jq in 0..count[q] {
            for jp in 0..count[p] {
                let mut c = [0; 3];
                (c[axis], c[p], c[q]) = (slab, jp, jq);
                let b = c[0] + count[0] * (c[1] + count[1] * c[2]);
                if bit(l.stored, b) {
                    stored.push(b);
                } else if bit(l.inside, b) {
                    out.inside.extend(grid_bricks_of(l, b).map(|(m, _)| m));
                }
            }
        }
        let decoded: Vec<Result<Vec<_>, FormatError>> = stored
            .par_iter()
            .map_init(
                || (BrickReader::default(), Vec::new()),
                |(reader, values), &b| {
                    let (_, n) = l.bricks.extent(b);
                    values.resize(n[0] * n[1] * n[2], 0.0);
                    reader.decode(l, b, self.entry(b), &self.path, values)?;
                    Ok(cut_into_grid_bricks(l, b, n, values))
                },
            )
            .collect();
        for pieces in decoded {
            out.stored.extend(pieces?);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::header::{header_for, PgvFile};
    use crate::pgv::decode_pgv;
    use crate::sparse::test_volumes::sparse;
    use crate::sparse::{encode_pgv_with, EncodeOptions};
    use pgvol_field::Basis;

    fn file_bytes_with(brick: usize) -> Vec<u8> {
        let volume = sparse(Basis::Bspline3, Background::clamp(0.5), 7);
        let file = PgvFile {
            header: header_for(&volume, "interp", None),
            volume,
        };
        let options = EncodeOptions {
            brick,
            ..Default::default()
        };
        encode_pgv_with(&file, &options).unwrap().0
    }

    fn file_bytes() -> Vec<u8> {
        file_bytes_with(16)
    }

    #[test]
    fn slabs_along_every_axis_hold_the_whole_read_bricks() {
        for brick in [8, 16] {
            slabs_hold_the_whole_read_bricks(&file_bytes_with(brick));
        }
    }

    fn slabs_hold_the_whole_read_bricks(bytes: &[u8]) {
        let path = Path::new("s.pgv");
        let whole = decode_pgv(bytes, path).unwrap().volume.coeffs;
        let whole_inside = whole
            .all_bricks()
            .filter(|&m| whole.brick(m).is_none() && whole.is_inside(m))
            .count();
        let reader = SlabReader::open(bytes, path).unwrap().unwrap();
        for axis in 0..3 {
            let (mut stored, mut inside) = (0, 0);
            for s in 0..reader.brick_counts()[axis] {
                let slab = reader.slab(axis, s).unwrap();
                for (m, values) in &slab.stored {
                    assert_eq!(whole.brick(*m).unwrap(), &**values, "brick {m:?}");
                    stored += 1;
                }
                for m in &slab.inside {
                    assert!(whole.brick(*m).is_none() && whole.is_inside(*m), "{m:?}");
                    inside += 1;
                }
            }
            assert_eq!(stored, whole.stored_count());
            assert_eq!(inside, whole_inside);
            assert!(stored > 0, "no stored brick");
        }
    }

    proptest::proptest! {
        #[test]
        fn corrupted_files_never_panic_and_what_reads_is_what_was_written(
            pos in 0usize..100_000,
            val in proptest::prelude::any::<u8>(),
            cut in 0usize..100_000,
        ) {
            let good = file_bytes();
            let mut bytes = good.clone();
            let n = bytes.len();
            bytes[pos % n] = val;
            bytes.truncate(cut % (n + 1));
            let path = Path::new("c.pgv");
            if let Ok(Some(reader)) = SlabReader::open(&bytes, path) {
                // Both checksums passed: the bytes are the file written.
                proptest::prop_assert_eq!(&bytes, &good);
                for axis in 0..3 {
                    for s in 0..reader.brick_counts()[axis] + 1 {
                        reader.slab(axis, s).unwrap();
                    }
                }
            }
        }
    }

    #[test]
    fn damaged_files_are_refused_on_opening() {
        let mut bytes = file_bytes();
        let n = bytes.len();
        bytes[n / 2] ^= 1;
        let e = SlabReader::open(&bytes, Path::new("d.pgv")).err().unwrap();
        assert!(e.to_string().contains("checksum"), "{e}");
    }
}
