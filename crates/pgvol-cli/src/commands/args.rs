//! Arguments and helpers the subcommands share.

use anyhow::Result;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};

use pgvol::Basis;

use crate::progress::Bars;

/// Grid size options shared by the commands that sample a mesh.
#[derive(Args, Clone, Copy, Debug)]
pub struct GridArgs {
    /// Nodes per axis of the grid (a cube 1.1 × the mesh's longest extent) [default: 128].
    #[arg(long, value_parser = clap::value_parser!(u32).range(pgvol::limits::MIN_RES as i64..=pgvol::limits::MAX_RES as i64))]
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
    #[arg(long, default_value_t = pgvol::limits::PG_ORDER)]
    pub pg_n: u8,
    /// Pseudo-Gaussian support radius r in grid spacings (0 < r ≤ 4); with --basis pg.
    #[arg(long, default_value_t = pgvol::limits::PG_RADIUS)]
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
            && self.pg_n == pgvol::limits::PG_ORDER
            && self.pg_r == pgvol::limits::PG_RADIUS
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
    /// Winding number on faces first turned outward: exact on closed meshes at no extra cost, robust on open ones.
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

/// Whether encoding stores sharp-feature vertices.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq)]
pub enum SharpArg {
    /// Stored where the shape has creases or corners.
    Auto,
    /// None stored.
    #[default]
    Off,
}

impl SharpArg {
    /// The library's options for this choice and crease angle (degrees).
    pub fn options(self, angle: f32) -> pgvol::sharp::SharpOptions {
        pgvol::sharp::SharpOptions {
            enabled: self == SharpArg::Auto,
            angle,
        }
    }
}

/// A crease angle in degrees, strictly between 0 and 180.
pub fn parse_angle(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(a) if a.is_finite() && a > 0.0 && a < 180.0 => Ok(a),
        _ => Err(format!(
            "'{s}' is not an angle in degrees between 0 and 180"
        )),
    }
}

/// Output options shared by every command.
#[derive(Args, Clone, Copy, Debug)]
pub struct OutputArgs {
    /// Print the results as one JSON object on standard output, with `warnings` (a list, empty
    /// when none) and `seconds` (stage times and their `total`).
    #[arg(long)]
    pub json: bool,
    /// No progress bars or notes on standard error.
    #[arg(long, short)]
    pub quiet: bool,
    /// Replace an output file even when it is read-only or is the command's input.
    #[arg(long)]
    pub force: bool,
    /// Refuse jobs whose estimated peak memory exceeds SIZE (e.g. 8G, 512M) [default: the
    /// memory available when the job starts].
    #[arg(long, value_name = "SIZE", value_parser = parse_memory)]
    pub max_memory: Option<u64>,
}

fn parse_memory(s: &str) -> Result<u64, String> {
    crate::parse::parse_size(s).map_err(|e| e.to_string())
}

/// Refuses an output path before any work is done: its folder must exist, it must not be a
/// folder itself, and a read-only file is replaced only when `force` is set.
fn check_output(path: &Path, force: bool) -> pgvol::Result<()> {
    let fail = |problem: String| pgvol::Error::new(pgvol::ErrorKind::OutputFile, problem).at(path);
    let folder = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(fail(format!(
            "the folder '{}' does not exist",
            folder.display()
        )));
    }
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_dir() => Err(fail("is a folder, not a file".into())),
        Ok(meta) if meta.is_file() && meta.permissions().readonly() && !force => Err(fail(
            "is read-only; make it writable or allow replacing it".into(),
        )
        .with_remedy(pgvol::Remedy::Replace)),
        _ => Ok(()),
    }
}

impl OutputArgs {
    /// Refuses `output` before any work: a missing folder, a folder, a read-only file without
    /// --force.
    pub fn check(self, output: &Path) -> Result<()> {
        Ok(check_output(output, self.force)?)
    }

    /// Refuses an `output` that is one of the command's `inputs` (the same file, by any path)
    /// unless --force is given: the input would be replaced by the result.
    pub fn check_not_an_input(self, output: &Path, inputs: &[&Path]) -> Result<()> {
        if self.force {
            return Ok(());
        }
        let Ok(out) = std::fs::canonicalize(output) else {
            return Ok(());
        };
        if inputs
            .iter()
            .any(|i| std::fs::canonicalize(i).is_ok_and(|i| i == out))
        {
            return Err(pgvol::Error::new(
                pgvol::ErrorKind::OutputFile,
                "is also the input, which the result would replace; write to another file, or \
                 allow replacing it",
            )
            .at(output)
            .with_remedy(pgvol::Remedy::Replace)
            .into());
        }
        Ok(())
    }

    /// Progress and notes are off in JSON mode too, so standard error stays clean for scripts.
    pub fn silent(self) -> bool {
        self.quiet || self.json
    }
}

pub type PathArg = PathBuf;

/// What a mesh file that declares its length unit (3MF) is read in.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MeshUnitsArg {
    /// Millimetres: an inch file's coordinates are multiplied by 25.4.
    #[default]
    Mm,
    /// The unit the file declares: its numbers as written.
    File,
}

/// How the commands that take a mesh read it.
#[derive(Args, Clone, Copy, Debug, Default)]
pub struct MeshInputArgs {
    /// Unit of a mesh from a file that declares one (3MF); other formats are read as written.
    #[arg(long, value_enum, default_value_t)]
    pub mesh_units: MeshUnitsArg,
}

impl MeshInputArgs {
    fn choice(self) -> pgvol::mesh::UnitChoice {
        match self.mesh_units {
            MeshUnitsArg::Mm => pgvol::mesh::UnitChoice::Millimetres,
            MeshUnitsArg::File => pgvol::mesh::UnitChoice::AsDeclared,
        }
    }
}

/// Reads a mesh through the library, warning of what cleaning removed (on standard error unless
/// `quiet`, and in the report). Merged vertices go unmentioned for STL, which stores every
/// triangle's corners apart.
pub fn load_mesh(path: &Path, input: MeshInputArgs, quiet: bool) -> Result<pgvol::Mesh> {
    load_mesh_with_unit(path, input, quiet).map(|(mesh, _)| mesh)
}

/// [`load_mesh`], with what was done with the file's declared length unit (3MF: "inch ->
/// millimetre x25.4", say), noted on standard error unless `quiet` when it scaled.
pub fn load_mesh_with_unit(
    path: &Path,
    input: MeshInputArgs,
    quiet: bool,
) -> Result<(pgvol::Mesh, Option<String>)> {
    let pgvol::io::ReadMesh {
        mesh,
        cleaned: report,
    } = pgvol::io::read_mesh_in(path, input.choice())?;
    let is_stl = matches!(
        pgvol::mesh::MeshFormat::from_path(path),
        Ok(pgvol::mesh::MeshFormat::Stl)
    );
    let merged = if is_stl { 0 } else { report.vertices_merged };
    if merged > 0 || report.degenerate_dropped > 0 || report.duplicates_dropped > 0 {
        crate::report::warn(
            quiet,
            &format!(
                "{}: merged {merged} duplicate vertices, dropped {} degenerate and {} repeated \
                 triangles",
                path.display(),
                report.degenerate_dropped,
                report.duplicates_dropped
            ),
        );
    }
    if let Some(unit) = report.unit {
        if unit.scale() != 1.0 && !quiet {
            eprintln!("note: {}: unit {unit}", path.display());
        }
    }
    Ok((mesh, report.unit.map(|u| u.to_string())))
}

/// A library error without a file, reported against the input that caused it.
pub fn at_input(e: pgvol::Error, input: &Path) -> pgvol::Error {
    match e.path() {
        Some(_) => e,
        None => e.at(input),
    }
}

/// A library error reported against `input` (see [`at_input`]), saying which `--res` gives the
/// grid the library names when the grid was too coarse.
pub fn grid_error(e: pgvol::Error, input: &Path) -> anyhow::Error {
    let e = at_input(e, input);
    // Past the largest grid the library's message already says so.
    let Some(nodes) = e
        .resolution()
        .filter(|&n| n <= pgvol::limits::MAX_RES as usize)
    else {
        return e.into();
    };
    let hint = if pgvol::io::is_pgv(input) {
        format!("encode the mesh again with --res {nodes} and the band it needs, or pass the mesh with --res {nodes}")
    } else {
        format!("run again with --res {nodes}")
    };
    anyhow::anyhow!("{e}; {hint}")
}

/// A finite number of at least zero.
pub fn non_negative(text: &str) -> std::result::Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("expected a number of at least 0, got '{text}'")),
    }
}

pub(super) fn check_output_name(output: &Path) -> Result<()> {
    if !pgvol::io::is_pgv(output) {
        pgvol::io::mesh_format(output)?;
    }
    Ok(())
}

/// Refuses --dense-file for an output that is not a .pgv file.
pub(super) fn check_dense_file(dense_file: bool, output: &Path) -> Result<()> {
    if dense_file && !pgvol::io::is_pgv(output) {
        anyhow::bail!("--dense-file applies to .pgv outputs");
    }
    Ok(())
}

/// Dense f32 with --dense-file, else the sparse bricks at the automatic precision.
pub(super) fn file_storage(dense_file: bool) -> pgvol::StorageOptions {
    pgvol::StorageOptions {
        precision: None,
        dense: dense_file,
    }
}

/// Options shared by the commands that turn a shape into a new shape.
#[derive(Args, Clone, Copy)]
pub struct ShapeOutputArgs {
    /// Grid nodes per axis when the input is a mesh.
    #[arg(long, default_value_t = pgvol::limits::SHAPE_RES as u32, value_parser = clap::value_parser!(u32).range(pgvol::limits::MIN_RES as i64..=pgvol::limits::MAX_RES as i64))]
    pub res: u32,
    /// Contouring method for mesh outputs.
    #[arg(long, value_enum, default_value_t)]
    pub method: MethodArg,
    /// Remove pieces of the output enclosing less than this volume (model units cubed); by
    /// default specks under 2 grid cells go, with a warning; 0 keeps every piece.
    #[arg(long, value_name = "VOLUME", value_parser = non_negative)]
    pub min_component: Option<f32>,
    /// How inside is told from outside when the input is a mesh.
    #[arg(long, value_enum, default_value_t)]
    pub sign: SignArg,
    /// Write a .pgv output with every coefficient as f32 instead of the sparse, compressed
    /// bricks around the surface.
    #[arg(long)]
    pub dense_file: bool,
}

impl ShapeOutputArgs {
    /// Refuses an output that is neither .pgv nor a mesh format, and --dense-file for a mesh.
    pub fn check_output(&self, output: &Path) -> Result<()> {
        check_output_name(output)?;
        check_dense_file(self.dense_file, output)
    }

    /// How a .pgv output is stored: sparse bricks at the automatic precision, as `encode`
    /// writes them, or dense with --dense-file.
    pub fn storage(&self) -> pgvol::StorageOptions {
        file_storage(self.dense_file)
    }

    /// How a mesh result is contoured: --method and --min-component.
    pub fn decode_options(&self) -> pgvol::DecodeOptions {
        pgvol::DecodeOptions {
            method: self.method.into(),
            min_component: self.min_component,
            ..Default::default()
        }
    }

    /// `input` as a field: a `.pgv` file, or a mesh encoded at `--res` with `--sign` over its
    /// box grown by `grow`, exact `reach` beyond the band (see [`pgvol::Field::open`]).
    pub fn load(
        &self,
        input: &Path,
        grow: f32,
        reach: f32,
        bars: &Bars,
    ) -> pgvol::Result<pgvol::Field> {
        let options = pgvol::OpenOptions {
            res: self.res as usize,
            grow,
            reach,
            wall: None,
            sign: self.sign.into(),
            sharp: pgvol::sharp::SharpOptions::default(),
        };
        pgvol::Field::open(input, &options, bars)
    }

    /// [`ShapeOutputArgs::load`] for an operation making walls as thin as `wall`: a grid too
    /// coarse for them is refused before a mesh is encoded, naming the --res that holds them.
    pub fn load_walled(
        &self,
        input: &Path,
        grow: f32,
        reach: f32,
        wall: f32,
        bars: &Bars,
    ) -> Result<pgvol::Field> {
        let options = pgvol::OpenOptions {
            res: self.res as usize,
            grow,
            reach,
            wall: Some(wall),
            sign: self.sign.into(),
            sharp: pgvol::sharp::SharpOptions::default(),
        };
        pgvol::Field::open(input, &options, bars).map_err(|e| grid_error(e, input))
    }
}
