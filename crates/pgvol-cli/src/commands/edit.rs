//! `pgvol csg`: Booleans of fields, meshes and analytic primaries, sharp or rounded.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::args::ShapeOutputArgs;
use super::args::{OutputArgs, PathArg};
use super::ops::report;
use crate::progress::Bars;
use crate::report::Seconds;

/// Writes an edited volume as .pgv, or contours it into a mesh file, by the output's
/// extension; returns the triangles written (0 for a .pgv).
pub(super) fn write_edited(
    output: &Path,
    result: &pgvol::Field,
    operation: &str,
    args: &ShapeOutputArgs,
    progress: &Bars,
) -> Result<usize> {
    if pgvol::io::is_pgv(output) {
        result.save(output, &args.storage())?;
        return Ok(0);
    }
    let mesh = result
        .to_mesh(&args.decode_options(), progress)
        .map_err(|e| anyhow::anyhow!("{operation}: the result is empty: {e}"))?;
    pgvol::io::write_mesh(output, &mesh)?;
    Ok(mesh.triangles.len())
}

/// What the output's extension and --dense-file make of an edit's result, for the library's
/// memory estimate.
pub(super) fn result_use(output: &Path, args: &ShapeOutputArgs) -> pgvol::ResultUse {
    match (pgvol::io::is_pgv(output), args.dense_file) {
        (true, false) => pgvol::ResultUse::File,
        (true, true) => pgvol::ResultUse::DenseFile,
        (false, _) => pgvol::ResultUse::Mesh,
    }
}

/// A box from `x0,y0,z0,x1,y1,z1`. Options taking such comma lists set `allow_hyphen_values`:
/// a list starting `-1,…` is not one number, so `allow_negative_numbers` would not admit it.
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

pub(super) fn parse_operand(text: &str) -> Result<pgvol::Operand, String> {
    pgvol::Operand::parse(text).map_err(|e| e.to_string())
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
    /// grown by the radius); needed when every operand is a plane or cylinder. With a plane or
    /// cylinder among the operands the result is cut at this box.
    #[arg(long = "box", value_parser = parse_box, allow_hyphen_values = true)]
    pub bounds: Option<(pgvol::glam::Vec3, pgvol::glam::Vec3)>,
    #[command(flatten)]
    pub shape: ShapeOutputArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn csg(a: CsgArgs) -> Result<()> {
    let start = Instant::now();
    a.shape.check_output(&a.output)?;
    let bars = Bars::new(a.out.silent());
    let settings = pgvol::CsgOptions {
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
        sign: a.shape.sign.into(),
        result: result_use(&a.output, &a.shape),
    };
    let result = pgvol::Field::csg(&a.operands, &settings, &bars)?;
    let triangles = write_edited(&a.output, &result, "the Boolean", &a.shape, &bars)?;
    report(&a.out, &a.output, triangles, start)
}

fn parse_mask(s: &str) -> Result<pgvol::edit::Mask, String> {
    crate::parse::parse_mask(s).map_err(|e| e.to_string())
}

fn parse_face(s: &str) -> Result<pgvol::edit::Face, String> {
    crate::parse::parse_face(s).map_err(|e| e.to_string())
}

/// Coarse samples: at least 4, and never more than a grid may have nodes along an axis (the
/// library refuses lattices finer than the field's own grid once it is read).
fn parse_coarse(s: &str) -> Result<usize, String> {
    let max = pgvol::limits::MAX_RES as usize;
    match s.trim().parse::<usize>() {
        Ok(n) if (4..=max).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected 4 to {max} samples along the mask's longest side, got '{s}'"
        )),
    }
}

#[derive(Args)]
#[command(
    after_help = "Examples:\n  pgvol repair part.pgv -o fixed.pgv --mask -5,-5,20,5,5,32 --face -z\n  \
pgvol repair scan.stl -o smooth.glb --mask 0,0,0,10,10,10 --denoise --coarse 20"
)]
pub struct RepairArgs {
    /// A .pgv file, or a mesh (encoded on the fly at --res with exact distances over the
    /// masks).
    pub input: PathArg,
    /// Output: .pgv, or a mesh (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    /// An axis-aligned box x0,y0,z0,x1,y1,z1 in model units to restore; repeat for more.
    /// Coefficients whose support misses every mask stay bit-identical.
    #[arg(long, required = true, value_parser = parse_mask, allow_hyphen_values = true)]
    pub mask: Vec<pgvol::edit::Mask>,
    /// Protrusion removal: the mask's face the protrusion's base crosses (+x, -x, +y, -y, +z,
    /// -z), where the new field joins the body.
    #[arg(long, value_parser = parse_face, allow_hyphen_values = true, required_unless_present = "denoise", conflicts_with = "denoise")]
    pub face: Option<pgvol::edit::Face>,
    /// Normal derivative of the field across --face: 1 (a distance's) continues the body;
    /// larger values lower and flatten the cap, smaller ones raise it.
    #[arg(long, default_value_t = pgvol::limits::DEFAULT_ALPHA, allow_negative_numbers = true, conflicts_with = "denoise")]
    pub alpha: f32,
    /// Denoise instead: resample the field coarsely inside the masks and interpolate it with
    /// the quadratic B-spline.
    #[arg(long)]
    pub denoise: bool,
    /// Coarse samples along a mask's longest side when denoising (fewer smooth more).
    #[arg(long, default_value_t = pgvol::limits::DEFAULT_COARSE, value_parser = parse_coarse, requires = "denoise")]
    pub coarse: usize,
    #[command(flatten)]
    pub shape: ShapeOutputArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn repair(a: RepairArgs) -> Result<()> {
    let start = Instant::now();
    a.shape.check_output(&a.output)?;
    let bars = Bars::new(a.out.silent());
    let restore = match a.face {
        Some(face) if !a.denoise => pgvol::edit::Restore::Protrusion {
            face,
            alpha: a.alpha,
        },
        _ => pgvol::edit::Restore::Denoise { coarse: a.coarse },
    };
    let reach = pgvol::checks::repair_reach(&a.mask);
    let shape = a.shape.load(&a.input, 0.0, reach, &bars)?;
    let repaired = shape
        .repair(&a.mask, restore, &bars)
        .map_err(|e| super::args::at_input(e, &a.input))?;
    let reports = &repaired.masks;
    let triangles = write_edited(&a.output, &repaired.field, "the repair", &a.shape, &bars)?;
    if a.out.json {
        let masks: Vec<_> = reports
            .iter()
            .map(|r| {
                serde_json::json!({
                    "nodes": r.nodes, "iterations": r.iterations,
                    "coefficients": r.refit.coefficients, "fit_error": r.refit.max_error,
                })
            })
            .collect();
        return crate::report::print(
            &serde_json::json!({ "output": a.output, "triangles": triangles, "masks": masks }),
            &Seconds::since(start),
        );
    }
    report(&a.out, &a.output, triangles, start)
}
