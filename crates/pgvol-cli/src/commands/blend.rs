//! `pgvol blend`: Liming rounding, functional splines and I-patches between primaries.

use std::time::Instant;

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};

use super::args::ShapeOutputArgs;
use super::args::{OutputArgs, PathArg};
use super::edit::{parse_box, parse_operand, result_use, write_edited};
use super::ops::report;
use crate::progress::Bars;

#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum BlendKind {
    /// Liming rounding (1 − λ)·P1·P2 + λ·C² of two primaries with a cutting surface (--cut).
    Liming,
    /// Functional spline (1 − λ)·ΠPi + λ·ΠBj² of two or more primaries with one or more
    /// bounds (--bound, repeated).
    Spline,
    /// I-patch Σ wi·Pi·Π(j≠i) |Bj|^(n+1) + w·Π |Bi|^(n+1), one bound per primary, Gⁿ with
    /// --continuity n; weights by --weights, fitted by least squares to --points, or w set so
    /// that the patch passes through --through.
    Ipatch,
}

fn parse_numbers(text: &str) -> Result<Vec<f32>, String> {
    text.split(',')
        .map(|x| {
            x.trim()
                .parse::<f32>()
                .map_err(|_| format!("'{x}' is not a number"))
        })
        .collect()
}

fn parse_point(text: &str) -> Result<pgvol::glam::DVec3, String> {
    match parse_numbers(text)?[..] {
        [x, y, z] => Ok(pgvol::glam::DVec3::new(x as f64, y as f64, z as f64)),
        _ => Err(format!("expected x,y,z, got '{text}'")),
    }
}

#[derive(Args)]
#[command(
    after_help = "Operands as for `pgvol csg`. Fields are negative inside; the edge blends \
round the edge of the primaries' intersection where every bound (or the cut) is negative.\n\n\
Examples:\n  pgvol blend liming plane:1,0,0,0 plane:0,1,0,0 --cut plane:-1,-1,0,0.5 --box -1,-1,-1,1,1,1 -o round.stl\n  \
pgvol blend spline plane:1,0,0,0 plane:0,1,0,0 plane:0,0,1,0 --bound plane:-1,-1,-1,1 --box -1,-1,-1,1,1,1 -o vertex.stl\n  \
pgvol blend ipatch plane:1,0,0,0 plane:0,1,0,0 --bound plane:-1,0,0,0.8 --bound plane:0,-1,0,0.8 --continuity 2 --through -0.3,-0.3,0 --box -1,-1,-1,1,1,1 -o patch.stl"
)]
pub struct BlendArgs {
    /// The blend.
    #[arg(value_enum)]
    pub kind: BlendKind,
    /// The primaries (two for liming; two or more for spline and ipatch).
    #[arg(required = true, num_args = 2.., value_parser = parse_operand)]
    pub primaries: Vec<pgvol::Operand>,
    /// Output: .pgv, or a mesh (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    /// Liming's cutting surface (negative on the edge's side).
    #[arg(long, value_parser = parse_operand)]
    pub cut: Option<pgvol::Operand>,
    /// A bound: spline takes one or more, ipatch one per primary, in order.
    #[arg(long, value_parser = parse_operand)]
    pub bound: Vec<pgvol::Operand>,
    /// λ in (0, 1) for liming and spline: larger moves the blend away from the edge.
    #[arg(long, default_value_t = pgvol::limits::DEFAULT_LAMBDA)]
    pub lambda: f32,
    /// I-patch: continuity order n, 1 to 4 (Gⁿ: the bounds raised to n + 1; default 1).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=pgvol::limits::MAX_CONTINUITY as i64))]
    pub continuity: Option<u32>,
    /// I-patch weights w1,..,wn,w; with --through only w1,..,wn (default all 1).
    #[arg(long, allow_hyphen_values = true, conflicts_with = "points")]
    pub weights: Option<String>,
    /// I-patch: a CSV of points (x,y,z per line) on the wanted surface, to fit the weights.
    #[arg(long, conflicts_with = "through")]
    pub points: Option<PathArg>,
    /// I-patch: a point x,y,z the patch passes through; w follows from w1,..,wn.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub through: Option<pgvol::glam::DVec3>,
    /// The box the result covers, x0,y0,z0,x1,y1,z1 (default: the bounded primaries' box).
    /// With a plane or cylinder among the primaries the result is cut at this box.
    #[arg(long = "box", value_parser = parse_box, allow_hyphen_values = true)]
    pub bounds: Option<(pgvol::glam::Vec3, pgvol::glam::Vec3)>,
    #[command(flatten)]
    pub shape: ShapeOutputArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

/// The I-patch's weights from --weights, --points and --through.
fn ipatch_weights(a: &BlendArgs) -> Result<pgvol::edit::IPatchWeights> {
    let n = a.primaries.len();
    let given = match &a.weights {
        Some(text) => Some(parse_numbers(text).map_err(|e| anyhow::anyhow!("--weights: {e}"))?),
        None => None,
    };
    Ok(match (given, &a.points, a.through) {
        (given, _, Some(point)) => {
            let w = given.unwrap_or_else(|| vec![1.0; n]);
            if w.len() != n {
                bail!(
                    "--weights with --through: expected w1,..,wn ({n} numbers, w follows from \
                     the point), got {}",
                    w.len()
                );
            }
            pgvol::edit::IPatchWeights::Through(w, point)
        }
        (Some(w), _, None) => match w.split_last() {
            Some((&w0, rest)) if !rest.is_empty() => {
                pgvol::edit::IPatchWeights::Given(rest.to_vec(), w0)
            }
            _ => bail!("--weights: expected w1,..,wn,w, got {} numbers", w.len()),
        },
        (None, Some(p), None) => {
            pgvol::edit::IPatchWeights::Fitted(pgvol::io::read_points_file(p)?)
        }
        (None, None, None) => {
            bail!("ipatch needs --weights, --points to fit them to, or --through")
        }
    })
}

/// The operator the arguments ask for, with the counts each blend needs checked in the
/// options' names.
fn operator(a: &BlendArgs) -> Result<pgvol::edit::BlendOperator> {
    let ipatch_only = a.continuity.is_some() || a.through.is_some() || a.weights.is_some();
    if !matches!(a.kind, BlendKind::Ipatch) && (ipatch_only || a.points.is_some()) {
        bail!("--continuity, --weights, --points and --through apply to ipatch only");
    }
    Ok(match a.kind {
        BlendKind::Liming => {
            if a.primaries.len() != 2 {
                bail!("liming needs two primaries, got {}", a.primaries.len());
            }
            pgvol::edit::BlendOperator::Liming {
                cut: a
                    .cut
                    .clone()
                    .ok_or_else(|| anyhow::anyhow!("liming needs --cut, the cutting surface"))?,
                lambda: a.lambda,
            }
        }
        BlendKind::Spline => {
            if a.bound.is_empty() {
                bail!("spline needs --bound, once or more");
            }
            pgvol::edit::BlendOperator::Spline {
                bounds: a.bound.clone(),
                lambda: a.lambda,
            }
        }
        BlendKind::Ipatch => {
            if a.bound.len() != a.primaries.len() {
                bail!(
                    "ipatch needs one --bound per primary, in order: got {} --bound for {} \
                     primaries",
                    a.bound.len(),
                    a.primaries.len()
                );
            }
            pgvol::edit::BlendOperator::IPatch {
                bounds: a.bound.clone(),
                weights: ipatch_weights(a)?,
                // The parser holds the order to its range.
                continuity: pgvol::edit::Continuity::new(a.continuity.unwrap_or(1))?,
            }
        }
    })
}

pub fn blend(a: BlendArgs) -> Result<()> {
    let start = Instant::now();
    a.shape.check_output(&a.output)?;
    let bars = Bars::new(a.out.silent());
    let operator = operator(&a)?;
    let settings = pgvol::edit::BlendOptions {
        res: a.shape.res as usize,
        bounds: a.bounds,
        sign: a.shape.sign.into(),
        result: result_use(&a.output, &a.shape),
    };
    let blended = pgvol::edit::blend(&a.primaries, &operator, &settings, &bars)?;
    let triangles = write_edited(&a.output, &blended.field, "the blend", &a.shape, &bars)?;
    if a.out.json {
        return crate::report::print(
            &serde_json::json!({
                "output": a.output, "triangles": triangles,
                "weights": blended.weights.map(|(w, w0)| serde_json::json!({"w": w, "w0": w0})),
                "continuity":
                    matches!(a.kind, BlendKind::Ipatch).then(|| a.continuity.unwrap_or(1)),
            }),
            &crate::report::Seconds::since(start),
        );
    }
    report(&a.out, &a.output, triangles, start)
}
