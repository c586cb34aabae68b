#![no_main]
//! Any bytes read as PLY (ASCII or binary): an error or a mesh that passes the readers' contract
//! and survives writing and reading back (see `pgvol_fuzz::mesh_target`).

use libfuzzer_sys::fuzz_target;
use pgvol_mesh::MeshFormat;

/// Valid files of the seed corpus.
const SEEDS: [&[u8]; 3] = [
    include_bytes!("../corpus/read_ply/octasphere.ply"),
    include_bytes!("../corpus/read_ply/cube-quads-ascii.ply"),
    include_bytes!("../corpus/read_ply/tetra-be.ply"),
];

fuzz_target!(|data: &[u8]| pgvol_fuzz::mesh_target(MeshFormat::Ply, &SEEDS, data));
