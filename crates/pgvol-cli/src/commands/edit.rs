//! `pgvol csg`: Booleans of fields, meshes and analytic primaries, sharp or rounded.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::args::{OutputArgs, PathArg};
use super::ops::{check_output_name, report, ShapeOutputArgs};
use crate::progress::Bars;

/// Writes an edited volume as .pgv, or contours it into a mesh file, by the output's
/// extension; returns the triangles written (0 for a .pgv).
pub(super) fn write_edited(
    output: &Path,
    volume: pgvol::CoefficientVolume,
    operation: &str,
    band: f32,
    args: &ShapeOutputArgs,
    progress: &Bars,
) -> Result<usize> {
    if pgvol::is_pgv(output) {
        let file = pgvol::edited_file(volume, operation, band);
        pgvol::write_pgv(output, &file, &pgvol::DERIVED_STORAGE)?;
        return Ok(0);
    }
    let options = pgvol::DecodeOptions {
        method: args.method.into(),
        min_component: args.min_component,
        ..Default::default()
    };
    let mesh = pgvol::decode(&volume, &options, progress)
        .map_err(|e| anyhow::anyhow!("{operation}: the result is empty: {e}"))?;
    pgvol::write_mesh(output, &mesh)?;
    Ok(mesh.triangles.len())
}

/// A box from `x0,y0,z0,x1,y1,z1`.
pub(super) fn parse_box(text: &str) -> Result<(pgvol::glam::Vec3, pgvol::glam::Vec3), String> {
    let v: Vec<f32> = text
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected six numbers x0,y0,z0,x1,y1,z1, got '{text}'"))?;
    if v.len() != 6 || v.iter().any(|x| !x.is_finite()) || v[3] < v[0] || v[4] < v[1] || v[5] < v[2]
    {
        return Err(format!(
            "expected six finite numbers x0,y0,z0,x1,y1,z1 with each upper corner coordinate \
             at least the lower one, got '{text}'"
        ));
    }
    Ok((
        pgvol::glam::Vec3::new(v[0], v[1], v[2]),
        pgvol::glam::Vec3::new(v[3], v[4], v[5]),
    ))
}

fn parse_operand(text: &str) -> Result<pgvol::Operand, String> {
    pgvol::parse_operand(text).map_err(|e| e.to_string())
}

#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum OpArg {
    /// Everything inside any operand.
    Union,
    /// What is inside every operand.
    Intersection,
    /// The first operand less all the others.
    Difference,
}

#[derive(Args)]
#[command(
    after_help = "Operands: a .pgv file, a mesh file (encoded onto the result's grid), or \
an analytic primary:\n  sphere:cx,cy,cz,r  box:cx,cy,cz,hx,hy,hz  plane:nx,ny,nz,d (the half-space \
n·p ≤ d)  cylinder:px,py,pz,ax,ay,az,r\n\nExample: pgvol csg union part.stl sphere:0,0,10,4 -o \
merged.glb --radius 1.5"
)]
pub struct CsgArgs {
    /// The operation.
    #[arg(value_enum)]
    pub op: OpArg,
    /// Two or more operands (see below).
    #[arg(required = true, num_args = 2.., value_parser = parse_operand)]
    pub operands: Vec<pgvol::Operand>,
    /// Output: .pgv, or a mesh (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    /// Fillet radius where the surfaces meet, in model units (default: sharp, min/max). The
    /// rounded field stays within the radius of the sharp one and equals it wherever the
    /// operands are more than the radius apart.
    #[arg(long, allow_negative_numbers = true)]
    pub radius: Option<f32>,
    /// The box the result covers, x0,y0,z0,x1,y1,z1 (default: every bounded operand's box,
    /// grown by the radius); needed when every operand is a plane or cylinder.
    #[arg(long = "box", value_parser = parse_box, allow_negative_numbers = true)]
    pub bounds: Option<(pgvol::glam::Vec3, pgvol::glam::Vec3)>,
    #[command(flatten)]
    pub shape: ShapeOutputArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn csg(a: CsgArgs) -> Result<()> {
    let start = Instant::now();
    check_output_name(&a.output)?;
    let bars = Bars::new(a.out.silent());
    let settings = pgvol::CsgSettings {
        op: match a.op {
            OpArg::Union => pgvol::BoolOp::Union,
            OpArg::Intersection => pgvol::BoolOp::Intersection,
            OpArg::Difference => pgvol::BoolOp::Difference,
        },
        blend: match a.radius {
            None => pgvol::Blend::Sharp,
            Some(r) => pgvol::Blend::Round(r),
        },
        res: a.shape.res as usize,
        bounds: a.bounds,
    };
    let volume = pgvol::csg(&a.operands, &settings, &bars)?;
    let band = pgvol::ENCODE_BAND * volume.grid.spacing;
    let operation = pgvol::csg_name(&settings);
    let triangles = write_edited(&a.output, volume, &operation, band, &a.shape, &bars)?;
    report(&a.out, &a.output, triangles, start)
}
