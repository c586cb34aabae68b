//! What every kernel gives: its value, gradient and Hessian at an offset from its node.

use glam::{Mat3, Vec3};

/// A function value with its gradient and Hessian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet {
    pub value: f32,
    pub gradient: Vec3,
    pub hessian: Mat3,
}

impl Jet {
    pub const ZERO: Jet = Jet {
        value: 0.0,
        gradient: Vec3::ZERO,
        hessian: Mat3::ZERO,
    };
}

/// A basis function `B(d)` of the offset `d` from its node, in grid units.
pub trait Kernel: Sync {
    /// `B` is zero when any `|d_i|` (separable) or `|d|` (radial) reaches this radius.
    fn support(&self) -> f32;
    /// Value, gradient and Hessian at offset `d`.
    fn jet(&self, d: Vec3) -> Jet;
    /// Whether the shifted copies on the integer lattice sum to one everywhere.
    fn partition_of_unity(&self) -> bool;
}
