#![no_main]
//! Any bytes: decoding (parallel and stage by stage), info and single-brick reads return
//! errors, never panic.

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.pgv");
    let _ = pgvol_format::decode_pgv(data, path);
    let _ = pgvol_format::read_profile::profile_sparse_read(data, path);
    let _ = pgvol_format::pgv_info(data, path);
    let _ = pgvol_format::read_brick(data, path, [0, 0, 0]);
});
