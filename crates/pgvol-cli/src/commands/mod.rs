//! The subcommands and their arguments.

mod compare;
mod eval;
mod export;
mod files;
mod ops;
mod remesh;
mod sdf;

use anyhow::Result;
use clap::{Args, Subcommand, ValueEnum};
use std::path::PathBuf;

use crate::output::outln;
use pgvol::Basis;

#[derive(Subcommand)]
pub enum Command {
    /// Mesh → signed distance → mesh, in one go: a clean, watertight remesh.
    ///
    /// Reads OBJ, glTF/GLB, STL or PLY and writes GLB, glTF, OBJ, STL or PLY (by extension). The
    /// output is watertight and manifold whatever the input's holes or flipped faces. Vertices
    /// lie on the input's exact distance (sharp edges stay sharp with --method dc), or with
    /// --field decoded on the coefficient volume that `encode` then `decode` would give.
    Remesh(remesh::RemeshArgs),
    /// Surface distances and statistics of mesh A against reference mesh B.
    ///
    /// Hausdorff and Chamfer-L1 (mean of the two mean distances) from area-uniform samples with
    /// exact point-to-triangle distances, in absolute units and as % of B's bounding-box diagonal;
    /// normal deviation between each sample and its closest point; triangles, boundary and
    /// non-manifold edges, watertightness, Euler characteristic, volume and area of both.
    Compare(compare::CompareArgs),
    /// Samples the signed distance of a mesh on a dense grid and writes NRRD or NPY (float32).
    Sdf(sdf::SdfArgs),
    /// Encodes a mesh as a .pgv coefficient-volume file.
    Encode(files::EncodeArgs),
    /// Contours a .pgv file into a mesh.
    Decode(files::DecodeArgs),
    /// Prints what a .pgv file holds.
    Info(files::InfoArgs),
    /// Exports a .pgv file as NRRD (coefficients or sampled field) or as a 3MF level set.
    ///
    /// A coefficient NRRD carries the basis in key/value fields and reads back with
    /// `pgvol encode --from`; a .3mf holds the field as a 16-bit PNG image stack under a
    /// Volumetric-extension level set.
    Export(export::ExportArgs),
    /// Evaluates a .pgv field (value and gradient) at the points of a CSV file (x,y,z per line).
    Eval(eval::EvalArgs),
    /// Cuts a field or mesh into layers of closed contours for additive manufacturing.
    ///
    /// Outer loops are counter-clockwise and holes clockwise (seen from +axis), simplified to
    /// --tolerance without breaking closure. Writes SVG, Common Layer Interface or JSON.
    Slice(ops::SliceArgs),
    /// Offsets a shape by a distance (positive outward, negative inward).
    Offset(ops::OffsetArgs),
    /// Turns a shape into a shell of given wall thickness, or hollows it with drain holes.
    Shell(ops::ShellArgs),
}

pub fn run(command: Command) -> Result<()> {
    pgvol::set_memory_limit(command.out().max_memory);
    if let Some((output, out)) = command.output() {
        out.check(output)?;
    }
    match command {
        Command::Remesh(a) => remesh::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Sdf(a) => sdf::run(a),
        Command::Encode(a) => files::encode(a),
        Command::Decode(a) => files::decode(a),
        Command::Info(a) => files::info(a),
        Command::Export(a) => export::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Slice(a) => ops::slice(a),
        Command::Offset(a) => ops::offset(a),
        Command::Shell(a) => ops::shell(a),
    }
}

impl Command {
    /// The output options every command has.
    fn out(&self) -> OutputArgs {
        match self {
            Command::Remesh(a) => a.out,
            Command::Compare(a) => a.out,
            Command::Sdf(a) => a.out,
            Command::Encode(a) => a.out,
            Command::Decode(a) => a.out,
            Command::Info(a) => a.out,
            Command::Export(a) => a.out,
            Command::Eval(a) => a.out,
            Command::Slice(a) => a.out,
            Command::Offset(a) => a.out,
            Command::Shell(a) => a.out,
        }
    }

    /// The file the command writes and its output options, when it writes one.
    fn output(&self) -> Option<(&std::path::Path, OutputArgs)> {
        match self {
            Command::Remesh(a) => Some((&a.output, a.out)),
            Command::Sdf(a) => Some((&a.output, a.out)),
            Command::Encode(a) => Some((&a.output, a.out)),
            Command::Decode(a) => Some((&a.output, a.out)),
            Command::Export(a) => Some((&a.output, a.out)),
            Command::Eval(a) => a.output.as_deref().map(|o| (o, a.out)),
            Command::Slice(a) => Some((&a.output, a.out)),
            Command::Offset(a) => Some((&a.output, a.out)),
            Command::Shell(a) => Some((&a.output, a.out)),
            Command::Compare(_) | Command::Info(_) => None,
        }
    }
}

/// Grid size options shared by the commands that sample a mesh.
#[derive(Args, Clone, Copy, Debug)]
pub struct GridArgs {
    /// Nodes per axis of the grid (a cube 1.1 × the mesh's longest extent) [default: 128].
    #[arg(long, value_parser = clap::value_parser!(u32).range(pgvol::MIN_RES as i64..=pgvol::MAX_RES as i64))]
    pub res: Option<u32>,
    /// Grid spacing in mesh units, instead of --res.
    #[arg(long, conflicts_with = "res")]
    pub voxel: Option<f32>,
}

impl GridArgs {
    /// The grid as the library takes it (its default resolution when neither is given).
    pub fn spec(self) -> pgvol::GridSpec {
        match (self.res, self.voxel) {
            (_, Some(h)) => pgvol::GridSpec::Voxel(h),
            (Some(n), None) => pgvol::GridSpec::Res(n as usize),
            (None, None) => pgvol::GridSpec::default(),
        }
    }
}

/// The basis of the coefficient volume.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BasisArg {
    /// Tensor-product cubic B-spline: C², 64 nodes per evaluation; the most accurate per byte
    /// in docs/basis-study.md.
    #[default]
    Bspline3,
    /// Tensor-product quadratic B-spline: C¹, 27 nodes per evaluation.
    Bspline2,
    /// The paper's pseudo-Gaussian (1 − d²/r²)^(n+1), radial; see --pg-n and --pg-r.
    Pg,
    /// The sampled values themselves, interpolated trilinearly (the baseline).
    Trilinear,
}

/// Basis choice with its parameters.
#[derive(Args, Clone, Copy, Debug)]
pub struct BasisArgs {
    /// Basis of the coefficient volume.
    #[arg(long, value_enum, default_value_t)]
    pub basis: BasisArg,
    /// Pseudo-Gaussian continuity order n (1 to 4); with --basis pg.
    #[arg(long, default_value_t = pgvol::PG_ORDER)]
    pub pg_n: u8,
    /// Pseudo-Gaussian support radius r in grid spacings (0 < r ≤ 4); with --basis pg.
    #[arg(long, default_value_t = pgvol::PG_RADIUS)]
    pub pg_r: f32,
}

impl BasisArgs {
    pub fn basis(self) -> Result<Basis> {
        let b = match self.basis {
            BasisArg::Bspline3 => Basis::Bspline3,
            BasisArg::Bspline2 => Basis::Bspline2,
            BasisArg::Trilinear => Basis::Trilinear,
            BasisArg::Pg => Basis::Pg {
                n: self.pg_n,
                r: self.pg_r,
            },
        };
        b.validate()
            .map_err(|e| anyhow::anyhow!("--pg-r/--pg-n: {e}"))?;
        Ok(b)
    }

    /// Whether any basis option differs from its default.
    pub fn is_default(self) -> bool {
        self.basis == BasisArg::default()
            && self.pg_n == pgvol::PG_ORDER
            && self.pg_r == pgvol::PG_RADIUS
    }
}

/// How the mesh is extracted from the field.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MethodArg {
    /// Marching cubes, vertices on the continuous field: watertight and manifold.
    #[default]
    Mc,
    /// Surface nets, vertices projected onto the field: watertight, manifold, smooth.
    Sn,
    /// Dual contouring with the analytic gradients: keeps sharp edges, manifold.
    Dc,
}

/// How inside and outside are told apart.
#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum SignArg {
    /// Pseudonormal for closed, consistently oriented meshes; winding number otherwise.
    #[default]
    Auto,
    /// Generalized winding number > 1/2: survives holes, flipped faces, self-intersections.
    Winding,
    /// Angle-weighted pseudonormal: for closed, consistently oriented meshes only.
    Pseudonormal,
    /// Ray parity, majority of three rays: for closed meshes, blind to orientation.
    Parity,
}

impl From<SignArg> for pgvol::SignMode {
    fn from(s: SignArg) -> Self {
        match s {
            SignArg::Auto => pgvol::SignMode::Auto,
            SignArg::Winding => pgvol::SignMode::Winding,
            SignArg::Pseudonormal => pgvol::SignMode::Pseudonormal,
            SignArg::Parity => pgvol::SignMode::Parity,
        }
    }
}

impl From<MethodArg> for pgvol::Method {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::Mc => pgvol::Method::MarchingCubes,
            MethodArg::Sn => pgvol::Method::SurfaceNets,
            MethodArg::Dc => pgvol::Method::DualContouring,
        }
    }
}

/// Output options shared by every command.
#[derive(Args, Clone, Copy, Debug)]
pub struct OutputArgs {
    /// Print the results as one JSON object on standard output.
    #[arg(long)]
    pub json: bool,
    /// No progress bars or notes on standard error.
    #[arg(long, short)]
    pub quiet: bool,
    /// Replace an output file even when it is read-only.
    #[arg(long)]
    pub force: bool,
    /// Refuse jobs whose estimated peak memory exceeds SIZE (e.g. 8G, 512M) [default: the
    /// memory available when the job starts].
    #[arg(long, value_name = "SIZE", value_parser = parse_memory)]
    pub max_memory: Option<u64>,
}

fn parse_memory(s: &str) -> Result<u64, String> {
    pgvol::parse_size(s).map_err(|e| e.to_string())
}

impl OutputArgs {
    /// Refuses `output` before any work: a missing folder, a folder, a read-only file without
    /// --force.
    pub fn check(self, output: &std::path::Path) -> Result<()> {
        Ok(pgvol::check_output(output, self.force)?)
    }

    /// Progress and notes are off in JSON mode too, so standard error stays clean for scripts.
    pub fn silent(self) -> bool {
        self.quiet || self.json
    }
}

pub type PathArg = PathBuf;

/// Reads a mesh through the library, saying on standard error what cleaning removed unless
/// `quiet`. Merged vertices go unmentioned for STL, which stores every triangle's corners apart.
pub fn load_mesh(path: &std::path::Path, quiet: bool) -> Result<pgvol::Mesh> {
    let (mesh, report) = pgvol::read_mesh(path)?;
    let is_stl = matches!(pgvol::mesh_format(path), Ok(pgvol::mesh::MeshFormat::Stl));
    let merged = if is_stl { 0 } else { report.vertices_merged };
    if !quiet && (merged > 0 || report.degenerate_dropped > 0 || report.duplicates_dropped > 0) {
        eprintln!(
            "{}: merged {merged} duplicate vertices, dropped {} degenerate and {} repeated triangles",
            path.display(),
            report.degenerate_dropped,
            report.duplicates_dropped
        );
    }
    Ok(mesh)
}

/// Prints `value` as pretty JSON on standard output.
pub fn print_json(value: &impl serde::Serialize) -> Result<()> {
    outln!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}
