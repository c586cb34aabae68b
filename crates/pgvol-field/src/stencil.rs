//! The nodes whose basis functions are non-zero at a point, with their weights: the one place
//! that knows how each basis is laid on the grid and what lies past its border.

use glam::{Mat3, Vec3};

use crate::basis::Basis;
use crate::kernel::{axis_window, separable_jet, Jet, Kernel, Profile, PseudoGaussian};

/// How much of the jet a visit needs; higher orders cost more per node.
pub const VALUE: u8 = 0;
pub const GRADIENT: u8 = 1;
pub const HESSIAN: u8 = 2;

/// Calls `f(flat index, jet)` for every node touching grid coordinate `u`, which must lie in
/// `[0, n−1]` per axis. Separable bases mirror indices past the border (a node may then be
/// visited twice); radial ones skip nodes outside the grid, whose coefficients are zero.
/// Parts of the jet above `ORDER` are left zero.
#[inline]
pub fn visit<const ORDER: u8>(
    basis: Basis,
    dims: [usize; 3],
    u: Vec3,
    mut f: impl FnMut(usize, Jet),
) {
    let [nx, ny, _] = dims;
    visit_nodes::<ORDER>(basis, dims, u, |[i, j, k], jet| {
        f(i + nx * (j + ny * k), jet)
    });
}

/// As [`visit`], with each node given by its indices.
#[inline]
pub fn visit_nodes<const ORDER: u8>(
    basis: Basis,
    dims: [usize; 3],
    u: Vec3,
    mut f: impl FnMut([usize; 3], Jet),
) {
    let [nx, ny, nz] = dims;
    match basis {
        Basis::Pg { n, r } => {
            let pg = PseudoGaussian { n, r };
            let r2 = r * r;
            let range = |u: f32, len: usize| {
                let lo = ((u - r).floor() as i64 + 1).max(0);
                let hi = ((u + r).ceil() as i64 - 1).min(len as i64 - 1);
                lo..=hi
            };
            for k in range(u.z, nz) {
                let dz = u.z - k as f32;
                for j in range(u.y, ny) {
                    let dy = u.y - j as f32;
                    let dyz = dy * dy + dz * dz;
                    if dyz >= r2 {
                        continue;
                    }
                    for i in range(u.x, nx) {
                        let dx = u.x - i as f32;
                        let d2 = dx * dx + dyz;
                        if d2 >= r2 {
                            continue;
                        }
                        let idx = [i as usize, j as usize, k as usize];
                        let jet = if ORDER == VALUE {
                            Jet {
                                value: pg.value_sq(d2),
                                ..Jet::ZERO
                            }
                        } else {
                            pg.jet(Vec3::new(dx, dy, dz))
                        };
                        f(idx, jet);
                    }
                }
            }
        }
        _ => {
            let profile = match basis {
                Basis::Trilinear => Profile::Linear,
                Basis::Bspline2 => Profile::Quadratic,
                _ => Profile::Cubic,
            };
            let wx = axis_window(profile, u.x, nx);
            let wy = axis_window(profile, u.y, ny);
            let wz = axis_window(profile, u.z, nz);
            for c in 0..wz.len {
                let kk = mirror(wz.first + c as i64, nz);
                let z = wz.w[c];
                for b in 0..wy.len {
                    let jj = mirror(wy.first + b as i64, ny);
                    let y = wy.w[b];
                    for a in 0..wx.len {
                        let x = wx.w[a];
                        let idx = [mirror(wx.first + a as i64, nx), jj, kk];
                        let jet = match ORDER {
                            VALUE => Jet {
                                value: x[0] * y[0] * z[0],
                                ..Jet::ZERO
                            },
                            GRADIENT => Jet {
                                value: x[0] * y[0] * z[0],
                                gradient: Vec3::new(
                                    x[1] * y[0] * z[0],
                                    x[0] * y[1] * z[0],
                                    x[0] * y[0] * z[1],
                                ),
                                hessian: Mat3::ZERO,
                            },
                            _ => separable_jet(x, y, z),
                        };
                        f(idx, jet);
                    }
                }
            }
        }
    }
}

/// Reflects an index about the end nodes (whole-sample symmetry), as the prefilter assumes.
#[inline]
pub fn mirror(i: i64, n: usize) -> usize {
    let n = n as i64;
    let m = if i < 0 {
        -i
    } else if i >= n {
        2 * (n - 1) - i
    } else {
        i
    };
    m.clamp(0, n - 1) as usize
}
