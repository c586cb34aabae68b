//! Writing a `sparse-bricks` file while its coefficients arrive in layers along z: each layer
//! of file bricks is decided, encoded and written as soon as every coefficient it reads is
//! there, and the index and header follow the bricks (format version 2), so the writer holds
//! the maps and the index, not the bricks. The file is byte for byte what
//! [`sparse_pgv`](super::sparse_pgv) writes of the whole volume.

use std::io::Write;
use std::ops::Range;
use std::path::Path;

use pgvol_field::CoefficientVolume;

use super::brick_encoder::{encode_bricks, StoredBricks};
use super::bricks::Bricks;
use super::coverage::Coverage;
use super::free_words::tolerance_steps;
use super::index::IndexBuilder;
use super::kept_bricks::{clamp_of, sides_of_layers};
use super::options::{EncodeOptions, EncodeReport};
use super::precision_choice::{basis_weight_bound, fixed_scale, AUTO_TOLERANCE};
use super::stored_band::{layer_reach, stored_band_layers};
use crate::container::{streamed_framing_bytes, write_streamed_end, write_streamed_start};
use crate::error::{err, FormatError};
use crate::header::PgvHeader;
use crate::sparse_params::{Precision, SparseParams, ENCODING_SPARSE};

/// Why a streamed write stopped.
#[derive(Debug)]
pub enum StreamError {
    /// The automatic precision's first choice (`fixed`) does not hold some brick within the
    /// tolerance, and choosing another needs every brick at once: write the whole volume with
    /// [`sparse_pgv`](super::sparse_pgv) instead.
    WholeVolume,
    /// The options or the volume are not valid.
    Invalid(FormatError),
    /// Writing to the output failed.
    Write(std::io::Error),
}

impl std::fmt::Display for StreamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StreamError::WholeVolume => f.write_str(
                "the automatic precision needs the whole volume: a brick is not held within the \
                 tolerance by the fixed precision",
            ),
            StreamError::Invalid(e) => write!(f, "{e}"),
            StreamError::Write(e) => write!(f, "write failed: {e}"),
        }
    }
}

impl std::error::Error for StreamError {}

/// A `sparse-bricks` file being written layer by layer; see the module.
pub struct StreamedPgv<'w> {
    out: &'w mut dyn Write,
    header: PgvHeader,
    opts: EncodeOptions,
    bricks: Bricks,
    sp: SparseParams,
    /// The largest error a stored coefficient may take under automatic precision.
    tolerance: Option<f32>,
    tolerance_steps: i32,
    index: IndexBuilder,
    /// The first file brick layer not written yet.
    next: usize,
    largest_unstored: f32,
    worst: f32,
}

impl<'w> StreamedPgv<'w> {
    /// Starts the file of a volume with `header`'s grid and basis on `out`.
    pub fn start(
        out: &'w mut dyn Write,
        header: PgvHeader,
        opts: &EncodeOptions,
    ) -> Result<StreamedPgv<'w>, StreamError> {
        let fail = |m: String| StreamError::Invalid(err(Path::new("<encode>"), m));
        opts.check().map_err(fail)?;
        let grid = header.grid;
        let weight = basis_weight_bound(header.basis);
        let scale = fixed_scale(opts, grid.spacing, weight).map_err(fail)?;
        let bricks = Bricks::new(grid.dims, opts.brick);
        let precision = opts.precision.unwrap_or(Precision::Fixed);
        let sp = SparseParams {
            brick: opts.brick,
            bricks: bricks.count,
            stored: 0,
            precision,
            predictor: opts.predictor,
            shuffle: opts.shuffle,
            compression: opts.compression,
            clamp: 0.0,
            band: opts.band,
            fixed: (precision == Precision::Fixed).then_some(scale),
        };
        write_streamed_start(out).map_err(StreamError::Write)?;
        Ok(StreamedPgv {
            out,
            header,
            opts: opts.clone(),
            bricks,
            sp,
            tolerance: opts
                .precision
                .is_none()
                .then_some(AUTO_TOLERANCE * grid.spacing / weight),
            tolerance_steps: tolerance_steps(opts, weight),
            index: IndexBuilder::new(bricks.total()),
            next: 0,
            largest_unstored: 0.0,
            worst: 0.0,
        })
    }

    /// Puts `section` in the header the file ends with (it is written by [`StreamedPgv::finish`]).
    pub fn set_sharp(&mut self, section: Option<crate::sharp::SharpSection>) {
        self.header.sharp = section;
    }

    /// The node layers along z whose coefficients writing the next file brick layers up to
    /// (not including) `end` reads.
    fn nodes_read(&self, end: usize) -> Range<usize> {
        layer_reach(&self.bricks, self.header.basis, self.next..end).nodes
    }

    /// The first node layer along z that writes still to come read: the caller may drop the
    /// coefficients below it.
    pub fn first_node_needed(&self) -> usize {
        if self.next >= self.bricks.count[2] {
            return self.bricks.dims[2];
        }
        self.nodes_read(self.next + 1).start
    }

    /// Writes every file brick layer not written yet whose coefficients lie in node layers
    /// below `complete` (every remaining layer when `complete` is the grid's node count along
    /// z). `volume` holds at least the coefficients from [`first_node_needed`] to `complete`;
    /// others may be absent.
    ///
    /// [`first_node_needed`]: StreamedPgv::first_node_needed
    pub fn write_ready(
        &mut self,
        volume: &CoefficientVolume,
        complete: usize,
    ) -> Result<(), StreamError> {
        let (count, nz) = (self.bricks.count[2], self.bricks.dims[2]);
        let mut end = self.next;
        while end < count && (complete >= nz || self.nodes_read(end + 1).end <= complete) {
            end += 1;
        }
        if end > self.next {
            self.write_layers(volume, self.next..end)?;
            self.next = end;
        }
        Ok(())
    }

    fn write_layers(
        &mut self,
        volume: &CoefficientVolume,
        layers: Range<usize>,
    ) -> Result<(), StreamError> {
        let reach = layer_reach(&self.bricks, volume.basis, layers.clone());
        let coverage = Coverage::layers(&volume.coeffs, &self.bricks, reach.coverage);
        let kept = stored_band_layers(
            volume,
            &self.bricks,
            &coverage,
            self.opts.band,
            layers.clone(),
        );
        for k in &kept {
            self.index.stored[k.index / 8] |= 1 << (k.index % 8);
        }
        let largest = sides_of_layers(
            volume,
            &self.bricks,
            &coverage,
            &self.index.stored,
            layers,
            &mut self.index.inside,
        );
        self.largest_unstored = self.largest_unstored.max(largest);
        let stored = StoredBricks {
            volume,
            bricks: &self.bricks,
            kept: &kept,
            tolerance_steps: self.tolerance_steps,
        };
        let invalid = |m: String| StreamError::Invalid(err(Path::new("<encode>"), m));
        let encoded = encode_bricks(&stored, &self.sp, self.opts.zstd_level).map_err(invalid)?;
        let Some((blobs, worst)) = encoded else {
            return Err(match self.tolerance {
                Some(_) => StreamError::WholeVolume,
                None => invalid(format!(
                    "precision {} cannot represent these coefficients",
                    self.sp.precision.name()
                )),
            });
        };
        if self.tolerance.is_some_and(|t| worst > t) {
            return Err(StreamError::WholeVolume);
        }
        self.worst = self.worst.max(worst);
        for blob in &blobs {
            self.out.write_all(blob).map_err(StreamError::Write)?;
            self.index.push(blob);
        }
        self.sp.stored += blobs.len();
        Ok(())
    }

    /// Writes the layers left, the index and the header. `volume` is the last window (its
    /// background and basis are the whole volume's); `full` tells whether every grid brick of
    /// the whole volume was stored, which decides the clamp as [`sparse_pgv`] does.
    ///
    /// [`sparse_pgv`]: super::sparse_pgv
    pub fn finish(
        mut self,
        volume: &CoefficientVolume,
        full: bool,
    ) -> Result<EncodeReport, StreamError> {
        self.write_ready(volume, self.bricks.dims[2])?;
        self.sp.clamp = clamp_of(volume, full, self.largest_unstored, self.opts.band);
        let mut header = self.header;
        header.encoding = ENCODING_SPARSE.to_string();
        header.sparse = Some(self.sp.clone());
        let header_len = serde_json::to_vec(&header)
            .expect("header serialises")
            .len();
        let data_len = self.index.data_bytes();
        let index = self.index.finish();
        write_streamed_end(self.out, data_len, &index, &header).map_err(StreamError::Write)?;
        Ok(EncodeReport {
            bricks_total: self.bricks.total(),
            bricks_stored: self.sp.stored,
            bytes_header: streamed_framing_bytes(header_len),
            bytes_index: index.len(),
            bytes_payload: data_len as usize,
            precision: self.sp.precision,
            max_quantisation_error: self.worst,
            clamp: self.sp.clamp,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::header::{header_for, PgvFile};
    use crate::sparse::sparse_pgv;
    use crate::sparse::test_volumes::{dense, sparse, BASES};
    use glam::Vec3;
    use pgvol_core::{Background, SparseGrid, BRICK_EDGE};
    use pgvol_field::{Basis, Grid};

    /// A capsule's clamped distance on a tall grid, bricks stored within `2.5` spacings of its
    /// surface, the others outside or inside as their centre is.
    fn capsule(basis: Basis) -> CoefficientVolume {
        let grid = Grid {
            origin: Vec3::ZERO,
            spacing: 0.1,
            dims: [21, 19, 75],
            offset: Default::default(),
        };
        let clamp = 0.4;
        let d = |p: Vec3| {
            let z = p.z.clamp(1.5, 6.0);
            (p - Vec3::new(1.0, 0.9, z)).length() - 0.6
        };
        let values: Vec<f32> = (0..grid.len())
            .map(|i| {
                let [nx, ny, _] = grid.dims;
                d(grid.point(i % nx, (i / nx) % ny, i / (nx * ny))).clamp(-clamp, clamp)
            })
            .collect();
        let coeffs =
            SparseGrid::from_dense_where(grid.dims, &values, Background::clamp(clamp), |b| {
                let lo = b.map(|c| c * BRICK_EDGE);
                let hi = [0, 1, 2].map(|a| (lo[a] + BRICK_EDGE).min(grid.dims[a]) - 1);
                let near = (lo[0]..=hi[0]).any(|i| {
                    (lo[1]..=hi[1])
                        .any(|j| (lo[2]..=hi[2]).any(|k| d(grid.point(i, j, k)).abs() < 0.25))
                });
                if near {
                    Some(true)
                } else if d(grid.point(lo[0], lo[1], lo[2])) < 0.0 {
                    None
                } else {
                    Some(false)
                }
            });
        CoefficientVolume::from_sparse(grid, basis, coeffs).unwrap()
    }

    /// Only the grid bricks of `volume` whose node layers along z overlap `nodes`; every other
    /// brick absent and outside, as a window of arriving layers has it.
    fn window(volume: &CoefficientVolume, nodes: Range<usize>) -> CoefficientVolume {
        let mut coeffs = SparseGrid::new(volume.grid.dims, volume.coeffs.background());
        for b in volume.coeffs.all_bricks() {
            let (lo, n) = volume.coeffs.brick_extent(b);
            if lo[2] + n[2] <= nodes.start || lo[2] >= nodes.end {
                continue;
            }
            match volume.coeffs.brick(b) {
                Some(v) => coeffs.insert(b, Box::new(*v)),
                None => coeffs.set_inside(b, volume.coeffs.is_inside(b)),
            }
        }
        CoefficientVolume::from_sparse(volume.grid, volume.basis, coeffs).unwrap()
    }

    /// The file of `volume` streamed in windows of grid brick layers `step` nodes apart.
    fn streamed(volume: &CoefficientVolume, opts: &EncodeOptions, step: usize) -> Vec<u8> {
        let header = header_for(volume, "interp", None);
        let mut out = Vec::new();
        let mut w = StreamedPgv::start(&mut out, header, opts).unwrap();
        let nz = volume.grid.dims[2];
        let mut complete = 0;
        while complete < nz {
            complete = (complete + step).min(nz);
            let from = w.first_node_needed();
            w.write_ready(&window(volume, from..complete), complete)
                .unwrap();
        }
        let from = w.first_node_needed();
        w.finish(&window(volume, from..nz), volume.coeffs.is_full())
            .unwrap();
        out
    }

    #[test]
    fn a_streamed_file_is_the_whole_volume_file_byte_for_byte() {
        let asymmetric = Background {
            outside: 0.25,
            inside: -0.5,
        };
        let mut compared = 0;
        for basis in BASES {
            for volume in [
                capsule(basis),
                sparse(basis, Background::clamp(0.3), 7),
                sparse(basis, asymmetric, 9),
                dense([13, 7, 20], basis, 3, 0.5),
            ] {
                for (brick, band, precision) in [
                    (8, 3.0, None),
                    (2, 1.0, Some(Precision::F32)),
                    (5, 2.0, Some(Precision::Q16)),
                    (16, 0.0, None),
                ] {
                    let opts = EncodeOptions {
                        brick,
                        band,
                        precision,
                        ..EncodeOptions::default()
                    };
                    let file = PgvFile {
                        header: header_for(&volume, "interp", None),
                        volume: volume.clone(),
                    };
                    let (whole, report) = sparse_pgv(&file, &opts).unwrap();
                    if opts.precision.is_none() && report.precision != Precision::Fixed {
                        continue;
                    }
                    let whole = whole.to_bytes();
                    for step in [BRICK_EDGE, 3 * BRICK_EDGE, volume.grid.dims[2]] {
                        let what = format!("{basis} brick {brick} band {band} step {step}");
                        assert!(streamed(&volume, &opts, step) == whole, "{what}");
                        compared += 1;
                    }
                }
            }
        }
        assert!(compared > 150, "{compared}");
    }

    #[test]
    fn a_precision_that_needs_the_whole_volume_is_reported() {
        // Coefficients the band needs beyond the range of the fixed precision's words.
        let volume = dense([9, 9, 9], Basis::Bspline3, 5, 1e8);
        let opts = EncodeOptions {
            band: 1e10,
            ..EncodeOptions::default()
        };
        let file = PgvFile {
            header: header_for(&volume, "interp", None),
            volume: volume.clone(),
        };
        assert_ne!(
            sparse_pgv(&file, &opts).unwrap().1.precision,
            Precision::Fixed
        );
        let mut out = Vec::new();
        let header = header_for(&volume, "interp", None);
        let mut w = StreamedPgv::start(&mut out, header, &opts).unwrap();
        let got = w.write_ready(&volume, 9);
        assert!(matches!(got, Err(StreamError::WholeVolume)), "{got:?}");
    }
}
