//! Quadratic error function of dual contouring: the point closest, in the least-squares sense,
//! to the tangent planes at a cell's edge crossings.

use glam::{DMat3, DVec3};

/// Accumulated planes `n · x = n · p` as `AᵀA`, `Aᵀb` and the mass point of the `p`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Qef {
    ata: DMat3,
    atb: DVec3,
    sum: DVec3,
    count: u32,
}

impl Default for Qef {
    // Not derived: glam's default matrix is the identity.
    fn default() -> Self {
        Self {
            ata: DMat3::ZERO,
            atb: DVec3::ZERO,
            sum: DVec3::ZERO,
            count: 0,
        }
    }
}

impl Qef {
    /// Adds the plane through `p` with unit normal `n`.
    pub fn add(&mut self, p: DVec3, n: DVec3) {
        self.ata += DMat3::from_cols(n * n.x, n * n.y, n * n.z);
        self.atb += n * n.dot(p);
        self.sum += p;
        self.count += 1;
    }

    /// Adds a crossing without its plane, for callers that only need the mass point.
    pub fn add_point(&mut self, p: DVec3) {
        self.sum += p;
        self.count += 1;
    }

    pub fn mass_point(&self) -> DVec3 {
        self.sum / f64::from(self.count.max(1))
    }

    /// The minimiser closest to the mass point, with directions whose singular value (square
    /// root of the eigenvalue of `AᵀA`) is below `rel_threshold` times the largest treated as
    /// unconstrained: along a flat face only the normal direction is fixed, and along a sharp
    /// edge two, so the rest stays at the mass point rather than running off with noise.
    #[cfg(test)]
    pub fn solve(&self, rel_threshold: f64) -> DVec3 {
        self.solve_about(self.mass_point(), rel_threshold).0
    }

    /// [`Self::solve`] about the point `c` instead of the mass point, and whether more than
    /// one direction passed the cut (the planes meet at an edge or corner).
    pub fn solve_about(&self, c: DVec3, rel_threshold: f64) -> (DVec3, bool) {
        if let Some(x) = self.solve_flat(c, rel_threshold) {
            return (x, false);
        }
        let (values, vectors) = symmetric_eigen(self.ata);
        let largest = values.max_element();
        if largest.is_nan() || largest <= 0.0 {
            return (c, false);
        }
        let cutoff = largest * rel_threshold * rel_threshold;
        let r = self.atb - self.ata * c;
        let mut x = c;
        let mut kept = 0;
        for i in 0..3 {
            if values[i] > cutoff {
                let v = vectors.col(i);
                x += v * (v.dot(r) / values[i]);
                kept += 1;
            }
        }
        (x, kept > 1)
    }
}

impl Qef {
    /// The direction of the line of minimisers where exactly two directions pass the cut of
    /// [`Self::solve_about`] (the planes meet at an edge): the eigenvector left out.
    pub fn edge_direction(&self, rel_threshold: f64) -> Option<DVec3> {
        let (values, vectors) = symmetric_eigen(self.ata);
        let largest = values.max_element();
        if largest.is_nan() || largest <= 0.0 {
            return None;
        }
        let cutoff = largest * rel_threshold * rel_threshold;
        let mut free = (0..3).filter(|&i| values[i] <= cutoff);
        match (free.next(), free.next()) {
            (Some(i), None) => Some(vectors.col(i)),
            _ => None,
        }
    }

    /// The common case without the eigen decomposition: planes so nearly parallel that only
    /// one direction passes the cut. A few power steps bring a direction `v` close to the top
    /// eigenvector; its Rayleigh quotient `q` is at most the largest eigenvalue, and the larger
    /// eigenvalue `mu` of the matrix restricted to the plane orthogonal to `v` is at least the
    /// second (Courant-Fischer), so `mu < q · threshold²` proves that only one direction passes,
    /// whichever way the power steps converged. `v` then alone moves the point. `None` when the
    /// test fails.
    fn solve_flat(&self, c: DVec3, rel_threshold: f64) -> Option<DVec3> {
        let a = self.ata;
        // Start from the column with the largest diagonal, which is never orthogonal to the
        // top eigenvector of a positive semi-definite matrix with a dominant eigenvalue.
        let diag = [a.x_axis.x, a.y_axis.y, a.z_axis.z];
        let col = (0..3).fold(0, |b, i| if diag[i] > diag[b] { i } else { b });
        // Unit normals keep every entry within ± the number of planes, so three unnormalised
        // steps cannot overflow and one normalisation at the end suffices.
        let v = (a * (a * (a * a.col(col)))).try_normalize()?;
        let q = v.dot(a * v);
        let cutoff = q * rel_threshold * rel_threshold;
        let (e1, e2) = v.any_orthonormal_pair();
        let (ae1, ae2) = (a * e1, a * e2);
        let (b11, b12, b22) = (e1.dot(ae1), e1.dot(ae2), e2.dot(ae2));
        let half_gap = 0.5 * (b11 - b22);
        let mu = 0.5 * (b11 + b22) + (half_gap * half_gap + b12 * b12).sqrt();
        if !(q > 0.0 && mu < cutoff) {
            return None;
        }
        let r = self.atb - a * c;
        Some(c + v * (v.dot(r) / q))
    }
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3x3 matrix by cyclic Jacobi rotations,
/// which converge quadratically and stay accurate for the rank-deficient matrices met here.
/// Only the six distinct entries are kept and rotated; feature cells solve two of these each.
pub(crate) fn symmetric_eigen(m: DMat3) -> (DVec3, DMat3) {
    let mut diag = [m.x_axis.x, m.y_axis.y, m.z_axis.z];
    // `off[r]` is the entry between the two indices other than `r`.
    let mut off = [m.z_axis.y, m.z_axis.x, m.y_axis.x];
    let mut vectors = [DVec3::X, DVec3::Y, DVec3::Z];
    let square = |x: [f64; 3]| x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
    let scale = square(diag) + 2.0 * square(off);
    for _sweep in 0..12 {
        // Off-diagonal entries below 1e-10 of the matrix leave eigenvector errors of that order
        // (1e-10 cells in a vertex) and eigenvalue errors of its square: far below f32
        // positions, and usually a sweep sooner than rounding level.
        let rest = square(off);
        if rest <= 1e-20 * scale || rest == 0.0 {
            break;
        }
        for (p, q, r) in [(0, 1, 2), (0, 2, 1), (1, 2, 0)] {
            let apq = off[r];
            if apq == 0.0 {
                continue;
            }
            // Rotation angle zeroing the (p, q) entry (Golub & Van Loan, symmetric Schur).
            let theta = (diag[q] - diag[p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            diag[p] -= t * apq;
            diag[q] += t * apq;
            off[r] = 0.0;
            // The entries (r, p) and (r, q).
            let (arp, arq) = (off[q], off[p]);
            off[q] = c * arp - s * arq;
            off[p] = s * arp + c * arq;
            let (vp, vq) = (vectors[p], vectors[q]);
            vectors[p] = c * vp - s * vq;
            vectors[q] = s * vp + c * vq;
        }
    }
    (
        DVec3::from_array(diag),
        DMat3::from_cols_array_2d(&vectors.map(|v| v.to_array())),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_decomposition_reconstructs_the_matrix() {
        let m = DMat3::from_cols(
            DVec3::new(4.0, 1.0, -2.0),
            DVec3::new(1.0, 3.0, 0.5),
            DVec3::new(-2.0, 0.5, 1.0),
        );
        let (l, v) = symmetric_eigen(m);
        let back = v * DMat3::from_diagonal(l) * v.transpose();
        for (x, y) in back.to_cols_array().iter().zip(m.to_cols_array()) {
            assert!((x - y).abs() < 1e-12, "{back:?} vs {m:?}");
        }
        let ortho = v.transpose() * v;
        assert!((ortho - DMat3::IDENTITY).abs_diff_eq(DMat3::ZERO, 1e-12));
    }

    #[test]
    fn two_planes_leave_their_edge_free() {
        let mut q = Qef::default();
        let (a, b) = (DVec3::new(1.0, 1.0, 0.0).normalize(), DVec3::Z);
        q.add(DVec3::new(0.5, 0.5, 0.0), a);
        q.add(DVec3::new(0.0, 0.0, 0.3), b);
        let d = q.edge_direction(0.1).expect("an edge");
        assert!(d.dot(a).abs() < 1e-12 && d.dot(b).abs() < 1e-12, "{d}");
        // One plane (a face) or three (a corner) have no single free direction.
        q.add(
            DVec3::new(0.5, 0.5, 0.0),
            DVec3::new(1.0, -1.0, 0.0).normalize(),
        );
        assert!(q.edge_direction(0.1).is_none());
        let mut face = Qef::default();
        face.add(DVec3::ZERO, DVec3::X);
        assert!(face.edge_direction(0.1).is_none());
    }

    #[test]
    fn three_planes_meet_at_the_corner() {
        let mut q = Qef::default();
        let corner = DVec3::new(0.3, 0.6, 0.2);
        for n in [DVec3::X, DVec3::Y, DVec3::Z] {
            q.add(corner + (DVec3::ONE - n) * 0.25, n);
        }
        let x = q.solve(0.1);
        assert!(x.distance(corner) < 1e-12, "{x:?}");
    }

    #[test]
    fn a_flat_face_keeps_the_tangential_mass_point() {
        let mut q = Qef::default();
        for p in [DVec3::new(0.0, 0.0, 0.4), DVec3::new(1.0, 0.2, 0.4)] {
            q.add(p, DVec3::Z);
        }
        // Slightly noisy normal: a tiny second direction must not move the point sideways.
        q.add(
            DVec3::new(0.5, 1.0, 0.4),
            DVec3::new(1e-4, 0.0, 1.0).normalize(),
        );
        let x = q.solve(0.1);
        let c = q.mass_point();
        assert!((x.z - 0.4).abs() < 1e-3);
        assert!(
            (x.x - c.x).abs() < 1e-3 && (x.y - c.y).abs() < 1e-3,
            "{x:?} vs {c:?}"
        );
    }
}
