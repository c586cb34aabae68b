//! 1D profiles of the separable bases and the window of nodes a point touches along one axis.

/// The 1D factor of a separable basis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Profile {
    /// Hat function, support ±1.
    Linear,
    /// Quadratic B-spline, support ±1.5.
    Quadratic,
    /// Cubic B-spline, support ±2.
    Cubic,
}

impl Profile {
    pub fn radius(self) -> f32 {
        match self {
            Profile::Linear => 1.0,
            Profile::Quadratic => 1.5,
            Profile::Cubic => 2.0,
        }
    }

    /// Value, first and second derivative at `x`. At the kinks of the hat the one-sided
    /// derivative of the right-hand piece is returned.
    #[inline]
    pub fn eval(self, x: f32) -> [f32; 3] {
        let a = x.abs();
        let s = if x < 0.0 { -1.0 } else { 1.0 };
        match self {
            Profile::Linear if a < 1.0 => [1.0 - a, -s, 0.0],
            Profile::Quadratic if a < 0.5 => [0.75 - x * x, -2.0 * x, -2.0],
            Profile::Quadratic if a < 1.5 => {
                let b = 1.5 - a;
                [0.5 * b * b, -s * b, 1.0]
            }
            Profile::Cubic if a < 1.0 => [
                2.0 / 3.0 - x * x + 0.5 * a * a * a,
                -2.0 * x + 1.5 * x * a,
                -2.0 + 3.0 * a,
            ],
            Profile::Cubic if a < 2.0 => {
                let b = 2.0 - a;
                [b * b * b / 6.0, -s * 0.5 * b * b, b]
            }
            _ => [0.0; 3],
        }
    }
}

/// The nodes a point touches along one axis: `first .. first + len`, with the weights
/// `[value, first derivative, second derivative]` of each.
#[derive(Clone, Copy, Debug)]
pub struct AxisWindow {
    pub first: i64,
    pub len: usize,
    pub w: [[f32; 3]; 4],
}

/// The window along an axis of `n` nodes at grid coordinate `u` (already clamped to `[0, n−1]`).
/// Cells are chosen so that a point on a node still sees the cell to its right (the far end
/// uses the last cell), which keeps the hat's derivative one-sided and the window inside the
/// grid for the trilinear basis.
#[inline]
pub fn axis_window(profile: Profile, u: f32, n: usize) -> AxisWindow {
    let (first, len, t) = match profile {
        Profile::Linear | Profile::Cubic => {
            let c = (u.floor() as i64).clamp(0, n as i64 - 2);
            let t = (u - c as f32).clamp(0.0, 1.0);
            if profile == Profile::Linear {
                let w = [[1.0 - t, -1.0, 0.0], [t, 1.0, 0.0], [0.0; 3], [0.0; 3]];
                return AxisWindow {
                    first: c,
                    len: 2,
                    w,
                };
            }
            (c - 1, 4, u - (c - 1) as f32)
        }
        Profile::Quadratic => {
            let c = ((u + 0.5).floor() as i64).clamp(0, n as i64 - 1);
            (c - 1, 3, u - (c - 1) as f32)
        }
    };
    let mut w = [[0.0f32; 3]; 4];
    for (a, slot) in w.iter_mut().enumerate().take(len) {
        *slot = profile.eval(t - a as f32);
    }
    AxisWindow { first, len, w }
}
