//! The subcommands and their arguments.

mod args;
mod blend;
mod compare;
mod edit;
mod eval;
mod export;
mod files;
mod lattice;
mod ops;
mod perturb;
mod points;
mod remesh;
mod sdf;
mod view;

use anyhow::Result;
use clap::Subcommand;

use args::OutputArgs;

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
    /// normal deviation between each sample and its closest point; the deviation of A's
    /// vertices and vertex normals from B and the mean depth-buffer difference over 14 views;
    /// triangles, boundary and non-manifold edges, watertightness, Euler characteristic, volume
    /// and area of both.
    Compare(compare::CompareArgs),
    /// Samples the signed distance of a mesh on a dense grid and writes NRRD or NPY (float32).
    Sdf(sdf::SdfArgs),
    /// Encodes a mesh as a .pgv coefficient-volume file.
    Encode(files::EncodeArgs),
    /// Contours a .pgv file into a mesh.
    Decode(files::DecodeArgs),
    /// Prints what a .pgv file holds.
    Info(files::InfoArgs),
    /// Exports a .pgv file as NRRD or .npy (a grid), or as a 3MF or OpenVDB level set.
    ///
    /// A coefficient NRRD carries the basis in key/value fields and reads back with
    /// `pgvol encode --from`; a .3mf holds the field as a 16-bit PNG image stack under a
    /// Volumetric-extension level set; a .vdb holds the narrow band as an OpenVDB FloatGrid of
    /// class level set (for Blender, Houdini and other OpenVDB tools).
    Export(export::ExportArgs),
    /// Evaluates a .pgv field (value and gradient) at the points of a CSV file (x,y,z per line).
    Eval(eval::EvalArgs),
    /// Cuts a field or mesh into layers of closed contours for additive manufacturing.
    ///
    /// Outer loops are counter-clockwise and holes clockwise (seen from +axis), simplified to
    /// --tolerance without breaking closure. Writes SVG, Common Layer Interface or JSON.
    Slice(ops::SliceArgs),
    /// Fits a smooth surface through a point cloud and writes it as .pgv or a mesh.
    ///
    /// Each point is a constraint (value 0) with one more at ±ε along its normal; the field
    /// through them is fitted into a cubic B-spline coefficient volume on the usual grid around
    /// the points. Clouds without normals get estimated, consistently oriented ones.
    Points(points::PointsArgs),
    /// Rebuilds a solid from a stack of closed planar contours (JSON, CLI or SVG layer files).
    ///
    /// Each plane's 2D signed distance, held to pass through its loops, is interpolated across
    /// the planes by a cubic spline along the axis; the solid closes half a layer beyond the
    /// outermost planes, and regions of neighbouring layers that do not overlap (a leaning
    /// part) are joined in a frame moving with them; branching and holes are handled. Evenly
    /// spaced planes are put on grid nodes (the spacing moves by at most 10 %). Slicing the
    /// result at the input planes gives back the contours.
    Contours(points::ContoursArgs),
    /// Offsets a shape by a distance (positive outward, negative inward).
    Offset(ops::OffsetArgs),
    /// Turns a shape into a shell of given wall thickness, or hollows it with drain holes,
    /// optionally filling the cavity with a lattice (--infill).
    Shell(ops::ShellArgs),
    /// Cuts a triply periodic lattice (gyroid, Schwarz P, diamond, Neovius) to a part.
    ///
    /// Sheet or strut solids with a cell size and thickness, optionally graded with depth or
    /// along a segment; reports the solid's volume fraction of the part and its surface area.
    Lattice(lattice::LatticeArgs),
    /// Union, intersection or difference of fields, meshes and analytic primaries, sharp or
    /// with round fillets (--radius).
    ///
    /// Every operand is placed on one grid covering all (meshes are encoded onto it) and the
    /// result is re-fitted brick by brick. With --radius r the rounded field lies between the
    /// sharp one and r below it (r above for intersections), equals it where the operands are
    /// more than r apart, and is Lipschitz with constant √2, so offsets and shells still work.
    Csg(edit::CsgArgs),
    /// Restores a field inside axis-aligned masks: removes a protrusion, or smooths noise.
    ///
    /// A protrusion is replaced by the least-squares solution of Laplace's equation inside the
    /// mask, with the field's values around the mask fixed and its normal derivative across
    /// --face set by --alpha; --denoise resamples coarsely instead. Only the coefficients whose
    /// support meets a mask change, so the field stays continuous at the mask's boundary.
    Repair(edit::RepairArgs),
    /// Blends primaries algebraically: Liming rounding, functional splines or I-patches.
    ///
    /// Primaries are analytic (plane, sphere, cylinder, box), .pgv files or meshes. The result is
    /// renormalised near its surface (value over gradient length) so it is distance-like again,
    /// and re-fitted into one coefficient volume.
    Blend(blend::BlendArgs),
    /// Converts a mesh into an implicit surface of quadric perturbations.
    ///
    /// A base quadric fitted by least squares plus local bumps f·Q³ (each quadric Q through ten
    /// vertices), added where the vertices are farthest from the zero set until --tolerance or
    /// --max-functions; the loop stops with a report when no bump lowers the error. The field is
    /// resampled into a coefficient volume (.pgv) or contoured into a mesh.
    Perturb(perturb::PerturbArgs),
    /// Writes one self-contained HTML page showing a field: its surface, lit and turnable, and
    /// an axis-aligned section with a slider, computed in the browser from the field itself.
    ///
    /// The page holds the surface decoded at up to --max-res nodes per axis and the field's
    /// bricks (resampled above --max-res), inlined; it opens from disk with no network. The
    /// section's inside is filled, with its height and area shown.
    View(view::ViewArgs),
}

pub fn run(command: Command) -> Result<()> {
    pgvol::limits::set_memory_limit(command.out().max_memory);
    if let Some((output, out)) = command.output() {
        out.check(output)?;
        out.check_not_an_input(output, &command.inputs())?;
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
        Command::Points(a) => points::run(a),
        Command::Contours(a) => points::contours(a),
        Command::Offset(a) => ops::offset(a),
        Command::Shell(a) => ops::shell(a),
        Command::Lattice(a) => lattice::lattice(a),
        Command::Csg(a) => edit::csg(a),
        Command::Repair(a) => edit::repair(a),
        Command::Blend(a) => blend::blend(a),
        Command::Perturb(a) => perturb::run(a),
        Command::View(a) => view::run(a),
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
            Command::Points(a) => a.out,
            Command::Contours(a) => a.out,
            Command::Offset(a) => a.out,
            Command::Shell(a) => a.out,
            Command::Lattice(a) => a.out,
            Command::Csg(a) => a.out,
            Command::Repair(a) => a.out,
            Command::Blend(a) => a.out,
            Command::Perturb(a) => a.out,
            Command::View(a) => a.out,
        }
    }

    /// The files the command reads (operands that name no file are left out).
    fn inputs(&self) -> Vec<&std::path::Path> {
        match self {
            Command::Remesh(a) => vec![&a.input],
            Command::Compare(a) => vec![&a.a, &a.b],
            Command::Sdf(a) => vec![&a.mesh],
            Command::Encode(a) => a.mesh.iter().map(|p| p.as_path()).collect(),
            Command::Decode(a) => vec![&a.input],
            Command::Info(a) => vec![&a.input],
            Command::Export(a) => vec![&a.input],
            Command::Eval(a) => vec![&a.input, &a.points],
            Command::Slice(a) => vec![&a.input],
            Command::Points(a) => vec![&a.input],
            Command::Contours(a) => vec![&a.input],
            Command::Offset(a) => vec![&a.input],
            Command::Shell(a) => vec![&a.input],
            Command::Lattice(a) => vec![&a.input],
            Command::Csg(a) => files(&a.operands),
            Command::Repair(a) => vec![&a.input],
            Command::Blend(a) => {
                let mut all = files(&a.primaries);
                all.extend(a.points.as_deref());
                all
            }
            Command::Perturb(a) => vec![&a.input],
            Command::View(a) => vec![&a.input],
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
            Command::Points(a) => Some((&a.output, a.out)),
            Command::Contours(a) => Some((&a.output, a.out)),
            Command::Offset(a) => Some((&a.output, a.out)),
            Command::Shell(a) => Some((&a.output, a.out)),
            Command::Lattice(a) => Some((&a.output, a.out)),
            Command::Csg(a) => Some((&a.output, a.out)),
            Command::Repair(a) => Some((&a.output, a.out)),
            Command::Blend(a) => Some((&a.output, a.out)),
            Command::Perturb(a) => Some((&a.output, a.out)),
            Command::View(a) => Some((&a.output, a.out)),
            Command::Compare(_) | Command::Info(_) => None,
        }
    }
}

/// The operands that name a file.
fn files(operands: &[pgvol::Operand]) -> Vec<&std::path::Path> {
    operands
        .iter()
        .filter_map(|o| match o {
            pgvol::Operand::File(p) => Some(p.as_path()),
            _ => None,
        })
        .collect()
}
