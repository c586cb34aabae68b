//! Setting an I-patch's weights from points: the one-point formula for the bounds' weight `w`,
//! and least squares over many points.

use crate::error::OpsError;

/// The bounds' weight `w` that makes the I-patch with weights `w` vanish at a point whose
/// [`super::ipatch_terms`] are `terms`: `w = −Σ wᵢ·termᵢ / ΠBᵢᵉ`. The slides print the
/// quotient without its minus sign; with it the patch passes through the point.
pub fn weight_through_point(terms: &[f64], w: &[f32]) -> Result<f32, OpsError> {
    let Some((bounds, primaries)) = terms.split_last() else {
        return Err(OpsError::BadParameter(
            "the patch through a point needs its terms".into(),
        ));
    };
    if primaries.len() != w.len() || w.iter().any(|x| !x.is_finite()) {
        return Err(OpsError::BadParameter(format!(
            "the patch through a point needs {} finite weights, got {}",
            primaries.len(),
            w.len()
        )));
    }
    let sum: f64 = primaries.iter().zip(w).map(|(t, &wi)| t * wi as f64).sum();
    let scale = primaries
        .iter()
        .zip(w)
        .fold(0.0f64, |m, (t, &wi)| m.max((t * wi as f64).abs()));
    // A point on a bound (or where the bounds' product is lost beside the other terms) fixes
    // no w: every w gives the patch the same value there.
    if bounds.abs() <= 1e-12 * scale || *bounds == 0.0 {
        return Err(OpsError::BadParameter(
            "the point lies on a bound, where the patch's value does not depend on w; take a \
             point inside the patch"
                .into(),
        ));
    }
    let w0 = -sum / bounds;
    if !(w0 as f32).is_finite() {
        return Err(OpsError::BadParameter(format!(
            "the weight through the point, {w0:e}, is beyond single precision; take a point \
             farther from the bounds"
        )));
    }
    Ok(w0 as f32)
}

/// I-patch weights fitted to points meant to lie on the surface: least squares of the
/// patch's values at the points with the first weight held at 1 (the patch's scale is free).
/// `terms` holds [`super::ipatch_terms`] per point. Returns the weights and `w`.
pub fn fit_ipatch_weights(terms: &[Vec<f64>]) -> Result<(Vec<f32>, f32), OpsError> {
    let Some(first) = terms.first() else {
        return Err(OpsError::BadParameter(
            "fitting I-patch weights needs points".into(),
        ));
    };
    let n = first.len() - 1; // unknowns: w₂..wₙ and w
                             // Normal equations of min ‖A x + a₀‖², A the columns 1..=n, a₀ the first.
    let mut ata = vec![0.0f64; n * n];
    let mut atb = vec![0.0f64; n];
    for t in terms {
        for r in 0..n {
            atb[r] -= t[r + 1] * t[0];
            for c in 0..n {
                ata[r * n + c] += t[r + 1] * t[c + 1];
            }
        }
    }
    let x = solve_dense(&mut ata, &mut atb, n).ok_or_else(|| {
        OpsError::BadParameter(
            "the points do not determine the I-patch's weights (too few, or all on one \
             primary); give points spread over the blend"
                .into(),
        )
    })?;
    let mut w = vec![1.0f32];
    w.extend(x[..n - 1].iter().map(|&v| v as f32));
    Ok((w, x[n - 1] as f32))
}

/// Gaussian elimination with partial pivoting; `None` when singular.
fn solve_dense(a: &mut [f64], b: &mut [f64], n: usize) -> Option<Vec<f64>> {
    let scale = a
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    for k in 0..n {
        let pivot = (k..n).max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))?;
        if a[pivot * n + k].abs() <= 1e-12 * scale {
            return None;
        }
        for c in 0..n {
            a.swap(k * n + c, pivot * n + c);
        }
        b.swap(k, pivot);
        for i in k + 1..n {
            let f = a[i * n + k] / a[k * n + k];
            for c in k..n {
                a[i * n + c] -= f * a[k * n + c];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|c| a[k * n + c] * x[c]).sum();
        x[k] = (b[k] - s) / a[k * n + k];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::super::{ipatch, ipatch_terms, Continuity};
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_one_point_weight_puts_the_patch_through_the_point() {
        // Two planes x = 0, y = 0 and a sphere, bounds x − 1, y − 1, z − 1, weights (1, 2, 0.5).
        let primaries = |p: Vec3| [p.x, p.y, p.length() - 0.9];
        let bounds = |p: Vec3| [p.x - 1.0, p.y - 1.0, p.z - 1.0];
        let w = [1.0f32, 2.0, 0.5];
        for n in 1..=3 {
            let order = Continuity::new(n).unwrap();
            for q in [Vec3::new(-0.3, -0.4, 0.2), Vec3::new(0.2, -0.6, -0.5)] {
                let as64 = |v: [f32; 3]| v.map(|x| x as f64);
                let terms = ipatch_terms(&as64(primaries(q)), &as64(bounds(q)), order);
                let w0 = weight_through_point(&terms, &w).unwrap();
                // Independently: the patch evaluated in f32 at the point is zero to rounding,
                // and not zero a little off it.
                let at = |p: Vec3| ipatch(&primaries(p), &bounds(p), &w, w0, order);
                let size: f32 = w.iter().map(|x| x.abs()).sum();
                assert!(at(q).abs() < 1e-5 * size, "order {n} at {q}: {}", at(q));
                assert!(at(q + Vec3::splat(0.05)).abs() > 1e-3, "order {n} at {q}");
            }
        }
    }

    #[test]
    fn a_point_on_a_bound_fixes_no_weight() {
        let terms = ipatch_terms(&[-0.2, 0.3], &[0.0, -0.5], Continuity::G1);
        let e = weight_through_point(&terms, &[1.0, 1.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("on a bound") && !e.contains("--"), "{e}");
        let terms = ipatch_terms(&[-0.2, 0.3], &[0.4, -0.5], Continuity::G1);
        assert!(weight_through_point(&terms, &[1.0]).is_err());
        assert!(weight_through_point(&terms, &[1.0, f32::NAN]).is_err());
    }

    #[test]
    fn ipatch_weights_are_recovered_from_points() {
        // Two planes x = 0, y = 0 with bounds x − 1, y − 1; known weights (1, 2, w = −0.5).
        let (w, w0) = (vec![1.0f32, 2.0], -0.5f32);
        let f = |p: Vec3| {
            let (pp, b) = ([p.x, p.y], [p.x - 1.0, p.y - 1.0]);
            ipatch(&pp, &b, &w, w0, Continuity::G1)
        };
        // Points on the patch: on vertical lines, the first sign change of y ↦ f.
        let mut terms = Vec::new();
        for k in 1..16 {
            let x = k as f32 / 8.0 - 0.9;
            let at = |y: f32| f(Vec3::new(x, y, 0.0));
            let mut y0 = -3.0f32;
            while at(y0).signum() == at(y0 + 0.01).signum() && y0 < 0.98 {
                y0 += 0.01;
            }
            let (mut a, mut b) = (y0, y0 + 0.01);
            for _ in 0..50 {
                let m = 0.5 * (a + b);
                if at(m).signum() == at(a).signum() {
                    a = m;
                } else {
                    b = m;
                }
            }
            let y = 0.5 * (a + b);
            if at(y).abs() > 1e-4 {
                continue;
            }
            let (x, y) = (x as f64, y as f64);
            terms.push(ipatch_terms(&[x, y], &[x - 1.0, y - 1.0], Continuity::G1));
        }
        assert!(terms.len() >= 3, "{} points", terms.len());
        let (fw, fw0) = fit_ipatch_weights(&terms).unwrap();
        assert!(
            (fw[1] - 2.0).abs() < 1e-3 && (fw0 + 0.5).abs() < 1e-3,
            "{fw:?} {fw0}"
        );
        assert!(fit_ipatch_weights(&terms[..1]).is_err());
    }
}
