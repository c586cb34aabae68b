//! Where layers sit in the world: the f64 translation a far shape's layers carry, applied only
//! when their files are written, so layer coordinates keep f32 precision relative to the part.

use glam::DVec3;

use crate::slice::Axis;

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
