#![no_main]
//! Any bytes read as GLB: an error or a mesh that passes the readers' contract
//! and survives writing and reading back (see `pgvol_fuzz::mesh_target`).

use libfuzzer_sys::fuzz_target;
use pgvol_mesh::MeshFormat;

/// Valid files of the seed corpus.
const SEEDS: [&[u8]; 2] = [
    include_bytes!("../corpus/read_glb/octasphere.glb"),
    include_bytes!("../corpus/read_glb/tetra-nodes.glb"),
];

fuzz_target!(|data: &[u8]| pgvol_fuzz::mesh_target(MeshFormat::Glb, &SEEDS, data));
