//! Kernels compiled twice, for the baseline target and with AVX2, the build chosen at run time.
//!
//! The baseline x86-64 target has four-lane vectors and no rounding instruction (`floor` and
//! `round` are library calls). AVX2 without FMA performs the same IEEE operations in the same
//! order, eight lanes at a time, so both builds of a kernel give the same bits; only where the
//! CPU has it does the AVX2 build run.
//!
//! A kernel is a value holding its arguments whose [`Kernel::run`] is `#[inline(always)]`: that
//! is what puts its body inside the AVX2 function, so the body's loops are compiled for AVX2
//! (the callees it does not inline stay baseline).

/// A loop worth compiling for AVX2; implement [`Kernel::run`] with `#[inline(always)]`.
pub trait Kernel {
    type Output;
    /// The kernel's work, on its own arguments.
    fn run(self) -> Self::Output;
}

/// Whether this CPU runs the AVX2 builds of kernels.
#[inline]
pub fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Runs `kernel`, compiled for AVX2 where the CPU has it.
#[inline]
pub fn run<K: Kernel>(kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    if has_avx2() {
        // SAFETY: the CPU has AVX2, the only feature `run_avx2` is compiled for.
        return unsafe { run_avx2(kernel) };
    }
    kernel.run()
}

/// Like [`run`], without the AVX2 build: the reference the tests compare it with.
pub fn run_baseline<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sums of products and floors over many lanes, where a build that fused or reordered
    /// operations would differ in the last bits.
    struct Mixed<'a>(&'a [f32], &'a mut [f32]);

    impl Kernel for Mixed<'_> {
        type Output = f32;
        #[inline(always)]
        fn run(self) -> f32 {
            let mut total = 0.0f32;
            for (o, &x) in self.1.iter_mut().zip(self.0) {
                *o = (x * 1.37 + 0.1).floor() * 0.3 + x * x * 0.7 - (x * 3.1).round();
                total += *o;
            }
            total
        }
    }

    #[test]
    fn both_builds_give_the_same_bits() {
        let xs: Vec<f32> = (0..1003)
            .map(|i| ((i * 7919) % 2003) as f32 * 0.0137 - 13.1)
            .collect();
        let (mut a, mut b) = (vec![0.0; xs.len()], vec![0.0; xs.len()]);
        let ta = run(Mixed(&xs, &mut a));
        let tb = run_baseline(Mixed(&xs, &mut b));
        assert_eq!(ta.to_bits(), tb.to_bits());
        assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
        assert!(a.iter().any(|&x| x != 0.0));
    }
}
