//! Text forms of the command line's values: masks and faces, drain holes, sizes. The library takes these as values; only the command line reads them as text.

use pgvol::edit::{Drain, Face, Mask};
use pgvol::glam::Vec3;
use pgvol::{Error, Result};

/// A drain hole from `x,y,z,dx,dy,dz,diameter`: a point inside the cavity, the direction out
/// through the wall (normalised here) and the hole's diameter.
pub fn parse_drain(text: &str) -> Result<Drain> {
    let numbers: Vec<f32> = text
        .split(',')
        .map(|x| {
            x.trim()
                .parse::<f32>()
                .map_err(|_| Error::parameter(format!("drain: '{x}' is not a number")))
        })
        .collect::<Result<_>>()?;
    if numbers.len() != 7 || numbers.iter().any(|x| !x.is_finite()) {
        return Err(Error::parameter(
            "drain: expected seven finite numbers x,y,z,dx,dy,dz,diameter",
        ));
    }
    let direction = Vec3::new(numbers[3], numbers[4], numbers[5]);
    if direction.length() == 0.0 || numbers[6] <= 0.0 {
        return Err(Error::parameter(
            "drain: the direction must be non-zero and the diameter positive",
        ));
    }
    Ok(Drain {
        point: Vec3::new(numbers[0], numbers[1], numbers[2]),
        direction: direction.normalize(),
        diameter: numbers[6],
    })
}

/// A mask from `x0,y0,z0,x1,y1,z1`.
pub fn parse_mask(text: &str) -> Result<Mask> {
    let v: Vec<f32> = text
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| {
            Error::parameter(format!(
                "mask: '{text}' is not six numbers x0,y0,z0,x1,y1,z1"
            ))
        })?;
    if v.len() != 6 || v.iter().any(|x| !x.is_finite()) {
        return Err(Error::parameter(format!(
            "mask: expected six finite numbers x0,y0,z0,x1,y1,z1, got '{text}'"
        )));
    }
    let (lo, hi) = (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
    if hi.cmple(lo).any() {
        return Err(Error::parameter(format!(
            "mask: the second corner must lie above the first on every axis, got '{text}'"
        )));
    }
    Ok(Mask { lo, hi })
}

/// A face from `+x`, `-x`, `+y`, `-y`, `+z` or `-z`.
pub fn parse_face(text: &str) -> Result<Face> {
    let t = text.trim();
    let (sign, axis) = t.split_at(t.len().min(1));
    let axis = match axis {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        _ => usize::MAX,
    };
    if axis == usize::MAX || !(sign == "+" || sign == "-") {
        return Err(Error::parameter(format!(
            "face: expected one of +x, -x, +y, -y, +z, -z, got '{text}'"
        )));
    }
    Ok(Face {
        axis,
        upper: sign == "+",
    })
}

/// Parses a size such as `8G`, `512M`, `2.5GB` or a plain number of bytes.
pub fn parse_size(text: &str) -> Result<u64> {
    let t = text.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let factor: f64 = match unit.trim().to_ascii_uppercase().as_str() {
        "" | "B" => 1.0,
        "K" | "KB" => 1e3,
        "M" | "MB" => 1e6,
        "G" | "GB" => 1e9,
        "T" | "TB" => 1e12,
        "KIB" => 1024.0,
        "MIB" => 1024.0 * 1024.0,
        "GIB" => 1024.0 * 1024.0 * 1024.0,
        _ => f64::NAN,
    };
    match number.trim().parse::<f64>() {
        Ok(n) if n.is_finite() && n > 0.0 && factor.is_finite() => Ok((n * factor) as u64),
        _ => Err(Error::parameter(format!(
            "'{text}' is not a size (examples: 8G, 512M, 2.5GB)"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks_and_faces_parse_and_bad_ones_are_refused() {
        let m = parse_mask("0,0,0,1,2,3").unwrap();
        assert_eq!(m.hi, Vec3::new(1.0, 2.0, 3.0));
        assert!(parse_mask("0,0,0,1,2").is_err());
        assert!(parse_mask("0,0,0,1,-2,3").is_err());
        assert_eq!(
            parse_face("-z").unwrap(),
            Face {
                axis: 2,
                upper: false
            }
        );
        assert_eq!(
            parse_face("+x").unwrap(),
            Face {
                axis: 0,
                upper: true
            }
        );
        assert!(parse_face("z").is_err());
        assert!(parse_face("+w").is_err());
    }

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("8G").unwrap(), 8_000_000_000);
        assert_eq!(parse_size("512 MiB").unwrap(), 512 << 20);
        assert_eq!(parse_size("1000").unwrap(), 1000);
        assert!(parse_size("lots").is_err() && parse_size("-1G").is_err());
    }
}
