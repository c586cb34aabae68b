//! `pgvol_field::Kernel`, one basis function: its peak, its support, its symmetries, its
//! derivatives against differences and the partition of unity where it claims one, for the 1D
//! profiles of the separable bases and for pseudo-Gaussians of every order over three radii.

use pgvol::field::kernel::{Profile, PseudoGaussian};
use pgvol::field::Kernel;
use pgvol::glam::{Mat3, Quat, Vec3};
use proptest::prelude::*;

use crate::support::{check, point_within};

/// A kernel and what is known of it independently of its code.
pub struct KernelCase<K> {
    pub kernel: K,
    /// Value at its own node, and whether the kernel is flat there (all but the hat).
    pub peak: f32,
    pub flat_peak: bool,
    /// Whether the value depends on `|d|` only (else it is a tensor product of one profile).
    pub radial: bool,
    /// Whether lattice sums of it are one.
    pub partition_of_unity: bool,
    /// Where the next derivative jumps: per axis at `breaks` offsets modulo 1 (separable), or at
    /// the support radius (radial).
    pub breaks: &'static [f32],
}

pub fn profile(profile: Profile) -> KernelCase<Profile> {
    let (peak, breaks): (f32, &[f32]) = match profile {
        Profile::Linear => (1.0, &[0.0]),
        Profile::Quadratic => (0.75f32.powi(3), &[0.5]),
        Profile::Cubic => ((2.0f32 / 3.0).powi(3), &[0.0]),
    };
    KernelCase {
        kernel: profile,
        peak,
        flat_peak: profile != Profile::Linear,
        radial: false,
        partition_of_unity: true,
        breaks,
    }
}

pub fn pseudo_gaussian(n: u8, r: f32) -> KernelCase<PseudoGaussian> {
    KernelCase {
        kernel: PseudoGaussian { n, r },
        peak: 1.0,
        flat_peak: true,
        radial: true,
        partition_of_unity: false,
        breaks: &[],
    }
}

impl<K: Kernel> KernelCase<K> {
    /// Derivative checks skip points this close to a piece boundary.
    pub fn near_break(&self, d: Vec3) -> bool {
        if self.radial {
            // C^n with n = 1 has a Hessian jump at the radius.
            return (d.length() - self.kernel.support()).abs() < 0.02;
        }
        d.to_array().iter().any(|&x| {
            self.breaks.iter().any(|&b| {
                let f = (x - b).rem_euclid(1.0);
                !(0.02..=0.98).contains(&f)
            })
        })
    }

    fn fd_gradient(&self, d: Vec3, e: f32) -> Vec3 {
        crate::support::fd_gradient(|q| self.kernel.jet(q).value, d, e)
    }

    fn fd_hessian(&self, d: Vec3, e: f32) -> Mat3 {
        let col = |a: Vec3| {
            (self.kernel.jet(d + a * e).gradient - self.kernel.jet(d - a * e).gradient) / (2.0 * e)
        };
        Mat3::from_cols(col(Vec3::X), col(Vec3::Y), col(Vec3::Z))
    }
}

fn mat_close(a: Mat3, b: Mat3, tol: f32) -> bool {
    (a - b).to_cols_array().iter().all(|x| x.abs() <= tol)
}

pub fn value_at_the_node<K: Kernel>(case: &KernelCase<K>) {
    let j = case.kernel.jet(Vec3::ZERO);
    assert!((j.value - case.peak).abs() < 1e-6, "{}", j.value);
    if case.flat_peak {
        assert!(j.gradient.length() < 1e-6, "peak must be flat");
    }
}

pub fn support_radius_is_exact<K: Kernel>(case: &KernelCase<K>) {
    let k = &case.kernel;
    let s = k.support();
    for dir in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X] {
        assert!(k.jet(dir * (s - 0.05)).value > 0.0, "zero inside");
        assert_eq!(k.jet(dir * s).value, 0.0, "non-zero at the radius");
        assert_eq!(k.jet(dir * (s + 0.3)).value, 0.0);
    }
    if case.radial {
        assert_eq!(k.jet(Vec3::splat(s / 3f32.sqrt() + 1e-3)).value, 0.0);
    } else {
        // Separable: the support is a cube, non-zero out to its corners.
        assert!(k.jet(Vec3::splat(s - 0.05)).value > 0.0);
    }
}

pub fn symmetric_under_reflection_and_axis_permutation<K: Kernel>(case: &KernelCase<K>) {
    let k = &case.kernel;
    check(64, point_within(3.0), |d| {
        let v = k.jet(d).value;
        prop_assert!((k.jet(-d).value - v).abs() < 1e-6);
        prop_assert!((k.jet(Vec3::new(d.y, d.z, d.x)).value - v).abs() < 1e-6);
        prop_assert!((k.jet(Vec3::new(-d.x, d.y, d.z)).value - v).abs() < 1e-6);
        Ok(())
    });
}

/// Radial kernels are invariant under rotations; separable ones are not (their support is a
/// cube), which tells the two apart.
pub fn radial_exactly_when_claimed<K: Kernel>(case: &KernelCase<K>) {
    let k = &case.kernel;
    check(64, (point_within(2.0), 0.0f32..6.0), |(d, a)| {
        let rot = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), a);
        if case.radial {
            prop_assert!((k.jet(rot * d).value - k.jet(d).value).abs() < 1e-5);
        }
        Ok(())
    });
    let corner = Vec3::splat(0.5 * k.support());
    let on_axis = Vec3::X * corner.length();
    let same = (k.jet(corner).value - k.jet(on_axis).value).abs() < 1e-6;
    assert_eq!(
        same,
        case.radial,
        "{} at the diagonal, {} on the axis",
        k.jet(corner).value,
        k.jet(on_axis).value
    );
}

pub fn gradient_matches_finite_differences<K: Kernel>(case: &KernelCase<K>) {
    check(64, point_within(2.6), |d| {
        if case.near_break(d) {
            return Ok(());
        }
        let g = case.kernel.jet(d).gradient;
        let fd = case.fd_gradient(d, 1e-3);
        prop_assert!((g - fd).length() < 3e-3, "{} vs {} at {}", g, fd, d);
        Ok(())
    });
}

pub fn hessian_matches_finite_differences_of_the_gradient<K: Kernel>(case: &KernelCase<K>) {
    check(64, point_within(2.6), |d| {
        if case.near_break(d) {
            return Ok(());
        }
        let h = case.kernel.jet(d).hessian;
        prop_assert!(mat_close(h, h.transpose(), 1e-5), "not symmetric");
        let fd = case.fd_hessian(d, 1e-3);
        prop_assert!(mat_close(h, fd, 2e-2), "{} vs {} at {}", h, fd, d);
        Ok(())
    });
}

/// Where a kernel claims a partition of unity, its lattice sum is one and it reproduces linear
/// functions; the pseudo-Gaussians claim neither (their sums ripple).
pub fn partition_of_unity_where_it_holds<K: Kernel>(case: &KernelCase<K>) {
    let k = &case.kernel;
    assert_eq!(k.partition_of_unity(), case.partition_of_unity);
    check(64, point_within(0.5), |u| {
        let (mut sum, mut lin) = (0.0f32, Vec3::ZERO);
        for z in -4..=4 {
            for y in -4..=4 {
                for x in -4..=4 {
                    let j = Vec3::new(x as f32, y as f32, z as f32);
                    let v = k.jet(u - j).value;
                    sum += v;
                    lin += v * j;
                }
            }
        }
        if case.partition_of_unity {
            prop_assert!((sum - 1.0).abs() < 1e-5, "{}", sum);
            prop_assert!((lin - u).length() < 1e-5);
        } else {
            prop_assert!(sum > 0.0);
        }
        Ok(())
    });
}

macro_rules! kernel_tests {
    ($($name:ident => $case:expr;)*) => {
        $(
            mod $name {
                use super::*;

                #[test]
                fn value_at_the_node() {
                    super::value_at_the_node(&$case);
                }

                #[test]
                fn support_radius_is_exact() {
                    super::support_radius_is_exact(&$case);
                }

                #[test]
                fn symmetric_under_reflection_and_axis_permutation() {
                    super::symmetric_under_reflection_and_axis_permutation(&$case);
                }

                #[test]
                fn radial_exactly_when_claimed() {
                    super::radial_exactly_when_claimed(&$case);
                }

                #[test]
                fn gradient_matches_finite_differences() {
                    super::gradient_matches_finite_differences(&$case);
                }

                #[test]
                fn hessian_matches_finite_differences_of_the_gradient() {
                    super::hessian_matches_finite_differences_of_the_gradient(&$case);
                }

                #[test]
                fn partition_of_unity_where_it_holds() {
                    super::partition_of_unity_where_it_holds(&$case);
                }
            }
        )*
    };
}

kernel_tests! {
    linear => profile(Profile::Linear);
    quadratic => profile(Profile::Quadratic);
    cubic => profile(Profile::Cubic);
    pg_n1_r1_5 => pseudo_gaussian(1, 1.5);
    pg_n1_r2 => pseudo_gaussian(1, 2.0);
    pg_n1_r2_5 => pseudo_gaussian(1, 2.5);
    pg_n2_r1_5 => pseudo_gaussian(2, 1.5);
    pg_n2_r2 => pseudo_gaussian(2, 2.0);
    pg_n2_r2_5 => pseudo_gaussian(2, 2.5);
    pg_n3_r1_5 => pseudo_gaussian(3, 1.5);
    pg_n3_r2 => pseudo_gaussian(3, 2.0);
    pg_n3_r2_5 => pseudo_gaussian(3, 2.5);
    pg_n4_r1_5 => pseudo_gaussian(4, 1.5);
    pg_n4_r2 => pseudo_gaussian(4, 2.0);
    pg_n4_r2_5 => pseudo_gaussian(4, 2.5);
}
