//! Operands of the editing operations: analytic primaries given by a short text, or fields read
//! from `.pgv` files or encoded from meshes onto the operation's grid.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{Quat, Vec3};
use pgvol_core::{Grid, Mesh};
use pgvol_field::analytic::{Cylinder, Plane, RotatedBox, Sphere};
use pgvol_field::{Basis, CoefficientVolume, FitMethod, SignedDistance};
use pgvol_sdf::SignMode;

use crate::encode::{fit_volume, is_pgv, EncodeOptions, ENCODE_BAND};
use crate::error::{Error, Result};
use crate::field_value::Field;
use crate::grid::GridSpec;
use crate::mesh_io;
use crate::pgv_io::read_pgv;
use crate::progress::Progress;
use crate::timings::Timings;

/// An analytic solid with its exact signed distance.
#[derive(Clone, Copy, Debug)]
pub enum Primary {
    /// A ball.
    Sphere(Sphere),
    /// An axis-aligned box.
    Box(RotatedBox),
    /// A half-space.
    Plane(Plane),
    /// An infinite cylinder.
    Cylinder(Cylinder),
}

impl Primary {
    /// Signed distance at `p`, negative inside.
    pub fn distance(&self, p: Vec3) -> f32 {
        match self {
            Primary::Sphere(s) => s.distance(p),
            Primary::Box(b) => b.distance(p),
            Primary::Plane(h) => h.distance(p),
            Primary::Cylinder(c) => c.distance(p),
        }
    }

    /// The solid's bounding box, when it is bounded.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        match self {
            Primary::Sphere(s) => Some((s.centre - s.radius, s.centre + s.radius)),
            Primary::Box(b) => Some((b.centre - b.half, b.centre + b.half)),
            Primary::Plane(_) | Primary::Cylinder(_) => None,
        }
    }
}

/// What an operand names before it is loaded.
#[derive(Clone, Debug)]
pub enum Operand {
    /// An analytic solid.
    Primary(Primary),
    /// A `.pgv` file or a mesh file.
    File(PathBuf),
    /// A field in memory.
    Field(Arc<Field>),
}

impl From<Field> for Operand {
    fn from(field: Field) -> Operand {
        Operand::Field(Arc::new(field))
    }
}

impl From<Primary> for Operand {
    fn from(primary: Primary) -> Operand {
        Operand::Primary(primary)
    }
}

/// An operand as a field to evaluate anywhere.
#[derive(Clone, Debug)]
pub enum OperandField {
    /// An analytic solid's exact distance.
    Primary(Primary),
    /// A coefficient volume.
    Volume(Box<CoefficientVolume>),
}

impl OperandField {
    /// The field's value at `p`.
    pub fn value(&self, p: Vec3) -> f32 {
        match self {
            OperandField::Primary(s) => s.distance(p),
            OperandField::Volume(v) => v.value(p),
        }
    }
}

/// Operands read, ready to be placed on one grid.
#[derive(Clone, Debug)]
pub enum LoadedOperand {
    /// An analytic solid.
    Primary(Primary),
    /// A `.pgv` file's field, or a field in memory.
    Field(Arc<Field>),
    /// A mesh, encoded later onto the operation's grid.
    Mesh(Box<Mesh>),
}

impl LoadedOperand {
    /// Reads a file operand (`.pgv` or mesh); primaries pass through.
    pub fn load(operand: &Operand) -> Result<LoadedOperand> {
        Ok(match operand {
            Operand::Primary(p) => LoadedOperand::Primary(*p),
            Operand::Field(field) => {
                crate::frame::require_near(field.file.volume.grid.offset, "combining shapes")?;
                LoadedOperand::Field(Arc::clone(field))
            }
            Operand::File(path) if is_pgv(path) => {
                let shape = Field::from_file(read_pgv(path)?);
                crate::frame::require_near(shape.file.volume.grid.offset, "combining shapes")
                    .map_err(|e| e.at(path))?;
                LoadedOperand::Field(Arc::new(shape))
            }
            Operand::File(path) => {
                let mesh = mesh_io::read_mesh(path)?.mesh;
                if mesh.bounds().is_none() {
                    return Err(Error::parameter("the mesh has no triangles").at(path));
                }
                crate::frame::require_near(mesh.offset, "combining shapes")
                    .map_err(|e| e.at(path))?;
                LoadedOperand::Mesh(Box::new(mesh))
            }
        })
    }

    /// The bounding box, when bounded.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        match self {
            LoadedOperand::Primary(p) => p.bounds(),
            LoadedOperand::Field(s) => Some(s.bounds),
            LoadedOperand::Mesh(m) => m.bounds(),
        }
    }

    /// An upper estimate of the operand's surface area inside `grid`'s box, for memory
    /// estimates: exact for spheres and boxes, a bound on the box's sections for planes, a
    /// cylinder's side along the box's diagonal, a mesh's area, and a field's from its stored
    /// bricks.
    pub fn surface_area(&self, grid: &Grid) -> f64 {
        let e = (grid.max_corner() - grid.origin).as_dvec3();
        match self {
            LoadedOperand::Primary(Primary::Sphere(s)) => {
                4.0 * std::f64::consts::PI * (s.radius as f64).powi(2)
            }
            LoadedOperand::Primary(Primary::Box(b)) => {
                let h = b.half.as_dvec3();
                8.0 * (h.x * h.y + h.y * h.z + h.z * h.x)
            }
            // A section S of the box with unit normal n projects onto the face normal to axis
            // i with area S·|nᵢ| ≤ that face's area Aᵢ, so S² = Σ (S·nᵢ)² ≤ Σ Aᵢ².
            LoadedOperand::Primary(Primary::Plane(_)) => {
                ((e.y * e.z).powi(2) + (e.z * e.x).powi(2) + (e.x * e.y).powi(2)).sqrt()
            }
            LoadedOperand::Primary(Primary::Cylinder(c)) => {
                2.0 * std::f64::consts::PI * c.radius as f64 * e.length()
            }
            LoadedOperand::Mesh(mesh) => crate::memory::mesh_area(mesh),
            LoadedOperand::Field(shape) => {
                // A surface crosses about 1.5 bricks per brick face of area.
                let side = 8.0 * shape.file.volume.grid.spacing as f64;
                shape.file.volume.coeffs.stored_count() as f64 * side * side / 1.5
            }
        }
    }

    /// Estimated peak bytes of [`Self::field`] on `grid` with `reach`, the field kept.
    pub fn field_bytes(&self, grid: &Grid, reach: f32) -> u64 {
        match self {
            LoadedOperand::Primary(_) => 0,
            LoadedOperand::Field(shape) => shape.file.volume.coeffs.memory_bytes() as u64,
            LoadedOperand::Mesh(mesh) => crate::memory::sparse_encode_bytes(
                crate::memory::mesh_area(mesh),
                mesh.triangles.len(),
                grid,
                ENCODE_BAND + reach / grid.spacing,
            ),
        }
    }

    /// The field on `grid`: meshes are encoded onto it with exact distances `reach` beyond the
    /// usual band; `.pgv` files keep their own grid and are refused when their band is too
    /// narrow for `reach`. `sign` applies to meshes.
    pub fn field(
        &self,
        grid: Grid,
        reach: f32,
        sign: SignMode,
        progress: &dyn Progress,
    ) -> Result<OperandField> {
        match self {
            LoadedOperand::Primary(p) => Ok(OperandField::Primary(*p)),
            LoadedOperand::Field(shape) => {
                shape.check_reach(reach)?;
                Ok(OperandField::Volume(Box::new(shape.file.volume.clone())))
            }
            LoadedOperand::Mesh(mesh) => {
                let options = EncodeOptions {
                    grid: GridSpec::Res(grid.dims[0]),
                    basis: Basis::Bspline3,
                    fit: FitMethod::Interp,
                    band: ENCODE_BAND + reach / grid.spacing,
                    sign,
                    sharp: crate::sharp::store::SharpOptions::default(),
                };
                crate::memory::check_sparse_encode("encoding the mesh", mesh, &grid, options.band)?;
                let fitted = fit_volume(mesh, grid, &options, &mut Timings::default(), progress)?;
                Ok(OperandField::Volume(Box::new(fitted.volume)))
            }
        }
    }
}

impl Operand {
    /// An analytic primary from `kind:numbers` (`sphere:cx,cy,cz,r`, `box:cx,cy,cz,hx,hy,hz`,
    /// `plane:nx,ny,nz,d`, `cylinder:px,py,pz,ax,ay,az,r`); anything else is a path.
    pub fn parse(text: &str) -> Result<Operand> {
        let Some((kind, rest)) = text.split_once(':') else {
            return Ok(Operand::File(PathBuf::from(text)));
        };
        let v3 = |v: &[f32]| Vec3::new(v[0], v[1], v[2]);
        let primary = match kind {
            "sphere" => {
                let v = numbers(kind, rest, 4, "cx,cy,cz,r")?;
                Primary::Sphere(Sphere {
                    centre: v3(&v),
                    radius: positive(kind, "radius", v[3])?,
                })
            }
            "box" => {
                let v = numbers(kind, rest, 6, "cx,cy,cz,hx,hy,hz")?;
                let half = v3(&v[3..]);
                if half.min_element() <= 0.0 {
                    return Err(Error::parameter(format!(
                        "box: the half-extents must be positive, got {half}"
                    )));
                }
                Primary::Box(RotatedBox {
                    centre: v3(&v),
                    half,
                    rotation: Quat::IDENTITY,
                })
            }
            "plane" => {
                let v = numbers(kind, rest, 4, "nx,ny,nz,d")?;
                let n = v3(&v);
                let length = n.length();
                let normal = unit(kind, n)?;
                Primary::Plane(Plane {
                    normal,
                    offset: v[3] / length,
                })
            }
            "cylinder" => {
                let v = numbers(kind, rest, 7, "px,py,pz,ax,ay,az,r")?;
                Primary::Cylinder(Cylinder {
                    point: v3(&v),
                    axis: unit(kind, v3(&v[3..]))?,
                    radius: positive(kind, "radius", v[6])?,
                })
            }
            // A word before the colon that names no file is a solid misspelt or unknown;
            // Windows drive letters (one letter) and other paths with a colon are files.
            _ if kind.len() > 1
                && kind.chars().all(|c| c.is_ascii_alphabetic())
                && !std::path::Path::new(text).exists() =>
            {
                return Err(Error::parameter(format!(
                    "'{kind}' is not an analytic solid: they are sphere:cx,cy,cz,r, \
                     box:cx,cy,cz,hx,hy,hz, plane:nx,ny,nz,d and cylinder:px,py,pz,ax,ay,az,r \
                     (and no file '{text}' exists)"
                )))
            }
            _ => return Ok(Operand::File(PathBuf::from(text))),
        };
        Ok(Operand::Primary(primary))
    }
}

fn numbers(kind: &str, text: &str, count: usize, form: &str) -> Result<Vec<f32>> {
    let values: Vec<f32> = text
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::parameter(format!("{kind}: '{text}' is not {count} numbers {form}")))?;
    if values.len() != count || values.iter().any(|x| !x.is_finite()) {
        return Err(Error::parameter(format!(
            "{kind}: expected {count} finite numbers {form}, got '{text}'"
        )));
    }
    Ok(values)
}

fn positive(kind: &str, what: &str, x: f32) -> Result<f32> {
    if x > 0.0 {
        Ok(x)
    } else {
        Err(Error::parameter(format!(
            "{kind}: the {what} must be positive, got {x}"
        )))
    }
}

fn unit(kind: &str, v: Vec3) -> Result<Vec3> {
    v.try_normalize()
        .ok_or_else(|| Error::parameter(format!("{kind}: the direction must be non-zero")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primaries_parse_and_bad_ones_are_refused() {
        let Operand::Primary(s) = Operand::parse("sphere:0,0,0,2").unwrap() else {
            panic!("not a primary")
        };
        assert_eq!(s.distance(Vec3::new(3.0, 0.0, 0.0)), 1.0);
        let Operand::Primary(h) = Operand::parse("plane:0,0,2,1").unwrap() else {
            panic!("not a primary")
        };
        assert!((h.distance(Vec3::new(0.0, 0.0, 1.0)) - 0.5).abs() < 1e-6);
        assert!(matches!(Operand::parse("part.stl"), Ok(Operand::File(_))));
        for bad in [
            "sphere:0,0,0",
            "sphere:0,0,0,-1",
            "box:0,0,0,1,0,1",
            "plane:0,0,0,1",
        ] {
            let e = Operand::parse(bad).unwrap_err().to_string();
            assert!(e.contains(bad.split(':').next().unwrap()), "{e}");
        }
    }
}
