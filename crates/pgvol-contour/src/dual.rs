//! Dual meshes with one vertex per surface component of each cell: dual contouring and surface
//! nets, which differ only in where that vertex goes.
//!
//! The components are the loops of the face-traced contour that marching cubes triangulates, so
//! the dual mesh is the polygonal dual of the marching cubes surface: each loop becomes a vertex,
//! each crossed grid edge a quad joining the vertices of the four loops through its crossing.
//! The dual of a closed manifold is a closed manifold, which carries over every guarantee of
//! the marching cubes topology. The one thing a triangle mesh cannot express is two distinct
//! dual edges between the same two vertices (a loop crossing a face twice, with the loop across
//! doing the same: a tunnel through the face); such edges get a vertex in their middle, and the
//! quads along them are fanned around their crossing instead of split in two.

use std::sync::atomic::Ordering::Relaxed;
use std::sync::atomic::{AtomicU32, AtomicU8};

use glam::{DVec3, Vec3};
use pgvol_core::Mesh;
use rayon::prelude::*;

use crate::cells::for_crossed_cells;
use crate::components::{components, ring_slot};
use crate::crossings::Crossings;
use crate::cube::{edge_axis, plane_axes, EDGE_START};
use crate::decider::joins_inside;
use crate::dual_options::{DualContourOptions, StoredVertices, MAX_OUTSIDE_REACH};
use crate::extract::EXTRA_FLAG;
use crate::field::Field;
use crate::project::project;
use crate::qef::Qef;
use crate::quads::split_quad;
use crate::samples::Samples;
use crate::samples::CROSSINGS_PART;
use crate::table::case_table;
use pgvol_core::progress::tick;

/// Fraction of the cell kept clear at each face when clamping, so vertices of neighbouring cells
/// never coincide and every quad projects along its edge onto four distinct open quadrants.
const CELL_MARGIN: f64 = 1e-3;

/// Longest move, in cells, of a smooth piece's vertex onto the zero set.
const MAX_PROJECTION: f32 = 0.25;

/// A plane vertex farther from the mass point than this many times the loop's own radius (the
/// largest distance of a crossing from the mass point) gives way to the mass point. A loop
/// around a sub-voxel blob has crossings a hundredth of a cell apart whose planes can meet a
/// fifth of a cell away, folding the blob inside out (found by the random-field topology test);
/// a corner or an edge of a sharp feature lies within a few loop radii.
const MAX_REACH: f64 = 4.0;

/// Newton steps taking a surface nets vertex onto the zero set. The mean of a loop's crossings
/// lies a fraction of a cell off the surface and each step squares that error (relative to the
/// curvature radius), so two reach float rounding on surfaces the grid resolves.
const NEWTON_STEPS: usize = 2;

/// Crossings per parallel task when building quads.
const QUAD_CHUNK: usize = 4096;

/// Marks an extra vertex key as a quad centre (otherwise it is a face segment midpoint).
const CENTRE_KEY: u64 = 1 << 63;

const UNSET: u32 = u32::MAX;

/// How the vertex of each loop is placed.
#[derive(Clone, Copy)]
pub(crate) enum Placement<'o> {
    /// At the least-squares meeting point of the crossings' tangent planes (dual contouring);
    /// the crossings must carry normals. Cells crossed once take the vertex the stored
    /// vertices give, when they give one.
    Planes(&'o DualContourOptions, Option<&'o StoredVertices<'o>>),
    /// At the mean of the crossings, moved onto the zero set (surface nets). Cells crossed
    /// once take the vertex the stored vertices give, when they give one.
    Mean(Option<&'o StoredVertices<'o>>),
}

impl<'o> Placement<'o> {
    /// The vertices given for cells crossed once, if any.
    fn stored(&self) -> Option<&'o StoredVertices<'o>> {
        match *self {
            Placement::Planes(_, stored) | Placement::Mean(stored) => stored,
        }
    }
}

struct CellVertices {
    positions: Vec<Vec3>,
    /// The lowest corner of each vertex's cell, when asked for.
    homes: Vec<Vec3>,
    double_faces: Vec<u8>,
    links: Vec<Link>,
}

/// A dual mesh and, when asked for, the cell each of its cell vertices belongs to.
#[derive(Clone, Debug, Default)]
pub struct DualMesh {
    pub mesh: Mesh,
    /// The lowest corner of the cell of each cell vertex, in the mesh's frame: one per vertex
    /// of the mesh but for the vertices after them, which lie on faces between cells (the
    /// middles of doubled dual edges). A vertex may lie outside its cell (see
    /// [`DualContourOptions::reach`]).
    pub homes: Vec<Vec3>,
}

/// Cell vertex `vertex` (part-local) is the corner `slot` of the quad of crossing `crossing`.
struct Link {
    crossing: u32,
    vertex: u32,
    slot: u8,
    /// Edge axis, and bit 2 set when the edge's lower node is inside.
    meta: u8,
}

/// Triangles of a run of crossings; indices with [`EXTRA_FLAG`] point into `extra`.
struct QuadRun {
    triangles: Vec<[u32; 3]>,
    extra: Vec<u64>,
}

/// Which cells get vertices, named by their lowest sample.
pub(crate) type CellKeep<'a> = dyn Fn([usize; 3]) -> bool + Sync + 'a;

/// The dual mesh of `crossings`; with `only`, just the vertices of the cells it keeps (with
/// their cells when `with_homes`) and no triangles.
pub(crate) fn dual_contour(
    samples: &Samples,
    crossings: &Crossings,
    field: &dyn Field,
    placement: Placement,
    with_homes: bool,
    only: Option<&CellKeep>,
) -> DualMesh {
    let verts = crossings;
    let blocks = crossings.blocks.active.len();
    let counter = samples.counter(CROSSINGS_PART, 1.0, blocks);
    let parts: Vec<CellVertices> = (0..blocks)
        .into_par_iter()
        .map(|slot| {
            tick(counter.as_ref());
            block_vertices(samples, verts, field, (placement, only), slot, with_homes)
        })
        .collect();
    if only.is_some() {
        let mut out = DualMesh::default();
        for part in parts {
            out.mesh.positions.extend_from_slice(&part.positions);
            out.homes.extend_from_slice(&part.homes);
        }
        return out;
    }

    // Each (crossing, ring slot) is written by exactly one cell, so the links can be stored in
    // parallel; the atomics only make that expressible, the result does not depend on order.
    let n_crossings = crossings.positions.len();
    let ring: Vec<[AtomicU32; 4]> = (0..n_crossings)
        .map(|_| [UNSET; 4].map(AtomicU32::new))
        .collect();
    let meta: Vec<AtomicU8> = (0..n_crossings).map(|_| AtomicU8::new(0)).collect();
    let mut firsts = Vec::with_capacity(parts.len());
    let mut n_vertices = 0u32;
    for part in &parts {
        firsts.push(n_vertices);
        n_vertices += part.positions.len() as u32;
    }
    parts.par_iter().zip(&firsts).for_each(|(part, &first)| {
        for link in &part.links {
            let g = link.crossing as usize;
            ring[g][link.slot as usize].store(first + link.vertex, Relaxed);
            meta[g].store(link.meta, Relaxed);
        }
    });
    let mut positions = Vec::with_capacity(n_vertices as usize);
    let mut double_faces = Vec::with_capacity(n_vertices as usize);
    let mut homes = Vec::with_capacity(if with_homes { n_vertices as usize } else { 0 });
    for part in &parts {
        positions.extend_from_slice(&part.positions);
        double_faces.extend_from_slice(&part.double_faces);
        homes.extend_from_slice(&part.homes);
    }
    drop(parts);
    assert!(positions.len() < EXTRA_FLAG as usize, "too many vertices");

    let runs: Vec<QuadRun> = ring
        .par_chunks(QUAD_CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut run = QuadRun {
                triangles: Vec::new(),
                extra: Vec::new(),
            };
            for (n, r) in chunk.iter().enumerate() {
                let g = (c * QUAD_CHUNK + n) as u32;
                quad(
                    samples,
                    verts,
                    &positions,
                    &double_faces,
                    g,
                    r.each_ref().map(|v| v.load(Relaxed)),
                    meta[g as usize].load(Relaxed),
                    &mut run,
                );
            }
            run
        })
        .collect();

    let mut keys: Vec<u64> = runs.iter().flat_map(|r| r.extra.iter().copied()).collect();
    keys.sort_unstable();
    keys.dedup();
    let first_extra = positions.len();
    assert!(
        first_extra + keys.len() < EXTRA_FLAG as usize,
        "too many vertices"
    );
    positions.extend(keys.iter().map(|&key| extra_position(samples, verts, key)));

    let mut triangles = Vec::with_capacity(runs.iter().map(|r| r.triangles.len()).sum());
    for run in runs {
        triangles.extend(run.triangles.iter().map(|t| {
            t.map(|v| {
                if v & EXTRA_FLAG == 0 {
                    v
                } else {
                    let key = run.extra[(v & !EXTRA_FLAG) as usize];
                    (first_extra + keys.binary_search(&key).unwrap()) as u32
                }
            })
        }));
    }
    DualMesh {
        mesh: Mesh::new(positions, triangles),
        homes,
    }
}

/// One vertex per loop of every cell owned by the active block at `slot`.
fn block_vertices(
    samples: &Samples,
    verts: &Crossings,
    field: &dyn Field,
    (placement, only): (Placement, Option<&CellKeep>),
    slot: usize,
    with_homes: bool,
) -> CellVertices {
    let table = case_table();
    let normals = &verts.normals;
    let inv_h = 1.0 / f64::from(samples.spacing);
    // About one vertex and four links per owned crossing, with room for the crossings of
    // neighbouring blocks that the block's cells also reach.
    let owned = verts.block_len(slot);
    let mut part = CellVertices {
        positions: Vec::with_capacity(owned + owned / 4),
        homes: Vec::new(),
        double_faces: Vec::with_capacity(owned + owned / 4),
        links: Vec::with_capacity(4 * owned + owned),
    };
    let block = verts.block(slot);
    let origin = block.origin;
    let find = |n: [usize; 3], axis: usize| verts.find_from(slot, origin, n, axis);
    for_crossed_cells(table, samples.iso, block, |cell, case, joined| {
        if only.is_some_and(|keep| !keep(cell)) {
            return;
        }
        let [i, j, k] = cell;
        let comps = components(case, joined);
        let corner = samples.node([i, j, k]);
        let mut qefs = [Qef::default(); 4];
        let first = part.positions.len() as u32;
        let mut crossed = table.crossed[case];
        while crossed != 0 {
            let e = crossed.trailing_zeros() as usize;
            crossed &= crossed - 1;
            let s = EDGE_START[e];
            let axis = edge_axis(e);
            let g = find([i + s[0], j + s[1], k + s[2]], axis);
            let lower = s[0] | (s[1] << 1) | (s[2] << 2);
            let lower_inside = (case >> lower) & 1 == 1;
            // Work in cell units about the lowest corner, so the QEF is well scaled.
            let p = (verts.positions[g as usize] - corner).as_dvec3() * inv_h;
            let l = comps.edge_loop[e] as usize;
            if let Placement::Planes(..) = placement {
                let mut n = normals[g as usize].as_dvec3();
                if n == DVec3::ZERO {
                    // No usable gradient: the edge itself, from inside to outside, is the best
                    // available normal.
                    n[axis] = if lower_inside { 1.0 } else { -1.0 };
                }
                qefs[l].add(p, n);
            } else {
                qefs[l].add_point(p);
            }
            part.links.push(Link {
                crossing: g,
                vertex: first + l as u32,
                slot: ring_slot(e) as u8,
                meta: axis as u8 | (u8::from(lower_inside) << 2),
            });
        }
        for (l, qef) in qefs.iter().take(comps.n_loops as usize).enumerate() {
            let given = placement
                .stored()
                .filter(|_| comps.n_loops == 1)
                .and_then(|f| f(corner))
                .map(|x| x.as_dvec3())
                .filter(|x| x.is_finite());
            let x = match (given, placement) {
                (Some(x), _) => {
                    let (lo, hi) = reach_bounds(case, f64::from(MAX_OUTSIDE_REACH));
                    x.clamp(lo, hi)
                }
                (None, Placement::Mean(_)) => {
                    mean_on_surface(field, samples, corner, qef.mass_point())
                }
                (None, Placement::Planes(options, _)) => {
                    let planes = (0..12).filter(|&e| comps.edge_loop[e] == l as u8).map(|e| {
                        let s = EDGE_START[e];
                        let g = find([i + s[0], j + s[1], k + s[2]], edge_axis(e));
                        (verts.positions[g as usize], normals[g as usize])
                    });
                    plane_vertex(qef, planes, field, samples, corner, options, case)
                }
            };
            part.positions.push(corner + x.as_vec3() * samples.spacing);
            if with_homes {
                part.homes.push(corner);
            }
            part.double_faces.push(comps.double_faces[l]);
        }
    });
    part
}

/// Dual contouring's vertex, in cell units about `corner`, of a loop whose crossings give the
/// tangent planes `qef` and, one by one, `planes` (point and unit normal).
fn plane_vertex(
    qef: &Qef,
    planes: impl Iterator<Item = (Vec3, Vec3)> + Clone,
    field: &dyn Field,
    samples: &Samples,
    corner: Vec3,
    options: &DualContourOptions,
    case: usize,
) -> DVec3 {
    let threshold = f64::from(options.singular_threshold);
    let h = samples.spacing;
    let inv_h = 1.0 / f64::from(h);
    let c = qef.mass_point();
    let radius = planes
        .clone()
        .map(|(p, _)| ((p - corner).as_dvec3() * inv_h).distance(c))
        .fold(0.0, f64::max);
    let (mut x, feature) = qef.solve_about(c, threshold);
    if feature && options.feature_offset > 0.0 {
        let centre = corner + c.as_vec3() * h;
        let offset = options.feature_offset * h;
        let mut away = Qef::default();
        for (p, n) in planes {
            let (q, m) = plane_away(field, p, n, centre, offset, samples.iso);
            away.add((q - corner).as_dvec3() * inv_h, m.as_dvec3());
        }
        // Taken only where it stays in the cell: elsewhere the field is not a pair of smooth
        // faces at this scale, and the crossings' own planes are safer.
        let y = away.solve_about(c, threshold).0;
        if y.cmpge(DVec3::ZERO).all() && y.cmple(DVec3::ONE).all() {
            x = y;
        }
    } else if !feature && options.project_smooth {
        // A smooth piece: onto the zero set, as marching cubes vertices are. Only a short move
        // is taken: a long one means the field is not smooth at this scale, and the QEF point
        // keeps the mesh's orientation safe there.
        let p = corner + x.as_vec3() * h;
        let (lo, hi) = (corner, corner + Vec3::splat(h));
        let q = project(field, p.clamp(lo, hi), samples.iso, lo, hi, 1);
        if q.distance(p) < MAX_PROJECTION * h {
            x = ((q - corner) / h).as_dvec3();
        }
    }
    if !x.is_finite() || x.distance(c) > MAX_REACH * radius + CELL_MARGIN {
        x = c;
    }
    if options.clamp_to_cell {
        let reach = f64::from(options.reach).clamp(0.0, f64::from(MAX_OUTSIDE_REACH));
        let (lo, hi) = reach_bounds(case, reach);
        if reach > 0.0 && feature {
            // Along an edge the planes leave a line of minimisers: the one nearest the solution
            // inside the bounds keeps the vertex on the crease, where clamping each axis would
            // move it off.
            if let Some(d) = qef.edge_direction(threshold) {
                x = slide_into(x, d, lo, hi);
            }
        }
        x = x.clamp(lo, hi);
    }
    x
}

/// The point of the line `x + t d` inside the box `[lo, hi]` nearest `x`, or `x` when the line
/// misses the box.
fn slide_into(x: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> DVec3 {
    let (mut first, mut last) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if d[a].abs() < 1e-9 {
            if x[a] < lo[a] || x[a] > hi[a] {
                return x;
            }
            continue;
        }
        let (s, t) = ((lo[a] - x[a]) / d[a], (hi[a] - x[a]) / d[a]);
        first = first.max(s.min(t));
        last = last.min(s.max(t));
    }
    if first <= last {
        x + d * 0.0f64.clamp(first, last)
    } else {
        x
    }
}

/// Where a vertex of a cell with corner signs `case` (bit `c` set when corner `c` is inside,
/// x in bit 0) may go, in cell units: the cell less its margin, and up to `reach` beyond each
/// face whose four corners agree. No edge of such a face is crossed, so the cell beyond it is
/// none of the four around any crossed edge of this cell: a vertex moved there stays in its
/// quadrant about each of its quads' edges (the guarantees hold), and two vertices entering
/// one such cell from opposite faces stay apart while `reach` is below half a cell.
fn reach_bounds(case: usize, reach: f64) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(CELL_MARGIN);
    let mut hi = DVec3::splat(1.0 - CELL_MARGIN);
    if reach <= 0.0 {
        return (lo, hi);
    }
    for axis in 0..3 {
        let face = |side: usize| {
            let mut corners = (0..8usize).filter(|c| (c >> axis) & 1 == side);
            let first = corners.next().map_or(0, |c| (case >> c) & 1);
            corners.all(|c| (case >> c) & 1 == first)
        };
        if face(0) {
            lo[axis] = CELL_MARGIN - reach;
        }
        if face(1) {
            hi[axis] = 1.0 - CELL_MARGIN + reach;
        }
    }
    (lo, hi)
}

/// Surface nets' vertex, in cell units about `corner`: the mean `c` of the loop's crossings,
/// moved onto the zero set by Newton steps that stay in the cell, clear of its faces.
fn mean_on_surface(field: &dyn Field, samples: &Samples, corner: Vec3, c: DVec3) -> DVec3 {
    let h = samples.spacing;
    let margin = Vec3::splat(CELL_MARGIN as f32 * h);
    let (lo, hi) = (corner + margin, corner + Vec3::splat(h) - margin);
    let p = (corner + c.as_vec3() * h).clamp(lo, hi);
    let q = project(field, p, samples.iso, lo, hi, NEWTON_STEPS);
    ((q - corner) / h).as_dvec3()
}

/// The tangent plane (point and unit normal) of `field` at `offset` from the crossing `p` (with
/// normal `n`) along the surface, away from `centre`: the point is moved in the tangent plane
/// and brought back onto the zero set by two Newton steps. Falls back to `(p, n)` where the
/// direction or the field gives nothing usable.
fn plane_away(
    field: &dyn Field,
    p: Vec3,
    n: Vec3,
    centre: Vec3,
    offset: f32,
    iso: f32,
) -> (Vec3, Vec3) {
    let d = p - centre;
    let Some(t) = (d - n * n.dot(d)).try_normalize() else {
        return (p, n);
    };
    let mut q = p + t * offset;
    for _ in 0..2 {
        let (v, g) = field.value_gradient(q);
        let g2 = g.length_squared();
        if !(g2 > 0.0 && v.is_finite()) {
            return (p, n);
        }
        q -= g * ((v - iso) / g2);
    }
    match field.value_gradient(q).1.try_normalize() {
        Some(m) if q.is_finite() => (q, m),
        _ => (p, n),
    }
}

/// Plane axis that changes between ring corners `q` and `q + 1`, and the face side (0 low,
/// 1 high) that the shared face is on for each of the two cells.
const RING_SIDES: [(usize, u8, u8); 4] = [(0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1)];

/// Ring corner offsets (0 for the cell below the edge along a plane axis, 1 above).
const RING_OFFSETS: [[usize; 2]; 4] = [[0, 0], [1, 0], [1, 1], [0, 1]];

/// Triangles of the quad around crossing `g`, whose cells hold the vertices `r` (in ring order).
#[allow(clippy::too_many_arguments)]
fn quad(
    samples: &Samples,
    verts: &Crossings,
    positions: &[Vec3],
    double_faces: &[u8],
    g: u32,
    r: [u32; 4],
    meta: u8,
    run: &mut QuadRun,
) {
    if r.contains(&UNSET) {
        // An edge on the grid border: the surface is left open there, as in marching cubes.
        return;
    }
    let axis = (meta & 3) as usize;
    let lower_inside = meta & 4 != 0;
    let (u, v) = plane_axes(axis);
    let plane = [u, v];
    let mut doubled = [false; 4];
    for (q, &(along, side_a, side_b)) in RING_SIDES.iter().enumerate() {
        let f = 2 * plane[along] as u8;
        let (a, b) = (r[q] as usize, r[(q + 1) % 4] as usize);
        doubled[q] = double_faces[a] & (1 << (f + side_a)) != 0
            && double_faces[b] & (1 << (f + side_b)) != 0;
    }
    let mut dir = Vec3::ZERO;
    dir[axis] = if lower_inside { 1.0 } else { -1.0 };

    if !doubled.contains(&true) {
        let ring = if lower_inside {
            r
        } else {
            [r[0], r[3], r[2], r[1]]
        };
        let p = ring.map(|i| positions[i as usize]);
        for t in split_quad(p, dir) {
            run.triangles.push(t.map(|c| ring[c]));
        }
        return;
    }

    // Rare: insert segment midpoints on the doubled sides and fan around the crossing, which
    // lies on the edge itself and so sees the ring's corners in order.
    let (node, _) = verts.locate(g);
    let mut polygon = Vec::with_capacity(8);
    for q in 0..4 {
        polygon.push(r[q]);
        if doubled[q] {
            let key = segment_key(samples, verts, node, axis, q, lower_inside);
            polygon.push(extra(run, key));
        }
    }
    if !lower_inside {
        polygon.reverse();
    }
    let centre = extra(run, CENTRE_KEY | u64::from(g));
    for i in 0..polygon.len() {
        run.triangles
            .push([centre, polygon[i], polygon[(i + 1) % polygon.len()]]);
    }
}

fn extra(run: &mut QuadRun, key: u64) -> u32 {
    run.extra.push(key);
    EXTRA_FLAG | (run.extra.len() - 1) as u32
}

/// Key of the contour segment on the face between ring corners `q` and `q + 1` around the edge
/// along `axis` from `node`, that ends at this edge's crossing: the face and the face corner the
/// segment cuts off. Both quads along the segment derive the same key.
fn segment_key(
    samples: &Samples,
    verts: &Crossings,
    node: [usize; 3],
    axis: usize,
    q: usize,
    lower_inside: bool,
) -> u64 {
    let (u, v) = plane_axes(axis);
    let (along, side_a, _) = RING_SIDES[q];
    let normal = [u, v][along];
    // The face's lowest node is the lowest node of its high-side cell.
    let high = if side_a == 0 { q } else { (q + 1) % 4 };
    let mut low = node;
    for (d, &a) in [u, v].iter().enumerate() {
        low[a] = node[a] + RING_OFFSETS[high][d] - 1;
    }
    let (p, pq) = plane_axes(normal);
    let offsets = [[0, 0], [1, 0], [1, 1], [0, 1]];
    let corner_nodes = offsets.map(|[a, b]| {
        let mut n = low;
        n[p] += a;
        n[pq] += b;
        n
    });
    // The face's corners are corners of the cell at `low`, which is crossed, so the box of its
    // block holds them and that block is active.
    let values = corner_nodes.map(|n| verts.box_value(low, n));
    let joined = joins_inside(values.map(|x| x - samples.iso), samples.inside(values[0]));
    // Separated inside corners are cut off by the segments; joined ones leave the outside
    // corners cut off. The segment through this edge cuts the edge's end of that kind.
    let mut cut = node;
    if lower_inside == joined {
        cut[axis] += 1;
    }
    let corner = (cut[p] - low[p]) + 2 * (cut[pq] - low[pq]);
    let face = samples.index(low[0], low[1], low[2]) as u64 * 3 + normal as u64;
    (face << 2) | corner as u64
}

fn extra_position(samples: &Samples, verts: &Crossings, key: u64) -> Vec3 {
    if key & CENTRE_KEY != 0 {
        return verts.positions[(key & !CENTRE_KEY) as usize];
    }
    let corner = (key & 3) as usize;
    let face = key >> 2;
    let normal = (face % 3) as usize;
    let low = face as usize / 3;
    let [nx, ny, _] = samples.dims;
    let low = [low % nx, (low / nx) % ny, low / (nx * ny)];
    let (p, q) = plane_axes(normal);
    let mut cut = low;
    cut[p] += corner & 1;
    cut[q] += corner >> 1;
    // The segment joins the crossings on the two face edges meeting at the cut corner.
    let ends = [(p, corner & 1), (q, corner >> 1)].map(|(a, high)| {
        let mut n = cut;
        n[a] -= high;
        verts.positions[verts.find(n, a) as usize]
    });
    0.5 * (ends[0] + ends[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_widen_only_past_faces_whose_corners_agree() {
        // Corner 0 alone inside: the three faces away from it have four outside corners.
        let (lo, hi) = reach_bounds(0b0000_0001, 0.4);
        assert_eq!(lo, DVec3::splat(CELL_MARGIN));
        assert_eq!(hi, DVec3::splat(1.4 - CELL_MARGIN));
        // The lower x half inside: only the x faces agree, each on its own side.
        let (lo, hi) = reach_bounds(0b0101_0101, 0.4);
        assert_eq!(lo, DVec3::new(CELL_MARGIN - 0.4, CELL_MARGIN, CELL_MARGIN));
        assert_eq!(
            hi,
            DVec3::new(1.4 - CELL_MARGIN, 1.0 - CELL_MARGIN, 1.0 - CELL_MARGIN)
        );
        // No reach: the cell less its margin whatever the signs.
        let (lo, hi) = reach_bounds(0b0000_0001, 0.0);
        assert_eq!(
            (lo, hi),
            (DVec3::splat(CELL_MARGIN), DVec3::splat(1.0 - CELL_MARGIN))
        );
    }

    #[test]
    fn sliding_keeps_the_point_on_its_line() {
        let d = DVec3::new(1.0, 1.0, 0.0).normalize();
        let x = slide_into(DVec3::new(1.2, 0.5, 0.5), d, DVec3::ZERO, DVec3::ONE);
        assert!(x.distance(DVec3::new(1.0, 0.3, 0.5)) < 1e-12, "{x}");
        // Inside already: unchanged.
        let inside = DVec3::splat(0.5);
        assert_eq!(slide_into(inside, d, DVec3::ZERO, DVec3::ONE), inside);
        // A line that misses the box leaves the point for the clamp.
        let miss = DVec3::new(0.5, 0.5, 2.0);
        assert_eq!(slide_into(miss, d, DVec3::ZERO, DVec3::ONE), miss);
    }
}
