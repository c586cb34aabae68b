//! Choosing the precision: how far a coefficient error can move the field, the `fixed` scale
//! asked for, and the smallest encoding within the tolerance.

use pgvol_field::Basis;

use super::brick_encoder::{encode_bricks, Encoded, StoredBricks};
use super::options::EncodeOptions;
use crate::fixed_step::{FixedScale, MAX_RATIO};
use crate::sparse_params::{Precision, SparseParams};

/// Auto precision keeps the surface error proxy under this fraction of the grid spacing.
pub const AUTO_TOLERANCE: f32 = 0.01;

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

/// The `fixed` scale `opts` asks for on a grid of `spacing`, for a basis whose weights sum to at
/// most `weight`; an error if a reader would refuse it.
pub(crate) fn fixed_scale(
    opts: &EncodeOptions,
    spacing: f32,
    weight: f32,
) -> Result<FixedScale, String> {
    let scale = FixedScale {
        step: opts.fixed_step * spacing / weight,
        knee: (opts.fixed_knee as f64 / opts.fixed_step as f64)
            .round()
            .clamp(0.0, i32::MAX as f64) as u32,
        ratio: opts.fixed_ratio,
    };
    if !scale.is_valid() {
        return Err(format!(
            "fixed step {}, knee {}, ratio {}: the step must be finite and > 0, the ratio in \
             1..={}",
            opts.fixed_step, opts.fixed_knee, opts.fixed_ratio, MAX_RATIO
        ));
    }
    Ok(scale)
}

/// The stored bricks encoded under the precision `opts` asks for or, when it asks for none, the
/// smallest encoding within [`AUTO_TOLERANCE`] (f32 if none is); `sp` is left set to the
/// choice. `weight` bounds the basis weights, `scale` is the `fixed` scale. With no precision
/// asked for, `prefer` (the precision a decoded file was written in) is taken when it holds
/// every stored coefficient exactly, so that writing a decoded file again reproduces it.
pub(crate) fn encode_smallest(
    s: &StoredBricks,
    sp: &mut SparseParams,
    scale: FixedScale,
    opts: &EncodeOptions,
    weight: f32,
    prefer: Option<Precision>,
) -> Result<Encoded, String> {
    if let (None, Some(p)) = (opts.precision, prefer) {
        sp.precision = p;
        sp.fixed = (p == Precision::Fixed).then_some(scale);
        if let Some((blobs, 0.0)) = encode_bricks(s, sp, opts.zstd_level)? {
            return Ok((blobs, 0.0));
        }
    }
    // `fixed` came out smallest on every volume measured (docs/format.md), so auto tries it first
    // and stops there when it meets the tolerance; the others are tried only when it does not.
    let candidates: Vec<Precision> = match opts.precision {
        Some(p) => vec![p],
        None => vec![Precision::Fixed, Precision::Q16, Precision::F16],
    };
    let tolerance = AUTO_TOLERANCE * s.volume.grid.spacing / weight;
    let mut best: Option<(Precision, Vec<Vec<u8>>, f32)> = None;
    for p in candidates {
        sp.precision = p;
        sp.fixed = (p == Precision::Fixed).then_some(scale);
        let Some((blobs, worst)) = encode_bricks(s, sp, opts.zstd_level)? else {
            if opts.precision.is_some() {
                return Err(format!(
                    "precision {} cannot represent these coefficients",
                    p.name()
                ));
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
            let (blobs, worst) =
                encode_bricks(s, sp, opts.zstd_level)?.expect("f32 holds every finite value");
            (Precision::F32, blobs, worst)
        }
    };
    sp.precision = precision;
    sp.fixed = (precision == Precision::Fixed).then_some(scale);
    Ok((blobs, worst))
}
