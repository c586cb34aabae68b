//! One basis function centred on a node, with value, gradient and Hessian, behind one trait so
//! every basis can be held to the same checks. Offsets and derivatives are in grid units.

mod jet;
mod radial;
mod separable;

pub use jet::{Jet, Kernel};
pub use radial::PseudoGaussian;
pub use separable::{axis_window, AxisWindow, Profile};

use glam::{Mat3, Vec3};

use crate::basis::Basis;

/// The kernel behind a basis. Separable bases are products of 1D profiles.
pub fn kernel(basis: Basis) -> Box<dyn Kernel> {
    match basis {
        Basis::Trilinear => Box::new(Profile::Linear),
        Basis::Bspline2 => Box::new(Profile::Quadratic),
        Basis::Bspline3 => Box::new(Profile::Cubic),
        Basis::Pg { n, r } => Box::new(PseudoGaussian { n, r }),
    }
}

impl Kernel for Profile {
    fn support(&self) -> f32 {
        self.radius()
    }

    fn jet(&self, d: Vec3) -> Jet {
        let (x, y, z) = (self.eval(d.x), self.eval(d.y), self.eval(d.z));
        separable_jet(x, y, z)
    }

    fn partition_of_unity(&self) -> bool {
        true
    }
}

/// The jet of `f(x) g(y) h(z)` from each factor's (value, first, second derivative).
#[inline]
pub fn separable_jet(x: [f32; 3], y: [f32; 3], z: [f32; 3]) -> Jet {
    let value = x[0] * y[0] * z[0];
    let gradient = Vec3::new(x[1] * y[0] * z[0], x[0] * y[1] * z[0], x[0] * y[0] * z[1]);
    let (xy, xz, yz) = (x[1] * y[1] * z[0], x[1] * y[0] * z[1], x[0] * y[1] * z[1]);
    let hessian = Mat3::from_cols(
        Vec3::new(x[2] * y[0] * z[0], xy, xz),
        Vec3::new(xy, x[0] * y[2] * z[0], yz),
        Vec3::new(xz, yz, x[0] * y[0] * z[2]),
    );
    Jet {
        value,
        gradient,
        hessian,
    }
}
