//! The conversion loop's state at the vertices and probes, and what a trial perturbation does
//! to it: the functional's decrease and the new values, or why it is refused.

use glam::DVec3;

use crate::field::Perturbation;
use crate::point_grid::PointGrid;

/// The loop's state at the vertices and probes.
pub(crate) struct State {
    pub(crate) points: Vec<DVec3>,
    pub(crate) value: Vec<f64>,
    pub(crate) gradient: Vec<DVec3>,
    /// Probes: points of known side, `P ± δn` along the vertex normals and the caller's sign
    /// points; a perturbation may not put more of them on the wrong side.
    pub(crate) probes: Vec<DVec3>,
    pub(crate) probe_value: Vec<f64>,
    pub(crate) probe_outside: Vec<bool>,
    pub(crate) point_grid: PointGrid,
    pub(crate) probe_grid: PointGrid,
}

impl State {
    /// Whether probe `i` is on the wrong side with value `v`.
    pub(crate) fn wrong(&self, i: usize, v: f64) -> bool {
        if self.probe_outside[i] {
            v <= 0.0
        } else {
            v >= 0.0
        }
    }
}

/// A perturbation tried at a seed, with its effect: the functional's decrease, the vertices'
/// new values and gradients and the probes' new values.
pub(crate) struct Trial {
    pub(crate) term: Perturbation,
    pub(crate) gain: f64,
    pub(crate) vertices: Vec<(u32, f64, DVec3)>,
    pub(crate) probes: Vec<(u32, f64)>,
}

/// Why a trial perturbation was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Refusal {
    /// It is not a bounded bump.
    Unbounded,
    /// It puts more probes on the wrong side.
    Probes,
}

/// `term`'s effect on the state (its gain may be negative: the descent may still make it
/// positive), or why it is refused: it puts more probes on the wrong side, or it is no bump.
pub(crate) fn evaluate(state: &State, term: Perturbation) -> Result<Trial, Refusal> {
    let (lo, hi) = term.quadric.positive_box().ok_or(Refusal::Unbounded)?;
    let inside = |p: DVec3| p.cmpge(lo).all() && p.cmple(hi).all();
    let (mut gain, mut vertices) = (0.0, Vec::new());
    state
        .point_grid
        .for_each_in_box(lo.as_vec3(), hi.as_vec3(), |i| {
            let p = state.points[i as usize];
            if !inside(p) {
                return;
            }
            if let Some((r, dr)) = term.shape(p) {
                let (v0, g0) = (state.value[i as usize], state.gradient[i as usize]);
                let (v, g) = (v0 + term.factor * r, g0 + term.factor * dr);
                gain += v0.abs() - v.abs();
                vertices.push((i, v, g));
            }
        });
    let (mut newly_wrong, mut probes) = (0i64, Vec::new());
    state
        .probe_grid
        .for_each_in_box(lo.as_vec3(), hi.as_vec3(), |i| {
            let p = state.probes[i as usize];
            if !inside(p) {
                return;
            }
            if let Some((r, _)) = term.shape(p) {
                let v0 = state.probe_value[i as usize];
                let v = v0 + term.factor * r;
                newly_wrong +=
                    state.wrong(i as usize, v) as i64 - state.wrong(i as usize, v0) as i64;
                probes.push((i, v));
            }
        });
    if newly_wrong > 0 {
        return Err(Refusal::Probes);
    }
    Ok(Trial {
        term,
        gain,
        vertices,
        probes,
    })
}
