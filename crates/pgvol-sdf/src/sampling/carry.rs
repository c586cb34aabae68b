//! Carries a winding number from point to point along a row of bricks.
//!
//! Across a segment the winding number changes by exactly ±1 per triangle crossed and otherwise
//! only smoothly, by at most the gradient bound of the rims (`rims.rs`) times the length. So a
//! value known up to an error bound stays known, with the error grown by that drift, and its
//! side of 1/2 is certain while the error is smaller than its distance to 1/2. Points where it
//! is not, or where a crossing is ambiguous on both the straight and two bent paths, are
//! evaluated afresh.

use glam::{Vec3, Vec3A};

use crate::sdf::MeshSdf;

/// What the carry needs to know about a segment.
pub(super) trait Segment {
    /// The change of the winding number across the triangles crossed from `a` to `b` (±1 each);
    /// `None` when a crossing is too close to an edge, a vertex or an end to count.
    fn jump(&self, a: Vec3A, b: Vec3A) -> Option<i32>;

    /// Where the path from `a` to `b` may bend (on the `side` given by its sign) so that both
    /// legs are segments `jump` can count; `None` when it may not.
    fn bend(&self, a: Vec3A, b: Vec3A, side: f32) -> Option<Vec3A>;

    /// A bound on the winding number's gradient along the segment. (Tighter bounds per
    /// segment were measured: they saved fewer evaluations than they cost.)
    fn gradient(&self) -> f32;
}

/// A winding number at a point: `|true − value| ≤ error`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Known {
    pub at: Vec3A,
    pub value: f32,
    pub error: f32,
}

#[derive(Default)]
pub(super) struct WindingCarry {
    /// The point carried on from, along the row.
    known: Option<Known>,
    /// The last point evaluated since: near rims, where the drift is large, it is usually
    /// nearer to the next node than `known`.
    evaluated: Option<Known>,
}

impl WindingCarry {
    /// The last point carried on from.
    pub fn last_point(&self) -> Option<Vec3A> {
        self.known.map(|k| k.at)
    }

    /// Starts afresh at the next point.
    pub fn forget(&mut self) {
        self.known = None;
        self.evaluated = None;
    }

    /// The winding number at `p`, which becomes the point carried on from. A carried value is
    /// kept only if it stays certain with `reserve` more error (the drift to the points that
    /// will be reached from it); otherwise `p` is evaluated.
    pub fn winding_at(
        &mut self,
        sdf: &MeshSdf,
        p: Vec3A,
        segment: &impl Segment,
        reserve: f32,
    ) -> Known {
        let known = self
            .known
            .or_else(|| outside_start(sdf, p))
            .and_then(|k| carried(k, p, segment, reserve))
            .unwrap_or_else(|| evaluated(sdf, p));
        self.known = Some(known);
        self.evaluated = None;
        known
    }

    /// The winding number at `p`, carried along a straight segment from the point carried on
    /// from (or from the last point evaluated), which stays the point carried on from: the
    /// nodes of a brick are all reached from points near them, so their drift bounds grow with
    /// that distance, not with a path through them.
    pub fn winding_near(&mut self, sdf: &MeshSdf, p: Vec3A, segment: &impl Segment) -> Known {
        if let Some(k) = self.evaluated.and_then(|k| carried(k, p, segment, 0.0)) {
            return k;
        }
        if let Some(k) = self.known.and_then(|k| carried(k, p, segment, 0.0)) {
            return k;
        }
        let known = evaluated(sdf, p);
        self.evaluated = Some(known);
        known
    }
}

/// The value `k` carried to `p`, if its side of 1/2 stays certain with `reserve` to spare.
fn carried(k: Known, p: Vec3A, segment: &impl Segment, reserve: f32) -> Option<Known> {
    if k.at == p {
        return Some(k);
    }
    // Jumps are whole numbers: the carried value is as far from 1/2 as its fractional part is,
    // whatever they turn out to be.
    let room = (k.value - k.value.floor() - 0.5).abs() - k.error - reserve;
    if room <= 0.0 {
        return None;
    }
    // The straight path first: the drift along it rules out most carries before any counting.
    if segment.gradient() * k.at.distance(p) >= room {
        return None;
    }
    let (jump, length) = path_jump(segment, k.at, p)?;
    let drift = segment.gradient() * length;
    if drift >= room {
        return None;
    }
    Some(Known {
        at: p,
        value: k.value + jump as f32,
        error: k.error + drift,
    })
}

/// The winding number's jump from `a` to `b` and the length of the path counted: the straight
/// segment, or when a crossing on it is unsure (it passes through an edge or a vertex, which
/// on extruded shapes happens at every height alike) a path bent to either side.
fn path_jump(segment: &impl Segment, a: Vec3A, b: Vec3A) -> Option<(i32, f32)> {
    if let Some(jump) = segment.jump(a, b) {
        return Some((jump, a.distance(b)));
    }
    [1.0, -1.0].into_iter().find_map(|side| {
        let m = segment.bend(a, b, side)?;
        let jump = segment.jump(a, m)? + segment.jump(m, b)?;
        Some((jump, a.distance(m) + m.distance(b)))
    })
}

/// A point off the segment from `a` to `b` by a quarter of its length, on one side (by the
/// sign of `side`) of it, in a direction that does not follow mesh or grid axes.
pub(super) fn bend_point(a: Vec3A, b: Vec3A, side: f32) -> Vec3A {
    const SKEWS: [Vec3A; 2] = [
        Vec3A::new(0.5773, 0.6118, 0.5407),
        Vec3A::new(-0.7072, 0.3162, 0.6325),
    ];
    let d = b - a;
    let across = SKEWS
        .iter()
        .map(|s| d.cross(*s))
        .max_by(|u, v| u.length_squared().total_cmp(&v.length_squared()))
        .unwrap_or(Vec3A::X)
        .normalize_or_zero();
    (a + b) * 0.5 + across * (0.25 * d.length() * side)
}

/// For a whole winding number, a start in line with `p` along x just outside the mesh's box,
/// where it is exactly 0: rows then begin without an evaluation.
fn outside_start(sdf: &MeshSdf, p: Vec3A) -> Option<Known> {
    let (min, max) = sdf.bvh().bounds()?;
    if !sdf.winding_is_whole() {
        return None;
    }
    let margin = (max - min).max_element() * 0.01 + min.x.abs() * 1e-6;
    Some(Known {
        at: Vec3A::new(min.x - margin, p.y, p.z),
        value: 0.0,
        error: 0.0,
    })
}

fn evaluated(sdf: &MeshSdf, p: Vec3A) -> Known {
    // Outside the box of a closed mesh the winding number is exactly 0.
    if sdf.winding_is_whole() && sdf.bvh().is_outside_box(p) {
        return Known {
            at: p,
            value: 0.0,
            error: 0.0,
        };
    }
    #[cfg(test)]
    sdf.sampler_windings
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let (value, error) = sdf.winding_with_error(Vec3::from(p));
    Known {
        at: p,
        value,
        error,
    }
}
