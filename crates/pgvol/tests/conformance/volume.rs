//! The coefficient volume in every basis: it is the sum of its node kernels, its batch calls
//! give the pointwise values bit for bit at any thread count, its evaluation paths agree, and
//! interpolation reproduces node samples where the collocation is definite.

use pgvol::contour::Field;
use pgvol::field::fit::collocation_is_spd;
use pgvol::field::kernel::{kernel, Profile, PseudoGaussian};
use pgvol::field::Kernel;
use pgvol::glam::{DVec3, Mat3, Vec3};
use pgvol::{Basis, CoefficientVolume, Grid};
use proptest::prelude::*;

use crate::kernel::{profile, pseudo_gaussian, KernelCase};
use crate::support::{bits, check, scattered, vec_bits, with_threads, THREADS};

pub struct VolumeCase<K> {
    pub basis: Basis,
    /// The basis's kernel, built directly.
    pub kernel: KernelCase<K>,
    /// Largest error of interpolation at the nodes, when the collocation is definite.
    pub interpolation: Option<f32>,
}

fn separable(basis: Basis, p: Profile) -> VolumeCase<Profile> {
    VolumeCase {
        basis,
        kernel: profile(p),
        interpolation: Some(1e-3),
    }
}

fn radial(n: u8, r: f32) -> VolumeCase<PseudoGaussian> {
    let basis = Basis::Pg { n, r };
    VolumeCase {
        basis,
        kernel: pseudo_gaussian(n, r),
        interpolation: collocation_is_spd(basis).then_some(1e-3),
    }
}

/// A grid off the origin with unequal sides.
const GRID: Grid = Grid {
    origin: Vec3::new(-1.0, 0.5, 2.0),
    spacing: 0.25,
    dims: [12, 11, 12],
    offset: DVec3::ZERO,
};

/// Coefficients in [-1, 1) from a hash of the node and `seed`.
fn coefficients(seed: u32) -> Vec<f32> {
    (0..GRID.len())
        .map(|i| {
            let h = (i as u32).wrapping_mul(2_654_435_761).wrapping_add(seed) >> 8;
            (h % 1000) as f32 / 500.0 - 1.0
        })
        .collect()
}

fn volume<K>(case: &VolumeCase<K>, seed: u32) -> CoefficientVolume {
    CoefficientVolume::new(GRID, case.basis, coefficients(seed)).unwrap()
}

/// The basis evaluates the kernel built for it.
pub fn basis_kernel_is_its_implementor<K: Kernel>(case: &VolumeCase<K>) {
    let from_basis = kernel(case.basis);
    assert_eq!(from_basis.support(), case.basis.support());
    assert_eq!(from_basis.support(), case.kernel.kernel.support());
    for d in scattered((Vec3::splat(-2.5), Vec3::splat(2.5)), 200) {
        assert_eq!(from_basis.jet(d), case.kernel.kernel.jet(d), "at {d}");
    }
}

/// The volume sums exactly the kernels of the nodes around the point, with their derivatives
/// scaled to world units.
pub fn is_the_sum_of_its_node_kernels<K: Kernel>(case: &VolumeCase<K>) {
    let u = (3.0f32..8.0, 3.0f32..8.0, 3.0f32..8.0).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    check(32, (u, 0u32..1000), |(u, seed)| {
        let vol = volume(case, seed);
        let k = &case.kernel.kernel;
        let (mut v, mut g, mut h) = (0.0f32, Vec3::ZERO, Mat3::ZERO);
        for kk in 0..GRID.dims[2] {
            for jj in 0..GRID.dims[1] {
                for ii in 0..GRID.dims[0] {
                    let jet = k.jet(u - Vec3::new(ii as f32, jj as f32, kk as f32));
                    let c = vol.coeffs.get([ii, jj, kk]);
                    v += c * jet.value;
                    g += c * jet.gradient;
                    h += jet.hessian * c;
                }
            }
        }
        let p = GRID.origin + u * GRID.spacing;
        let (fv, fg, fh) = vol.eval_hessian(p);
        let s = GRID.spacing;
        prop_assert!((fv - v).abs() < 1e-4, "{} vs {}", fv, v);
        if !case.kernel.near_break(u) {
            prop_assert!((fg - g / s).length() < 1e-3 * (1.0 + fg.length()));
            let scale = fh.abs().to_cols_array().iter().cloned().fold(0.0, f32::max);
            let diff = (fh - h * (1.0 / (s * s))).to_cols_array();
            prop_assert!(diff.iter().all(|x| x.abs() <= 1e-2 * (1.0 + scale)));
        }
        Ok(())
    });
}

/// Value alone, value with gradient, with Hessian, and through the contouring trait: one field.
pub fn evaluation_paths_agree<K>(case: &VolumeCase<K>) {
    let vol = volume(case, 7);
    let (lo, hi) = (GRID.origin, GRID.max_corner());
    // Also outside the box, where the field continues at slope one.
    for p in scattered((lo - 0.5, hi + 0.5), 2000) {
        let v = vol.value(p);
        let (ev, eg) = vol.eval(p);
        let (hv, hg, _) = vol.eval_hessian(p);
        let (fv, fg) = Field::value_gradient(&vol, p);
        let tol = 1e-6 * (1.0 + v.abs());
        assert!(
            (ev - v).abs() <= tol && (hv - v).abs() <= tol && (fv - v).abs() <= tol,
            "{v} {ev} {hv} {fv} at {p}"
        );
        assert!(
            (hg - eg).length() <= 1e-5 * (1.0 + eg.length()),
            "{eg} {hg} at {p}"
        );
        assert!(
            (fg - eg).length() <= 1e-5 * (1.0 + eg.length()),
            "{eg} {fg} at {p}"
        );
        assert_eq!(bits(Field::value(&vol, p)), bits(v));
    }
}

/// Batch calls equal pointwise ones bit for bit, at any thread count: `eval_many`,
/// `eval_hessian_many`, and `sample` on the volume's own nodes and on another grid.
pub fn batch_evaluation_equals_pointwise_at_every_thread_count<K>(case: &VolumeCase<K>) {
    let vol = volume(case, 11);
    let points = scattered((GRID.origin - 0.3, GRID.max_corner() + 0.3), 1500);
    let pointwise: Vec<_> = points
        .iter()
        .map(|&p| {
            let (v, g) = vol.eval(p);
            (bits(v), vec_bits(g))
        })
        .collect();
    let hessians: Vec<_> = points.iter().map(|&p| vol.eval_hessian(p)).collect();
    let other = Grid {
        origin: GRID.origin - Vec3::splat(0.1),
        spacing: 0.17,
        dims: [19, 17, 20],
        offset: Default::default(),
    };
    let nodes = |g: &Grid| {
        let mut v = Vec::with_capacity(g.len());
        for k in 0..g.dims[2] {
            for j in 0..g.dims[1] {
                for i in 0..g.dims[0] {
                    v.push(bits(vol.value(g.point(i, j, k))));
                }
            }
        }
        v
    };
    let (own, resampled) = (nodes(&GRID), nodes(&other));
    for threads in THREADS {
        let (many, hessian_many, own_sample, other_sample) = with_threads(threads, || {
            (
                vol.eval_many(&points),
                vol.eval_hessian_many(&points),
                vol.sample(&GRID),
                vol.sample(&other),
            )
        });
        let many: Vec<_> = many.iter().map(|&(v, g)| (bits(v), vec_bits(g))).collect();
        assert!(many == pointwise, "eval_many, {threads} threads");
        let same_hessians = hessian_many.iter().zip(&hessians).all(|(a, b)| {
            bits(a.0) == bits(b.0)
                && vec_bits(a.1) == vec_bits(b.1)
                && a.2.to_cols_array().map(bits) == b.2.to_cols_array().map(bits)
        });
        assert!(same_hessians, "eval_hessian_many, {threads} threads");
        let own_sample: Vec<_> = own_sample.into_iter().map(bits).collect();
        assert!(own_sample == own, "sample on its nodes, {threads} threads");
        let other_sample: Vec<_> = other_sample.into_iter().map(bits).collect();
        assert!(
            other_sample == resampled,
            "sample on another grid, {threads} threads"
        );
    }
}

/// Interpolating node samples gives them back at the nodes, where the collocation is definite;
/// where it is not, the case must say so.
pub fn interpolation_reproduces_node_samples<K>(case: &VolumeCase<K>) {
    let Some(tolerance) = case.interpolation else {
        assert!(
            !collocation_is_spd(case.basis),
            "a definite basis must interpolate"
        );
        return;
    };
    let grid = Grid {
        origin: Vec3::splat(-1.0),
        spacing: 2.0 / 13.0,
        dims: [14, 14, 14],
        offset: Default::default(),
    };
    let f = |p: Vec3| p.length() - 0.6 + 0.1 * (3.0 * p.x).sin();
    let samples: Vec<f32> = (0..grid.len())
        .map(|i| f(grid.point(i % 14, (i / 14) % 14, i / 196)))
        .collect();
    let vol = CoefficientVolume::interpolate(grid, case.basis, samples.clone()).unwrap();
    let worst = vol
        .sample(&grid)
        .iter()
        .zip(&samples)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(worst < tolerance, "worst node error {worst}");
}

macro_rules! volume_tests {
    ($($name:ident => $case:expr;)*) => {
        $(
            mod $name {
                use super::*;

                #[test]
                fn basis_kernel_is_its_implementor() {
                    super::basis_kernel_is_its_implementor(&$case);
                }

                #[test]
                fn is_the_sum_of_its_node_kernels() {
                    super::is_the_sum_of_its_node_kernels(&$case);
                }

                #[test]
                fn evaluation_paths_agree() {
                    super::evaluation_paths_agree(&$case);
                }

                #[test]
                fn batch_evaluation_equals_pointwise_at_every_thread_count() {
                    super::batch_evaluation_equals_pointwise_at_every_thread_count(&$case);
                }

                #[test]
                fn interpolation_reproduces_node_samples() {
                    super::interpolation_reproduces_node_samples(&$case);
                }
            }
        )*
    };
}

volume_tests! {
    trilinear => separable(Basis::Trilinear, Profile::Linear);
    bspline2 => separable(Basis::Bspline2, Profile::Quadratic);
    bspline3 => separable(Basis::Bspline3, Profile::Cubic);
    pg_n1_r1_5 => radial(1, 1.5);
    pg_n1_r2 => radial(1, 2.0);
    pg_n1_r2_5 => radial(1, 2.5);
    pg_n2_r1_5 => radial(2, 1.5);
    pg_n2_r2 => radial(2, 2.0);
    pg_n2_r2_5 => radial(2, 2.5);
    pg_n3_r1_5 => radial(3, 1.5);
    pg_n3_r2 => radial(3, 2.0);
    pg_n3_r2_5 => radial(3, 2.5);
    pg_n4_r1_5 => radial(4, 1.5);
    pg_n4_r2 => radial(4, 2.0);
    pg_n4_r2_5 => radial(4, 2.5);
}
