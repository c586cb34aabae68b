//! Which coefficients the surface band needs: those a point within `band` spacings of the zero
//! set can reach through the basis. The encoder stores every brick holding one, and may code
//! the others in a stored brick more loosely (`free_words`).

use pgvol_field::{Basis, CoefficientVolume};

/// Nodes a coefficient reaches, in grid spacings (per axis; Euclidean for pg, bounded by the
/// same number per axis).
pub(crate) fn dilation(basis: Basis) -> usize {
    match basis {
        Basis::Trilinear => 1,
        Basis::Bspline2 | Basis::Bspline3 => 2,
        Basis::Pg { r, .. } => r.ceil().max(1.0) as usize,
    }
}

/// Per node (x fastest): whether it lies within the basis reach (per axis) of a node where the
/// field is within `band` spacings of zero. Judged on the field's node values, not the
/// coefficients: a B-spline coefficient is not the field value and can differ in sign from it
/// near thin features.
pub(crate) fn needed_nodes(volume: &CoefficientVolume, band: f32) -> Vec<bool> {
    let g = &volume.grid;
    // Three 3-tap passes for the B-splines instead of a full evaluation per node.
    let values = pgvol_field::fit::node_values(volume);
    let limit = band * g.spacing;
    let mut mask: Vec<bool> = values.iter().map(|v| v.abs() <= limit).collect();
    let d = dilation(volume.basis);
    for axis in 0..3 {
        mask = dilate_along(&mask, g.dims, axis, d);
    }
    mask
}

/// `mask` grown by `d` nodes both ways along one axis (a box dilation is three of these).
fn dilate_along(mask: &[bool], dims: [usize; 3], axis: usize, d: usize) -> Vec<bool> {
    let stride = [1, dims[0], dims[0] * dims[1]][axis];
    let n = dims[axis];
    let mut out = vec![false; mask.len()];
    for (idx, _) in mask.iter().enumerate().filter(|(_, &m)| m) {
        let at = idx / stride % n;
        let line_start = idx - at * stride;
        for t in at.saturating_sub(d)..=(at + d).min(n - 1) {
            out[line_start + t * stride] = true;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_grows_a_single_node_into_a_box_clipped_at_the_border() {
        let dims = [6, 5, 4];
        let mut mask = vec![false; 120];
        mask[1 + 6 * (2 + 5 * 3)] = true;
        for axis in 0..3 {
            mask = dilate_along(&mask, dims, axis, 2);
        }
        for k in 0..4 {
            for j in 0..5 {
                for i in 0..6 {
                    let inside = i <= 3 && j <= 4 && k >= 1;
                    assert_eq!(mask[i + 6 * (j + 5 * k)], inside, "({i}, {j}, {k})");
                }
            }
        }
    }
}
