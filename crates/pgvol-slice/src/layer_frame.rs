//! Where layers sit in the world: the f64 translation a far shape's layers carry, applied only
//! when their files are written, so layer coordinates keep f32 precision relative to the part.

use glam::DVec3;

use crate::slice::{Axis, Layer};

/// Layer coordinates and heights must be below this in magnitude: the limit mesh coordinates
/// have, beyond which f32 distances and grid spacings lose their meaning (a contour at 1e20
/// asks for a grid of that extent).
pub const MAX_LAYER_COORDINATE: f32 = 1e8;

/// What is wrong with the first layer height or contour point that is not finite or not below
/// [`MAX_LAYER_COORDINATE`] in magnitude, or `None` when every one is in range.
pub fn layer_coordinate_problem(layers: &[Layer]) -> Option<String> {
    let bad = |c: f32| !(c.is_finite() && c.abs() < MAX_LAYER_COORDINATE);
    let advice = "(|x| must be < 1e8); give the layers relative to a nearer origin or in larger \
                  units";
    for (i, layer) in layers.iter().enumerate() {
        if bad(layer.height) {
            return Some(format!(
                "the height {:e} of layer {i} is out of range {advice}",
                layer.height
            ));
        }
        let point = layer.loops.iter().flat_map(|l| &l.points).flatten();
        if let Some(c) = point.copied().find(|&c| bad(c)) {
            return Some(format!(
                "coordinate {c:e} in layer {i} (height {}) is out of range {advice}",
                layer.height
            ));
        }
    }
    None
}

/// The world translation of layer coordinates: `height` along the stacking axis and `u`, `v`
/// in the plane (the axis's in-plane coordinates, as in [`Axis::indices`]). Zero for shapes
/// near the origin, whose files are written exactly as the layers hold them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LayerFrame {
    pub height: f64,
    pub u: f64,
    pub v: f64,
}

impl LayerFrame {
    /// The frame of layers stacked along `axis` in a field whose frame offset is `offset`.
    pub fn new(axis: Axis, offset: DVec3) -> LayerFrame {
        let [a, u, v] = axis.indices();
        LayerFrame {
            height: offset[a],
            u: offset[u],
            v: offset[v],
        }
    }

    /// Whether nothing is translated.
    pub fn is_zero(&self) -> bool {
        *self == LayerFrame::default()
    }
}

/// `local + shift` as text: the f32's own shortest text when there is no shift (as files near
/// the origin always had), the f64 sum's otherwise.
pub(crate) fn world_text(local: f32, shift: f64) -> String {
    if shift == 0.0 {
        local.to_string()
    } else {
        (shift + f64::from(local)).to_string()
    }
}

/// The rounding (half an f32 step at the farthest world coordinate) that f32 storage adds to
/// layers spanning `extent` in a frame, and that error relative to the extent's size; `None`
/// in a zero frame.
pub(crate) fn f32_loss(frame: &LayerFrame, extent: [f32; 4], heights: (f32, f32)) -> Option<f64> {
    if frame.is_zero() {
        return None;
    }
    let far = |shift: f64, a: f32, b: f32| {
        (shift + f64::from(a))
            .abs()
            .max((shift + f64::from(b)).abs())
    };
    let far = far(frame.u, extent[0], extent[2])
        .max(far(frame.v, extent[1], extent[3]))
        .max(far(frame.height, heights.0, heights.1));
    let size = f64::from((extent[2] - extent[0]).max(extent[3] - extent[1])).max(f64::MIN_POSITIVE);
    let step = f64::from((far as f32).next_up() - far as f32) * 0.5;
    Some(step / size)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slice::Loop;

    #[test]
    fn layer_coordinates_beyond_the_mesh_limit_are_named() {
        let layer = |height: f32, x: f32| Layer {
            height,
            loops: vec![Loop {
                points: vec![[0.0, 0.0], [x, 0.0], [0.0, 1.0]],
                hole: false,
            }],
        };
        assert_eq!(layer_coordinate_problem(&[layer(0.0, 9.9e7)]), None);
        let e = layer_coordinate_problem(&[layer(0.0, 1.0), layer(0.5, -1e20)]).unwrap();
        assert!(
            e.contains("coordinate -1e20 in layer 1") && e.contains("< 1e8"),
            "{e}"
        );
        let e = layer_coordinate_problem(&[layer(1e8, 1.0)]).unwrap();
        assert!(e.contains("height 1e8 of layer 0"), "{e}");
    }
}
