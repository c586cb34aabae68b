//! Surface nets through the `fast-surface-nets` crate, on chunks run in parallel.
//!
//! Each chunk holds the nodes of `CHUNK`³ cells plus one node layer on every side; the crate
//! makes quads only for edges it owns (those not on the chunk's upper faces nor on a lower face
//! along the other two axes), so chunks placed every `CHUNK` nodes own every edge exactly once.
//! Vertices are keyed by their global cell, which welds the copies that neighbouring chunks make
//! of the cells on their shared border.

use fast_surface_nets::ndshape::{ConstShape, ConstShape3u32};
use fast_surface_nets::{surface_nets as fsn, SurfaceNetsBuffer};
use glam::{IVec3, Vec3};
use pgvol_mesh::Mesh;
use rayon::prelude::*;

use crate::field::Field;
use crate::project::project;
use crate::quads::split_quad;
use crate::samples::Samples;

/// Cells per chunk along each axis; 32³ keeps a chunk's 34³ values (150 kB) in cache.
const CHUNK: usize = 32;
const SIDE: u32 = CHUNK as u32 + 2;
type ChunkShape = ConstShape3u32<SIDE, SIDE, SIDE>;

/// Kept clear of the cell faces, as in dual contouring, so the vertices of a quad project along
/// its edge into four distinct quadrants.
const CELL_MARGIN: f32 = 1e-3;
const NEWTON_STEPS: usize = 3;

struct ChunkOut {
    /// Global cell key and first estimate (world position) of each vertex the quads use.
    vertices: Vec<(u64, Vec3)>,
    /// Quads as global cell keys, in winding order seen from outside.
    quads: Vec<[u64; 4]>,
}

pub(crate) fn surface_nets(samples: &Samples, field: &dyn Field) -> Mesh {
    let n = samples.dims;
    let counts = n.map(|d| (d - 1) / CHUNK + 1);
    let chunks: Vec<[usize; 3]> = (0..counts[2])
        .flat_map(|z| (0..counts[1]).flat_map(move |y| (0..counts[0]).map(move |x| [x, y, z])))
        .collect();
    let outs: Vec<ChunkOut> = chunks
        .par_iter()
        .map_init(
            || (vec![0f32; ChunkShape::USIZE], SurfaceNetsBuffer::default()),
            |(buf, out), &c| chunk(samples, c.map(|x| x * CHUNK), buf, out),
        )
        .collect();

    // Weld: one vertex per cell, keeping the first copy in chunk order.
    let mut vertices: Vec<(u64, Vec3)> = outs
        .iter()
        .flat_map(|o| o.vertices.iter().copied())
        .collect();
    vertices.sort_by_key(|v| v.0);
    vertices.dedup_by_key(|v| v.0);
    assert!(vertices.len() < u32::MAX as usize, "too many vertices");
    let keys: Vec<u64> = vertices.iter().map(|v| v.0).collect();
    let positions: Vec<Vec3> = vertices
        .par_iter()
        .map(|&(key, p)| {
            let cell = cell_of(samples, key);
            let lo = samples.node(cell) + Vec3::splat(CELL_MARGIN * samples.spacing);
            let hi = samples.node(cell.map(|x| x + 1)) - Vec3::splat(CELL_MARGIN * samples.spacing);
            project(field, p.clamp(lo, hi), samples.iso, lo, hi, NEWTON_STEPS)
        })
        .collect();

    let triangles: Vec<[u32; 3]> = outs
        .par_iter()
        .flat_map_iter(|o| {
            o.quads.iter().flat_map(|q| {
                let ring = q.map(|k| keys.binary_search(&k).expect("welded vertex") as u32);
                let cells = q
                    .map(|k| cell_of(samples, k).map(|x| x as i32))
                    .map(IVec3::from_array);
                // The cells share the quad's edge axis; the ring's turn about it gives the
                // outward direction along the edge.
                let dir = (cells[2] - cells[0]).cross(cells[3] - cells[1]).as_vec3();
                let p = ring.map(|i| positions[i as usize]);
                split_quad(p, dir).map(|t| t.map(|c| ring[c]))
            })
        })
        .collect();
    Mesh::new(positions, triangles)
}

fn cell_of(samples: &Samples, key: u64) -> [usize; 3] {
    let (cx, cy) = (samples.dims[0] - 1, samples.dims[1] - 1);
    let key = key as usize;
    [key % cx, (key / cx) % cy, key / (cx * cy)]
}

/// Surface nets of the chunk whose own cells start at node `start`; it reads nodes from
/// `start - 1` to `start + CHUNK`, with nodes off the grid outside.
fn chunk(
    samples: &Samples,
    start: [usize; 3],
    buf: &mut [f32],
    out: &mut SurfaceNetsBuffer,
) -> ChunkOut {
    let n = samples.dims;
    // Values off the grid and NaN are outside; their magnitude only affects first estimates.
    let outside = samples.spacing;
    let mut any_inside = false;
    let mut any_outside = false;
    let side = SIDE as usize;
    // Grid node of chunk-local coordinate `l` along axis `a`, if on the grid.
    let node = |a: usize, l: usize| (start[a] + l).checked_sub(1).filter(|&g| g < n[a]);
    for z in 0..side {
        for y in 0..side {
            let row = &mut buf[side * (y + side * z)..side * (y + 1 + side * z)];
            let (Some(k), Some(j)) = (node(2, z), node(1, y)) else {
                row.fill(outside);
                any_outside = true;
                continue;
            };
            for (x, v) in row.iter_mut().enumerate() {
                *v = match node(0, x) {
                    Some(i) => {
                        let d = samples.values[samples.index(i, j, k)] - samples.iso;
                        if d.is_nan() {
                            outside
                        } else {
                            d
                        }
                    }
                    None => outside,
                };
                any_inside |= *v < 0.0;
                any_outside |= *v >= 0.0;
            }
        }
    }
    let mut result = ChunkOut {
        vertices: Vec::new(),
        quads: Vec::new(),
    };
    if !(any_inside && any_outside) {
        return result;
    }
    fsn(buf, &ChunkShape {}, [0; 3], [SIDE - 1; 3], out);

    // Global cell of each local vertex, or None for cells reaching off the grid (their quads
    // are dropped, leaving the surface open at the grid border as marching cubes does).
    let global: Vec<Option<[usize; 3]>> = out
        .surface_points
        .iter()
        .map(|p| {
            let mut c = [0usize; 3];
            for a in 0..3 {
                c[a] = (start[a] + p[a] as usize).checked_sub(1)?;
                if c[a] + 1 >= n[a] {
                    return None;
                }
            }
            Some(c)
        })
        .collect();
    let key = |c: [usize; 3]| (c[0] + (n[0] - 1) * (c[1] + (n[1] - 1) * c[2])) as u64;
    let mut used = vec![false; global.len()];
    for tri in out.indices.chunks_exact(6) {
        let Some(ring) = ring_of(tri) else { continue };
        let Some(cells) = ring
            .iter()
            .map(|&v| global[v as usize])
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        result.quads.push([0, 1, 2, 3].map(|i| key(cells[i])));
        for v in ring {
            if !used[v as usize] {
                used[v as usize] = true;
                let local = out.surface_points[v as usize];
                let offset = Vec3::from_array(out.positions[v as usize])
                    - Vec3::from_array(local.map(|x| x as f32));
                let cell = global[v as usize].expect("checked above");
                let p = samples.node(cell) + offset * samples.spacing;
                result.vertices.push((key(cell), p));
            }
        }
    }
    result
}

/// The quad of two triangles sharing a diagonal, in their winding order.
fn ring_of(t: &[u32]) -> Option<[u32; 4]> {
    let (a, b) = (&t[0..3], &t[3..6]);
    let unique = *b.iter().find(|v| !a.contains(v))?;
    for s in 0..3 {
        let (x, y, z) = (a[s], a[(s + 1) % 3], a[(s + 2) % 3]);
        // The shared diagonal runs x -> y in the first triangle and y -> x in the second.
        let reversed = (0..3).any(|i| b[i] == y && b[(i + 1) % 3] == x);
        if reversed {
            return Some([x, unique, y, z]);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_the_quad_of_a_split() {
        // Quad 0 1 2 3 split along 0-2 and along 1-3.
        assert_eq!(ring_of(&[0, 1, 2, 0, 2, 3]), Some([2, 3, 0, 1]));
        assert_eq!(ring_of(&[1, 2, 3, 1, 3, 0]), Some([3, 0, 1, 2]));
    }
}
