//! Encoding in parts: the grid cut into slabs of layers of fitting groups along z, each
//! sampled and fitted alone, and the file assembled from their coefficient bricks.

use std::ops::Range;

use pgvol_core::{Grid, Mesh, SparseGrid, BRICK_EDGE};
use pgvol_field::{Basis, CoefficientVolume, FitMethod, SPARSE_GROUP};
use pgvol_sdf::{MeshSdf, SignMode};

use super::slab::Slab;
use super::split;
use crate::encode::{encoded_file, EncodeOptions, Encoded};
use crate::error::{Error, ErrorKind, Result};
use crate::Timings;

/// How an encode is cut into parts.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodePlan {
    /// The grid of the whole encode.
    pub grid: Grid,
    /// Per part, its z layers of fitting groups (each [`SPARSE_GROUP`] grid bricks thick).
    pub parts: Vec<Range<usize>>,
}

/// Layers of fitting groups along z in `grid`.
fn group_layers(grid: &Grid) -> usize {
    grid.dims[2].div_ceil(BRICK_EDGE).div_ceil(SPARSE_GROUP)
}

/// Refuses what cannot be encoded in parts: fits other than `Interp` and pseudo-Gaussians
/// solve one global system.
fn check_parts_options(options: &EncodeOptions) -> Result<()> {
    options.validate()?;
    if options.fit != FitMethod::Interp {
        return Err(Error::parameter(
            "only the interp fit can be computed in parts (iso and wls solve one system for \
             the whole grid)",
        ));
    }
    if matches!(options.basis, Basis::Pg { .. }) {
        return Err(Error::parameter(
            "pseudo-Gaussian coefficients come from one global solve and cannot be computed in \
             parts; use bspline3, bspline2 or trilinear",
        ));
    }
    Ok(())
}

/// Cuts the encode of `mesh` by `options` into at most `parts` slabs of equal numbers of
/// layers of fitting groups (fewer when the grid has fewer layers).
pub fn plan_encode(mesh: &Mesh, options: &EncodeOptions, parts: usize) -> Result<EncodePlan> {
    check_parts_options(options)?;
    let grid = options.grid.grid_for(mesh)?;
    Ok(EncodePlan {
        grid,
        parts: split(group_layers(&grid), parts)?,
    })
}

/// One part's result: its coefficient bricks and what the assembly needs to decide.
#[derive(Clone, Debug)]
pub struct EncodedPart {
    /// The coefficient bricks and sides of the part's layers, as [`Slab`] bytes.
    pub bricks: Vec<u8>,
    /// Pairs of neighbouring nodes in the part whose signs contradict their distances; with
    /// an automatic sign that chose the pseudonormal, any contradiction in any part means the
    /// whole encode must be redone with the winding number.
    pub contradictions: usize,
    /// Whether the samples were signed by the pseudonormal chosen by `Auto`.
    pub may_fall_back: bool,
    /// Nodes whose distance was computed exactly.
    pub exact_nodes: usize,
}

/// What every part of one encode shares: the mesh's distance query and the grid. Build it once
/// per process and encode any number of parts with it.
pub struct EncodeJob {
    sdf: MeshSdf,
    grid: Grid,
    options: EncodeOptions,
}

impl EncodeJob {
    /// Prepares the distance query of `mesh` (oriented under the automatic sign).
    pub fn new(mesh: &Mesh, options: &EncodeOptions) -> Result<EncodeJob> {
        check_parts_options(options)?;
        let grid = options.grid.grid_for(mesh)?;
        Ok(EncodeJob {
            sdf: crate::distance::mesh_sdf(mesh, options.sign)?,
            grid,
            options: *options,
        })
    }

    /// The grid of the encode.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// Samples and fits the group layers `layers`: the distances of their grid bricks and of
    /// the bricks around them the fit reads, then their coefficient bricks, bit for bit those
    /// of [`encode`](crate::encode()) on the whole grid. `winding` signs by the winding number
    /// where `Auto` had chosen the pseudonormal (after a part found contradictions); once set
    /// in a process it stays set for this job. Calling it again gives the same bytes.
    pub fn encode_part(&self, layers: Range<usize>, winding: bool) -> Result<EncodedPart> {
        let total = group_layers(&self.grid);
        if layers.start >= layers.end || layers.end > total {
            return Err(Error::parameter(format!(
                "group layers {}..{} are not within the grid's 0..{total}",
                layers.start, layers.end
            )));
        }
        if winding {
            self.sdf.fall_back_to_winding();
        }
        let may_fall_back =
            self.options.sign == SignMode::Auto && self.sdf.sign_mode() == SignMode::Pseudonormal;
        let bz = self.grid.dims[2].div_ceil(BRICK_EDGE);
        let owned = layers.start * SPARSE_GROUP..(layers.end * SPARSE_GROUP).min(bz);
        let reach = pgvol_field::sparse_reach(self.options.basis);
        let sampled_layers = owned.start.saturating_sub(reach)..(owned.end + reach).min(bz);
        let sampled =
            self.sdf
                .sample_sparse_layers(&self.grid, self.options.band, sampled_layers, &|_| {});
        let contradictions =
            pgvol_sdf::sparse_sign_contradictions_in(&self.grid, &sampled.values, owned.clone());
        let (bricks, _) = pgvol_field::interp_sparse_layers(
            self.grid,
            self.options.basis,
            &sampled.values,
            layers,
        )
        .map_err(|e| Error::new(ErrorKind::Internal, format!("cannot fit a part: {e}")))?;
        let counts = sampled.values.brick_counts();
        let full = [0..counts[0], 0..counts[1], owned.clone()];
        let mut slab = Slab::cut(self.grid, self.options.basis, &sampled.values, full);
        slab.stored = bricks;
        let exact_nodes = exact_in(&sampled.values, &owned, self.options.band, &self.grid);
        Ok(EncodedPart {
            bricks: slab.to_bytes(),
            contradictions,
            may_fall_back,
            exact_nodes,
        })
    }
}

/// Nodes of the stored sample bricks of layers `owned` within the band (an approximation of
/// the sampler's count, which also counts nodes it had to compute beyond the band).
fn exact_in(values: &SparseGrid, owned: &Range<usize>, band: f32, grid: &Grid) -> usize {
    let clamp = band * grid.spacing;
    values
        .stored()
        .filter(|(b, _)| owned.contains(&b[2]))
        .map(|(_, v)| v.iter().filter(|x| x.abs() < clamp).count())
        .sum()
}

/// Whether the parts' results ask for the encode to be redone with the winding number, as the
/// single-process encode falls back when the whole sampled grid contradicts itself.
pub fn needs_winding(parts: &[EncodedPart]) -> bool {
    parts.iter().any(|p| p.may_fall_back)
        && parts.iter().map(|p| p.contradictions).sum::<usize>() > 0
}

/// The encoded file of `mesh` by `options` from its parts' coefficient bricks, given in the
/// order of the plan's parts (which must tile the grid's layers): the same file, bit for bit,
/// as [`encode`](crate::encode()) gives.
pub fn assemble_encode(mesh: &Mesh, options: &EncodeOptions, parts: &[&[u8]]) -> Result<Encoded> {
    check_parts_options(options)?;
    let grid = options.grid.grid_for(mesh)?;
    let bz = grid.dims[2].div_ceil(BRICK_EDGE);
    let mut coeffs: Option<SparseGrid> = None;
    let mut next = 0;
    for bytes in parts {
        let slab = Slab::from_bytes(bytes)?;
        if slab.grid != grid || slab.basis != options.basis {
            return Err(Error::parameter(
                "a part was encoded on another grid or basis than the options give",
            ));
        }
        if slab.bricks[2].start != next {
            return Err(Error::parameter(format!(
                "the parts do not tile the grid: a part starts at brick layer {} where {next} \
                 was expected",
                slab.bricks[2].start
            )));
        }
        next = slab.bricks[2].end;
        let values = coeffs.get_or_insert_with(|| SparseGrid::new(grid.dims, slab.background));
        slab.apply(values);
    }
    let Some(mut coeffs) = coeffs.filter(|_| next == bz) else {
        return Err(Error::parameter(format!(
            "the parts cover brick layers 0..{next} of the grid's 0..{bz}"
        )));
    };
    coeffs.compact_tiles();
    // The report interp_sparse gives, from no samples: it depends only on the basis.
    let empty = SparseGrid::new(grid.dims, coeffs.background());
    let (_, fit) = pgvol_field::interp_sparse_layers(grid, options.basis, &empty, 0..0)
        .map_err(|e| Error::new(ErrorKind::Internal, format!("{e}")))?;
    let volume = CoefficientVolume::from_sparse(grid, options.basis, coeffs).map_err(|e| {
        Error::new(
            ErrorKind::Internal,
            format!("cannot assemble the parts: {e}"),
        )
    })?;
    let file = encoded_file(mesh, volume, &fit, Some(options.band));
    Ok(Encoded {
        file,
        fit,
        timings: Timings::default(),
    })
}
