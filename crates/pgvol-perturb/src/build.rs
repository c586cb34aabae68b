//! The iterative conversion of a mesh into a [`PerturbationField`]: a base quadric fitted by
//! least squares, then perturbations added one at a time where the vertices are farthest from
//! the zero set, each accepted only if it lowers the paper's functional, the sum of `|M|` over
//! the vertices.
//!
//! One step (see `docs/perturbation.md` for the choices the paper leaves open):
//! 1. the seed is the vertex with the largest deviation estimate `|M| / |∇M|`;
//! 2. for each trial radius, ten vertices of the seed's sign of `M` within that radius
//!    (the seed and nine spread by farthest-point sampling) give the rows `m(uᵢ)` and the
//!    right-hand sides `|M(Pᵢ)|^(1/3)`, so that `M + f Q³` with `f = −sign M` vanishes there;
//! 3. the 10 × 10 system is solved exactly when its solution is a bounded bump, otherwise in
//!    the least-squares sense with a growing pull toward a spherical bump at the seed; a bump
//!    reaching too far or peaking too high is refused;
//! 4. the trial lowering the functional most, without turning more probes (points a little
//!    outside and inside along the normals, and the caller's sign points) to the wrong side,
//!    is kept.
//!
//! A seed whose every trial fails is set aside until a later term changes its neighbourhood;
//! the loop stops at the tolerance, at the function budget or when no seed is left.

use std::time::Instant;

use glam::{DVec3, Vec3};
use pgvol_core::Mesh;
use serde::Serialize;

use crate::descent::refine;
use crate::field::{Perturbation, PerturbationField};
use crate::point_grid::PointGrid;
use crate::quadric::{self, monomials, Quadric, TERMS};
use crate::trial::{evaluate, Refusal, State, Trial};

/// Points per perturbation, as in the paper.
pub const POINTS_PER_TERM: usize = 10;

/// Trial radii per seed, doubling from [`RADIUS_EDGES`] mean edge lengths.
pub const TRIAL_RADII: usize = 4;

/// The smallest trial radius, in mean edge lengths.
pub const RADIUS_EDGES: f64 = 2.0;

/// A bump may reach at most this many trial radii from its seed, so each term stays local.
pub const MAX_REACH: f64 = 2.0;

/// A bump's apex may exceed the largest of its ten right-hand sides by at most this factor:
/// a narrow quadric through ten points can peak far above them between or beside them, which
/// makes a steep field and surface pieces away from the mesh.
pub const MAX_PEAK_RATIO: f64 = 2.0;

/// Probe offset along the vertex normals, in mean edge lengths.
pub const PROBE_EDGES: f64 = 0.25;

/// Offset of the base fit's off-surface targets, as a fraction of the diagonal.
pub const BASE_OFFSET: f64 = 0.01;

/// Pulls toward the prior tried in turn (after the exact solve for perturbations).
const LAMBDAS: [f64; 6] = [1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4];

/// How far the conversion goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerturbOptions {
    /// Most perturbations added (default 2000).
    pub max_functions: usize,
    /// Stop once every vertex's deviation estimate is within this fraction of the bounding-box
    /// diagonal (default 0.001, 0.1 %).
    pub tolerance: f64,
    /// Most descent steps on each chosen perturbation's coefficients (the paper's optimisation
    /// step; 0 keeps the solved quadric as it is). Default [`DESCENT_STEPS`].
    pub descent_steps: usize,
}

/// Default descent steps per perturbation.
pub const DESCENT_STEPS: usize = 20;

impl Default for PerturbOptions {
    fn default() -> Self {
        Self {
            max_functions: 2000,
            tolerance: 1e-3,
            descent_steps: DESCENT_STEPS,
        }
    }
}

/// Why the loop ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// Every vertex within the tolerance.
    Tolerance,
    /// The function budget was spent.
    MaxFunctions,
    /// No vertex beyond the tolerance had a perturbation that lowered the error.
    NoImprovement,
    /// The caller asked to stop.
    Cancelled,
}

/// What the conversion did, deviations in mesh units.
#[derive(Clone, Debug, Serialize)]
pub struct PerturbReport {
    /// Perturbations in the field: the loop's plus the clearing bumps.
    pub functions: usize,
    /// Perturbations the paper's loop added.
    pub loop_functions: usize,
    /// Sign points given, and how many were on the wrong side of the base quadric, after the
    /// loop (before its clearing pass) and at the end.
    pub sign_points: usize,
    pub wrong_side_of_base: usize,
    pub wrong_side_before_clearing: usize,
    pub wrong_side_after: usize,
    pub vertices: usize,
    pub diagonal: f64,
    /// Mean and largest vertex deviation estimate of the base quadric alone.
    pub base_mean: f64,
    pub base_max: f64,
    /// The same after the last perturbation.
    pub mean: f64,
    pub max: f64,
    /// The functional the loop lowers, the mean of `|M|` over the vertices, for the base
    /// quadric alone and after each accepted perturbation (never increasing).
    pub base_functional: f64,
    pub history: Vec<f64>,
    /// Whether the base quadric took the exact least-squares fit (else it was pulled toward a
    /// sphere to stay an ellipsoid).
    pub base_exact: bool,
    /// Trial perturbations evaluated and seeds set aside.
    pub trials: usize,
    pub seeds_set_aside: usize,
    /// Perturbations whose ten-point system was solved exactly.
    pub exact_solves: usize,
    /// Descent steps taken on the chosen perturbations' coefficients (the paper's optimisation).
    pub descent_steps: usize,
    /// Trial radii refused at the seeds, and seeds left without a bump, by reason.
    pub refusals: Refusals,
    pub stop: StopReason,
    pub seconds: f64,
}

/// Why a mesh could not be converted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PerturbError {
    #[error("the mesh has {0} vertices; a quadric needs at least {POINTS_PER_TERM}")]
    TooFewVertices(usize),
    #[error("the base quadric could not be fitted (the vertices are degenerate)")]
    BaseFit,
}

/// Unit area-weighted vertex normals.
fn vertex_normals(mesh: &Mesh) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
        let face = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += face;
        }
    }
    n.iter().map(|v| v.normalize_or_zero()).collect()
}

fn mean_edge(mesh: &Mesh) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            sum += (mesh.positions[a as usize] - mesh.positions[b as usize]).length() as f64;
            count += 1;
        }
    }
    sum / count.max(1) as f64
}

/// The base quadric: least squares on `F(P) = 0`, `F(P ± δn) = ±δ` over the vertices,
/// kept an ellipsoid (one closed zero set, no sheets crossing the volume) by pulling it toward
/// the sphere through the vertices' mean radius when the plain fit is not one.
fn fit_base(points: &[DVec3], normals: &[DVec3], diagonal: f64) -> Option<(Quadric, bool)> {
    let (lo, hi) = points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let centre = 0.5 * (lo + hi);
    let scale = 0.5 * diagonal;
    let delta = BASE_OFFSET * diagonal;
    let stride = points.len().div_ceil(20_000).max(1);
    let (mut rows, mut targets) = (Vec::new(), Vec::new());
    for (p, n) in points.iter().zip(normals).step_by(stride) {
        for (offset, target) in [(0.0, 0.0), (delta, delta), (-delta, -delta)] {
            rows.push(monomials((*p + *n * offset - centre) / scale));
            targets.push(target);
        }
    }
    let rho = points.iter().map(|p| (*p - centre).length()).sum::<f64>() / points.len() as f64;
    let rho = rho.max(1e-9 * diagonal);
    let k = scale * scale / (2.0 * rho);
    let prior = [k, k, k, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.5 * rho];
    let weight = rows.len() as f64;
    for (attempt, lambda) in std::iter::once(0.0).chain(LAMBDAS).enumerate() {
        if let Some(q) = quadric::least_squares(&rows, &targets, &prior, lambda * weight) {
            let quad = Quadric { centre, scale, q };
            if quad.is_ellipsoid() {
                return Some((quad, attempt == 0));
            }
        }
    }
    None
}

/// Deviation estimate of one vertex from its value and gradient.
#[inline]
fn deviation(v: f64, g: DVec3) -> f64 {
    v.abs() / g.length().max(1e-300)
}

/// How many trial perturbations were refused, and why, over the whole loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Refusals {
    /// Fewer than ten vertices of the seed's sign within the trial radius.
    pub too_few_points: usize,
    /// No solve (exact or pulled toward the prior) gave a local bump.
    pub not_local: usize,
    /// Seeds whose best bump (after the descent) did not lower the functional.
    pub no_gain: usize,
    /// The bump put more probes on the wrong side.
    pub probes: usize,
}

/// The ten points for a seed: the seed, then the farthest from those chosen, among the
/// vertices within `radius` whose field value has the seed's sign.
fn pick_points(state: &State, seed: usize, radius: f64) -> Option<Vec<usize>> {
    let c = state.points[seed];
    let sign = state.value[seed].signum();
    let r = Vec3::splat(radius as f32);
    let mut near = Vec::new();
    state.point_grid.for_each_in_box(
        (c - radius).as_vec3() - r * 1e-3,
        (c + radius).as_vec3() + r * 1e-3,
        |i| {
            let i = i as usize;
            if (state.points[i] - c).length() <= radius
                && state.value[i].signum() == sign
                && state.value[i] != 0.0
            {
                near.push(i);
            }
        },
    );
    if near.len() < POINTS_PER_TERM {
        return None;
    }
    let mut gap: Vec<f64> = near
        .iter()
        .map(|&i| (state.points[i] - c).length_squared())
        .collect();
    let mut chosen = vec![seed];
    while chosen.len() < POINTS_PER_TERM {
        let (k, _) = gap.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
        let pick = near[k];
        chosen.push(pick);
        for (g, &i) in gap.iter_mut().zip(&near) {
            *g = g.min((state.points[i] - state.points[pick]).length_squared());
        }
    }
    Some(chosen)
}

/// The perturbation through `chosen` around `seed`, or `None` when no pull keeps it a local
/// bump. Returns whether the exact ten-point solve was used, and the largest right-hand side.
fn solve_term(
    state: &State,
    seed: usize,
    chosen: &[usize],
    radius: f64,
) -> Option<(Perturbation, bool, f64)> {
    let centre = state.points[seed];
    let mut rows = [[0.0; TERMS]; TERMS];
    let mut targets = [0.0; TERMS];
    for (k, &i) in chosen.iter().enumerate() {
        rows[k] = monomials((state.points[i] - centre) / radius);
        targets[k] = state.value[i].abs().cbrt();
    }
    let factor = -state.value[seed].signum();
    let s0 = targets[0];
    let prior = [-s0, -s0, -s0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, s0];
    let highest = targets.iter().cloned().fold(0.0, f64::max);
    let local = |q: [f64; TERMS]| {
        let quadric = Quadric {
            centre,
            scale: radius,
            q,
        };
        let ok = quadric.positive_reach().is_some_and(|r| r <= MAX_REACH)
            && quadric
                .peak()
                .is_some_and(|p| p <= MAX_PEAK_RATIO * highest);
        ok.then_some(Perturbation { quadric, factor })
    };
    if let Some(term) = quadric::interpolate(&rows, &targets).and_then(local) {
        return Some((term, true, highest));
    }
    LAMBDAS
        .iter()
        .find_map(|&l| quadric::least_squares(&rows, &targets, &prior, l).and_then(local))
        .map(|t| (t, false, highest))
}

/// Converts `mesh` into a perturbation field. `sign_points` are points off the surface with
/// their signed distance (negative inside), from any exact source: no perturbation may turn
/// more of them to the wrong side, and after the loop those still on the wrong side are
/// cleared (by spherical bumps that reach no vertex). `progress` gets the fraction of the
/// function budget used and returns `false` to stop (the field so far is returned, marked
/// cancelled).
pub fn build(
    mesh: &Mesh,
    sign_points: &[(Vec3, f32)],
    options: &PerturbOptions,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<(PerturbationField, PerturbReport), PerturbError> {
    let start = Instant::now();
    let n = mesh.positions.len();
    if n < POINTS_PER_TERM {
        return Err(PerturbError::TooFewVertices(n));
    }
    let points: Vec<DVec3> = mesh.positions.iter().map(|p| p.as_dvec3()).collect();
    let normals = vertex_normals(mesh);
    let (lo, hi) = points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let diagonal = (hi - lo).length();
    let edge = mean_edge(mesh).max(1e-9 * diagonal);
    let (base, base_exact) = fit_base(&points, &normals, diagonal).ok_or(PerturbError::BaseFit)?;

    let probe_offset = PROBE_EDGES * edge;
    let mut probes: Vec<DVec3> = [1.0, -1.0]
        .iter()
        .flat_map(|s| {
            points
                .iter()
                .zip(&normals)
                .map(move |(p, n)| *p + *n * (s * probe_offset))
        })
        .collect();
    let mut probe_outside: Vec<bool> = (0..2 * n).map(|i| i < n).collect();
    for &(p, d) in sign_points {
        if d != 0.0 && d.is_finite() && p.is_finite() {
            probes.push(p.as_dvec3());
            probe_outside.push(d > 0.0);
        }
    }
    let cell = (RADIUS_EDGES * edge) as f32;
    let as_f32 = |v: &[DVec3]| v.iter().map(|p| p.as_vec3()).collect::<Vec<_>>();
    let (value, gradient): (Vec<f64>, Vec<DVec3>) =
        points.iter().map(|&p| base.value_gradient(p)).unzip();
    let mut state = State {
        point_grid: PointGrid::new(&as_f32(&points), cell),
        probe_grid: PointGrid::new(&as_f32(&probes), cell),
        probe_value: probes.iter().map(|&p| base.value(p)).collect(),
        probes,
        probe_outside,
        points,
        value,
        gradient,
    };

    let deviations = |s: &State| -> Vec<f64> {
        s.value
            .iter()
            .zip(&s.gradient)
            .map(|(&v, &g)| deviation(v, g))
            .collect()
    };
    // The base quadric's sheets far from every vertex are cleared first, so that the loop's
    // rule (no probe turned to the wrong side) starts from a field with none there.
    let wrong_base = count_wrong(&state);
    let mut terms = Vec::new();
    clear_wrong_sides(&mut state, sign_points, &mut terms);
    let clearing_terms = terms.len();
    let mut dev = deviations(&state);
    let mean_of = |d: &[f64]| d.iter().sum::<f64>() / d.len() as f64;
    let max_of = |d: &[f64]| d.iter().cloned().fold(0.0, f64::max);
    let (base_mean, base_max) = (mean_of(&dev), max_of(&dev));
    let mut sum: f64 = state.value.iter().map(|v| v.abs()).sum();
    let base_functional = sum / n as f64;
    let limit = options.tolerance * diagonal;
    let mut set_aside = vec![false; n];
    let mut history = Vec::new();
    let (mut trials, mut seeds_set_aside, mut exact_solves, mut descent_steps) = (0, 0, 0, 0);
    let mut refusals = Refusals::default();
    let stop = loop {
        let added = terms.len() - clearing_terms;
        if added >= options.max_functions {
            break StopReason::MaxFunctions;
        }
        if !progress(added as f64 / options.max_functions.max(1) as f64) {
            break StopReason::Cancelled;
        }
        let worst = (0..n)
            .filter(|&i| !set_aside[i])
            .max_by(|&a, &b| dev[a].total_cmp(&dev[b]));
        let seed = match worst {
            Some(i) if dev[i] > limit => i,
            _ if max_of(&dev) <= limit => break StopReason::Tolerance,
            _ => break StopReason::NoImprovement,
        };
        let mut best: Option<(Trial, bool, f64)> = None;
        if state.value[seed] != 0.0 {
            for k in 0..TRIAL_RADII {
                let radius = RADIUS_EDGES * edge * f64::from(1u32 << k);
                let Some(chosen) = pick_points(&state, seed, radius) else {
                    refusals.too_few_points += 1;
                    continue;
                };
                let Some((term, exact, highest)) = solve_term(&state, seed, &chosen, radius) else {
                    refusals.not_local += 1;
                    continue;
                };
                trials += 1;
                match evaluate(&state, term) {
                    Ok(trial) => {
                        if best.as_ref().is_none_or(|(b, _, _)| trial.gain > b.gain) {
                            best = Some((trial, exact, highest));
                        }
                    }
                    Err(Refusal::Unbounded) => refusals.not_local += 1,
                    Err(Refusal::Probes) => refusals.probes += 1,
                }
            }
        }
        // The paper's optimisation step, then its acceptance rule: the functional must fall.
        let best = best.map(|(trial, exact, highest)| {
            let (trial, steps) = refine(
                &state,
                trial,
                MAX_REACH,
                MAX_PEAK_RATIO * highest,
                options.descent_steps,
            );
            descent_steps += steps;
            (trial, exact)
        });
        let tried = best.is_some();
        let Some((trial, exact)) = best.filter(|(t, _)| t.gain > 0.0) else {
            refusals.no_gain += tried as usize;
            set_aside[seed] = true;
            seeds_set_aside += 1;
            continue;
        };
        exact_solves += exact as usize;
        for &(i, v, g) in &trial.vertices {
            let i = i as usize;
            state.gradient[i] = g;
            sum += v.abs() - state.value[i].abs();
            state.value[i] = v;
            dev[i] = deviation(v, g);
            // Its neighbourhood changed: a set-aside vertex may now find a term.
            set_aside[i] = false;
        }
        for &(i, v) in &trial.probes {
            state.probe_value[i as usize] = v;
        }
        terms.push(trial.term);
        history.push(sum / n as f64);
    };
    let paper_terms = terms.len() - clearing_terms;
    let wrong_before = count_wrong(&state);
    if stop != StopReason::Cancelled {
        clear_wrong_sides(&mut state, sign_points, &mut terms);
    }
    let wrong_after = count_wrong(&state);
    let dev = deviations(&state);
    let field = PerturbationField::new(base, terms).expect("every accepted term is a bounded bump");
    let report = PerturbReport {
        functions: field.terms().len(),
        loop_functions: paper_terms,
        sign_points: sign_points.len(),
        wrong_side_of_base: wrong_base,
        wrong_side_before_clearing: wrong_before,
        wrong_side_after: wrong_after,
        vertices: n,
        diagonal,
        base_mean,
        base_max,
        mean: mean_of(&dev),
        max: max_of(&dev),
        base_functional,
        history,
        base_exact,
        trials,
        seeds_set_aside,
        exact_solves,
        descent_steps,
        refusals,
        stop,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((field, report))
}

fn count_wrong(state: &State) -> usize {
    let first = 2 * state.points.len();
    (first..state.probes.len())
        .filter(|&i| state.wrong(i, state.probe_value[i]))
        .count()
}

/// Clears sign points left on the wrong side, deepest first, each with a spherical bump
/// `f · Q³`, `Q = a (1 − |x − s|² / ρ²)`, centred on the point `s` with `ρ` 0.9 of its distance to
/// the surface: the ball holds no surface, so the bump moves no vertex and turns no point of
/// the right side to the wrong one; `a³ = |M(s)| + |d(s)|` puts the point on its side with a
/// margin of its distance. The paper's loop pins the zero set at the vertices only, so
/// without this a sheet of the base quadric far from every vertex would stay.
fn clear_wrong_sides(
    state: &mut State,
    sign_points: &[(Vec3, f32)],
    terms: &mut Vec<Perturbation>,
) {
    let first = 2 * state.points.len();
    let mut order: Vec<usize> = (first..state.probes.len()).collect();
    let depth: Vec<f64> = sign_points
        .iter()
        .filter(|(p, d)| *d != 0.0 && d.is_finite() && p.is_finite())
        .map(|(_, d)| d.abs() as f64)
        .collect();
    order.sort_by(|&a, &b| {
        depth[b - first]
            .total_cmp(&depth[a - first])
            .then(a.cmp(&b))
    });
    for i in order {
        let v = state.probe_value[i];
        if !state.wrong(i, v) {
            continue;
        }
        let rho = 0.9 * depth[i - first];
        let a = (v.abs() + depth[i - first]).cbrt();
        let term = Perturbation {
            quadric: Quadric {
                centre: state.probes[i],
                scale: rho,
                q: [-a, -a, -a, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, a],
            },
            factor: if state.probe_outside[i] { 1.0 } else { -1.0 },
        };
        let Some((lo, hi)) = term.quadric.positive_box() else {
            continue;
        };
        let inside = |p: DVec3| p.cmpge(lo).all() && p.cmple(hi).all();
        state
            .probe_grid
            .for_each_in_box(lo.as_vec3(), hi.as_vec3(), |k| {
                let p = state.probes[k as usize];
                if inside(p) {
                    if let Some((r, _)) = term.shape(p) {
                        state.probe_value[k as usize] += term.factor * r;
                    }
                }
            });
        // No vertex lies in the ball; the update keeps the state exact all the same.
        state
            .point_grid
            .for_each_in_box(lo.as_vec3(), hi.as_vec3(), |k| {
                let p = state.points[k as usize];
                if inside(p) {
                    if let Some((r, dr)) = term.shape(p) {
                        state.value[k as usize] += term.factor * r;
                        state.gradient[k as usize] += term.factor * dr;
                    }
                }
            });
        terms.push(term);
    }
}
