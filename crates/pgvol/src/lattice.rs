//! Lattices for additive manufacturing on a shape: a triply periodic lattice cut to the part, or
//! filling the cavity of the hollowed part with drain holes through both; and the report of the
//! solid they make (volume fraction and surface area).

use pgvol_core::Mesh;
use pgvol_ops::{Drain, FieldMeasure, Grade, Lattice, LatticeSolid, LatticeStyle, Ramp, Tpms};

use crate::error::{Error, Result};
use crate::field_value::{check_drains, check_thickness, Field};
use crate::memory::check_memory;
use crate::progress::{self, Progress};

/// Bytes per brick of 8³ nodes a lattice stores: the node values and the coefficients (2 KiB
/// each), and the local fit's working copy with its halo.
pub const BYTES_PER_LATTICE_BRICK: u64 = 8 * 1024;

/// The lattice of these parameters, checked: the far values of a grading default to the near
/// ones and need a ramp.
pub fn make_lattice(
    surface: Tpms,
    style: LatticeStyle,
    cell: f32,
    thickness: f32,
    ramp: Option<Ramp>,
    cell_far: Option<f32>,
    thickness_far: Option<f32>,
) -> Result<Lattice> {
    if ramp.is_none() && (cell_far.is_some() || thickness_far.is_some()) {
        return Err(Error::parameter(
            "a far cell size or thickness needs a ramp: a grading depth or a linear segment",
        ));
    }
    let lattice = Lattice {
        surface,
        style,
        cell,
        thickness,
        grade: ramp.map(|ramp| Grade {
            ramp,
            cell: cell_far.unwrap_or(cell),
            thickness: thickness_far.unwrap_or(thickness),
        }),
    };
    lattice.check()?;
    Ok(lattice)
}

/// How far into the part the lattice reads the part's field as a distance: the depth of a depth
/// ramp, and `wall` for an infill.
pub fn lattice_reach(lattice: &Lattice, wall: f32) -> f32 {
    let depth = match lattice.grade.map(|g| g.ramp) {
        Some(Ramp::Depth { depth }) => depth,
        _ => 0.0,
    };
    depth.max(wall)
}

/// Refuses a lattice whose finest wall is thinner than two grid spacings: the field cannot
/// hold it and the solid would break into specks.
fn check_resolution(shape: &Field, lattice: &Lattice) -> Result<()> {
    lattice.check()?;
    let spacing = shape.file.volume.grid.spacing;
    let thinnest = lattice
        .grade
        .map_or(lattice.thickness, |g| g.thickness.min(lattice.thickness));
    if lattice.style == LatticeStyle::Sheet && thinnest < 2.0 * spacing {
        return Err(Error::parameter(format!(
            "the sheet thickness {thinnest} is under two grid spacings ({}); use a thicker \
             sheet or a finer grid",
            2.0 * spacing
        ))
        .with_remedy(crate::error::Remedy::FinerGrid));
    }
    let finest = lattice
        .grade
        .map_or(lattice.cell, |g| g.cell.min(lattice.cell));
    if finest < 8.0 * spacing {
        return Err(Error::parameter(format!(
            "the cell size {finest} is under eight grid spacings ({}); use a larger cell or a \
             finer grid",
            8.0 * spacing
        ))
        .with_remedy(crate::error::Remedy::FinerGrid));
    }
    Ok(())
}

/// Refuses a lattice on `shape` that would not fit in memory.
fn check_lattice_memory(shape: &Field) -> Result<()> {
    let bricks = pgvol_ops::lattice_bricks(&shape.file.volume) as u64;
    let [nx, ny, nz] = shape.file.volume.grid.dims;
    check_memory(
        &format!("a lattice filling {bricks} bricks of a {nx} x {ny} x {nz} grid"),
        bricks.saturating_mul(BYTES_PER_LATTICE_BRICK),
        "lower the resolution",
    )
}

/// A lattice solid and what the field measures of it and of the part it was cut from.
#[derive(Clone, Debug)]
pub struct Latticed {
    /// The solid.
    pub field: Field,
    /// The solid's volume and area, from its node values.
    pub solid: FieldMeasure,
    /// The part's, likewise.
    pub part: FieldMeasure,
}

impl Latticed {
    fn of(part: &Field, solid: LatticeSolid, operation: &str, shift: f32) -> Latticed {
        Latticed {
            field: part.derived(solid.volume, operation, shift),
            solid: solid.solid,
            part: solid.part,
        }
    }

    /// The solid's volume fraction and area: on `mesh`, the contoured solid, when there is one
    /// (exact sums over its triangles), else from the field's node values (no contouring).
    pub fn report(&self, mesh: Option<&Mesh>, progress: &dyn Progress) -> SolidReport {
        solid_report(self, mesh, progress)
    }
}

impl Field {
    /// The part intersected with `lattice`.
    pub fn lattice(&self, lattice: &Lattice, progress: &dyn Progress) -> Result<Latticed> {
        crate::frame::require_near(self.file.volume.grid.offset, "a lattice")?;
        check_resolution(self, lattice)?;
        self.check_reach(lattice_reach(lattice, 0.0))?;
        check_lattice_memory(self)?;
        let solid = progress::stage(progress, "lattice", |_| {
            pgvol_ops::lattice_part(&self.file.volume, lattice)
        })??;
        let operation = format!(
            "lattice {} cell {} thickness {}",
            lattice.surface, lattice.cell, lattice.thickness
        );
        Ok(Latticed::of(self, solid, &operation, 0.0))
    }

    /// The part hollowed to walls of `wall` thickness, the cavity filled with `lattice` and
    /// the drains (world coordinates) cut through wall and lattice.
    pub fn infill(
        &self,
        wall: f32,
        lattice: &Lattice,
        drains: &[Drain],
        progress: &dyn Progress,
    ) -> Result<Latticed> {
        check_thickness(wall)?;
        crate::resolution::check_wall("the wall thickness", wall, &self.file.volume.grid)?;
        crate::frame::require_near(self.file.volume.grid.offset, "an infill")?;
        check_resolution(self, lattice)?;
        self.check_reach(lattice_reach(lattice, wall))?;
        check_drains(self, wall, drains, progress)?;
        check_lattice_memory(self)?;
        let solid = progress::stage(progress, "infill", |_| {
            pgvol_ops::infill(&self.file.volume, wall, lattice, drains)
        })??;
        let operation = format!(
            "hollow {wall} infill {} cell {} thickness {}",
            lattice.surface, lattice.cell, lattice.thickness
        );
        Ok(Latticed::of(self, solid, &operation, wall))
    }
}

/// What a lattice solid measures.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SolidReport {
    /// Volume of the solid, model units cubed.
    pub volume: f64,
    /// Its surface area, model units squared.
    pub area: f64,
    /// Volume of the part it was cut from, estimated from the part's field.
    pub part_volume: f64,
    /// `volume / part_volume`.
    pub fraction: f64,
    /// Where volume and area come from: `"mesh"` (the contoured solid, exact sums over its
    /// triangles) or `"field"` (node values, see [`pgvol_ops::measure_field`]).
    pub measured_on: &'static str,
    /// Closed voids inside the solid (mesh pieces enclosing negative volume), when measured on
    /// a mesh: pockets of powder or resin with no way out. A sheet splits a cavity into two
    /// labyrinths, so an infill needs a drain into each.
    pub enclosed_voids: Option<usize>,
}

/// See [`Latticed::report`].
fn solid_report(solid: &Latticed, mesh: Option<&Mesh>, progress: &dyn Progress) -> SolidReport {
    let (volume, area, enclosed_voids) = match mesh {
        Some(mesh) => {
            let pieces = piece_volumes(mesh);
            let voids = pieces.iter().filter(|&&v| v < 0.0).count();
            if voids > 0 {
                progress.warn(&format!(
                    "the solid encloses {voids} void{} with no way out; add a drain hole into \
                     each",
                    if voids == 1 { "" } else { "s" }
                ));
            }
            (pieces.iter().sum(), mesh_area(mesh), Some(voids))
        }
        None => (solid.solid.volume, solid.solid.area, None),
    };
    SolidReport {
        volume,
        area,
        part_volume: solid.part.volume,
        fraction: volume / solid.part.volume,
        measured_on: if mesh.is_some() { "mesh" } else { "field" },
        enclosed_voids,
    }
}

fn mesh_area(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// The signed volume enclosed by each connected piece of `mesh` (triangles sharing vertices).
fn piece_volumes(mesh: &Mesh) -> Vec<f64> {
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    let mut parent: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    for t in &mesh.triangles {
        for &other in &t[1..] {
            let (a, b) = (root(&mut parent, t[0]), root(&mut parent, other));
            parent[a as usize] = b;
        }
    }
    let mut volume = vec![None; mesh.positions.len()];
    for t in &mesh.triangles {
        let [p, q, r] = t.map(|i| mesh.positions[i as usize].as_dvec3());
        let slot = &mut volume[root(&mut parent, t[0]) as usize];
        *slot = Some(slot.unwrap_or(0.0) + p.dot(q.cross(r)) / 6.0);
    }
    volume.into_iter().flatten().collect()
}
