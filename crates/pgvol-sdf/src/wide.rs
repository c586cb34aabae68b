//! Several f32 lanes behind one interface, so that a scan kernel is written once and compiled
//! both for AVX2 (eight lanes in one register) and for baseline x86-64 (two SSE2 registers).
//!
//! Every operation is a single IEEE operation per lane (no fused multiply-add, no
//! approximations) with the same NaN and signed-zero behaviour in every implementation, so a
//! kernel gives bit-identical lanes whichever implementation it runs on.

use glam::{BVec4A, Vec4};
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

/// A vector of `LANES` floats.
pub(crate) trait Wide:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// Lane-wise comparison results.
    type Mask: Copy
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;

    const LANES: usize;

    fn splat(x: f32) -> Self;

    /// The first `LANES` values of `s` (panics when it is shorter).
    fn load(s: &[f32]) -> Self;

    /// The `LANES` values from `p`, without a bounds check.
    ///
    /// # Safety
    /// `p` points to `LANES` readable floats.
    unsafe fn load_unchecked(p: *const f32) -> Self;

    /// Writes the lanes to `out[..LANES]` (panics when it is shorter).
    fn store(self, out: &mut [f32]);

    /// `max(self, o)` lane-wise; `o` where they compare equal or either is NaN (as `maxps`).
    fn max(self, o: Self) -> Self;

    fn le(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn lt(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;

    /// `t` where `mask` holds, else `f`.
    fn select(mask: Self::Mask, t: Self, f: Self) -> Self;

    /// Bit `l` set where lane `l` of `mask` holds.
    fn bits(mask: Self::Mask) -> u32;
}

/// Four lanes: one SSE2 register on x86-64.
impl Wide for Vec4 {
    type Mask = BVec4A;
    const LANES: usize = 4;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Vec4::splat(x)
    }
    #[inline(always)]
    unsafe fn load_unchecked(p: *const f32) -> Self {
        // SAFETY: the caller promises four readable floats.
        Vec4::from_array(unsafe { p.cast::<[f32; 4]>().read_unaligned() })
    }
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        Vec4::from_slice(&s[..4])
    }
    #[inline(always)]
    fn store(self, out: &mut [f32]) {
        self.write_to_slice(&mut out[..4])
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Vec4::max(self, o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> BVec4A {
        self.cmple(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> BVec4A {
        self.cmpge(o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> BVec4A {
        self.cmplt(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> BVec4A {
        self.cmpgt(o)
    }
    #[inline(always)]
    fn select(mask: BVec4A, t: Self, f: Self) -> Self {
        Vec4::select(mask, t, f)
    }
    #[inline(always)]
    fn bits(mask: BVec4A) -> u32 {
        mask.bitmask()
    }
}

/// Eight lanes as two [`Vec4`]: the portable form of [`Avx`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pair(Vec4, Vec4);

#[derive(Clone, Copy, Debug)]
pub(crate) struct PairMask(BVec4A, BVec4A);

macro_rules! pair_op {
    ($tr:ident, $f:ident, $ty:ident) => {
        impl $tr for $ty {
            type Output = $ty;
            #[inline(always)]
            fn $f(self, o: $ty) -> $ty {
                $ty(self.0.$f(o.0), self.1.$f(o.1))
            }
        }
    };
}
pair_op!(Add, add, Pair);
pair_op!(Sub, sub, Pair);
pair_op!(Mul, mul, Pair);
pair_op!(Div, div, Pair);
pair_op!(BitAnd, bitand, PairMask);
pair_op!(BitOr, bitor, PairMask);

impl Not for PairMask {
    type Output = PairMask;
    #[inline(always)]
    fn not(self) -> PairMask {
        PairMask(!self.0, !self.1)
    }
}

impl Wide for Pair {
    type Mask = PairMask;
    const LANES: usize = 8;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Pair(Vec4::splat(x), Vec4::splat(x))
    }
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        Pair(Vec4::from_slice(&s[..4]), Vec4::from_slice(&s[4..8]))
    }
    #[inline(always)]
    unsafe fn load_unchecked(p: *const f32) -> Self {
        // SAFETY: the caller promises eight readable floats.
        unsafe { Pair(Vec4::load_unchecked(p), Vec4::load_unchecked(p.add(4))) }
    }
    #[inline(always)]
    fn store(self, out: &mut [f32]) {
        self.0.write_to_slice(&mut out[..4]);
        self.1.write_to_slice(&mut out[4..8]);
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Pair(self.0.max(o.0), self.1.max(o.1))
    }
    #[inline(always)]
    fn le(self, o: Self) -> PairMask {
        PairMask(self.0.cmple(o.0), self.1.cmple(o.1))
    }
    #[inline(always)]
    fn ge(self, o: Self) -> PairMask {
        PairMask(self.0.cmpge(o.0), self.1.cmpge(o.1))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> PairMask {
        PairMask(self.0.cmplt(o.0), self.1.cmplt(o.1))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> PairMask {
        PairMask(self.0.cmpgt(o.0), self.1.cmpgt(o.1))
    }
    #[inline(always)]
    fn select(mask: PairMask, t: Self, f: Self) -> Self {
        Pair(
            Vec4::select(mask.0, t.0, f.0),
            Vec4::select(mask.1, t.1, f.1),
        )
    }
    #[inline(always)]
    fn bits(mask: PairMask) -> u32 {
        mask.0.bitmask() | (mask.1.bitmask() << 4)
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::Avx;

/// Eight lanes in one AVX register.
///
/// Safety: the methods execute AVX instructions. They are inlined into, and only ever called
/// from, functions compiled with `#[target_feature(enable = "avx2")]` that are entered after
/// [`avx2_available`] returned true; nothing else constructs an [`Avx`].
#[cfg(target_arch = "x86_64")]
mod avx {
    use super::Wide;
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx(__m256);

    macro_rules! avx_op {
        ($tr:ident, $f:ident, $intrinsic:ident) => {
            impl $tr for Avx {
                type Output = Avx;
                #[inline(always)]
                fn $f(self, o: Avx) -> Avx {
                    // SAFETY: see the module documentation.
                    Avx(unsafe { $intrinsic(self.0, o.0) })
                }
            }
        };
    }
    avx_op!(Add, add, _mm256_add_ps);
    avx_op!(Sub, sub, _mm256_sub_ps);
    avx_op!(Mul, mul, _mm256_mul_ps);
    avx_op!(Div, div, _mm256_div_ps);
    avx_op!(BitAnd, bitand, _mm256_and_ps);
    avx_op!(BitOr, bitor, _mm256_or_ps);

    impl Not for Avx {
        type Output = Avx;
        #[inline(always)]
        fn not(self) -> Avx {
            // SAFETY: see the module documentation.
            Avx(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
        }
    }

    /// Comparisons are ordered and quiet: false where either lane is NaN, as SSE's `cmpps`.
    macro_rules! avx_cmp {
        ($f:ident, $pred:ident) => {
            #[inline(always)]
            fn $f(self, o: Avx) -> Avx {
                // SAFETY: see the module documentation.
                Avx(unsafe { _mm256_cmp_ps::<$pred>(self.0, o.0) })
            }
        };
    }

    impl Wide for Avx {
        /// All ones where the lane holds, all zeros elsewhere.
        type Mask = Avx;
        const LANES: usize = 8;

        #[inline(always)]
        fn splat(x: f32) -> Self {
            // SAFETY: see the module documentation.
            Avx(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        fn load(s: &[f32]) -> Self {
            let s = &s[..8];
            // SAFETY: `s` holds eight floats; unaligned loads are allowed. AVX: see the module.
            Avx(unsafe { _mm256_loadu_ps(s.as_ptr()) })
        }
        #[inline(always)]
        unsafe fn load_unchecked(p: *const f32) -> Self {
            // SAFETY: the caller promises eight readable floats; AVX: see the module.
            Avx(unsafe { _mm256_loadu_ps(p) })
        }
        #[inline(always)]
        fn store(self, out: &mut [f32]) {
            let out = &mut out[..8];
            // SAFETY: `out` has room for eight floats; unaligned stores are allowed. AVX: see
            // the module documentation.
            unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            // SAFETY: see the module documentation.
            Avx(unsafe { _mm256_max_ps(self.0, o.0) })
        }
        avx_cmp!(le, _CMP_LE_OQ);
        avx_cmp!(ge, _CMP_GE_OQ);
        avx_cmp!(lt, _CMP_LT_OQ);
        avx_cmp!(gt, _CMP_GT_OQ);
        #[inline(always)]
        fn select(mask: Avx, t: Self, f: Self) -> Self {
            // SAFETY: see the module documentation.
            Avx(unsafe { _mm256_blendv_ps(f.0, t.0, mask.0) })
        }
        #[inline(always)]
        fn bits(mask: Avx) -> u32 {
            // SAFETY: see the module documentation.
            unsafe { _mm256_movemask_ps(mask.0) as u32 }
        }
    }
}

/// Whether this CPU runs the AVX2 kernels.
#[inline]
pub(crate) fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
