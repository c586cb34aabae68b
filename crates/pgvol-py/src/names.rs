//! The names Python callers give options by, mapped to the library's enums.

use pyo3::prelude::*;

use crate::errors;

fn unknown(py: Python<'_>, what: &str, got: &str, expected: &str) -> PyErr {
    errors::parameter(py, format!("unknown {what} '{got}' (expected {expected})"))
}

/// "bspline3", "bspline2", "trilinear", "pg" (the default order and radius) or
/// "pg-n<N>-r<R>".
pub(crate) fn basis(py: Python<'_>, name: &str) -> PyResult<pgvol::Basis> {
    if name == "pg" {
        return Ok(pgvol::Basis::Pg {
            n: pgvol::limits::PG_ORDER,
            r: pgvol::limits::PG_RADIUS,
        });
    }
    pgvol::Basis::from_name(name).ok_or_else(|| {
        unknown(
            py,
            "basis",
            name,
            "bspline3, bspline2, trilinear, pg or pg-n<N>-r<R> with N in 1..4",
        )
    })
}

/// "zip" (zlib) or "none": how a `.vdb`'s value chunks are stored.
pub(crate) fn vdb_compression(py: Python<'_>, name: &str) -> PyResult<pgvol::io::VdbCompression> {
    match name {
        "zip" => Ok(pgvol::io::VdbCompression::Zip),
        "none" => Ok(pgvol::io::VdbCompression::None),
        _ => Err(unknown(py, "vdb compression", name, "zip or none")),
    }
}

/// "interp", "iso" (with an optional step in grid spacings) or "wls".
pub(crate) fn fit(py: Python<'_>, name: &str, z_step: Option<f32>) -> PyResult<pgvol::FitMethod> {
    let method = match name {
        "interp" => pgvol::FitMethod::Interp,
        "iso" => pgvol::FitMethod::Iso { z_step },
        "wls" => pgvol::FitMethod::Wls,
        _ => return Err(unknown(py, "fit", name, "interp, iso or wls")),
    };
    if z_step.is_some() && name != "iso" {
        return Err(errors::parameter(py, "z_step applies to fit='iso' only"));
    }
    Ok(method)
}

/// "auto", "winding", "pseudonormal" or "parity".
pub(crate) fn sign(py: Python<'_>, name: &str) -> PyResult<pgvol::SignMode> {
    Ok(match name {
        "auto" => pgvol::SignMode::Auto,
        "winding" => pgvol::SignMode::Winding,
        "pseudonormal" => pgvol::SignMode::Pseudonormal,
        "parity" => pgvol::SignMode::Parity,
        _ => {
            return Err(unknown(
                py,
                "sign",
                name,
                "auto, winding, pseudonormal or parity",
            ))
        }
    })
}

/// "off" or "auto": whether encoding stores sharp-feature vertices.
pub(crate) fn sharp(py: Python<'_>, name: &str) -> PyResult<bool> {
    match name {
        "off" => Ok(false),
        "auto" => Ok(true),
        _ => Err(unknown(py, "sharp", name, "off or auto")),
    }
}

/// "mc" (marching cubes), "sn" (surface nets) or "dc" (dual contouring).
pub(crate) fn method(py: Python<'_>, name: &str) -> PyResult<pgvol::Method> {
    Ok(match name {
        "mc" => pgvol::Method::MarchingCubes,
        "sn" => pgvol::Method::SurfaceNets,
        "dc" => pgvol::Method::DualContouring,
        _ => return Err(unknown(py, "method", name, "mc, sn or dc")),
    })
}

/// "x", "y" or "z".
pub(crate) fn axis(py: Python<'_>, name: &str) -> PyResult<pgvol::Axis> {
    Ok(match name {
        "x" => pgvol::Axis::X,
        "y" => pgvol::Axis::Y,
        "z" => pgvol::Axis::Z,
        _ => return Err(unknown(py, "axis", name, "x, y or z")),
    })
}

/// "spline", "tangent", "rbf-wendland" or "rbf-cubic".
pub(crate) fn points_method(
    py: Python<'_>,
    name: &str,
) -> PyResult<pgvol::reconstruct::PointsMethod> {
    Ok(match name {
        "spline" => pgvol::reconstruct::PointsMethod::Spline,
        "tangent" => pgvol::reconstruct::PointsMethod::Tangent,
        "rbf-wendland" => pgvol::reconstruct::PointsMethod::RbfWendland,
        "rbf-cubic" => pgvol::reconstruct::PointsMethod::RbfCubic,
        _ => {
            return Err(unknown(
                py,
                "method",
                name,
                "spline, tangent, rbf-wendland or rbf-cubic",
            ))
        }
    })
}

/// "inner", "outer" or "centred".
pub(crate) fn side(py: Python<'_>, name: &str) -> PyResult<pgvol::edit::ShellSide> {
    Ok(match name {
        "inner" => pgvol::edit::ShellSide::Inner,
        "outer" => pgvol::edit::ShellSide::Outer,
        "centred" | "centered" => pgvol::edit::ShellSide::Centred,
        _ => return Err(unknown(py, "side", name, "inner, outer or centred")),
    })
}

/// "f32", "f16", "q16" or "fixed".
pub(crate) fn precision(py: Python<'_>, name: &str) -> PyResult<pgvol::Precision> {
    pgvol::Precision::ALL
        .into_iter()
        .find(|p| p.name() == name)
        .ok_or_else(|| unknown(py, "precision", name, "f32, f16, q16 or fixed"))
}

/// "gyroid", "schwarz-p" (or "primitive"), "diamond" or "neovius".
pub(crate) fn tpms(py: Python<'_>, name: &str) -> PyResult<pgvol::lattices::Tpms> {
    name.parse()
        .map_err(|_| unknown(py, "surface", name, "gyroid, schwarz-p, diamond or neovius"))
}

/// "sheet" or "strut".
pub(crate) fn lattice_style(py: Python<'_>, name: &str) -> PyResult<pgvol::lattices::LatticeStyle> {
    match name {
        "sheet" => Ok(pgvol::lattices::LatticeStyle::Sheet),
        "strut" => Ok(pgvol::lattices::LatticeStyle::Strut),
        _ => Err(unknown(py, "lattice style", name, "sheet or strut")),
    }
}

/// "+x", "-x", "+y", "-y", "+z" or "-z": a face of a repair mask.
pub(crate) fn face(py: Python<'_>, name: &str) -> PyResult<pgvol::edit::Face> {
    let axis = match name.get(1..) {
        Some("x") => 0,
        Some("y") => 1,
        Some("z") => 2,
        _ => usize::MAX,
    };
    let upper = name.starts_with('+');
    if axis == usize::MAX || !(upper || name.starts_with('-')) {
        return Err(unknown(py, "face", name, "+x, -x, +y, -y, +z or -z"));
    }
    Ok(pgvol::edit::Face { axis, upper })
}

/// "union", "intersection" or "difference".
pub(crate) fn bool_op(py: Python<'_>, name: &str) -> PyResult<pgvol::BoolOp> {
    Ok(match name {
        "union" => pgvol::BoolOp::Union,
        "intersection" => pgvol::BoolOp::Intersection,
        "difference" => pgvol::BoolOp::Difference,
        _ => {
            return Err(unknown(
                py,
                "operation",
                name,
                "union, intersection or difference",
            ))
        }
    })
}

/// Slice settings from the keywords of `Field.slice`.
pub(crate) fn slice_settings(
    py: Python<'_>,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<pgvol::SliceOptions> {
    Ok(pgvol::SliceOptions {
        axis: self::axis(py, axis)?,
        layer_height,
        first: first.map(f64::from),
        resolution,
        tolerance,
    })
}
