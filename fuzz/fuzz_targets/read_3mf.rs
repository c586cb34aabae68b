#![no_main]
//! Any bytes read as a 3MF package: an error or a mesh that passes the readers' contract and,
//! written as PLY (3MF is read only), reads back the same (see `pgvol_fuzz::mesh_target_via`).

use libfuzzer_sys::fuzz_target;
use pgvol_mesh::MeshFormat;

/// Valid files of the seed corpus.
const SEEDS: [&[u8]; 3] = [
    include_bytes!("../corpus/read_3mf/components-lib3mf.3mf"),
    include_bytes!("../corpus/read_3mf/production-lib3mf.3mf"),
    include_bytes!("../corpus/read_3mf/inch-mirror-support.3mf"),
];

fuzz_target!(|data: &[u8]| pgvol_fuzz::mesh_target_via(
    MeshFormat::ThreeMf,
    MeshFormat::Ply,
    &SEEDS,
    data
));
