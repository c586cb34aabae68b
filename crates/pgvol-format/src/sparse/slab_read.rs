//! Reading a `sparse-bricks` payload one slab of file bricks at a time (the bricks sharing one
//! coordinate along an axis), so a caller walking along the axis holds a window of the volume
//! instead of all of it. Each slab is cut into the sparse grid's bricks as the whole read does.

use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use pgvol_core::sparse::BrickValues;
use pgvol_core::{Background, WordScale, BRICK_EDGE, BRICK_NODES};
use rayon::prelude::*;

use super::brick_read::{check_all_bricks, checked_blob, BrickReader};
use super::index::{bit, layout, layout_in_file, BrickData, IndexBuilder, Layout};
use super::payload_read::{cut_into_grid_bricks, cut_into_grid_bricks_of, grid_bricks_of};
use crate::container::{
    parse_container, v2_header, v2_sizes, write_streamed_end, write_streamed_start, MAGIC, TRAILER,
    VERSION_STREAMED,
};
use crate::error::err;
use crate::error::FormatError;
use crate::header::PgvHeader;
use crate::sparse_params::{Precision, ENCODING_SPARSE};

/// A checked `sparse-bricks` file, read slab by slab.
pub struct SlabReader<'a> {
    header: PgvHeader,
    layout: Layout<'a>,
    path: PathBuf,
    /// Per row of file bricks along x: the index entry of its first stored brick.
    row_entries: Vec<usize>,
    /// The words of [`SlabReader::compact_slab`], worked out at its first call.
    words: OnceLock<Option<WordTable>>,
}

/// How a `fixed` file's 16-bit words map to values, and the word of the clamp, if one.
struct WordTable {
    scale: WordScale,
    clamp: Option<i16>,
}

/// The sparse grid's bricks within one slab of file bricks.
#[derive(Default)]
pub struct SlabBricks {
    /// Stored bricks with their coordinates, in file brick order.
    pub stored: Vec<([usize; 3], Box<BrickValues>)>,
    /// Coordinates of the absent bricks that are inside.
    pub inside: Vec<[usize; 3]>,
}

/// A grid brick's coefficients from [`SlabReader::compact_slab`].
pub enum CompactBrick {
    /// The `fixed` precision's words, mapped to values by [`SlabReader::word_scale`].
    Words(Box<[i16; BRICK_NODES]>),
    Values(Box<BrickValues>),
}

/// The sparse grid's bricks within one slab of file bricks, as [`CompactBrick`]s.
#[derive(Default)]
pub struct CompactSlab {
    /// Stored bricks with their coordinates, in file brick order.
    pub stored: Vec<([usize; 3], CompactBrick)>,
    /// Coordinates of the absent bricks that are inside.
    pub inside: Vec<[usize; 3]>,
}

/// What a [`SlabReader`] reads from: a whole file in memory, or a version 2 file's index and
/// header with its bricks left in the file, read a slab at a time, so a reader walking the
/// slabs holds the index and a window of bricks, not the file.
pub enum SlabSource {
    Bytes(Vec<u8>),
    File {
        file: std::fs::File,
        header: Box<PgvHeader>,
        /// The brick maps, index and its CRC.
        index: Vec<u8>,
        /// Bytes of brick data, from byte 12 of the file.
        data_len: u64,
    },
}

impl SlabSource {
    /// Opens the file at `path`: a version 2 file keeps its bricks on disk, any other file (and
    /// anything that is not a regular file) is read whole.
    pub fn open(path: &Path) -> Result<SlabSource, FormatError> {
        let whole = || {
            pgvol_core::read_input(path)
                .map(SlabSource::Bytes)
                .map_err(|e| err(path, e.problem))
        };
        let Ok(mut file) = std::fs::File::open(path) else {
            return whole();
        };
        let len = match file.metadata() {
            Ok(m) if m.is_file() => m.len(),
            _ => return whole(),
        };
        let mut head = [0u8; 12];
        let streamed = len >= (head.len() + TRAILER) as u64
            && file.read_exact(&mut head).is_ok()
            && &head[..8] == MAGIC
            && head[8..] == VERSION_STREAMED.to_le_bytes();
        if !streamed {
            return whole();
        }
        let read = |file: &mut std::fs::File, at: u64, n: u64| -> Result<Vec<u8>, FormatError> {
            let mut buf = vec![0u8; n as usize];
            file.seek(SeekFrom::Start(at))
                .and_then(|_| file.read_exact(&mut buf))
                .map_err(|e| err(path, format!("cannot read file: {e}")))?;
            Ok(buf)
        };
        let trailer = read(&mut file, len - TRAILER as u64, TRAILER as u64)?;
        let sizes = v2_sizes(len, &trailer, path)?;
        let start = head.len() as u64;
        let mut rest = read(
            &mut file,
            start + sizes.dlen,
            sizes.ilen + sizes.hlen as u64,
        )?;
        let header = v2_header(&rest[sizes.ilen as usize..], sizes.hcrc, path)?;
        rest.truncate(sizes.ilen as usize);
        Ok(SlabSource::File {
            file,
            header: Box::new(header),
            index: rest,
            data_len: sizes.dlen,
        })
    }

    /// The whole file's bytes, when it was read whole.
    pub fn bytes(&self) -> Option<&[u8]> {
        match self {
            SlabSource::Bytes(b) => Some(b),
            SlabSource::File { .. } => None,
        }
    }
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
        Ok(Self::with_layout(c.header, layout, path))
    }

    /// A reader of `source`: as [`open`](SlabReader::open) for bytes; for a version 2 file left
    /// on disk, the header and index are checked now and each brick's CRC as it is read.
    pub fn from_source(source: &'a SlabSource, path: &Path) -> Result<Option<Self>, FormatError> {
        match source {
            SlabSource::Bytes(bytes) => SlabReader::open(bytes, path),
            SlabSource::File {
                file,
                header,
                index,
                data_len,
            } => {
                let data = BrickData::File {
                    file,
                    start: 12,
                    len: *data_len,
                };
                let layout = layout_in_file(header, index, data, path)?;
                Ok(Self::with_layout((**header).clone(), layout, path))
            }
        }
    }

    fn with_layout(header: PgvHeader, layout: Layout<'a>, path: &Path) -> Option<Self> {
        if !layout.bricks.edge.is_multiple_of(BRICK_EDGE) {
            return None;
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
        Some(SlabReader {
            header,
            layout,
            path: path.to_path_buf(),
            row_entries,
            words: OnceLock::new(),
        })
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

    /// A box of the sparse grid's bricks (per axis, a range of brick indices) holding every
    /// stored brick and every absent brick inside; each grid brick outside it is absent and
    /// outside. From the index alone: a byte of the brick maps at a time, so a file of mostly
    /// absent bricks costs its bytes, not its bricks. Empty ranges when nothing is stored or
    /// inside.
    pub fn occupied_bricks(&self) -> [std::ops::Range<usize>; 3] {
        let l = &self.layout;
        let count = l.bricks.count;
        let total = count.iter().product::<usize>();
        let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
        for (byte, (&s, &i)) in l.stored.iter().zip(l.inside).enumerate() {
            let mut set = s | i;
            while set != 0 {
                let b = 8 * byte + set.trailing_zeros() as usize;
                set &= set - 1;
                if b >= total {
                    break;
                }
                let c = [
                    b % count[0],
                    b / count[0] % count[1],
                    b / (count[0] * count[1]),
                ];
                for a in 0..3 {
                    lo[a] = lo[a].min(c[a]);
                    hi[a] = hi[a].max(c[a] + 1);
                }
            }
        }
        // File bricks to grid bricks; the last file brick along an axis may hold fewer.
        let per = self.grid_bricks_per_slab();
        let grid_counts = l.bricks.dims.map(|n| n.div_ceil(BRICK_EDGE));
        std::array::from_fn(|a| {
            if lo[a] < hi[a] {
                lo[a] * per..(hi[a] * per).min(grid_counts[a])
            } else {
                0..0
            }
        })
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
        let (stored, inside) = self.slab_with(axis, slab, |reader, values, b| {
            let l = &self.layout;
            let (_, n) = l.bricks.extent(b);
            values.resize(n[0] * n[1] * n[2], 0.0);
            reader.decode(l, b, self.entry(b), &self.path, values)?;
            Ok(cut_into_grid_bricks(l, b, n, values))
        })?;
        Ok(SlabBricks { stored, inside })
    }

    /// [`SlabReader::slab`], each brick kept as the file's 16-bit words where the file is in
    /// the default `fixed` encoding, [`SlabReader::word_scale`] maps every word and the file
    /// brick's words fit (and, for a brick reaching past the grid, the clamp is a word); as
    /// values otherwise. Half the memory for a reader holding many bricks, the same
    /// coefficients.
    pub fn compact_slab(&self, axis: usize, slab: usize) -> Result<CompactSlab, FormatError> {
        let words = self.words();
        let (stored, inside) = self.slab_with(axis, slab, |reader, values, b| {
            let l = &self.layout;
            let (_, n) = l.bricks.extent(b);
            // Only grid bricks reaching past the file brick need the clamp's word as filling.
            let whole = n.iter().all(|c| c.is_multiple_of(BRICK_EDGE));
            let fill = words.and_then(|t| if whole { Some(0) } else { t.clamp });
            if let Some(fill) = fill {
                let mut words = vec![0i16; n[0] * n[1] * n[2]];
                if reader.decode_words16(l, b, self.entry(b), &self.path, &mut words)? {
                    let bricks = cut_into_grid_bricks_of(l, b, n, &words, fill);
                    return Ok(bricks
                        .into_iter()
                        .map(|(at, w)| (at, CompactBrick::Words(w)))
                        .collect());
                }
            }
            values.resize(n[0] * n[1] * n[2], 0.0);
            reader.decode(l, b, self.entry(b), &self.path, values)?;
            let bricks = cut_into_grid_bricks(l, b, n, values);
            Ok(bricks
                .into_iter()
                .map(|(at, v)| (at, CompactBrick::Values(v)))
                .collect())
        })?;
        Ok(CompactSlab { stored, inside })
    }

    /// A version 2 file of the same volume holding only the bricks whose coordinate along
    /// `axis` lies in `slabs`: the stored ones' blobs copied as they are (each CRC checked), the
    /// others' sides; every brick beyond is absent and outside, as a cut of the volume. For a
    /// reader of those slabs, the file's own bricks. The sharp section is left out. A part of a
    /// job gets these bytes instead of the whole file or its decoded coefficients.
    pub fn part_file(
        &self,
        axis: usize,
        slabs: std::ops::Range<usize>,
    ) -> Result<Vec<u8>, FormatError> {
        let l = &self.layout;
        let total = l.bricks.total();
        let mut index = IndexBuilder::new(total);
        let mut data = Vec::new();
        let mut entry = 0;
        for b in 0..total {
            let within = slabs.contains(&l.bricks.coords(b)[axis]);
            if !bit(l.stored, b) {
                if within && bit(l.inside, b) {
                    index.inside[b / 8] |= 1 << (b % 8);
                }
                continue;
            }
            if within {
                let blob = checked_blob(l, b, entry, &self.path)?;
                index.stored[b / 8] |= 1 << (b % 8);
                index.push(&blob);
                data.extend_from_slice(&blob);
            }
            entry += 1;
        }
        let mut header = self.header.clone();
        header.sharp = None;
        if let Some(sp) = header.sparse.as_mut() {
            sp.stored = index.stored.iter().map(|m| m.count_ones() as usize).sum();
        }
        let mut out = Vec::with_capacity(data.len() + 1024);
        write_streamed_start(&mut out).expect("writing to memory");
        out.extend_from_slice(&data);
        let index = index.finish();
        write_streamed_end(&mut out, data.len() as u64, &index, &header)
            .expect("writing to memory");
        Ok(out)
    }

    /// How the 16-bit words of [`SlabReader::compact_slab`] map to values, exactly for every
    /// such word; `None` where the file is not in the `fixed` precision or some 16-bit word's
    /// value is not finite or not exact in f32 (bricks then come as values).
    pub fn word_scale(&self) -> Option<WordScale> {
        self.words().map(|t| t.scale)
    }

    fn words(&self) -> Option<&WordTable> {
        let words = self.words.get_or_init(|| {
            let sp = &self.layout.sp;
            let fixed = sp.fixed.filter(|_| sp.precision == Precision::Fixed)?;
            let scale = fixed.words();
            // Values grow with the magnitude, so the largest word bounds them all.
            let largest = i16::MIN as i32;
            if !(scale.exact_up_to(largest.unsigned_abs()) && scale.value(largest).is_finite()) {
                return None;
            }
            let clamp = (i16::MIN..=i16::MAX)
                .find(|&w| scale.value(w as i32).to_bits() == sp.clamp.to_bits());
            Some(WordTable { scale, clamp })
        });
        words.as_ref()
    }

    /// The stored bricks (by `decode`, given a reader, a buffer and a file brick) and the
    /// inside absent bricks of slab `slab` along `axis`.
    #[allow(clippy::type_complexity)]
    fn slab_with<T: Send>(
        &self,
        axis: usize,
        slab: usize,
        decode: impl Fn(&mut BrickReader, &mut Vec<f32>, usize) -> Result<Vec<([usize; 3], T)>, FormatError>
            + Sync,
    ) -> Result<(Vec<([usize; 3], T)>, Vec<[usize; 3]>), FormatError> {
        let l = &self.layout;
        let count = l.bricks.count;
        if axis > 2 || slab >= count[axis] {
            return Ok((Vec::new(), Vec::new()));
        }
        let [p, q] = [(axis + 1) % 3, (axis + 2) % 3];
        let mut stored = Vec::new();
        let mut inside = Vec::new();
        for jq in 0..count[q] {
            for jp in 0..count[p] {
                let mut c = [0; 3];
                (c[axis], c[p], c[q]) = (slab, jp, jq);
                let b = c[0] + count[0] * (c[1] + count[1] * c[2]);
                if bit(l.stored, b) {
                    stored.push(b);
                } else if bit(l.inside, b) {
                    inside.extend(grid_bricks_of(l, b).map(|(m, _)| m));
                }
            }
        }
        let decoded: Vec<Result<Vec<_>, FormatError>> = stored
            .par_iter()
            .map_init(
                || (BrickReader::default(), Vec::new()),
                |(reader, values), &b| decode(reader, values, b),
            )
            .collect();
        let mut out = Vec::new();
        for pieces in decoded {
            out.extend(pieces?);
        }
        Ok((out, inside))
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
        file_bytes_in(None, brick)
    }

    fn file_bytes() -> Vec<u8> {
        file_bytes_with(16)
    }

    /// The test volume in `precision` (the encoder's choice for `None`) and file bricks of
    /// `brick` nodes.
    fn file_bytes_in(precision: Option<Precision>, brick: usize) -> Vec<u8> {
        let volume = sparse(Basis::Bspline3, Background::clamp(0.5), 7);
        let file = PgvFile {
            header: header_for(&volume, "interp", None),
            volume,
        };
        let options = EncodeOptions {
            brick,
            precision,
            ..Default::default()
        };
        encode_pgv_with(&file, &options).unwrap().0
    }

    /// A `fixed` scale whose 16-bit words the f32 computation does not give exactly (a coarse
    /// step of 65,536 fine ones puts words past 256 beyond 2²⁴ steps) offers no words: compact
    /// slabs hold the values.
    #[test]
    fn a_scale_inexact_for_some_words_gives_values() {
        let volume = sparse(Basis::Bspline3, Background::clamp(0.5), 7);
        let file = PgvFile {
            header: header_for(&volume, "interp", None),
            volume,
        };
        let options = EncodeOptions {
            precision: Some(Precision::Fixed),
            fixed_ratio: 1 << 16,
            ..Default::default()
        };
        let bytes = encode_pgv_with(&file, &options).unwrap().0;
        let reader = SlabReader::open(&bytes, Path::new("s.pgv"))
            .unwrap()
            .unwrap();
        assert!(reader.word_scale().is_none());
        let mut stored = 0;
        for s in 0..reader.brick_counts()[2] {
            let plain = reader.slab(2, s).unwrap();
            let compact = reader.compact_slab(2, s).unwrap();
            assert_eq!(plain.stored.len(), compact.stored.len());
            for ((_, want), (_, got)) in plain.stored.iter().zip(&compact.stored) {
                let CompactBrick::Values(got) = got else {
                    panic!("words without a scale for them");
                };
                assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits));
                stored += 1;
            }
        }
        assert!(stored > 0);
    }

    /// Compact slabs hold the slabs' coefficients bit for bit, as words where the file is
    /// `fixed` (bricks cut at the grid's far faces included), as values otherwise.
    #[test]
    fn compact_slabs_hold_the_same_coefficients() {
        for (precision, brick) in [
            (Precision::Fixed, 8),
            (Precision::Fixed, 16),
            (Precision::F32, 16),
        ] {
            let bytes = file_bytes_in(Some(precision), brick);
            let reader = SlabReader::open(&bytes, Path::new("s.pgv"))
                .unwrap()
                .unwrap();
            let scale = reader.word_scale();
            assert_eq!(scale.is_some(), precision == Precision::Fixed);
            let mut words = 0;
            for axis in 0..3 {
                for s in 0..reader.brick_counts()[axis] {
                    let plain = reader.slab(axis, s).unwrap();
                    let compact = reader.compact_slab(axis, s).unwrap();
                    assert_eq!(plain.inside, compact.inside);
                    assert_eq!(plain.stored.len(), compact.stored.len());
                    for ((m, values), (n, brick)) in plain.stored.iter().zip(&compact.stored) {
                        assert_eq!(m, n);
                        let got: Vec<u32> = match brick {
                            CompactBrick::Words(w) => {
                                words += 1;
                                let scale = scale.expect("words come with their values");
                                w.iter().map(|&w| scale.value(w as i32).to_bits()).collect()
                            }
                            CompactBrick::Values(v) => v.iter().map(|v| v.to_bits()).collect(),
                        };
                        let want: Vec<u32> = values.iter().map(|v| v.to_bits()).collect();
                        assert_eq!(got, want, "brick {m:?}");
                    }
                }
            }
            assert_eq!(
                words > 0,
                precision == Precision::Fixed,
                "{precision:?} {brick}"
            );
        }
    }

    #[test]
    fn slabs_along_every_axis_hold_the_whole_read_bricks() {
        for brick in [8, 16] {
            slabs_hold_the_whole_read_bricks(&file_bytes_with(brick));
        }
    }

    fn slabs_hold_the_whole_read_bricks(bytes: &[u8]) {
        let reader = SlabReader::open(bytes, Path::new("s.pgv"))
            .unwrap()
            .unwrap();
        slabs_hold_the_bricks_of(&reader, bytes);
    }

    fn slabs_hold_the_bricks_of(reader: &SlabReader, bytes: &[u8]) {
        let path = Path::new("s.pgv");
        let whole = decode_pgv(bytes, path).unwrap().volume.coeffs;
        let whole_inside = whole
            .all_bricks()
            .filter(|&m| whole.brick(m).is_none() && whole.is_inside(m))
            .count();
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
                        reader.compact_slab(axis, s).unwrap();
                    }
                }
            }
        }
    }

    /// A part file's slabs in its range are the whole file's, brick for brick and side for
    /// side, and the slabs outside hold nothing stored or inside; a damaged brick is refused,
    /// not copied under a fresh checksum.
    #[test]
    fn part_files_hold_the_slabs_of_their_range() {
        for brick in [8, 16] {
            let bytes = file_bytes_with(brick);
            let path = Path::new("s.pgv");
            let whole = SlabReader::open(&bytes, path).unwrap().unwrap();
            for axis in 0..3 {
                let n = whole.brick_counts()[axis];
                assert!(n >= 2, "brick {brick} axis {axis}: {n} slabs");
                // Every slab but the first, and the last too where there are more than two.
                let range = 1..if n > 2 { n - 1 } else { n };
                let part_bytes = whole.part_file(axis, range.clone()).unwrap();
                assert!(part_bytes.len() < bytes.len(), "brick {brick} axis {axis}");
                let part = SlabReader::open(&part_bytes, Path::new("p.pgv"))
                    .unwrap()
                    .unwrap();
                let mut stored = 0;
                for s in 0..n {
                    let (a, b) = (whole.slab(axis, s).unwrap(), part.slab(axis, s).unwrap());
                    if range.contains(&s) {
                        assert_eq!(a.stored, b.stored, "slab {s} along {axis}");
                        assert_eq!(a.inside, b.inside, "slab {s} along {axis}");
                        stored += b.stored.len();
                    } else {
                        assert!(b.stored.is_empty() && b.inside.is_empty(), "slab {s}");
                    }
                }
                assert!(stored > 0, "brick {brick} axis {axis}");
            }
        }
        let bytes = file_bytes();
        let n = bytes.len();
        let dlen = u64::from_le_bytes(bytes[n - 32..n - 24].try_into().unwrap()) as usize;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.pgv");
        let mut bad = bytes.clone();
        bad[12 + dlen / 2] ^= 1;
        std::fs::write(&path, &bad).unwrap();
        let source = SlabSource::open(&path).unwrap();
        let reader = SlabReader::from_source(&source, &path).unwrap().unwrap();
        let count = reader.brick_counts()[2];
        let e = reader.part_file(2, 0..count).err().unwrap().to_string();
        assert!(
            e.contains("checksum mismatch") && e.contains("d.pgv"),
            "{e}"
        );
        let empty = reader.part_file(2, 0..0).unwrap();
        let part = SlabReader::open(&empty, Path::new("e.pgv"))
            .unwrap()
            .unwrap();
        assert!((0..count).all(|s| part.slab(2, s).unwrap().stored.is_empty()));
    }

    #[test]
    fn a_version_2_file_is_read_from_disk_a_brick_at_a_time() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.pgv");
        for brick in [8, 16] {
            let bytes = file_bytes_with(brick);
            std::fs::write(&path, &bytes).unwrap();
            let source = SlabSource::open(&path).unwrap();
            assert!(
                source.bytes().is_none(),
                "a version 2 file is not read whole"
            );
            let reader = SlabReader::from_source(&source, &path).unwrap().unwrap();
            assert_eq!(
                reader.header(),
                &parse_container(&bytes, &path, true).unwrap().header
            );
            slabs_hold_the_bricks_of(&reader, &bytes);
        }
        // Version 1 is read whole, and reads the same.
        let volume = sparse(Basis::Bspline3, Background::clamp(0.5), 7);
        let file = PgvFile {
            header: header_for(&volume, "interp", None),
            volume,
        };
        let v1 = crate::sparse::sparse_pgv(&file, &EncodeOptions::default())
            .unwrap()
            .0
            .to_bytes_v1();
        std::fs::write(&path, &v1).unwrap();
        let source = SlabSource::open(&path).unwrap();
        assert_eq!(source.bytes(), Some(&v1[..]));
        slabs_hold_the_bricks_of(
            &SlabReader::from_source(&source, &path).unwrap().unwrap(),
            &v1,
        );
    }

    #[test]
    fn damage_in_a_file_on_disk_is_found_where_it_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.pgv");
        let good = file_bytes();
        // Cut short: the trailer is missing.
        std::fs::write(&path, &good[..good.len() - 5]).unwrap();
        let e = SlabSource::open(&path).err().unwrap().to_string();
        assert!(e.contains("truncated") && e.contains("d.pgv"), "{e}");
        // A damaged index.
        let n = good.len();
        let dlen = u64::from_le_bytes(good[n - 32..n - 24].try_into().unwrap()) as usize;
        let mut bad = good.clone();
        bad[12 + dlen + 3] ^= 1;
        std::fs::write(&path, &bad).unwrap();
        let source = SlabSource::open(&path).unwrap();
        let e = SlabReader::from_source(&source, &path)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("index checksum"), "{e}");
        // A damaged brick: found by the slab that holds it.
        let mut bad = good.clone();
        bad[12 + 1] ^= 1;
        std::fs::write(&path, &bad).unwrap();
        let source = SlabSource::open(&path).unwrap();
        let reader = SlabReader::from_source(&source, &path).unwrap().unwrap();
        let errors: Vec<String> = (0..reader.brick_counts()[2])
            .filter_map(|s| reader.slab(2, s).err().map(|e| e.to_string()))
            .collect();
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert!(errors[0].contains("checksum mismatch"), "{}", errors[0]);
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
