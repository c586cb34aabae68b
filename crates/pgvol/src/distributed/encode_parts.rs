//! Encoding in parts: the grid cut into boxes of fitting groups (slabs along z, and rows of
//! groups along y when there are more parts than slabs), each sampled and fitted alone, and
//! the file assembled from their coefficient bricks.

use std::ops::Range;

use pgvol_core::{Grid, Mesh, SparseGrid, BRICK_EDGE};
use pgvol_field::{Basis, CoefficientVolume, FitMethod, FitReport, SPARSE_GROUP};
use pgvol_sdf::MeshSdf;

use super::slab::Slab;
use super::split::split;
use super::tiling::Tiling;
use crate::encode::{encoded_file, EncodeOptions, Encoded};
use crate::error::{Error, ErrorKind, Result};
use crate::timings::Timings;

/// One part of an encode: the fitting groups (each [`SPARSE_GROUP`]³ grid bricks) whose y and
/// z group indices lie in `gy` and `gz`, with every group along x.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GroupBox {
    /// Group indices along y.
    pub gy: Range<usize>,
    /// Group indices along z.
    pub gz: Range<usize>,
}

/// How an encode is cut into parts.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodePlan {
    /// The grid of the whole encode.
    pub grid: Grid,
    /// The parts in assembly order: z slabs, each cut along y when there are more parts than
    /// z layers of groups.
    pub parts: Vec<GroupBox>,
}

/// Fitting groups along each axis of `grid`.
fn group_counts(grid: &Grid) -> [usize; 3] {
    grid.dims
        .map(|n| n.div_ceil(BRICK_EDGE).div_ceil(SPARSE_GROUP))
}

/// Refuses what cannot be encoded in parts: fits other than `Interp` and pseudo-Gaussians
/// solve one global system.
pub(crate) fn check_parts_options(options: &EncodeOptions) -> Result<()> {
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

/// Cuts the encode of `mesh` by `options` into about `parts` boxes of fitting groups: z slabs
/// of equal numbers of group layers, each cut into rows along y when `parts` exceeds the
/// layers (at most one part per group column, so fewer on small grids).
pub fn plan_encode(mesh: &Mesh, options: &EncodeOptions, parts: usize) -> Result<EncodePlan> {
    check_parts_options(options)?;
    crate::frame::require_near(mesh.offset, "an encode in parts")?;
    let grid = options.grid.grid_for(mesh)?;
    let [_, ny, nz] = group_counts(&grid);
    let slabs = split(nz, parts)?;
    let per_slab = parts.div_ceil(slabs.len());
    let mut out = Vec::new();
    for gz in slabs {
        for gy in split(ny, per_slab)? {
            out.push(GroupBox { gy, gz: gz.clone() });
        }
    }
    Ok(EncodePlan { grid, parts: out })
}

/// Bytes per triangle of an [`EncodeJob`] at its peak, while its distance queries are built
/// (BVH, winding tree, pseudonormals, the mesh's copy): measured 388 on the bunny subdivided to
/// 1.11M triangles and 501 on the rocker arm subdivided to 1.29M (394 held once built), so the
/// single-process figure of 400 is raised to cover the closed mesh's pseudonormals.
pub const JOB_BYTES_PER_TRIANGLE: u64 = 500;

/// Estimated peak bytes of one part's encode, [`EncodeJob`] included: the mesh's distance
/// queries, the sampler's flags over the part's rows of bricks and the fit's reach around them
/// (widened to whole region tiles), and the band bricks of the surface there, each at the
/// single-process encode's per-brick figure (samples, coefficients and their neighbours).
/// Nothing in it grows with the whole grid.
pub fn part_encode_bytes(mesh: &Mesh, options: &EncodeOptions, part: &GroupBox) -> Result<u64> {
    let grid = options.grid.grid_for(mesh)?;
    let [ys, zs] = part_spans(&grid, options, part);
    let area: f64 = mesh
        .triangles
        .iter()
        .filter_map(|t| {
            let (lo, hi, area) = triangle_extent(mesh, t);
            (hi.y >= ys.0 && lo.y <= ys.1 && hi.z >= zs.0 && lo.z <= zs.1).then_some(area)
        })
        .sum();
    Ok(bytes_of_part(mesh, options, &grid, part, area))
}

/// [`part_encode_bytes`] of every part of `plan`, in one pass over the triangles (each one
/// visits the slabs and then the rows its bounds reach), so planning thousands of parts of a
/// large mesh stays quick. The same figures, bit for bit: each part's area is summed over the
/// same triangles in the same order.
pub fn plan_encode_bytes(
    mesh: &Mesh,
    options: &EncodeOptions,
    plan: &EncodePlan,
) -> Result<Vec<u64>> {
    let grid = options.grid.grid_for(mesh)?;
    let spans: Vec<[(f32, f32); 2]> = plan
        .parts
        .iter()
        .map(|p| part_spans(&grid, options, p))
        .collect();
    // Runs of parts that share a z slab, in plan order.
    let mut slabs: Vec<Range<usize>> = Vec::new();
    for (i, p) in plan.parts.iter().enumerate() {
        match slabs.last_mut() {
            Some(r) if plan.parts[r.start].gz == p.gz => r.end = i + 1,
            _ => slabs.push(i..i + 1),
        }
    }
    let mut areas = vec![0.0f64; plan.parts.len()];
    for t in &mesh.triangles {
        let (lo, hi, area) = triangle_extent(mesh, t);
        for slab in &slabs {
            let zs = spans[slab.start][1];
            if !(hi.z >= zs.0 && lo.z <= zs.1) {
                continue;
            }
            for i in slab.clone() {
                let ys = spans[i][0];
                if hi.y >= ys.0 && lo.y <= ys.1 {
                    areas[i] += area;
                }
            }
        }
    }
    Ok(plan
        .parts
        .iter()
        .zip(areas)
        .map(|(p, area)| bytes_of_part(mesh, options, &grid, p, area))
        .collect())
}

/// A triangle's bounds and area.
fn triangle_extent(mesh: &Mesh, t: &[u32; 3]) -> (glam::Vec3, glam::Vec3, f64) {
    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
    let area = 0.5 * (b - a).cross(c - a).length() as f64;
    (a.min(b).min(c), a.max(b).max(c), area)
}

/// The spans along y and z, in the mesh's units, of the triangles whose band reaches a part's
/// sampled bricks.
fn part_spans(grid: &Grid, options: &EncodeOptions, part: &GroupBox) -> [(f32, f32); 2] {
    let reach = pgvol_field::sparse_reach(options.basis);
    let brick = (BRICK_EDGE as f32) * grid.spacing;
    let margin = options.band * grid.spacing;
    let span = |r: &Range<usize>, a: usize| {
        let lo = grid.origin[a] + brick * (r.start * SPARSE_GROUP).saturating_sub(reach) as f32;
        let hi = grid.origin[a] + brick * (r.end * SPARSE_GROUP + reach) as f32;
        (lo - margin, hi + margin)
    };
    [span(&part.gy, 1), span(&part.gz, 2)]
}

/// The estimate of a part whose band holds triangles of `area`.
fn bytes_of_part(
    mesh: &Mesh,
    options: &EncodeOptions,
    grid: &Grid,
    part: &GroupBox,
    area: f64,
) -> u64 {
    use crate::memory::{band_bricks, BYTES_PER_BAND_BRICK, BYTES_PER_PLAN_NODE};
    let [ys, zs] = sampled_rows(grid, options, part);
    let plan_nodes = pgvol_sdf::sampling::plan_bricks(grid, ys, zs) as f64
        * (pgvol_sdf::sampling::BRICK as f64).powi(3);
    let plan = (plan_nodes * BYTES_PER_PLAN_NODE) as u64;
    band_bricks(area, grid.spacing, options.band)
        .saturating_mul(BYTES_PER_BAND_BRICK)
        .saturating_add(plan)
        .saturating_add((mesh.triangles.len() as u64).saturating_mul(JOB_BYTES_PER_TRIANGLE))
}

/// The rows of grid bricks along y and z a part samples: its groups' bricks and the fit's
/// reach around them.
fn sampled_rows(grid: &Grid, options: &EncodeOptions, part: &GroupBox) -> [Range<usize>; 2] {
    let counts = grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
    let reach = pgvol_field::sparse_reach(options.basis);
    let around = |r: &Range<usize>, a: usize| {
        (r.start * SPARSE_GROUP).saturating_sub(reach)
            ..(r.end * SPARSE_GROUP + reach).min(counts[a])
    };
    [around(&part.gy, 1), around(&part.gz, 2)]
}

/// One part's result: its coefficient bricks and what the assembly needs to decide.
#[derive(Clone, Debug)]
pub struct EncodedPart {
    /// The coefficient bricks and sides of the part's box, as [`Slab`] bytes.
    pub bricks: Vec<u8>,
    /// Nodes of the part's stored sample bricks within the band.
    pub exact_nodes: usize,
}

/// What every part of one encode shares: the mesh's distance query and the grid. Build it once
/// per process and encode any number of parts with it.
pub struct EncodeJob {
    sdf: MeshSdf,
    grid: Grid,
    options: EncodeOptions,
    /// The mesh, kept for the memory estimates of its parts.
    mesh: Mesh,
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
            mesh: mesh.clone(),
        })
    }

    /// The grid of the encode.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// [`part_encode_bytes`] of `part`.
    pub fn part_bytes(&self, part: &GroupBox) -> u64 {
        part_encode_bytes(&self.mesh, &self.options, part).unwrap_or(u64::MAX)
    }

    /// Samples and fits the groups of `part`: the distances of their grid bricks and of the
    /// bricks around them the fit reads, then their coefficient bricks, bit for bit those of
    /// [`encode`](crate::encode()) on the whole grid. Calling it again gives the same bytes.
    pub fn encode_part(&self, part: &GroupBox) -> Result<EncodedPart> {
        let [_, ny, nz] = group_counts(&self.grid);
        let inside = |r: &Range<usize>, n: usize| r.start < r.end && r.end <= n;
        if !(inside(&part.gy, ny) && inside(&part.gz, nz)) {
            return Err(Error::parameter(format!(
                "groups y {:?}, z {:?} are not within the grid's 0..{ny}, 0..{nz}",
                part.gy, part.gz
            )));
        }
        crate::memory::check_memory(
            &format!("encoding groups y {:?}, z {:?}", part.gy, part.gz),
            self.part_bytes(part),
            "use more parts",
        )?;
        let counts = self.grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
        let owned = |r: &Range<usize>, a: usize| {
            r.start * SPARSE_GROUP..(r.end * SPARSE_GROUP).min(counts[a])
        };
        let (oy, oz) = (owned(&part.gy, 1), owned(&part.gz, 2));
        let [ys, zs] = sampled_rows(&self.grid, &self.options, part);
        let sampled = self
            .sdf
            .sample_sparse_rows(&self.grid, self.options.band, ys, zs, &|_| {});
        let (bricks, _) = pgvol_field::interp_sparse_groups(
            self.grid,
            self.options.basis,
            &sampled.values,
            part.gy.clone(),
            part.gz.clone(),
            pgvol_core::progress::QUIET,
        )
        .map_err(|e| Error::new(ErrorKind::Internal, format!("cannot fit a part: {e}")))?;
        let owned_box = [0..counts[0], oy, oz];
        let exact_nodes = exact_in(&sampled.values, &owned_box, self.options.band, &self.grid);
        let mut slab = Slab::cut(self.grid, self.options.basis, &sampled.values, owned_box);
        slab.stored = bricks;
        Ok(EncodedPart {
            bricks: slab.to_bytes(),
            exact_nodes,
        })
    }
}

/// Nodes of the stored sample bricks of the box `owned` within the band.
fn exact_in(values: &SparseGrid, owned: &[Range<usize>; 3], band: f32, grid: &Grid) -> usize {
    let clamp = band * grid.spacing;
    values
        .stored()
        .filter(|(b, _)| (0..3).all(|a| owned[a].contains(&b[a])))
        .map(|(_, v)| v.iter().filter(|x| x.abs() < clamp).count())
        .sum()
}

/// A part's slab checked against the encode's grid and basis.
pub(crate) fn check_slab(slab: &Slab, grid: &Grid, options: &EncodeOptions) -> Result<()> {
    if slab.grid != *grid || slab.basis != options.basis {
        return Err(Error::parameter(
            "a part was encoded on another grid or basis than the options give",
        ));
    }
    Ok(())
}

/// The fit report of an encode assembled from parts: the one `interp_sparse` gives from no
/// samples, which depends only on the basis.
pub(crate) fn assembled_fit(
    grid: &Grid,
    options: &EncodeOptions,
    background: pgvol_core::Background,
) -> Result<FitReport> {
    let empty = SparseGrid::new(grid.dims, background);
    let (_, fit) = pgvol_field::interp_sparse_groups(
        *grid,
        options.basis,
        &empty,
        0..0,
        0..0,
        pgvol_core::progress::QUIET,
    )
    .map_err(|e| Error::new(ErrorKind::Internal, format!("{e}")))?;
    Ok(fit)
}

/// The encoded file of `mesh` by `options` from its parts' coefficient bricks, given in the
/// order of the plan's parts (which must tile the grid): the same file, bit for bit, as
/// [`encode`](crate::encode()) gives. The fit report is the single-process one less its
/// timings and its sign check, which needs neighbouring parts' coefficients.
pub fn assemble_encode(mesh: &Mesh, options: &EncodeOptions, parts: &[&[u8]]) -> Result<Encoded> {
    check_parts_options(options)?;
    let grid = options.grid.grid_for(mesh)?;
    let counts = grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
    let mut coeffs: Option<SparseGrid> = None;
    let mut tiling = Tiling::new(counts);
    for bytes in parts {
        let slab = Slab::from_bytes(bytes)?;
        check_slab(&slab, &grid, options)?;
        tiling.accept(&slab.bricks)?;
        let values = coeffs.get_or_insert_with(|| SparseGrid::new(grid.dims, slab.background));
        slab.apply(values);
    }
    tiling.finish()?;
    let mut coeffs = coeffs.ok_or_else(|| Error::parameter("no parts to assemble"))?;
    coeffs.compact_tiles();
    let fit = assembled_fit(&grid, options, coeffs.background())?;
    let volume = CoefficientVolume::from_sparse(grid, options.basis, coeffs).map_err(|e| {
        Error::new(
            ErrorKind::Internal,
            format!("cannot assemble the parts: {e}"),
        )
    })?;
    let mut file = encoded_file(mesh, volume, &fit, Some(options.band));
    // The parts hold coefficients only: the sharp-feature vertices are chosen here, against
    // the assembled file, as a single process does.
    let sharp = crate::sharp::store::attach(
        &mut file,
        mesh,
        options.sign,
        &options.sharp,
        &crate::progress::Silent,
    )?;
    Ok(Encoded {
        file,
        fit,
        sharp,
        timings: Timings::default(),
    })
}
