//! Dense linear algebra for systems of a few hundred unknowns: LU with partial pivoting, the
//! 1-norm condition number, symmetric eigenvalues by cyclic Jacobi, and CGLS (the iterative
//! solver pgvol uses in 3D) to see whether it would converge.

/// Row-major square or rectangular matrix.
#[derive(Clone)]
pub struct Mat {
    pub rows: usize,
    pub cols: usize,
    pub a: Vec<f64>,
}

impl Mat {
    pub fn zeros(rows: usize, cols: usize) -> Mat {
        Mat {
            rows,
            cols,
            a: vec![0.0; rows * cols],
        }
    }
    pub fn at(&self, r: usize, c: usize) -> f64 {
        self.a[r * self.cols + c]
    }
    pub fn add(&mut self, r: usize, c: usize, v: f64) {
        self.a[r * self.cols + c] += v;
    }
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        self.a.chunks(self.cols).map(|row| dot(row, x)).collect()
    }
    pub fn mul_t(&self, y: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.cols];
        for (row, &yr) in self.a.chunks(self.cols).zip(y) {
            for (o, &v) in out.iter_mut().zip(row) {
                *o += v * yr;
            }
        }
        out
    }
    fn norm1(&self) -> f64 {
        (0..self.cols)
            .map(|c| (0..self.rows).map(|r| self.at(r, c).abs()).sum::<f64>())
            .fold(0.0, f64::max)
    }
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// LU factors of a square matrix; `None` if a pivot is exactly zero.
pub struct Lu {
    n: usize,
    lu: Vec<f64>,
    perm: Vec<usize>,
}

impl Lu {
    pub fn new(m: &Mat) -> Option<Lu> {
        let n = m.rows;
        let mut lu = m.a.clone();
        let mut perm: Vec<usize> = (0..n).collect();
        for k in 0..n {
            let p = (k..n).max_by(|&x, &y| lu[x * n + k].abs().total_cmp(&lu[y * n + k].abs()))?;
            if lu[p * n + k] == 0.0 {
                return None;
            }
            if p != k {
                for c in 0..n {
                    lu.swap(k * n + c, p * n + c);
                }
                perm.swap(k, p);
            }
            let pivot = lu[k * n + k];
            for r in k + 1..n {
                let f = lu[r * n + k] / pivot;
                lu[r * n + k] = f;
                if f != 0.0 {
                    for c in k + 1..n {
                        lu[r * n + c] -= f * lu[k * n + c];
                    }
                }
            }
        }
        Some(Lu { n, lu, perm })
    }

    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut x: Vec<f64> = self.perm.iter().map(|&p| b[p]).collect();
        for r in 0..n {
            let s = dot(&self.lu[r * n..r * n + r], &x[..r]);
            x[r] -= s;
        }
        for r in (0..n).rev() {
            let s = dot(&self.lu[r * n + r + 1..(r + 1) * n], &x[r + 1..]);
            x[r] = (x[r] - s) / self.lu[r * n + r];
        }
        x
    }

    /// `‖A‖₁ ‖A⁻¹‖₁`, with the inverse formed column by column.
    pub fn condition(&self, m: &Mat) -> f64 {
        let n = self.n;
        let mut inv_norm = 0.0f64;
        let mut e = vec![0.0; n];
        for c in 0..n {
            e[c] = 1.0;
            let col = self.solve(&e);
            e[c] = 0.0;
            inv_norm = inv_norm.max(col.iter().map(|v| v.abs()).sum());
        }
        m.norm1() * inv_norm
    }
}

/// Smallest and largest eigenvalue of the symmetric part `(A + Aᵀ)/2` (cyclic Jacobi).
pub fn symmetric_eigen_range(m: &Mat) -> (f64, f64) {
    let n = m.rows;
    let mut a: Vec<f64> = (0..n * n)
        .map(|i| 0.5 * (m.at(i / n, i % n) + m.at(i % n, i / n)))
        .collect();
    for _sweep in 0..50 {
        let off: f64 = (0..n * n)
            .filter(|i| i / n != i % n)
            .map(|i| a[i] * a[i])
            .sum();
        if off < 1e-22 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
            }
        }
    }
    (0..n)
        .map(|i| a[i * n + i])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

/// CGLS from zero until `‖A x − b‖ ≤ tol ‖b‖` or the normal-equation residual stalls;
/// returns the iterations used and whether the tolerance was met.
pub fn cgls_iterations(m: &Mat, b: &[f64], tol: f64, max_iterations: usize) -> (usize, bool) {
    let bn = norm(b).max(1e-300);
    let mut x = vec![0.0; m.cols];
    let mut r = b.to_vec();
    let mut s = m.mul_t(&r);
    let mut p = s.clone();
    let mut gamma = dot(&s, &s);
    for it in 1..=max_iterations {
        let q = m.mul(&p);
        let qq = dot(&q, &q);
        if qq <= 0.0 || !qq.is_finite() {
            return (it, false);
        }
        let alpha = gamma / qq;
        for (xi, pi) in x.iter_mut().zip(&p) {
            *xi += alpha * pi;
        }
        for (ri, qi) in r.iter_mut().zip(&q) {
            *ri -= alpha * qi;
        }
        if norm(&r) <= tol * bn {
            return (it, true);
        }
        s = m.mul_t(&r);
        let gamma_new = dot(&s, &s);
        let beta = gamma_new / gamma;
        gamma = gamma_new;
        for (pi, si) in p.iter_mut().zip(&s) {
            *pi = si + beta * *pi;
        }
    }
    (max_iterations, false)
}

/// Relative residual `‖A x − b‖ / ‖b‖`.
pub fn relative_residual(m: &Mat, x: &[f64], b: &[f64]) -> f64 {
    let ax = m.mul(x);
    let r: Vec<f64> = ax.iter().zip(b).map(|(a, b)| a - b).collect();
    norm(&r) / norm(b).max(1e-300)
}
