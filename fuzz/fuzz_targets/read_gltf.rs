#![no_main]
//! Any bytes read as glTF JSON: an error or a mesh that passes the readers' contract
//! and survives writing and reading back (see `pgvol_fuzz::mesh_target`).

use libfuzzer_sys::fuzz_target;
use pgvol_mesh::MeshFormat;

/// Valid files of the seed corpus.
const SEEDS: [&[u8]; 2] = [
    include_bytes!("../corpus/read_gltf/octasphere.gltf"),
    include_bytes!("../corpus/read_gltf/tetra-nodes.gltf"),
];

fuzz_target!(|data: &[u8]| pgvol_fuzz::mesh_target(MeshFormat::Gltf, &SEEDS, data));
