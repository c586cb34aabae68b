//! 3MF transforms: twelve numbers `m00 m01 m02 m10 m11 m12 m20 m21 m22 m30 m31 m32` that map a
//! point as the row vector `(x, y, z, 1)` times the 4 × 3 matrix they fill row by row (3MF core
//! specification, "3D Matrices"), so `x' = x·m00 + y·m10 + z·m20 + m30`.

use glam::{DAffine3, DMat3, DVec3};

use super::text::{clip, number};

/// Parses a `transform` attribute into the equivalent column-vector affine map: the rows of the
/// 3MF matrix are the images of the axes, so they become the columns of the linear part.
pub(super) fn parse(text: &str) -> Result<DAffine3, String> {
    let mut m = [0.0f64; 12];
    let mut count = 0;
    for word in text.split_ascii_whitespace() {
        if count == 12 {
            return Err(format!(
                "transform '{}' has more than 12 numbers",
                clip(text)
            ));
        }
        m[count] = number(word)?;
        count += 1;
    }
    if count != 12 {
        return Err(format!(
            "transform '{}' has {count} numbers, not 12",
            clip(text)
        ));
    }
    let row = |r: usize| DVec3::new(m[3 * r], m[3 * r + 1], m[3 * r + 2]);
    Ok(DAffine3::from_mat3_translation(
        DMat3::from_cols(row(0), row(1), row(2)),
        row(3),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).abs().max_element() < 1e-12
    }

    #[test]
    fn rows_are_axis_images_and_the_last_row_a_translation() {
        // A quarter turn about z (x → y, y → −x), then a shift by (10, 20, 30).
        let t = parse("0 1 0  -1 0 0  0 0 1  10 20 30").unwrap();
        assert!(close(
            t.transform_point3(DVec3::X),
            DVec3::new(10.0, 21.0, 30.0)
        ));
        assert!(close(
            t.transform_point3(DVec3::Y),
            DVec3::new(9.0, 20.0, 30.0)
        ));
        assert!(close(
            t.transform_point3(DVec3::new(1.0, 2.0, 3.0)),
            DVec3::new(8.0, 21.0, 33.0)
        ));
    }

    #[test]
    fn a_component_is_placed_first_and_the_build_item_after() {
        // Component: scale x by 2 then move +1 in x. Item: quarter turn about z.
        let component = parse("2 0 0 0 1 0 0 0 1 1 0 0").unwrap();
        let item = parse("0 1 0 -1 0 0 0 0 1 0 0 0").unwrap();
        let placed = item * component;
        // (1, 0, 0) → component (3, 0, 0) → item (0, 3, 0).
        assert!(close(
            placed.transform_point3(DVec3::X),
            DVec3::new(0.0, 3.0, 0.0)
        ));
        // The other order would give (1, 1, 0): composition is not commutative.
        let wrong = component * item;
        assert!(close(
            wrong.transform_point3(DVec3::X),
            DVec3::new(1.0, 1.0, 0.0)
        ));
    }

    #[test]
    fn malformed_transforms_are_refused_with_the_count_or_the_word() {
        assert!(parse("1 0 0 0 1 0 0 0 1 0 0")
            .unwrap_err()
            .contains("11 numbers"));
        assert!(parse("1 0 0 0 1 0 0 0 1 0 0 0 0")
            .unwrap_err()
            .contains("more than 12"));
        assert!(parse("1 0 0 0 1 0 0 0 1 0 0 x")
            .unwrap_err()
            .contains("'x'"));
        assert!(parse("1 0 0 0 1 0 0 0 1 0 0 inf").is_err());
    }
}
