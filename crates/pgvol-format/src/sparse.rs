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
//! This module encodes and checks the layout; `sparse_read` decodes whole payloads (in
//! parallel) and `brick_codec` the values of one brick.

use rayon::prelude::*;
use std::path::Path;

use pgvol_field::{Basis, CoefficientVolume, Grid};
use serde::{Deserialize, Serialize};

use crate::fixed_step::{
    settle_free_words, FixedScale, FIXED_KNEE, FIXED_RATIO, FIXED_STEP, FREE_TOLERANCE,
};
use crate::pgv::{container, err, parse_container, FormatError, PgvFile, PgvHeader};
use crate::sparse_read::{background, BrickReader};
use crate::stored_band::needed_nodes;

/// The header's `encoding` for this payload.
pub const ENCODING_SPARSE: &str = "sparse-bricks";
/// Brick edges accepted by the reader; 32³ nodes × 4 bytes bounds every decompression buffer.
pub const BRICK_RANGE: std::ops::RangeInclusive<usize> = 2..=32;
/// Bytes of one index entry: offset u64, length u32, CRC-32 u32.
const ENTRY: usize = 16;
/// Bytes of the q16 parameters (offset f32, scale f32) in front of a brick's values.
pub(crate) const Q16_PARAMS: usize = 8;
/// Auto precision keeps the surface error proxy under this fraction of the grid spacing.
pub const AUTO_TOLERANCE: f32 = 0.01;

/// How stored coefficients are quantised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// IEEE binary32: bit-exact.
    F32,
    /// IEEE binary16 (round to nearest even).
    F16,
    /// 16-bit fixed point with a per-brick offset and scale.
    Q16,
    /// Signed 32-bit integer words on one scale for the whole file (`SparseParams::fixed`):
    /// steps tied to the grid spacing, fine near the surface and coarser far from it.
    Fixed,
}

impl Precision {
    pub const ALL: [Precision; 4] = [
        Precision::F32,
        Precision::F16,
        Precision::Q16,
        Precision::Fixed,
    ];

    /// Bytes per quantised value before compression.
    pub fn width(self) -> usize {
        match self {
            Precision::F32 | Precision::Fixed => 4,
            Precision::F16 | Precision::Q16 => 2,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
            Precision::Q16 => "q16",
            Precision::Fixed => "fixed",
        }
    }
}

/// How each quantised value is predicted from its already decoded neighbours in the brick.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Predictor {
    /// No prediction: the residual is the value.
    None,
    /// The previous value along x; a row's first value from the row before, a slice's first from
    /// the slice before.
    DeltaX,
    /// The 3-D Lorenzo predictor (parallelogram rule over the 7 lower neighbours; neighbours
    /// outside the brick count as 0).
    Lorenzo,
}

/// How each brick's bytes are compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compression {
    None,
    /// One zstd frame per brick.
    Zstd,
}

/// The header's `sparse` object: everything needed to parse the payload.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparseParams {
    /// Brick edge in nodes.
    pub brick: usize,
    /// Bricks per axis: `ceil(dims / brick)`.
    pub bricks: [usize; 3],
    /// Number of stored bricks.
    pub stored: usize,
    pub precision: Precision,
    pub predictor: Predictor,
    /// Whether residual bytes are grouped by significance (byte planes).
    pub shuffle: bool,
    pub compression: Compression,
    /// Magnitude of every coefficient of an unstored brick.
    pub clamp: f32,
    /// The band (grid spacings) the encoder kept; informative only.
    pub band: f32,
    /// With `fixed` precision (and only then): the scale of its words.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed: Option<FixedScale>,
}

/// Choices for [`encode_pgv_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct EncodeOptions {
    /// `None`: the smallest of q16, f16 and fixed within [`AUTO_TOLERANCE`], else f32.
    pub precision: Option<Precision>,
    /// A brick is stored if the field at any node within the basis support of its nodes is
    /// within `band` grid spacings of zero.
    pub band: f32,
    /// Brick edge in nodes (in [`BRICK_RANGE`]).
    pub brick: usize,
    pub predictor: Predictor,
    pub shuffle: bool,
    pub compression: Compression,
    pub zstd_level: i32,
    /// The `fixed` precision's fine step, in grid spacings (divided by the basis weight bound).
    pub fixed_step: f32,
    /// The magnitude, in grid spacings, up to which `fixed` uses the fine step.
    pub fixed_knee: f32,
    /// The coarse step beyond the knee, in fine steps.
    pub fixed_ratio: u32,
    /// With `fixed`: how far (grid spacings) a stored coefficient that no point within the band
    /// reaches may move towards its prediction; 0 keeps every coefficient within half a step.
    pub free_tolerance: f32,
}

impl Default for EncodeOptions {
    /// The best measured settings (`docs/format.md`, "Measurements").
    fn default() -> Self {
        EncodeOptions {
            precision: None,
            band: 3.0,
            brick: 16,
            predictor: Predictor::DeltaX,
            shuffle: true,
            compression: Compression::Zstd,
            zstd_level: 15,
            fixed_step: FIXED_STEP,
            fixed_knee: FIXED_KNEE,
            fixed_ratio: FIXED_RATIO,
            free_tolerance: FREE_TOLERANCE,
        }
    }
}

/// What an encode produced. The four byte counts add up to the file size.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodeReport {
    pub bricks_total: usize,
    pub bricks_stored: usize,
    /// Container framing and JSON header: magic, version, lengths, header, both CRCs.
    pub bytes_header: usize,
    /// Bitmaps, index and index CRC.
    pub bytes_index: usize,
    /// Brick blobs.
    pub bytes_payload: usize,
    pub precision: Precision,
    /// Largest |decoded − original| over stored coefficients (field units).
    pub max_quantisation_error: f32,
    /// Magnitude given to unstored bricks.
    pub clamp: f32,
}

/// What [`pgv_info`] finds from the header and index alone.
#[derive(Clone, Debug, PartialEq)]
pub struct PgvInfo {
    pub header: PgvHeader,
    /// `None` for `dense-f32`.
    pub bricks_total: Option<usize>,
    pub bricks_stored: Option<usize>,
    pub precision: Precision,
    /// As in [`EncodeReport`]; for `dense-f32` the index is empty and the payload is the
    /// coefficients.
    pub bytes_header: usize,
    pub bytes_index: usize,
    pub bytes_payload: usize,
}

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

/// Geometry of the brick decomposition.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bricks {
    pub(crate) dims: [usize; 3],
    pub(crate) edge: usize,
    pub(crate) count: [usize; 3],
}

impl Bricks {
    fn new(dims: [usize; 3], edge: usize) -> Bricks {
        Bricks {
            dims,
            edge,
            count: dims.map(|n| n.div_ceil(edge)),
        }
    }

    pub(crate) fn total(&self) -> usize {
        self.count.iter().product()
    }

    pub(crate) fn coords(&self, b: usize) -> [usize; 3] {
        [
            b % self.count[0],
            (b / self.count[0]) % self.count[1],
            b / (self.count[0] * self.count[1]),
        ]
    }

    /// First node and node counts of brick `b`.
    pub(crate) fn extent(&self, b: usize) -> ([usize; 3], [usize; 3]) {
        let c = self.coords(b);
        let lo = [0, 1, 2].map(|a| c[a] * self.edge);
        let n = [0, 1, 2].map(|a| (lo[a] + self.edge).min(self.dims[a]) - lo[a]);
        (lo, n)
    }

    /// Flat grid indices of brick `b`'s nodes, x fastest.
    fn nodes(&self, b: usize) -> impl Iterator<Item = usize> {
        let (lo, n) = self.extent(b);
        let [nx, ny, _] = self.dims;
        (0..n[2]).flat_map(move |k| {
            (0..n[1]).flat_map(move |j| {
                (0..n[0]).map(move |i| lo[0] + i + nx * (lo[1] + j + ny * (lo[2] + k)))
            })
        })
    }
}

/// Upper bound of `Σ_j |B_j(x)|`: how much a coefficient error of δ can move the field value.
/// Separable bases are non-negative partitions of unity (1); pg weights are not normalised, so
/// their sum is taken at nodes, cell centres and face/edge centres (the sum is smooth; these
/// are its extremes by symmetry).
pub fn basis_weight_bound(basis: Basis) -> f32 {
    let Basis::Pg { n, r } = basis else {
        return 1.0;
    };
    let reach = r.ceil() as i32 + 1;
    let mut best = 0.0f32;
    for corner in 0..8 {
        let t = [0, 1, 2].map(|a| if corner >> a & 1 == 1 { 0.5 } else { 0.0 });
        let mut sum = 0.0f32;
        for k in -reach..=reach {
            for j in -reach..=reach {
                for i in -reach..=reach {
                    let d2 = (i as f32 - t[0]).powi(2)
                        + (j as f32 - t[1]).powi(2)
                        + (k as f32 - t[2]).powi(2);
                    let q = d2 / (r * r);
                    if q < 1.0 {
                        sum += (1.0 - q).powi(n as i32 + 1);
                    }
                }
            }
        }
        best = best.max(sum);
    }
    best
}

/// Maps float bits to integers in the same order as the floats, so that neighbouring values
/// have nearby integers and prediction residuals stay small across zero.
fn order16(b: u16) -> u16 {
    if b & 0x8000 != 0 {
        !b
    } else {
        b | 0x8000
    }
}

pub(crate) fn unorder16(m: u16) -> u16 {
    if m & 0x8000 != 0 {
        m & 0x7fff
    } else {
        !m
    }
}

fn order32(b: u32) -> u32 {
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

pub(crate) fn unorder32(m: u32) -> u32 {
    if m & 0x8000_0000 != 0 {
        m & 0x7fff_ffff
    } else {
        !m
    }
}

/// Per-brick q16 parameters: offset and step.
fn q16_params(values: &[f32]) -> Option<(f32, f32)> {
    let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let scale = ((hi as f64 - lo as f64) / 65535.0) as f32;
    (lo.is_finite() && scale.is_finite()).then_some((lo, scale))
}

fn q16_decode(q: u16, lo: f32, scale: f32) -> f32 {
    lo + q as f32 * scale
}

/// Quantises `values` to words (and the bytes that precede them). `None` if the precision
/// cannot represent them (f16 overflow, q16 range overflow, fixed without a step or beyond
/// 32 bits).
pub(crate) fn quantise(
    values: &[f32],
    p: Precision,
    fixed: Option<FixedScale>,
) -> Option<(Vec<u8>, Vec<u32>)> {
    match p {
        Precision::Fixed => {
            let scale = fixed.filter(FixedScale::is_valid)?;
            let words: Option<Vec<u32>> = values.iter().map(|&v| scale.word(v)).collect();
            Some((Vec::new(), words?))
        }
        Precision::F32 => Some((
            Vec::new(),
            values.iter().map(|v| order32(v.to_bits())).collect(),
        )),
        Precision::F16 => {
            let words: Option<Vec<u32>> = values
                .iter()
                .map(|&v| {
                    let h = half::f16::from_f32(v);
                    h.is_finite().then_some(order16(h.to_bits()) as u32)
                })
                .collect();
            Some((Vec::new(), words?))
        }
        Precision::Q16 => {
            let (lo, scale) = q16_params(values)?;
            let words = values
                .iter()
                .map(|&v| {
                    if scale > 0.0 {
                        ((v - lo) / scale).round().clamp(0.0, 65535.0) as u32
                    } else {
                        0
                    }
                })
                .collect();
            let mut params = lo.to_le_bytes().to_vec();
            params.extend_from_slice(&scale.to_le_bytes());
            Some((params, words))
        }
    }
}

/// The values that `words` decode to.
pub(crate) fn dequantise(
    params: &[u8],
    words: &[u32],
    p: Precision,
    fixed: Option<FixedScale>,
) -> Vec<f32> {
    match p {
        Precision::Fixed => match fixed {
            Some(scale) => words.iter().map(|&w| scale.value(w)).collect(),
            None => vec![f32::NAN; words.len()],
        },
        Precision::F32 => words
            .iter()
            .map(|&w| f32::from_bits(unorder32(w)))
            .collect(),
        Precision::F16 => words
            .iter()
            .map(|&w| half::f16::from_bits(unorder16(w as u16)).to_f32())
            .collect(),
        Precision::Q16 => {
            let lo = f32::from_le_bytes(params[0..4].try_into().expect("4 bytes"));
            let scale = f32::from_le_bytes(params[4..8].try_into().expect("4 bytes"));
            words
                .iter()
                .map(|&w| q16_decode(w as u16, lo, scale))
                .collect()
        }
    }
}

/// The prediction of word `at` (x fastest in a brick of `n` nodes) from words before it.
pub(crate) fn predict(words: &[u32], n: [usize; 3], at: usize, pred: Predictor, mask: u32) -> u32 {
    let (i, j, k) = (at % n[0], (at / n[0]) % n[1], at / (n[0] * n[1]));
    let (sx, sy, sz) = (1, n[0], n[0] * n[1]);
    let get = |di: usize, dj: usize, dk: usize| -> u32 {
        if i < di || j < dj || k < dk {
            0
        } else {
            words[at - di * sx - dj * sy - dk * sz]
        }
    };
    let p = match pred {
        Predictor::None => 0,
        Predictor::DeltaX => {
            if i > 0 {
                get(1, 0, 0)
            } else if j > 0 {
                get(0, 1, 0)
            } else {
                get(0, 0, 1)
            }
        }
        Predictor::Lorenzo => get(1, 0, 0)
            .wrapping_add(get(0, 1, 0))
            .wrapping_add(get(0, 0, 1))
            .wrapping_sub(get(1, 1, 0))
            .wrapping_sub(get(1, 0, 1))
            .wrapping_sub(get(0, 1, 1))
            .wrapping_add(get(1, 1, 1)),
    };
    p & mask
}

fn zigzag(r: u32, bits: u32) -> u32 {
    let half = 1u64 << (bits - 1);
    let s = if (r as u64) >= half {
        r as i64 - (1i64 << bits)
    } else {
        r as i64
    };
    (if s >= 0 { 2 * s } else { -2 * s - 1 }) as u32
}

/// Encodes one brick's values to its blob (before compression: q16 parameters, then residual
/// bytes, byte planes if shuffled).
pub(crate) fn brick_raw(params: &[u8], words: &[u32], n: [usize; 3], sp: &SparseParams) -> Vec<u8> {
    let w = sp.precision.width();
    let bits = 8 * w as u32;
    let mask = if w == 4 { u32::MAX } else { 0xffff };
    let residuals: Vec<u32> = (0..words.len())
        .map(|at| {
            let r = words[at].wrapping_sub(predict(words, n, at, sp.predictor, mask)) & mask;
            zigzag(r, bits)
        })
        .collect();
    let mut raw = params.to_vec();
    if sp.shuffle {
        for b in 0..w {
            raw.extend(residuals.iter().map(|r| (r >> (8 * b)) as u8));
        }
    } else {
        for r in &residuals {
            raw.extend_from_slice(&r.to_le_bytes()[..w]);
        }
    }
    raw
}

/// The blobs of the stored bricks and their largest coefficient error.
type Encoded = (Vec<Vec<u8>>, f32);

/// Which stored coefficients the band needs (per grid node), and how many `fixed` steps the
/// others may move.
struct FreeNodes<'a> {
    needed: &'a [bool],
    tolerance_steps: i32,
}

/// Stored bricks under one precision: blobs and the largest error of a coefficient the band
/// needs, or `None` if the precision cannot hold the values.
fn encode_bricks(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    keep: &[bool],
    free: &FreeNodes,
    sp: &SparseParams,
    level: i32,
) -> Result<Option<Encoded>, String> {
    // Bricks are independent: encode them in parallel, collected in brick order so the file
    // does not depend on the thread count.
    let stored: Vec<usize> = (0..bricks.total()).filter(|&b| keep[b]).collect();
    let encoded: Vec<Option<(Vec<u8>, f32)>> = stored
        .par_iter()
        .map(|&b| encode_brick(volume, bricks, free, sp, level, b))
        .collect::<Result<_, String>>()?;
    let mut blobs = Vec::with_capacity(encoded.len());
    let mut worst = 0.0f32;
    for brick in encoded {
        let Some((blob, brick_worst)) = brick else {
            return Ok(None);
        };
        blobs.push(blob);
        worst = worst.max(brick_worst);
    }
    Ok(Some((blobs, worst)))
}

/// One stored brick's compressed bytes and its largest error over needed coefficients; `None`
/// when `sp.precision` cannot represent its coefficients.
fn encode_brick(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    free: &FreeNodes,
    sp: &SparseParams,
    level: i32,
    b: usize,
) -> Result<Option<(Vec<u8>, f32)>, String> {
    let nodes: Vec<usize> = bricks.nodes(b).collect();
    let values: Vec<f32> = nodes.iter().map(|&i| volume.coeffs[i]).collect();
    let Some((params, mut words)) = quantise(&values, sp.precision, sp.fixed) else {
        return Ok(None);
    };
    let (_, n) = bricks.extent(b);
    let loose: Vec<bool> = nodes.iter().map(|&i| !free.needed[i]).collect();
    if sp.precision == Precision::Fixed && free.tolerance_steps > 0 {
        settle_free_words(&mut words, &loose, n, sp.predictor, free.tolerance_steps);
    }
    let decoded = dequantise(&params, &words, sp.precision, sp.fixed);
    let mut worst = 0.0f32;
    for ((a, d), l) in values.iter().zip(decoded).zip(&loose) {
        if !l {
            worst = worst.max((a - d).abs());
        }
    }
    let raw = brick_raw(&params, &words, n, sp);
    let blob = match sp.compression {
        Compression::None => raw,
        Compression::Zstd => zstd::bulk::compress(&raw, level)
            .map_err(|e| format!("zstd compression failed: {e}"))?,
    };
    Ok(Some((blob, worst)))
}

/// Encodes `file` in the `sparse-bricks` encoding.
pub fn encode_pgv_with(
    file: &PgvFile,
    opts: &EncodeOptions,
) -> Result<(Vec<u8>, EncodeReport), FormatError> {
    let fail = |m: String| err(Path::new("<encode>"), m);
    let volume = &file.volume;
    let g = volume.grid;
    if !BRICK_RANGE.contains(&opts.brick) {
        return Err(fail(format!(
            "brick edge {} is outside {:?}",
            opts.brick, BRICK_RANGE
        )));
    }
    if !(opts.band.is_finite() && opts.band >= 0.0) {
        return Err(fail(format!("band {} must be finite and >= 0", opts.band)));
    }
    CoefficientVolume::new(g, volume.basis, volume.coeffs.clone())
        .map_err(|e| fail(format!("invalid volume: {e}")))?;
    // Steps in units of field error: a coefficient error δ moves the field by at most W·δ.
    let weight = basis_weight_bound(volume.basis);
    let scale = FixedScale {
        step: opts.fixed_step * g.spacing / weight,
        knee: (opts.fixed_knee as f64 / opts.fixed_step as f64)
            .round()
            .clamp(0.0, i32::MAX as f64) as u32,
        ratio: opts.fixed_ratio,
    };
    if !scale.is_valid() {
        return Err(fail(format!(
            "fixed step {}, knee {}, ratio {}: the step must be finite and > 0, the ratio in \
             1..={}",
            opts.fixed_step,
            opts.fixed_knee,
            opts.fixed_ratio,
            crate::fixed_step::MAX_RATIO
        )));
    }
    let bricks = Bricks::new(g.dims, opts.brick);
    let needed = needed_nodes(volume, opts.band);
    let keep: Vec<bool> = (0..bricks.total())
        .map(|b| bricks.nodes(b).any(|i| needed[i]))
        .collect();
    let free = FreeNodes {
        needed: &needed,
        // In coarse words, so that no value moves further than the tolerance.
        tolerance_steps: (opts.free_tolerance
            / (opts.fixed_step / weight * opts.fixed_ratio as f32))
            .clamp(0.0, 1e9) as i32,
    };

    // Background: sign by the brick's mean coefficient, magnitude the largest background one,
    // so a banded distance field keeps its clamp value exactly.
    let mut inside = vec![false; bricks.total()];
    let mut clamp = 0.0f32;
    for b in (0..bricks.total()).filter(|&b| !keep[b]) {
        let mut sum = 0.0f64;
        for i in bricks.nodes(b) {
            let c = volume.coeffs[i];
            sum += c as f64;
            clamp = clamp.max(c.abs());
        }
        inside[b] = sum < 0.0;
    }
    if clamp == 0.0 {
        clamp = opts.band.max(1.0) * g.spacing;
    }

    let mut sp = SparseParams {
        brick: opts.brick,
        bricks: bricks.count,
        stored: keep.iter().filter(|&&k| k).count(),
        precision: Precision::F32,
        predictor: opts.predictor,
        shuffle: opts.shuffle,
        compression: opts.compression,
        clamp,
        band: opts.band,
        fixed: None,
    };
    // `fixed` came out smallest on every volume measured (docs/format.md), so auto tries it first
    // and stops there when it meets the tolerance; the others are tried only when it does not.
    let candidates: Vec<Precision> = match opts.precision {
        Some(p) => vec![p],
        None => vec![Precision::Fixed, Precision::Q16, Precision::F16],
    };
    let tolerance = AUTO_TOLERANCE * g.spacing / weight;
    let mut best: Option<(Precision, Vec<Vec<u8>>, f32)> = None;
    for p in candidates {
        sp.precision = p;
        sp.fixed = (p == Precision::Fixed).then_some(scale);
        let Some((blobs, worst)) =
            encode_bricks(volume, &bricks, &keep, &free, &sp, opts.zstd_level).map_err(fail)?
        else {
            if opts.precision.is_some() {
                return Err(fail(format!(
                    "precision {} cannot represent these coefficients",
                    p.name()
                )));
            }
            continue;
        };
        if opts.precision.is_none() && worst > tolerance {
            continue;
        }
        let size: usize = blobs.iter().map(Vec::len).sum();
        let better = match &best {
            None => true,
            Some((_, b, _)) => size < b.iter().map(Vec::len).sum(),
        };
        if better {
            best = Some((p, blobs, worst));
        }
        if opts.precision.is_none() && p == Precision::Fixed {
            break;
        }
    }
    let (precision, blobs, worst) = match best {
        Some(b) => b,
        None => {
            sp.precision = Precision::F32;
            let (blobs, worst) = encode_bricks(volume, &bricks, &keep, &free, &sp, opts.zstd_level)
                .map_err(fail)?
                .expect("f32 holds every finite value");
            (Precision::F32, blobs, worst)
        }
    };
    sp.precision = precision;
    sp.fixed = (precision == Precision::Fixed).then_some(scale);

    let nb = bricks.total();
    let mut meta = vec![0u8; 2 * nb.div_ceil(8)];
    let half = nb.div_ceil(8);
    for b in 0..nb {
        if keep[b] {
            meta[b / 8] |= 1 << (b % 8);
        } else if inside[b] {
            meta[half + b / 8] |= 1 << (b % 8);
        }
    }
    let mut offset = 0u64;
    for blob in &blobs {
        meta.extend_from_slice(&offset.to_le_bytes());
        meta.extend_from_slice(&(blob.len() as u32).to_le_bytes());
        meta.extend_from_slice(&crc32fast::hash(blob).to_le_bytes());
        offset += blob.len() as u64;
    }
    let icrc = crc32fast::hash(&meta);
    meta.extend_from_slice(&icrc.to_le_bytes());
    let bytes_index = meta.len();
    let mut payload = meta;
    for blob in &blobs {
        payload.extend_from_slice(blob);
    }
    let mut header = file.header.clone();
    header.grid = g;
    header.basis = volume.basis;
    header.encoding = ENCODING_SPARSE.to_string();
    header.sparse = Some(sp.clone());
    let bytes = container(&header, &payload);
    let report = EncodeReport {
        bricks_total: nb,
        bricks_stored: sp.stored,
        bytes_header: bytes.len() - payload.len(),
        bytes_index,
        bytes_payload: payload.len() - bytes_index,
        precision,
        max_quantisation_error: worst,
        clamp,
    };
    Ok((bytes, report))
}

/// Writes `file` to `path` atomically in the `sparse-bricks` encoding.
pub fn write_pgv_with(
    path: &Path,
    file: &PgvFile,
    opts: &EncodeOptions,
) -> Result<EncodeReport, FormatError> {
    let (bytes, report) = encode_pgv_with(file, opts).map_err(|e| err(path, e.problem))?;
    pgvol_core::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| err(path, e.problem))?;
    Ok(report)
}

/// A checked sparse payload: its parameters, bitmaps and index, and where the data starts.
pub(crate) struct Layout<'a> {
    pub(crate) sp: SparseParams,
    pub(crate) bricks: Bricks,
    pub(crate) stored: &'a [u8],
    pub(crate) inside: &'a [u8],
    /// (offset, length, crc) per stored brick, in brick order.
    pub(crate) entries: Vec<(u64, u32, u32)>,
    pub(crate) data: &'a [u8],
    pub(crate) index_bytes: usize,
}

pub(crate) fn bit(map: &[u8], b: usize) -> bool {
    map[b / 8] >> (b % 8) & 1 == 1
}

/// Checks the sparse parameters against the grid and the payload, and reads the index.
pub(crate) fn layout<'a>(
    header: &PgvHeader,
    payload: &'a [u8],
    path: &Path,
) -> Result<Layout<'a>, FormatError> {
    let Some(sp) = header.sparse.clone() else {
        return Err(err(
            path,
            "the header has no 'sparse' parameters for the sparse-bricks encoding",
        ));
    };
    if !BRICK_RANGE.contains(&sp.brick) {
        return Err(err(
            path,
            format!("brick edge {} is outside {:?}", sp.brick, BRICK_RANGE),
        ));
    }
    let bricks = Bricks::new(header.grid.dims, sp.brick);
    if sp.bricks != bricks.count {
        return Err(err(
            path,
            format!(
                "the header counts {:?} bricks but a {:?} grid in bricks of {} has {:?}",
                sp.bricks, header.grid.dims, sp.brick, bricks.count
            ),
        ));
    }
    let nb = bricks.total();
    if sp.stored > nb {
        return Err(err(
            path,
            format!(
                "{} stored bricks claimed, but there are only {nb}",
                sp.stored
            ),
        ));
    }
    let scale_ok = match sp.fixed {
        None => sp.precision != Precision::Fixed,
        Some(f) => sp.precision == Precision::Fixed && f.is_valid(),
    };
    if !scale_ok {
        return Err(err(
            path,
            format!(
                "fixed scale {:?} with precision {}: 'fixed' needs a valid scale, others none",
                sp.fixed,
                sp.precision.name()
            ),
        ));
    }
    if !(sp.clamp.is_finite() && sp.clamp >= 0.0) {
        return Err(err(
            path,
            format!("clamp {} is not finite and >= 0", sp.clamp),
        ));
    }
    let map = nb.div_ceil(8);
    let meta = (2 * map as u64) + (sp.stored as u64) * ENTRY as u64;
    if meta + 4 > payload.len() as u64 {
        return Err(err(
            path,
            format!(
                "truncated payload: the brick maps and index need {} bytes, the payload has {}",
                meta + 4,
                payload.len()
            ),
        ));
    }
    let meta = meta as usize;
    let icrc = u32::from_le_bytes(payload[meta..meta + 4].try_into().expect("4 bytes"));
    if crc32fast::hash(&payload[..meta]) != icrc {
        return Err(err(
            path,
            "brick index checksum mismatch: the file is corrupt",
        ));
    }
    let (stored, inside) = (&payload[..map], &payload[map..2 * map]);
    let set: usize = stored.iter().map(|b| b.count_ones() as usize).sum();
    let stray = (nb..map * 8).any(|b| bit(stored, b) || bit(inside, b));
    if set != sp.stored || stray {
        return Err(err(
            path,
            format!(
                "the brick map marks {set} bricks stored (or bits past the last brick), the header {}",
                sp.stored
            ),
        ));
    }
    let data = &payload[meta + 4..];
    let mut entries = Vec::with_capacity(sp.stored);
    let mut next = 0u64;
    for e in payload[2 * map..meta].chunks_exact(ENTRY) {
        let offset = u64::from_le_bytes(e[0..8].try_into().expect("8 bytes"));
        let len = u32::from_le_bytes(e[8..12].try_into().expect("4 bytes"));
        let crc = u32::from_le_bytes(e[12..16].try_into().expect("4 bytes"));
        if offset != next || offset + len as u64 > data.len() as u64 {
            return Err(err(
                path,
                format!(
                    "brick index entry {} (offset {offset}, length {len}) does not follow the \
                     previous one inside the {} bytes of brick data",
                    entries.len(),
                    data.len()
                ),
            ));
        }
        next = offset + len as u64;
        entries.push((offset, len, crc));
    }
    if next != data.len() as u64 {
        return Err(err(
            path,
            format!(
                "the index covers {next} bytes of brick data but the payload holds {}",
                data.len()
            ),
        ));
    }
    Ok(Layout {
        sp,
        bricks,
        stored,
        inside,
        entries,
        data,
        index_bytes: meta + 4,
    })
}

/// Every coefficient of a sparse payload, x fastest.
pub(crate) fn decode_payload(
    header: &PgvHeader,
    payload: &[u8],
    path: &Path,
) -> Result<Vec<f32>, FormatError> {
    let l = layout(header, payload, path)?;
    crate::sparse_read::decode_all(&l, path)
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
    let l = layout(&c.header, c.payload, path)?;
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

/// Header, brick counts, precision and bytes per part, from the header and index alone.
pub fn pgv_info(bytes: &[u8], path: &Path) -> Result<PgvInfo, FormatError> {
    let c = parse_container(bytes, path, false)?;
    let framing = bytes.len() - c.payload.len();
    if c.header.encoding != ENCODING_SPARSE {
        return Ok(PgvInfo {
            header: c.header,
            bricks_total: None,
            bricks_stored: None,
            precision: Precision::F32,
            bytes_header: framing,
            bytes_index: 0,
            bytes_payload: c.payload.len(),
        });
    }
    let l = layout(&c.header, c.payload, path)?;
    Ok(PgvInfo {
        bricks_total: Some(l.bricks.total()),
        bricks_stored: Some(l.sp.stored),
        precision: l.sp.precision,
        bytes_header: framing,
        bytes_index: l.index_bytes,
        bytes_payload: l.data.len(),
        header: c.header,
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
    }
}
