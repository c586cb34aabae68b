//! What a `.pgv` file holds: its JSON header and the coefficient volume, and the header of a
//! freshly fitted volume.

use std::collections::BTreeMap;

use pgvol_field::{Basis, CoefficientVolume, Grid};
use serde::{Deserialize, Serialize};

use crate::sharp::SharpSection;
use crate::sparse_params::SparseParams;

/// The only payload encoding of version 1: every coefficient as f32, x fastest.
pub const ENCODING_DENSE_F32: &str = "dense-f32";

/// The encoding name of a stored function list (see `perturbation`).
pub const ENCODING_PERTURBATION: &str = "perturbation-f64";

/// What a `.pgv` header holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PgvHeader {
    pub basis: Basis,
    /// How the coefficients were found (e.g. "interp").
    pub fit: String,
    pub grid: Grid,
    /// Units of positions and values: those of the source mesh.
    pub units: String,
    pub encoding: String,
    /// Bounding box of the source mesh, `[min, max]`.
    pub source_bounds: Option<[[f32; 3]; 2]>,
    /// 64-bit FNV-1a hash of the source mesh's positions and triangles, hex.
    pub source_hash: Option<String>,
    #[serde(default)]
    pub metadata: BTreeMap<String, String>,
    /// Parameters of the `sparse-bricks` encoding; absent for `dense-f32`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sparse: Option<SparseParams>,
    /// Dual-contouring vertices at the source's creases and corners (`crate::sharp`); absent
    /// for smooth shapes and for fields not encoded from a mesh.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sharp: Option<SharpSection>,
}

/// A decoded file.
#[derive(Clone, Debug, PartialEq)]
pub struct PgvFile {
    pub header: PgvHeader,
    pub volume: CoefficientVolume,
}

/// FNV-1a (64-bit) over a mesh's positions and indices: a cheap content fingerprint.
pub fn mesh_hash(mesh: &pgvol_core::Mesh) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for p in &mesh.positions {
        for c in p.to_array() {
            eat(&c.to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        for i in t {
            eat(&i.to_le_bytes());
        }
    }
    // Only a far mesh's offset is hashed, so meshes near the origin keep their hashes.
    if mesh.offset != glam::DVec3::ZERO {
        for c in mesh.offset.to_array() {
            eat(&c.to_le_bytes());
        }
    }
    format!("{h:016x}")
}

/// A header for a freshly fitted volume.
pub fn header_for(
    volume: &CoefficientVolume,
    fit: &str,
    source: Option<&pgvol_core::Mesh>,
) -> PgvHeader {
    let bounds = source
        .and_then(|m| m.bounds())
        .map(|(lo, hi)| [lo.to_array(), hi.to_array()]);
    PgvHeader {
        basis: volume.basis,
        fit: fit.to_string(),
        grid: volume.grid,
        units: "source mesh units".to_string(),
        encoding: ENCODING_DENSE_F32.to_string(),
        source_bounds: bounds,
        source_hash: source.map(mesh_hash),
        metadata: BTreeMap::new(),
        sparse: None,
        sharp: None,
    }
}
