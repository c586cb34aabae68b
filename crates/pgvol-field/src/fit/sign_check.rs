//! The check every fit reports: nodes where the fitted field's sign contradicts the SDF's.

use super::node_values;
use crate::volume::CoefficientVolume;

/// Counts nodes with `|SDF| > k` where the field's sign differs from the SDF's.
pub fn spurious_sign_changes(volume: &CoefficientVolume, node_sdf: &[f32]) -> usize {
    let k = volume.grid.spacing;
    node_values::count_nodes(volume, |f, i| {
        let d = node_sdf[i];
        d.abs() > k && (f < 0.0) != (d < 0.0)
    })
}
