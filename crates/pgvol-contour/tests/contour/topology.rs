//! Checks that a mesh is a closed, oriented 2-manifold without degenerate triangles.

use std::collections::{HashMap, HashSet};

use glam::DVec3;
use pgvol_core::Mesh;

/// Facts about a mesh that passed [`check_closed_manifold`].
#[derive(Debug)]
pub struct Closed {
    pub euler: i64,
    pub volume: f64,
    /// Signed volume of each connected component.
    pub component_volumes: Vec<f64>,
}

fn pos(mesh: &Mesh, v: u32) -> DVec3 {
    mesh.positions[v as usize].as_dvec3()
}

/// Asserts that every triangle has three distinct vertices and positive area, no triangle repeats,
/// every vertex is used, every edge is traversed exactly once in each direction (watertight and
/// consistently oriented), and the triangles around each vertex form a single disk.
pub fn check_closed_manifold(mesh: &Mesh) -> Closed {
    let n = mesh.positions.len();
    let mut seen = HashSet::new();
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    // For each vertex, the opposite edge of each triangle around it (its link).
    let mut link: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
    for (t, &[a, b, c]) in mesh.triangles.iter().enumerate() {
        assert!(a != b && b != c && a != c, "triangle {t} repeats a vertex");
        assert!(
            [a, b, c].iter().all(|&v| (v as usize) < n),
            "triangle {t} out of range"
        );
        let p = [a, b, c].map(|v| mesh.positions[v as usize]);
        let area = (p[1] - p[0]).cross(p[2] - p[0]).length();
        assert!(area > 0.0, "triangle {t} has zero area: {p:?}");
        let mut key = [a, b, c];
        key.sort_unstable();
        assert!(seen.insert(key), "triangle {t} duplicates another");
        for (x, y, z) in [(a, b, c), (b, c, a), (c, a, b)] {
            *directed.entry((x, y)).or_default() += 1;
            link[x as usize].push((y, z));
        }
    }
    for (&(x, y), &count) in &directed {
        assert_eq!(count, 1, "edge {x}->{y} traversed {count} times");
        assert!(
            directed.contains_key(&(y, x)),
            "edge {x}-{y} is a border or inconsistently oriented"
        );
    }
    for (v, around) in link.iter().enumerate() {
        assert!(!around.is_empty(), "vertex {v} is unused");
        // Oriented and closed: the link edges chain into cycles; a disk means exactly one.
        let next: HashMap<u32, u32> = around.iter().copied().collect();
        assert_eq!(next.len(), around.len(), "vertex {v} has a pinched link");
        let start = around[0].0;
        let (mut at, mut steps) = (start, 0);
        loop {
            at = next[&at];
            steps += 1;
            if at == start {
                break;
            }
        }
        assert_eq!(
            steps,
            around.len(),
            "triangles around vertex {v} form several fans"
        );
    }

    let components = components(mesh);
    let mut component_volumes = vec![0.0; components.1];
    for (t, &[a, b, c]) in mesh.triangles.iter().enumerate() {
        let v = pos(mesh, a).dot(pos(mesh, b).cross(pos(mesh, c))) / 6.0;
        component_volumes[components.0[t]] += v;
    }
    let edges = directed.len() as i64 / 2;
    Closed {
        euler: n as i64 - edges + mesh.triangles.len() as i64,
        volume: component_volumes.iter().sum(),
        component_volumes,
    }
}

/// Connected component of each triangle (through shared vertices), and the component count.
fn components(mesh: &Mesh) -> (Vec<usize>, usize) {
    let mut parent: Vec<usize> = (0..mesh.positions.len()).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    for t in &mesh.triangles {
        for w in [t[1], t[2]] {
            let (x, y) = (
                root(&mut parent, t[0] as usize),
                root(&mut parent, w as usize),
            );
            parent[x] = y;
        }
    }
    let mut ids = HashMap::new();
    let per_triangle = mesh
        .triangles
        .iter()
        .map(|t| {
            let r = root(&mut parent, t[0] as usize);
            let next = ids.len();
            *ids.entry(r).or_insert(next)
        })
        .collect();
    (per_triangle, ids.len())
}

/// The checks of [`check_closed_manifold`], plus a positive enclosed volume, for a field whose
/// inside region stays away from the grid border.
pub fn check_surface(mesh: &Mesh) -> Closed {
    let closed = check_closed_manifold(mesh);
    if !mesh.triangles.is_empty() {
        assert!(closed.volume > 0.0, "negative volume {}", closed.volume);
    }
    closed
}

/// Edge and vertex statistics of a mesh that may be non-manifold, from [`check_balanced`].
#[derive(Debug, Default)]
pub struct Balanced {
    /// Most triangles on one undirected edge.
    pub max_uses: usize,
    /// Undirected edges with more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices whose triangles form more than one fan (or a pinched link).
    pub non_manifold_vertices: usize,
}

/// Asserts that the mesh is closed and consistently oriented in the weakest sense: every
/// directed edge is traversed as often as its reverse, so there is no border and no flipped
/// neighbour. Counts the places where it is not a manifold.
pub fn check_balanced(mesh: &Mesh) -> Balanced {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    let mut link: Vec<Vec<(u32, u32)>> = vec![Vec::new(); mesh.positions.len()];
    for &[a, b, c] in &mesh.triangles {
        for (x, y, z) in [(a, b, c), (b, c, a), (c, a, b)] {
            *directed.entry((x, y)).or_default() += 1;
            link[x as usize].push((y, z));
        }
    }
    let mut out = Balanced::default();
    for (&(x, y), &n) in &directed {
        let back = directed.get(&(y, x)).copied().unwrap_or(0);
        assert_eq!(
            n, back,
            "edge {x}->{y} used {n} times, {y}->{x} {back} times"
        );
        if x < y {
            out.max_uses = out.max_uses.max(2 * n);
            out.non_manifold_edges += usize::from(n > 1);
        }
    }
    for around in &link {
        if around.is_empty() {
            continue;
        }
        let next: HashMap<u32, u32> = around.iter().copied().collect();
        let single_fan = next.len() == around.len() && {
            let start = around[0].0;
            let (mut at, mut steps) = (start, 0);
            while let Some(&n) = next.get(&at) {
                at = n;
                steps += 1;
                if at == start || steps > around.len() {
                    break;
                }
            }
            steps == around.len()
        };
        out.non_manifold_vertices += usize::from(!single_fan);
    }
    out
}
