//! `pgvol encode`, `pgvol decode` and `pgvol info`: the .pgv file.

use std::time::Instant;

use anyhow::{bail, Result};
use clap::Args;
use serde::Serialize;

use super::args::{
    at_input, load_mesh_with_unit, non_negative, parse_angle, BasisArgs, GridArgs, MeshInputArgs,
    MethodArg, OutputArgs, PathArg, SharpArg, SignArg,
};
use crate::output::outln;
use crate::progress::Bars;
use crate::report::{self, Seconds};
use clap::ValueEnum;

#[derive(Args)]
#[command(group(clap::ArgGroup::new("input").args(["mesh", "from"]).required(true)))]
#[command(
    after_help = "Examples:\n  pgvol encode bunny.obj -o bunny.pgv --res 256\n  pgvol encode fandisk.obj -o fandisk.pgv --res 128 --sharp auto\n  pgvol encode bunny.vdb -o bunny.pgv --vdb-grid surface"
)]
pub struct EncodeArgs {
    /// Input mesh, or an OpenVDB level set (.vdb), fitted on its own voxel grid (a node at
    /// each voxel centre) within its band.
    pub mesh: Option<PathArg>,
    #[command(flatten)]
    pub read: MeshInputArgs,
    /// The grid of a .vdb input to encode [default: the first float level set].
    #[arg(long, value_name = "NAME")]
    pub vdb_grid: Option<String>,
    /// Read the coefficients from a NRRD written by `pgvol export --what coefficients` instead
    /// of fitting a mesh; written dense and unchanged unless --precision is given.
    #[arg(long, value_name = "NRRD", conflicts_with_all = ["res", "voxel", "basis", "pg_n", "pg_r", "fit", "band", "z_step", "sign", "sharp", "sharp_angle"])]
    pub from: Option<PathArg>,
    /// Output .pgv file.
    #[arg(short, long)]
    pub output: PathArg,
    #[command(flatten)]
    pub grid: GridArgs,
    #[command(flatten)]
    pub basis: BasisArgs,
    /// How the coefficients are found.
    #[arg(long, value_enum, default_value_t)]
    pub fit: FitArg,
    /// Node values are exact distances within W grid spacings of the surface (--fit interp),
    /// clamped beyond. Offsets, shells and levels read from the file are exact within W − 2
    /// spacings (the cubic B-spline's support blends in the clamp), as `pgvol info` shows.
    #[arg(long, value_name = "W", default_value_t = pgvol::limits::ENCODE_BAND, value_parser = parse_band)]
    pub band: f32,
    /// How inside is told from outside.
    #[arg(long, value_enum, default_value_t)]
    pub sign: SignArg,
    /// For --fit iso: the isosurface step in grid spacings, at most 1 (the method needs an
    /// isosurface within half a spacing of every node) [default: searched in 0.05..1].
    #[arg(long)]
    pub z_step: Option<f32>,
    /// Coefficient precision in the file; `auto` picks the smallest that keeps the stored
    /// coefficients within 1 % of the grid spacing, which is `fixed` for distance fields
    /// (measured to keep Chamfer-L1 within 0.35 % of f32's) [default: auto].
    #[arg(long, value_enum)]
    pub precision: Option<PrecisionArg>,
    /// Write every coefficient as f32 instead of the sparse, compressed bricks around the surface.
    #[arg(long, conflicts_with = "precision")]
    pub dense_file: bool,
    /// `auto` stores the exact dual-contouring vertices of the cells at creases and corners, so
    /// that `decode --method dc` (or `sn`) keeps them sharp; smooth shapes store nothing and cost nothing,
    /// and elsewhere the work follows the cells near creases (measured CPU time of the whole
    /// encoding: 1.1x that of `off` on the bunny at 256³-512³, 1.6x on fandisk at 256³,
    /// 1.3x at 512³, 1.1x at 1024³-2048³).
    /// `off` stores none: the default decoding (marching cubes) does not read the section.
    #[arg(long, value_enum, default_value_t)]
    pub sharp: SharpArg,
    /// Crease angle in degrees: edges of the mesh whose faces turn by more (and still do a grid
    /// spacing away, along at least 4 spacings) are creases, and the cells around them get
    /// stored vertices. Creases turning by less than 50° count only where the surface beside
    /// them stays flat for 8 spacings, which the facets of a coarse curved mesh do not.
    #[arg(long, value_name = "DEG", default_value_t = pgvol::sharp::DEFAULT_SHARP_ANGLE, value_parser = parse_angle)]
    pub sharp_angle: f32,
    /// Print the solver's iterations and residual.
    #[arg(long, short)]
    pub verbose: bool,
    #[command(flatten)]
    pub out: OutputArgs,
}

/// Coefficient precision in the file.
#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum PrecisionArg {
    #[default]
    Auto,
    F32,
    F16,
    Q16,
    /// Integers on a scale tied to the grid spacing: steps of h/512 up to |c| = h, h/64 beyond.
    Fixed,
}

/// How the coefficients are found.
#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum FitArg {
    /// The field passes through the signed distance at every node (B-splines: exact prefilter;
    /// pseudo-Gaussian: CG or CGLS).
    #[default]
    Interp,
    /// The paper's points: nodes moved to the nearest isosurface SDF = q·z_step.
    Iso,
    /// Weighted least squares on surface and offset samples (most accurate, slowest).
    Wls,
}

#[derive(Args)]
#[command(after_help = "Example: pgvol decode bunny.pgv -o bunny.glb --method dc")]
pub struct DecodeArgs {
    /// Input .pgv file, or an OpenVDB level set (.vdb: its first float level set, fitted first).
    pub input: PathArg,
    /// Output mesh (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    /// The level set to extract: 0 is the surface, positive values offset it outward; levels
    /// beyond the band the file stores as exact distances are refused.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub iso: f32,
    /// Contouring method.
    #[arg(long, value_enum, default_value_t)]
    pub method: MethodArg,
    /// Resample the field on a grid of N nodes per axis over the same box (default: the
    /// stored grid).
    #[arg(long, value_parser = clap::value_parser!(u32).range(pgvol::limits::MIN_RES as i64..=pgvol::limits::MAX_RES as i64))]
    pub res: Option<u32>,
    /// Remove pieces of the output enclosing less than this volume (model units cubed); by
    /// default specks under 2 grid cells go, with a warning; 0 keeps every piece.
    #[arg(long, value_name = "VOLUME", value_parser = non_negative)]
    pub min_component: Option<f32>,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
#[command(after_help = "Example: pgvol info bunny.pgv --json")]
pub struct InfoArgs {
    /// A .pgv file.
    pub input: PathArg,
    #[command(flatten)]
    pub out: OutputArgs,
}

fn parse_band(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(w) if w.is_finite() && w >= pgvol::limits::MIN_BAND => Ok(w),
        _ => Err(format!(
            "'{s}' is not a number of grid spacings of at least {}",
            pgvol::limits::MIN_BAND
        )),
    }
}

impl PrecisionArg {
    fn precision(self) -> Option<pgvol::Precision> {
        match self {
            PrecisionArg::Auto => None,
            PrecisionArg::F32 => Some(pgvol::Precision::F32),
            PrecisionArg::F16 => Some(pgvol::Precision::F16),
            PrecisionArg::Q16 => Some(pgvol::Precision::Q16),
            PrecisionArg::Fixed => Some(pgvol::Precision::Fixed),
        }
    }
}

/// `encode --from`: a coefficient NRRD to .pgv, copied bit for bit unless a precision is given.
fn encode_from(a: &EncodeArgs, from: &std::path::Path) -> Result<()> {
    let start = Instant::now();
    let file = pgvol::io::read_coefficients_nrrd(from)?;
    let precision = a.precision.and_then(PrecisionArg::precision);
    let storage = match (a.dense_file, a.precision) {
        (true, _) => pgvol::StorageOptions {
            precision: None,
            dense: true,
        },
        (false, None) => pgvol::StorageOptions::for_copy(None),
        (false, Some(_)) => pgvol::StorageOptions {
            precision,
            dense: false,
        },
    };
    let stored = pgvol::io::write_pgv(&a.output, &file, &storage)?;
    let bytes = std::fs::metadata(&a.output)?.len();
    let grid = file.volume.grid;
    if a.out.json {
        return report::print(
            &serde_json::json!({
                "output": a.output, "from": from, "grid": grid, "basis": file.volume.basis,
                "bytes": bytes, "dense": stored.is_none(),
            }),
            &Seconds::since(start),
        );
    }
    if !a.out.quiet {
        outln!(
            "{}: {} x {} x {} {} coefficients from {}, {} bytes",
            a.output.display(),
            grid.dims[0],
            grid.dims[1],
            grid.dims[2],
            file.volume.basis,
            from.display(),
            bytes
        );
    }
    Ok(())
}

pub fn encode(a: EncodeArgs) -> Result<()> {
    pgvol::io::check_pgv_name(&a.output)?;
    if let Some(from) = &a.from {
        return encode_from(&a, from);
    }
    let Some(mesh_path) = &a.mesh else {
        bail!("give a mesh or --from NRRD");
    };
    if a.z_step.is_some() && !matches!(a.fit, FitArg::Iso) {
        bail!("--z-step applies to --fit iso only");
    }
    let quiet = a.out.silent();
    let start = Instant::now();
    let (encoded, unit, sharp) = if pgvol::io::is_vdb(mesh_path) {
        (encode_vdb(&a, mesh_path)?, None, None)
    } else {
        if a.vdb_grid.is_some() {
            bail!("--vdb-grid applies to .vdb inputs");
        }
        encode_mesh(&a, mesh_path)?
    };
    let report = &encoded.fit;
    if a.verbose && !a.out.json {
        eprintln!(
            "fit {}: solver {}, {} iterations, relative residual {:.3e}, {}, {} spurious sign changes{}",
            report.method,
            report.solver,
            report.iterations,
            report.residual,
            if report.converged { "converged" } else { "NOT converged" },
            report.spurious_sign_changes,
            report.z_step.map(|z| format!(", z_step {z:.4} k")).unwrap_or_default()
        );
    }
    // An unconverged fit is warned of by the library, through the progress bars.
    if report.spurious_sign_changes > 0 {
        report::warn(
            quiet,
            &format!(
                "{} nodes farther than one spacing from the surface have the wrong sign: the \
                 field has spurious surface pieces",
                report.spurious_sign_changes
            ),
        );
    }
    let storage = pgvol::StorageOptions {
        precision: a.precision.and_then(PrecisionArg::precision),
        dense: a.dense_file,
    };
    let file = &encoded.file;
    let stored = pgvol::io::write_pgv(&a.output, file, &storage)?;
    let bytes = std::fs::metadata(&a.output)?.len();
    let grid = file.volume.grid;
    if a.out.json {
        let storage = stored.as_ref().map(|r| {
            serde_json::json!({
                "bricks_total": r.bricks_total, "bricks_stored": r.bricks_stored,
                "bytes_header": r.bytes_header, "bytes_index": r.bytes_index, "bytes_payload": r.bytes_payload,
                "precision": r.precision, "max_quantisation_error": r.max_quantisation_error,
            })
        });
        return report::print(
            &serde_json::json!({
                "output": a.output, "grid": grid, "basis": file.volume.basis, "bytes": bytes,
                "storage": storage, "fit": report, "unit": unit, "sharp": sharp,
            }),
            &Seconds::since(start).stages([
                ("sdf", encoded.timings.sdf),
                ("fit", encoded.timings.fit),
                ("sharp", encoded.timings.sharp),
            ]),
        );
    }
    if !a.out.quiet {
        let detail = match &stored {
            Some(r) => format!(
                ", {} of {} bricks stored as {:?}",
                r.bricks_stored, r.bricks_total, r.precision
            ),
            None => ", dense f32".to_string(),
        };
        let detail = match sharp {
            Some(r) if r.stored_cells > 0 => {
                format!(
                    "{detail}, {} cells of sharp-feature vertices",
                    r.stored_cells
                )
            }
            _ => detail,
        };
        // Mesh grids are cubes; a .vdb input's grid follows its leaves.
        let [nx, ny, nz] = grid.dims;
        let dims = if nx == ny && ny == nz {
            format!("{nx}^3")
        } else {
            format!("{nx} x {ny} x {nz}")
        };
        outln!(
            "{}: {} {} coefficients, {} bytes{}",
            a.output.display(),
            dims,
            file.volume.basis,
            bytes,
            detail
        );
    }
    Ok(())
}

/// `encode` of a mesh: sampled and fitted on the grid the options give.
/// `encode` of a mesh, with what was done with the file's declared length unit.
fn encode_mesh(
    a: &EncodeArgs,
    mesh_path: &std::path::Path,
) -> Result<(
    pgvol::Encoded,
    Option<String>,
    Option<pgvol::sharp::SharpReport>,
)> {
    let (mesh, unit) = load_mesh_with_unit(mesh_path, a.read, a.out.silent())?;
    let options = pgvol::EncodeOptions {
        grid: a.grid.spec(),
        basis: a.basis.basis()?,
        fit: match a.fit {
            FitArg::Interp => pgvol::FitMethod::Interp,
            FitArg::Iso => pgvol::FitMethod::Iso { z_step: a.z_step },
            FitArg::Wls => pgvol::FitMethod::Wls,
        },
        band: a.band,
        sign: a.sign.into(),
        sharp: a.sharp.options(a.sharp_angle),
    };
    let bars = Bars::new(a.out.silent());
    let encoded = pgvol::encode(&mesh, &options, &bars).map_err(|e| at_input(e, mesh_path))?;
    let sharp = encoded.sharp;
    Ok((encoded, unit, Some(sharp)))
}

/// `encode` of an OpenVDB level set: fitted on the file's own voxel grid and band.
fn encode_vdb(a: &EncodeArgs, path: &std::path::Path) -> Result<pgvol::Encoded> {
    if a.grid.res.is_some() || a.grid.voxel.is_some() {
        bail!("a .vdb input keeps its own voxel grid: --res and --voxel apply to meshes");
    }
    if !matches!(a.fit, FitArg::Interp) {
        bail!("a .vdb input is fitted by interpolating its voxels: --fit applies to meshes");
    }
    let options = pgvol::io::VdbEncodeOptions {
        grid_name: a.vdb_grid.clone(),
        basis: a.basis.basis()?,
    };
    Ok(
        pgvol::io::encode_vdb(path, &options, &Bars::new(a.out.silent()))
            .map_err(|e| at_input(e, path))?,
    )
}

pub fn decode(a: DecodeArgs) -> Result<()> {
    let start = Instant::now();
    pgvol::io::mesh_format(&a.output)?;
    let t = Instant::now();
    let options = pgvol::DecodeOptions {
        iso: a.iso,
        method: a.method.into(),
        res: a.res.map(|r| r as usize),
        min_component: a.min_component,
    };
    let mesh = pgvol::stream::decode_file(&a.input, &options, &Bars::new(a.out.silent()))
        .map_err(|e| at_input(e, &a.input))?;
    let seconds = t.elapsed().as_secs_f64();
    pgvol::io::write_mesh(&a.output, &mesh)?;
    if a.out.json {
        return report::print(
            &serde_json::json!({
                "output": a.output, "triangles": mesh.triangles.len(),
                "vertices": mesh.positions.len(),
            }),
            &Seconds::since(start).stage("contour", seconds),
        );
    }
    if !a.out.quiet {
        outln!(
            "{}: {} triangles in {:.2} s",
            a.output.display(),
            mesh.triangles.len(),
            seconds
        );
    }
    Ok(())
}

#[derive(Serialize)]
struct Info<'a> {
    file: &'a std::path::Path,
    bytes: u64,
    /// The `.pgv` format version.
    version: u32,
    header: &'a pgvol::PgvHeader,
    coefficients: usize,
    coefficient_range: [f32; 2],
    bricks_total: Option<usize>,
    bricks_stored: Option<usize>,
    precision: pgvol::Precision,
    bytes_header: usize,
    bytes_index: usize,
    bytes_payload: usize,
    /// Distance from the surface (model units) within which offsets, shells, levels and
    /// evaluation read exact distances.
    exact_reach: f32,
}

pub fn info(a: InfoArgs) -> Result<()> {
    let start = Instant::now();
    let raw = pgvol::core::read_input(&a.input)?;
    let parts = pgvol::io::pgv_info(&raw, &a.input)?;
    let file = pgvol::io::read_pgv_bytes(&raw, &a.input)?;
    let bytes = raw.len() as u64;
    let range = file.volume.coeffs.value_range();
    let count = file.volume.grid.len();
    let info = Info {
        file: &a.input,
        bytes,
        version: parts.version,
        header: &file.header,
        coefficients: count,
        coefficient_range: range,
        bricks_total: parts.bricks_total,
        bricks_stored: parts.bricks_stored,
        precision: parts.precision,
        bytes_header: parts.bytes_header,
        bytes_index: parts.bytes_index,
        bytes_payload: parts.bytes_payload,
        exact_reach: pgvol::checks::exact_reach(&file),
    };
    if a.out.json {
        return report::print(&info, &Seconds::since(start));
    }
    let h = &file.header;
    let g = h.grid;
    outln!(
        "file          {} ({} bytes, format version {})",
        a.input.display(),
        bytes,
        parts.version
    );
    outln!("basis         {} (fit: {})", h.basis, h.fit);
    outln!(
        "grid          {} x {} x {}, spacing {}, origin ({}, {}, {})",
        g.dims[0],
        g.dims[1],
        g.dims[2],
        g.spacing,
        g.origin.x,
        g.origin.y,
        g.origin.z
    );
    if g.offset != pgvol::glam::DVec3::ZERO {
        outln!(
            "frame offset  ({}, {}, {}): world = offset + the local positions above",
            g.offset.x,
            g.offset.y,
            g.offset.z
        );
    }
    let list = pgvol::format::is_perturbation(h);
    if list {
        outln!(
            "encoding      {} (a perturbation field's function list, resampled on the grid above when read)",
            h.encoding
        );
    } else {
        outln!("encoding      {} ({:?})", h.encoding, parts.precision);
    }
    if let (Some(stored), Some(total)) = (parts.bricks_stored, parts.bricks_total) {
        outln!("bricks        {stored} of {total} stored");
    }
    outln!(
        "bytes         header {}, index {}, {} {}",
        parts.bytes_header,
        parts.bytes_index,
        if list {
            "function list"
        } else {
            "coefficients"
        },
        parts.bytes_payload
    );
    outln!(
        "coefficients  {} in [{}, {}]{}",
        count,
        range[0],
        range[1],
        if list { " (resampled)" } else { "" }
    );
    outln!(
        "exact reach   {} ({:.2} spacings): offsets, shells, levels and eval are exact within \
         this distance of the surface",
        info.exact_reach,
        info.exact_reach / g.spacing
    );
    if let Some([lo, hi]) = h.source_bounds {
        outln!("source box    {lo:?} .. {hi:?}");
    }
    if let Some(hash) = &h.source_hash {
        outln!("source hash   {hash}");
    }
    if let Some(sharp) = &h.sharp {
        outln!(
            "sharp         {} cells with stored dual-contouring vertices ({} bytes), used by \
             decode --method dc on the stored grid",
            sharp.cells,
            sharp.data.len()
        );
    }
    for (k, v) in &h.metadata {
        outln!("{k:<13} {v}");
    }
    Ok(())
}
