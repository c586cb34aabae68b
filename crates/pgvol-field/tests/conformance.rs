//! One suite of checks run against every basis: the kernel's value, support, symmetry,
//! derivatives and partition of unity, and the coefficient volume built on it.

use glam::{Mat3, Quat, Vec3};
use pgvol_field::kernel::kernel;
use pgvol_field::{Basis, CoefficientVolume, Grid, Kernel};
use proptest::prelude::*;

fn all_bases() -> Vec<Basis> {
    let mut v = Basis::SEPARABLE.to_vec();
    for n in 1..=4 {
        for r in [1.5, 2.0, 2.5] {
            v.push(Basis::Pg { n, r });
        }
    }
    v
}

/// Derivative checks skip points this close to a piece boundary, where the next derivative
/// jumps (hat kinks at integers, quadratic B-spline at half-integers, cubic at integers).
fn near_breakpoint(basis: Basis, d: Vec3) -> bool {
    let step = match basis {
        Basis::Trilinear | Basis::Bspline3 => 1.0,
        Basis::Bspline2 => 0.5,
        // C^n with n = 1 has a Hessian jump at the radius.
        Basis::Pg { r, .. } => return (d.length() - r).abs() < 0.02,
    };
    d.to_array().iter().any(|&x| {
        let off = if basis == Basis::Bspline2 { x + 0.5 } else { x };
        let f = (off / step).rem_euclid(1.0);
        !(0.02..=0.98).contains(&f)
    })
}

fn fd_gradient(k: &dyn Kernel, d: Vec3, e: f32) -> Vec3 {
    Vec3::new(
        k.jet(d + Vec3::X * e).value - k.jet(d - Vec3::X * e).value,
        k.jet(d + Vec3::Y * e).value - k.jet(d - Vec3::Y * e).value,
        k.jet(d + Vec3::Z * e).value - k.jet(d - Vec3::Z * e).value,
    ) / (2.0 * e)
}

fn fd_hessian(k: &dyn Kernel, d: Vec3, e: f32) -> Mat3 {
    let col = |a: Vec3| (k.jet(d + a * e).gradient - k.jet(d - a * e).gradient) / (2.0 * e);
    Mat3::from_cols(col(Vec3::X), col(Vec3::Y), col(Vec3::Z))
}

fn mat_close(a: Mat3, b: Mat3, tol: f32) -> bool {
    (a - b).to_cols_array().iter().all(|x| x.abs() <= tol)
}

fn point(s: f32) -> impl Strategy<Value = Vec3> {
    (-s..s, -s..s, -s..s).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

#[test]
fn value_at_the_node() {
    for b in all_bases() {
        let want = match b {
            Basis::Trilinear => 1.0,
            Basis::Bspline2 => 0.75f32.powi(3),
            Basis::Bspline3 => (2.0f32 / 3.0).powi(3),
            Basis::Pg { .. } => 1.0,
        };
        let j = kernel(b).jet(Vec3::ZERO);
        assert!((j.value - want).abs() < 1e-6, "{b}");
        if b != Basis::Trilinear {
            assert!(j.gradient.length() < 1e-6, "{b}: peak must be flat");
        }
    }
}

#[test]
fn support_radius_is_exact() {
    for b in all_bases() {
        let k = kernel(b);
        let s = k.support();
        assert_eq!(s, b.support());
        for dir in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X] {
            assert!(k.jet(dir * (s - 0.05)).value > 0.0, "{b}: zero inside");
            assert_eq!(k.jet(dir * s).value, 0.0, "{b}: non-zero at the radius");
            assert_eq!(k.jet(dir * (s + 0.3)).value, 0.0, "{b}");
        }
        if b.is_separable() {
            // Separable: the support is a cube, non-zero out to its corners.
            assert!(k.jet(Vec3::splat(s - 0.05)).value > 0.0, "{b}");
        } else {
            assert_eq!(k.jet(Vec3::splat(s / 3f32.sqrt() + 1e-3)).value, 0.0, "{b}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn symmetric_under_reflection_and_axis_permutation(d in point(3.0)) {
        for b in all_bases() {
            let k = kernel(b);
            let v = k.jet(d).value;
            prop_assert!((k.jet(-d).value - v).abs() < 1e-6, "{}", b);
            prop_assert!((k.jet(Vec3::new(d.y, d.z, d.x)).value - v).abs() < 1e-6, "{}", b);
            prop_assert!((k.jet(Vec3::new(-d.x, d.y, d.z)).value - v).abs() < 1e-6, "{}", b);
        }
    }

    #[test]
    fn radial_bases_depend_only_on_distance(d in point(2.0), a in 0.0f32..6.0) {
        for b in all_bases().into_iter().filter(|b| !b.is_separable()) {
            let k = kernel(b);
            let rot = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), a);
            prop_assert!((k.jet(rot * d).value - k.jet(d).value).abs() < 1e-5);
        }
    }

    #[test]
    fn gradient_matches_finite_differences(d in point(2.6)) {
        for b in all_bases() {
            if near_breakpoint(b, d) { continue; }
            let k = kernel(b);
            let g = k.jet(d).gradient;
            let fd = fd_gradient(k.as_ref(), d, 1e-3);
            prop_assert!((g - fd).length() < 3e-3, "{}: {} vs {} at {}", b, g, fd, d);
        }
    }

    #[test]
    fn hessian_matches_finite_differences_of_the_gradient(d in point(2.6)) {
        for b in all_bases() {
            if near_breakpoint(b, d) { continue; }
            let k = kernel(b);
            let h = k.jet(d).hessian;
            prop_assert!(mat_close(h, h.transpose(), 1e-5), "{}: not symmetric", b);
            let fd = fd_hessian(k.as_ref(), d, 1e-3);
            prop_assert!(mat_close(h, fd, 2e-2), "{}: {} vs {} at {}", b, h, fd, d);
        }
    }

    /// Where a basis claims a partition of unity, its lattice sum is one and it reproduces
    /// linear functions; the pseudo-Gaussians do neither (their sums ripple).
    #[test]
    fn partition_of_unity_where_it_holds(u in point(0.5)) {
        for b in all_bases() {
            let k = kernel(b);
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
            if k.partition_of_unity() {
                prop_assert!((sum - 1.0).abs() < 1e-5, "{}: {}", b, sum);
                prop_assert!((lin - u).length() < 1e-5, "{}", b);
            } else {
                prop_assert!(sum > 0.0);
            }
        }
    }

    /// The volume sums exactly the kernels of the nodes around the point, with their
    /// derivatives scaled to world units.
    #[test]
    fn volume_is_the_sum_of_node_kernels(u in (3.0f32..8.0, 3.0f32..8.0, 3.0f32..8.0), seed in 0u32..1000) {
        let grid = Grid { origin: Vec3::new(-1.0, 0.5, 2.0), spacing: 0.25, dims: [12, 11, 12] };
        let coeffs: Vec<f32> = (0..grid.len())
            .map(|i| (((i as u32).wrapping_mul(2654435761).wrapping_add(seed) >> 8) % 1000) as f32 / 500.0 - 1.0)
            .collect();
        let u = Vec3::new(u.0, u.1, u.2);
        for b in all_bases() {
            let vol = CoefficientVolume::new(grid, b, coeffs.clone()).unwrap();
            let k = kernel(b);
            let (mut v, mut g, mut h) = (0.0f32, Vec3::ZERO, Mat3::ZERO);
            for kk in 0..12 { for jj in 0..11 { for ii in 0..12 {
                let d = u - Vec3::new(ii as f32, jj as f32, kk as f32);
                let jet = k.jet(d);
                let c = coeffs[grid.index(ii, jj, kk)];
                v += c * jet.value; g += c * jet.gradient; h += jet.hessian * c;
            }}}
            let p = grid.origin + u * grid.spacing;
            let (fv, fg, fh) = vol.eval_hessian(p);
            let s = grid.spacing;
            prop_assert!((fv - v).abs() < 1e-4, "{}: {} vs {}", b, fv, v);
            if !near_breakpoint(b, u) {
                prop_assert!((fg - g / s).length() < 1e-3 * (1.0 + fg.length()), "{}", b);
                prop_assert!(mat_close(fh, h * (1.0 / (s * s)), 1e-2 * (1.0 + fh.abs().to_cols_array().iter().cloned().fold(0.0, f32::max))), "{}", b);
            }
            prop_assert!((vol.value(p) - fv).abs() < 1e-5);
            let (ev, eg) = vol.eval(p);
            prop_assert!((ev - fv).abs() < 1e-5 && (eg - fg).length() < 1e-4);
        }
    }
}

#[test]
fn node_interpolation_reproduces_samples_for_every_basis() {
    let grid = Grid {
        origin: Vec3::splat(-1.0),
        spacing: 2.0 / 13.0,
        dims: [14, 14, 14],
    };
    let f = |p: Vec3| p.length() - 0.6 + 0.1 * (3.0 * p.x).sin();
    let samples: Vec<f32> = (0..grid.len())
        .map(|i| f(grid.point(i % 14, (i / 14) % 14, i / 196)))
        .collect();
    for b in all_bases() {
        if !pgvol_field::fit::collocation_is_spd(b) {
            continue;
        }
        let vol = CoefficientVolume::interpolate(grid, b, samples.clone()).unwrap();
        let back = vol.sample(&grid);
        let worst = back
            .iter()
            .zip(&samples)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        assert!(worst < 1e-3, "{b}: worst node error {worst}");
    }
}
