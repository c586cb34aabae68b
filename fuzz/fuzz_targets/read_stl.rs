#![no_main]
//! Any bytes read as STL (binary or ASCII): an error or a mesh that passes the readers' contract
//! and survives writing and reading back (see `pgvol_fuzz::mesh_target`).

use libfuzzer_sys::fuzz_target;
use pgvol_mesh::MeshFormat;

/// Valid files of the seed corpus.
const SEEDS: [&[u8]; 2] = [
    include_bytes!("../corpus/read_stl/octasphere.stl"),
    include_bytes!("../corpus/read_stl/tetra-ascii.stl"),
];

fuzz_target!(|data: &[u8]| pgvol_fuzz::mesh_target(MeshFormat::Stl, &SEEDS, data));
