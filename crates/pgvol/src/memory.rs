//! Memory estimates made before work starts, so a job too large for the machine is refused with
//! its figure instead of aborting halfway.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, ErrorKind, Result};

/// Bytes per grid node while encoding, remeshing or decoding: the sampled distances, the
/// coefficients and the contouring or prefilter working copy, 4 bytes each (peak RSS of the
/// whole process: 11.4 bytes per node encoding the bunny at 512³, 12.7 decoding it).
pub const BYTES_PER_NODE: u64 = 13;

/// Bytes per stored brick of 8³ nodes while encoding sparse: the band's samples (2 KiB), the
/// coefficients of the brick and of the neighbours the local fit adds, and the compressed
/// blobs.
pub const BYTES_PER_BAND_BRICK: u64 = 10 * 1024;

/// Bytes per node of a part's box in an encode in parts, whatever the band: the sampler's flags
/// per brick of 4³ nodes (near a triangle, and the sign of a far region), 3 bytes per 64 nodes.
pub const BYTES_PER_PLAN_NODE: f64 = 3.0 / 64.0;

/// Bytes per grid node, whatever the band, of an encode in one process: the sampler's flags and
/// far-region signs, the fit's brick maps and the grid's tile tables. A thin rod (radius 1,
/// length 200: a band of a few MB) peaks at 92 MB at 2048³, 512 MB at 4096³ and 2.6 GB at
/// 8192³, 0.004–0.007 bytes per node between those sizes; one byte per 64 nodes keeps a margin.
pub const BYTES_PER_GRID_NODE: f64 = 1.0 / 64.0;

/// Bytes per stored coefficient brick while contouring at the volume's own grid: the active
/// blocks' samples and crossings, and the output mesh with its normals as it is written (peak
/// RSS of the whole decode of the bunny at 1024³: 1.0 GB for 134 k stored bricks).
pub const BYTES_PER_CONTOUR_BRICK: u64 = 8 * 1024;

/// Bytes per node of a grid finer than the volume's inside its stored bricks while contouring:
/// the active blocks' samples (9³ f32 per 8³ nodes) and their crossings.
pub const BYTES_PER_RESAMPLED_NODE: f64 = 8.0;

/// Bytes per triangle of the input mesh with its distance queries (BVH, winding tree).
pub const BYTES_PER_TRIANGLE: u64 = 400;

/// Bytes per node of a sampled distance grid: the values and the writer's copy.
pub const BYTES_PER_SDF_NODE: u64 = 8;

/// Bytes per cell within the ring of a crease while encoding finds the sharp-feature vertices:
/// its key in the list of such cells and in its box's list, with room for the boxes of 16³
/// cells being contoured and their vertices.
pub const BYTES_PER_SHARP_RING_CELL: u64 = 64;

/// Bytes per triangle of the mesh while encoding finds its creases (`--sharp auto`): every
/// half-edge with its triangle, sorted, and each triangle's normal (peak RSS grew by 67 bytes
/// per triangle encoding the rocker arm subdivided to 1.29 M triangles at 1024³).
pub const BYTES_PER_SHARP_TRIANGLE: u64 = 64;

/// Bytes per surface sample of a mesh comparison (measured: peak memory grew by 112 bytes per
/// sample from 2 to 4 million samples).
pub const BYTES_PER_SAMPLE: u64 = 120;

/// Bytes per brick of 8³ nodes of the whole grid while an edit samples its result brick by
/// brick: the list of bricks (24), the result of each (40) and the sparse grid's slot and side
/// bits until its tiles are compacted.
pub const BYTES_PER_SAMPLED_BRICK: u64 = 72;

/// Bytes per stored brick of 8³ nodes of the input while an operation maps the field's node
/// values and fits them again (shells, hollowing), a layer of fitting groups at a time: the
/// result, whose bricks spread one beyond the input's, and the window of node values (peak RSS
/// grew by 2.8 KB per input brick shelling spot at 1024³ and 2048³: 122,863 and 493,440 bricks).
pub const BYTES_PER_REMAP_BRICK: u64 = 3584;

/// Bytes per grid node of a dense `.pgv` written from a sparse volume: the dense coefficients,
/// their little-endian bytes and the file's bytes, 4 each (peak RSS of a 600³ union written
/// dense: 8.3 bytes per node).
pub const BYTES_PER_DENSE_FILE_NODE: u64 = 12;

/// Bytes per stored brick of 8³ nodes while a sparse `.pgv` is written from a sparse volume:
/// the band search's masks of nodes near zero and of needed nodes (a byte per node each), the
/// compressed blobs and the payload and file assembled from them (under 200 bytes per brick of
/// the cow at 128³ each), with room for a rough surface's larger blobs.
pub const BYTES_PER_FILE_BRICK: u64 = 2 * 1024;

/// Peak bytes of writing a sparse `.pgv` of a volume whose grid has `bricks` bricks of 8³
/// nodes, `near` of them around the surface: [`BYTES_PER_FILE_BRICK`] per brick near the
/// surface, and a byte per file brick of 16³ nodes for the coverage the band search reads.
pub fn sparse_file_bytes(bricks: u64, near: u64) -> u64 {
    near.saturating_mul(BYTES_PER_FILE_BRICK)
        .saturating_add(bricks.div_ceil(8))
}

/// 0 means no limit was set: the memory the machine has available is the limit.
static LIMIT: AtomicU64 = AtomicU64::new(0);

/// Sets the largest estimated peak memory a call may start with; `None` returns to the default,
/// the memory the machine has available when the call starts.
pub fn set_memory_limit(bytes: Option<u64>) {
    LIMIT.store(bytes.unwrap_or(0), Ordering::Relaxed);
}

/// The limit in force: the one set, or the memory available now (unlimited where the platform
/// does not say).
pub fn memory_limit() -> Option<u64> {
    match LIMIT.load(Ordering::Relaxed) {
        0 => available_memory(),
        n => Some(n),
    }
}

/// `MemAvailable` of `/proc/meminfo`, where there is one.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses a job whose estimated peak, `bytes`, exceeds the limit; `job` names it and `advice`
/// says what would make it smaller.
pub(crate) fn check_memory(job: &str, bytes: u64, advice: &str) -> Result<()> {
    match memory_limit() {
        Some(limit) if bytes > limit => Err(Error::new(
            ErrorKind::ResourceLimit,
            format!(
                "{job} needs about {} of memory, more than the {} {}; {advice}, or raise the \
                 limit",
                human(bytes),
                human(limit),
                if LIMIT.load(Ordering::Relaxed) == 0 {
                    "available"
                } else {
                    "allowed"
                }
            ),
        )
        .with_remedy(crate::error::Remedy::MemoryLimit)),
        _ => Ok(()),
    }
}

/// Refuses `job` on `grid` at `per_node` bytes per node when it would not fit in memory.
pub(crate) fn check_grid(job: &str, grid: &pgvol_core::Grid, per_node: u64) -> Result<()> {
    let [nx, ny, nz] = grid.dims;
    check_memory(
        &format!("{job} on a {nx} x {ny} x {nz} grid"),
        grid_bytes(grid.len(), per_node),
        "lower the resolution",
    )
}

/// Bricks of 8³ nodes within `band` spacings of a surface of `area` on a grid of `spacing`: a
/// surface crosses about 1.5 bricks per brick face of area, and the band adds its thickness
/// (2 · band spacings of 8).
pub fn band_bricks(area: f64, spacing: f32, band: f32) -> u64 {
    let side = 8.0 * spacing as f64;
    (area / (side * side) * (1.5 + band as f64 / 4.0)).ceil() as u64
}

/// Estimated peak bytes of a sparse encode of a mesh of `area` and `triangles` on `grid`.
pub fn sparse_encode_bytes(area: f64, triangles: usize, grid: &pgvol_core::Grid, band: f32) -> u64 {
    let bricks = band_bricks(area, grid.spacing, band);
    let plan = (grid.len() as f64 * BYTES_PER_GRID_NODE) as u64;
    bricks
        .saturating_mul(BYTES_PER_BAND_BRICK)
        .saturating_add(plan)
        .saturating_add((triangles as u64).saturating_mul(BYTES_PER_TRIANGLE))
}

/// Refuses a sparse encode of `mesh` on `grid` that would not fit in memory.
pub(crate) fn check_sparse_encode(
    job: &str,
    mesh: &pgvol_core::Mesh,
    grid: &pgvol_core::Grid,
    band: f32,
) -> Result<()> {
    check_sparse_encode_then(job, mesh, grid, band, 0)
}

/// [`check_sparse_encode`] of an encode whose field an operation then needs `then` more bytes
/// for, the encoded field kept.
pub(crate) fn check_sparse_encode_then(
    job: &str,
    mesh: &pgvol_core::Mesh,
    grid: &pgvol_core::Grid,
    band: f32,
    then: u64,
) -> Result<()> {
    let [nx, ny, nz] = grid.dims;
    check_memory(
        &format!("{job} on a {nx} x {ny} x {nz} grid"),
        sparse_encode_bytes(mesh_area(mesh), mesh.triangles.len(), grid, band).saturating_add(then),
        "lower the resolution",
    )
}

/// What finding the creases of `mesh` adds to an encoding's estimate when it is asked for
/// (`sharp`): [`BYTES_PER_SHARP_TRIANGLE`] per triangle.
pub(crate) fn crease_bytes(mesh: &pgvol_core::Mesh, sharp: bool) -> u64 {
    match sharp {
        true => (mesh.triangles.len() as u64).saturating_mul(BYTES_PER_SHARP_TRIANGLE),
        false => 0,
    }
}

/// The surface area of `mesh`.
pub(crate) fn mesh_area(mesh: &pgvol_core::Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Refuses contouring `volume` on `grid` when it would not fit in memory: the work follows the
/// stored bricks, scaled by the surface's growth on a finer grid. On a grid much finer than the
/// volume's, the blocks whose coefficient support straddles the level fill the volume's
/// straddling bricks rather than a surface through them, so the estimate is at least every
/// node inside the stored bricks at [`BYTES_PER_RESAMPLED_NODE`].
pub(crate) fn check_contour(
    volume: &pgvol_field::CoefficientVolume,
    grid: &pgvol_core::Grid,
) -> Result<()> {
    check_contour_of(volume.coeffs.stored_count(), volume.grid.spacing, grid)
}

/// [`check_contour`] for a volume of `stored` stored bricks on a grid of `spacing`.
pub(crate) fn check_contour_of(stored: usize, spacing: f32, grid: &pgvol_core::Grid) -> Result<()> {
    let [nx, ny, nz] = grid.dims;
    let scale = (spacing / grid.spacing).max(1.0) as f64;
    let stored = stored as f64;
    let surface = stored * scale * scale * BYTES_PER_CONTOUR_BRICK as f64;
    let filled = if scale > 1.0 {
        stored * (8.0 * scale).powi(3) * BYTES_PER_RESAMPLED_NODE
    } else {
        0.0
    };
    check_memory(
        &format!("contouring on a {nx} x {ny} x {nz} grid"),
        surface.max(filled).min(u64::MAX as f64) as u64,
        "lower the resolution",
    )
}

/// Bytes for a grid of `nodes` at `per_node` bytes, saturating.
pub(crate) fn grid_bytes(nodes: usize, per_node: u64) -> u64 {
    (nodes as u64).saturating_mul(per_node)
}

/// A size for a person: `1.6 GB`, `340 MB`.
pub(crate) fn human(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "kB", "MB", "GB", "TB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_print_for_people() {
        assert_eq!(human(1_600_000_000), "1.6 GB");
        assert_eq!(human(999), "999 B");
    }

    #[test]
    fn a_job_over_the_limit_is_refused_with_its_figure() {
        set_memory_limit(Some(1_000_000));
        let e = check_memory("encoding at 256³", 2_000_000, "lower the resolution").unwrap_err();
        set_memory_limit(None);
        assert_eq!(e.kind(), ErrorKind::ResourceLimit);
        assert_eq!(e.remedy(), Some(crate::error::Remedy::MemoryLimit));
        assert!(
            e.message().contains("2.0 MB") && e.message().contains("1.0 MB"),
            "{e}"
        );
        assert!(!e.message().contains("--"), "{e}");
        assert!(check_memory("a small job", 10, "").is_ok());
    }
}
