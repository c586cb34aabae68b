//! What the page inlines: the decoded surface and the field's bricks, quantised and base64'd,
//! with the frame that places them. Serialised as one JSON object read by the page's script.

use glam::Vec3;
use pgvol_contour::Method;
use pgvol_core::sparse::{brick_offset, BRICK_EDGE, BRICK_NODES};
use pgvol_core::{Grid, Mesh, SparseGrid};
use pgvol_field::{Basis, CoefficientVolume};
use rayon::prelude::*;
use serde::Serialize;

use super::colour::ViewColours;
use super::options::ViewOptions;
use crate::decode::DecodeOptions;
use crate::error::Result;
use crate::field_value::Field;
use crate::progress::{self, Progress};
use pgvol_core::base64;

/// Brick states in the page's brick table.
const OUTSIDE: u8 = 0;
const INSIDE: u8 = 1;
const STORED: u8 = 2;

/// Bytes one stored brick takes in the page once base64'd (512 int16 values).
const BRICK_PAGE_BYTES: u64 = (BRICK_NODES as u64 * 2).div_ceil(3) * 4;

/// Everything the page's script reads.
#[derive(Serialize)]
pub(crate) struct Payload {
    /// Layout version of this object, checked by the script.
    format: u32,
    title: String,
    iso: f32,
    /// The world position of the local frame every coordinate below is given in.
    offset: [f64; 3],
    colours: ViewColours,
    section: Option<Section>,
    surface: Surface,
    field: FieldBricks,
}

#[derive(Serialize)]
struct Section {
    axis: &'static str,
    /// In the model's own (world) coordinates.
    height: f64,
}

/// The decoded surface: positions as u16 steps across its box, indices as u16 or u32, both
/// little-endian.
#[derive(Serialize)]
struct Surface {
    lo: [f32; 3],
    hi: [f32; 3],
    vertices: usize,
    triangles: usize,
    /// Nodes per axis of the grid it was contoured on.
    grid: [usize; 3],
    positions: String,
    index_bytes: u8,
    indices: String,
}

/// The field for sections: node values of a sparse brick grid (8³ nodes a brick, x fastest
/// inside a brick and across bricks), each stored value `scale × int16`, absent bricks at
/// the `inside` or `outside` value.
#[derive(Serialize)]
struct FieldBricks {
    /// How node values make the field: "bspline3" or "trilinear".
    basis: &'static str,
    /// "coefficients" when the values are the file's own, "samples" when the field was
    /// resampled onto a coarser grid (or from a basis the page does not evaluate).
    source: &'static str,
    origin: [f32; 3],
    spacing: f32,
    dims: [usize; 3],
    bricks: [usize; 3],
    /// One byte per brick: 0 outside, 1 inside, 2 stored (the next stored block of values).
    states: String,
    values: String,
    scale: f32,
    inside: f32,
    outside: f32,
}

impl Payload {
    pub(crate) fn of(
        field: &Field,
        options: &ViewOptions,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let volume = field.volume();
        let capped = volume.grid.dims.iter().any(|&n| n > options.max_res);
        let res = capped.then_some(options.max_res);
        let bricks = match (volume.basis, capped) {
            (Basis::Bspline3 | Basis::Trilinear, false) => stored_bricks(volume)?,
            _ => {
                // Never finer than the file's own grid (a basis the page does not evaluate is
                // sampled at its own nodes when within the cap).
                let longest = volume.grid.dims.into_iter().max().unwrap_or(2);
                let res = options.max_res.min(longest);
                let grid = crate::decode::target_grid(volume, Some(res))?;
                progress::stage(progress, "view: resample the field", |_| {
                    resampled_bricks(volume, &grid)
                })??
            }
        };
        // A file with sharp-feature vertices is drawn with them: dual contouring places them on
        // the file's own grid at level 0 (elsewhere it would only round the edges differently).
        let sharp = field.header().sharp.is_some() && !capped && options.iso == 0.0;
        let decode = DecodeOptions {
            iso: options.iso,
            res,
            method: if sharp {
                Method::DualContouring
            } else {
                DecodeOptions::default().method
            },
            ..DecodeOptions::default()
        };
        let mesh = field.to_mesh(&decode, progress)?;
        let surface = surface_of(&mesh, crate::decode::target_grid(volume, res)?.dims);
        let offset = volume.grid.offset.to_array();
        let section = options.section.map(|(axis, height)| Section {
            axis: ["x", "y", "z"][axis.indices()[0]],
            height,
        });
        Ok(Payload {
            format: 1,
            title: options.title.clone().unwrap_or_default(),
            iso: options.iso,
            offset,
            colours: options.colours.clone(),
            section,
            surface,
            field: bricks,
        })
    }

    /// The JSON text, safe inside a `<script>` element: `<` only occurs in strings, where
    /// `\u003c` reads the same.
    pub(crate) fn to_json(&self) -> String {
        serde_json::to_string(self)
            .expect("the payload has only strings, numbers and arrays")
            .replace('<', "\\u003c")
    }
}

/// The surface's positions quantised to u16 steps across its box, and its indices.
fn surface_of(mesh: &Mesh, grid: [usize; 3]) -> Surface {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for &p in &mesh.positions {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let step = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE)) / 65535.0;
    let mut positions = Vec::with_capacity(mesh.positions.len() * 6);
    for &p in &mesh.positions {
        for q in ((p - lo) / step).round().to_array() {
            positions.extend_from_slice(&(q.clamp(0.0, 65535.0) as u16).to_le_bytes());
        }
    }
    let wide = mesh.positions.len() > usize::from(u16::MAX) + 1;
    let mut indices = Vec::with_capacity(mesh.triangles.len() * if wide { 12 } else { 6 });
    for &i in mesh.triangles.iter().flatten() {
        if wide {
            indices.extend_from_slice(&i.to_le_bytes());
        } else {
            indices.extend_from_slice(&(i as u16).to_le_bytes());
        }
    }
    Surface {
        lo: lo.to_array(),
        hi: hi.to_array(),
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
        grid,
        positions: base64::encode(&positions),
        index_bytes: if wide { 4 } else { 2 },
        indices: base64::encode(&indices),
    }
}

/// The volume's own coefficients, for a basis the page evaluates.
fn stored_bricks(volume: &CoefficientVolume) -> Result<FieldBricks> {
    let coeffs = &volume.coeffs;
    check_page_size(coeffs.stored_count())?;
    let mut states = Vec::new();
    let mut blocks: Vec<&[f32; BRICK_NODES]> = Vec::new();
    for b in coeffs.all_bricks() {
        match coeffs.brick(b) {
            Some(values) => {
                states.push(STORED);
                blocks.push(values);
            }
            None => states.push(if coeffs.is_inside(b) { INSIDE } else { OUTSIDE }),
        }
    }
    let basis = match volume.basis {
        Basis::Trilinear => "trilinear",
        _ => "bspline3",
    };
    Ok(bricks_of(
        &volume.grid,
        coeffs,
        basis,
        "coefficients",
        &states,
        &blocks,
    ))
}

/// The field's values at the nodes of `grid` (the same box, coarser), to be interpolated
/// trilinearly. A brick of `grid` is stored unless every brick of the volume its nodes' basis
/// supports reach is absent and on one side; such a brick holds that side's value everywhere.
fn resampled_bricks(volume: &CoefficientVolume, grid: &Grid) -> Result<FieldBricks> {
    let coeffs = &volume.coeffs;
    let sampled = SparseGrid::new(grid.dims, coeffs.background());
    let reach = volume.basis.support().ceil() as usize + 1;
    let fine_dims = volume.grid.dims;
    let side_of = |b: [usize; 3]| -> Option<u8> {
        let (lo, n) = sampled.brick_extent(b);
        let range = |a: usize| {
            let first = volume.grid.to_grid(grid.point(lo[0], lo[1], lo[2]))[a];
            let last = volume.grid.to_grid(grid.point(
                lo[0] + n[0] - 1,
                lo[1] + n[1] - 1,
                lo[2] + n[2] - 1,
            ))[a];
            let start = (first.floor().max(0.0) as usize).saturating_sub(reach);
            let end = ((last.ceil().max(0.0) as usize) + reach).min(fine_dims[a] - 1);
            (start / BRICK_EDGE)..=(end / BRICK_EDGE)
        };
        let (rx, ry, rz) = (range(0), range(1), range(2));
        let mut side = None;
        for k in rz {
            for j in ry.clone() {
                for i in rx.clone() {
                    let fine = [i, j, k];
                    if coeffs.is_stored(fine) {
                        return None;
                    }
                    let here = if coeffs.is_inside(fine) {
                        INSIDE
                    } else {
                        OUTSIDE
                    };
                    if side.is_some_and(|s| s != here) {
                        return None;
                    }
                    side = Some(here);
                }
            }
        }
        side
    };
    let all: Vec<[usize; 3]> = sampled.all_bricks().collect();
    let states: Vec<u8> = all
        .par_iter()
        .map(|&b| side_of(b).unwrap_or(STORED))
        .collect();
    let stored = states.iter().filter(|&&s| s == STORED).count();
    check_page_size(stored)?;
    let blocks: Vec<[f32; BRICK_NODES]> = all
        .par_iter()
        .zip(&states)
        .filter(|(_, &s)| s == STORED)
        .map(|(&b, _)| {
            let (lo, n) = sampled.brick_extent(b);
            let mut values = [0.0f32; BRICK_NODES];
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let p = grid.point(lo[0] + i, lo[1] + j, lo[2] + k);
                        values[brick_offset([i, j, k])] = volume.value(p);
                    }
                }
            }
            values
        })
        .collect();
    let blocks: Vec<&[f32; BRICK_NODES]> = blocks.iter().collect();
    Ok(bricks_of(
        grid,
        &sampled,
        "trilinear",
        "samples",
        &states,
        &blocks,
    ))
}

/// Refuses a page whose field alone would pass a gigabyte.
fn check_page_size(stored: usize) -> Result<()> {
    let bytes = stored as u64 * BRICK_PAGE_BYTES;
    crate::memory::check_memory(
        "the viewer page's field",
        bytes * 3,
        "lower the viewer's resolution cap",
    )?;
    if bytes > 1 << 30 {
        return Err(crate::error::Error::new(
            crate::error::ErrorKind::ResourceLimit,
            format!(
                "the viewer page would hold {} of field bricks, more than a browser opens; \
                 lower the viewer's resolution cap",
                crate::memory::human(bytes)
            ),
        ));
    }
    Ok(())
}

/// The brick table and the stored values quantised to int16 with one scale.
fn bricks_of(
    grid: &Grid,
    values: &SparseGrid,
    basis: &'static str,
    source: &'static str,
    states: &[u8],
    blocks: &[&[f32; BRICK_NODES]],
) -> FieldBricks {
    let largest = blocks
        .iter()
        .flat_map(|b| b.iter())
        .fold(0.0f32, |m, v| m.max(v.abs()));
    let scale = if largest > 0.0 {
        largest / 32767.0
    } else {
        1.0
    };
    let mut quantised = Vec::with_capacity(blocks.len() * BRICK_NODES * 2);
    for &v in blocks.iter().flat_map(|b| b.iter()) {
        let q = (v / scale).round().clamp(-32767.0, 32767.0) as i16;
        quantised.extend_from_slice(&q.to_le_bytes());
    }
    let background = values.background();
    FieldBricks {
        basis,
        source,
        origin: grid.origin.to_array(),
        spacing: grid.spacing,
        dims: grid.dims,
        bricks: values.brick_counts(),
        states: base64::encode(states),
        values: base64::encode(&quantised),
        scale,
        inside: background.inside,
        outside: background.outside,
    }
}
