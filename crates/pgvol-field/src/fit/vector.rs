//! Vector kernels of the Krylov solvers, run in parallel over spans of fixed length: sums add
//! each span's partial sum in span order, so they do not depend on the number of threads.

use rayon::prelude::*;

/// Elements per span: long enough to amortise scheduling, short enough to spread a vector of a
/// few hundred thousand elements over the threads.
const SPAN: usize = 1 << 14;

/// `Σ a_i b_i`.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let partial: Vec<f64> = a
        .par_chunks(SPAN)
        .zip(b.par_chunks(SPAN))
        .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x * y).sum())
        .collect();
    partial.iter().sum()
}

/// `y += alpha · x`.
pub fn axpy(y: &mut [f64], alpha: f64, x: &[f64]) {
    y.par_chunks_mut(SPAN)
        .zip(x.par_chunks(SPAN))
        .for_each(|(y, x)| {
            for (y, x) in y.iter_mut().zip(x) {
                *y += alpha * x;
            }
        });
}

/// `y += alpha · x`, returning `‖y‖²` afterwards.
pub fn axpy_norm_sq(y: &mut [f64], alpha: f64, x: &[f64]) -> f64 {
    let partial: Vec<f64> = y
        .par_chunks_mut(SPAN)
        .zip(x.par_chunks(SPAN))
        .map(|(y, x)| {
            let mut s = 0.0;
            for (y, x) in y.iter_mut().zip(x) {
                *y += alpha * x;
                s += *y * *y;
            }
            s
        })
        .collect();
    partial.iter().sum()
}

/// `p = s + beta · p`.
pub fn xpby(p: &mut [f64], s: &[f64], beta: f64) {
    p.par_chunks_mut(SPAN)
        .zip(s.par_chunks(SPAN))
        .for_each(|(p, s)| {
            for (p, s) in p.iter_mut().zip(s) {
                *p = s + beta * *p;
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_match_their_definitions_and_thread_counts() {
        let n = 3 * SPAN + 17;
        let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        let serial: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        assert!((dot(&a, &b) - serial).abs() < 1e-9 * n as f64);

        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut y = b.clone();
                axpy(&mut y, 0.5, &a);
                let norm = axpy_norm_sq(&mut y, -0.25, &a);
                let mut p = a.clone();
                xpby(&mut p, &y, 0.3);
                (dot(&a, &b), norm, y, p)
            })
        };
        let (d, norm, y, p) = run(1);
        for (i, y) in y.iter().enumerate() {
            assert!((y - (b[i] + 0.25 * a[i])).abs() < 1e-12);
            assert!((p[i] - (y + 0.3 * a[i])).abs() < 1e-12);
        }
        assert!((norm - y.iter().map(|v| v * v).sum::<f64>()).abs() < 1e-9 * n as f64);
        for threads in [2, 5] {
            assert!(run(threads) == (d, norm, y.clone(), p.clone()), "{threads}");
        }
    }
}
