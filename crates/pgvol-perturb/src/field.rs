//! The perturbation field `M(x) = F(x) + Σ fᵢ Rᵢ(x)`: a base quadric `F` plus local terms
//! `Rᵢ = Qᵢ³` where `Qᵢ ≥ 0` (zero elsewhere), each with a factor `fᵢ = ±1`. The cube keeps
//! the value and the gradient continuous where a term fades out. Evaluation visits only the
//! terms whose box contains the point, through a [`BoxTree`].

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::box_tree::BoxTree;
use crate::quadric::Quadric;

/// One local term `f · Q³` on `Q ≥ 0`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Perturbation {
    pub quadric: Quadric,
    /// −1 pulls the surface outward (lowers the field), +1 inward.
    pub factor: f64,
}

impl Perturbation {
    /// `(R, ∇R)` of the term without its factor: `(Q³, 3Q²∇Q)` where `Q > 0`, else zero.
    #[inline]
    pub fn shape(&self, p: DVec3) -> Option<(f64, DVec3)> {
        let (q, g) = self.quadric.value_gradient(p);
        (q > 0.0).then(|| (q * q * q, 3.0 * q * q * g))
    }
}

/// A base quadric plus perturbations, negative inside.
#[derive(Clone, Debug)]
pub struct PerturbationField {
    base: Quadric,
    terms: Vec<Perturbation>,
    boxes: Vec<(Vec3, Vec3)>,
    tree: BoxTree,
}

/// Why a list of terms does not make a field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PerturbationError {
    #[error("perturbation {0} is not a bounded bump (its positive region is not an ellipsoid)")]
    Unbounded(usize),
    #[error("perturbation {0} has a factor of {1}; it must be +1 or -1")]
    Factor(usize, f64),
    #[error("the {0} has a non-finite coefficient, centre or a scale that is not positive")]
    NotFinite(String),
    #[error("perturbation {0} reaches beyond the range of single precision")]
    TooLarge(usize),
}

fn check_quadric(q: &Quadric, what: impl Fn() -> String) -> Result<(), PerturbationError> {
    if q.centre.is_finite()
        && q.scale.is_finite()
        && q.scale > 0.0
        && q.q.iter().all(|c| c.is_finite())
    {
        Ok(())
    } else {
        Err(PerturbationError::NotFinite(what()))
    }
}

impl PerturbationField {
    /// The field of `base` and `terms`; every term must be a bounded bump with a factor of ±1.
    pub fn new(base: Quadric, terms: Vec<Perturbation>) -> Result<Self, PerturbationError> {
        check_quadric(&base, || "base quadric".into())?;
        let mut boxes = Vec::with_capacity(terms.len());
        for (i, t) in terms.iter().enumerate() {
            check_quadric(&t.quadric, || format!("perturbation {i}"))?;
            if t.factor != 1.0 && t.factor != -1.0 {
                return Err(PerturbationError::Factor(i, t.factor));
            }
            let (lo, hi) = t
                .quadric
                .positive_box()
                .ok_or(PerturbationError::Unbounded(i))?;
            // Rounded outward so that f32 boxes still hold every point where Q > 0.
            let pad = 1e-6 * (hi - lo).max_element().max(1e-30);
            let (lo, hi) = ((lo - pad).as_vec3(), (hi + pad).as_vec3());
            // A box beyond f32 cannot be queried (the tree's centres would be NaN).
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(PerturbationError::TooLarge(i));
            }
            boxes.push((lo, hi));
        }
        let tree = BoxTree::build(&boxes);
        Ok(Self {
            base,
            terms,
            boxes,
            tree,
        })
    }

    pub fn base(&self) -> &Quadric {
        &self.base
    }

    pub fn terms(&self) -> &[Perturbation] {
        &self.terms
    }

    /// The box of term `i`, where its quadric is positive.
    pub fn term_box(&self, i: usize) -> (Vec3, Vec3) {
        self.boxes[i]
    }

    /// Field value in double precision.
    pub fn value_f64(&self, p: DVec3) -> f64 {
        let mut v = self.base.value(p);
        self.tree.for_each_containing(p.as_vec3(), |i| {
            let t = &self.terms[i as usize];
            let q = t.quadric.value(p);
            if q > 0.0 {
                v += t.factor * q * q * q;
            }
        });
        v
    }

    /// Field value and gradient in double precision.
    pub fn value_gradient_f64(&self, p: DVec3) -> (f64, DVec3) {
        let (mut v, mut g) = self.base.value_gradient(p);
        self.tree.for_each_containing(p.as_vec3(), |i| {
            let t = &self.terms[i as usize];
            if let Some((r, dr)) = t.shape(p) {
                v += t.factor * r;
                g += t.factor * dr;
            }
        });
        (v, g)
    }

    pub fn value(&self, p: Vec3) -> f32 {
        self.value_f64(p.as_dvec3()) as f32
    }

    pub fn value_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let (v, g) = self.value_gradient_f64(p.as_dvec3());
        (v as f32, g.as_vec3())
    }

    /// The first-order distance estimate `M / |∇M|` (the field is not a distance: its scale
    /// changes along the surface), with the gradient normalised; `±f32::MAX` where the
    /// gradient vanishes.
    pub fn distance_estimate(&self, p: Vec3) -> (f32, Vec3) {
        let (v, g) = self.value_gradient_f64(p.as_dvec3());
        let n = g.length();
        if n > 0.0 && n.is_finite() {
            ((v / n) as f32, (g / n).as_vec3())
        } else {
            (f32::MAX.copysign(v as f32), Vec3::ZERO)
        }
    }
}
