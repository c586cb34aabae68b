//! The indexed triangle mesh every stage passes around; reading and writing files is
//! `pgvol-mesh`'s job.

mod clean;
mod collinear;
mod components;
mod orient;
pub mod stats;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::frame;

/// The key of the undirected edge between vertices `a` and `b`: the smaller index in the high
/// half, so sorted keys put each edge's uses together, in order of (smaller, larger) vertex.
#[inline]
pub fn edge_key(a: u32, b: u32) -> u64 {
    ((a.min(b) as u64) << 32) | a.max(b) as u64
}

/// An indexed triangle mesh in the units of its source file.
///
/// Triangles are counter-clockwise seen from outside (right-hand rule gives the outward normal).
/// `positions` are local: the world position of a vertex is `offset + position`, with the
/// offset zero unless the mesh sits far from the origin (see [`crate::frame`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// The world translation of the local frame, in f64.
    pub offset: DVec3,
    /// Unit normals per position where the mesh's source knows them exactly (a contour gives
    /// the field's gradient direction at each vertex; zero where it has none), else empty.
    /// Writers use them only when there is one per position; the operations here that remove
    /// vertices carry them along, and those that turn faces drop them.
    pub normals: Vec<Vec3>,
}

impl Mesh {
    /// A mesh in the world frame (offset zero).
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            positions,
            triangles,
            offset: DVec3::ZERO,
            normals: Vec::new(),
        }
    }

    /// A mesh from f64 world positions, recentred when it sits far from the origin
    /// ([`frame::recentring_offset`]); near the origin the positions are rounded to f32 as
    /// they are.
    pub fn from_world(world: &[DVec3], triangles: Vec<[u32; 3]>) -> Self {
        let offset = frame::world_bounds(world)
            .map_or(DVec3::ZERO, |(lo, hi)| frame::recentring_offset(lo, hi));
        Self {
            positions: world.iter().map(|&p| frame::to_local(p, offset)).collect(),
            triangles,
            offset,
            normals: Vec::new(),
        }
    }

    /// The world position of vertex `i`.
    #[inline]
    pub fn world(&self, i: usize) -> DVec3 {
        frame::to_world(self.positions[i], self.offset)
    }

    /// The same surface with its local coordinates taken relative to `offset` (rounded once
    /// to f32 from the f64 world positions).
    pub fn in_frame(&self, offset: DVec3) -> Mesh {
        if offset == self.offset {
            return self.clone();
        }
        let positions = (0..self.positions.len())
            .map(|i| frame::to_local(self.world(i), offset))
            .collect();
        Mesh {
            positions,
            triangles: self.triangles.clone(),
            offset,
            // A translation turns no direction.
            normals: self.normals.clone(),
        }
    }

    /// The three corners of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Axis-aligned bounds of the vertices referenced by triangles, `None` when there are none.
    /// Taken over chunks of faces in parallel: a least and a greatest value do not depend on
    /// the order they are taken in.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.triangles
            .par_chunks(1 << 16)
            .filter_map(|faces| {
                let mut corners = faces.iter().flatten().map(|&i| self.positions[i as usize]);
                let first = corners.next()?;
                Some(corners.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
            })
            .reduce_with(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    }
}
