//! Jobs are refused before they allocate when their estimate exceeds the memory limit. One test
//! per process state: the limit is global, so this file holds a single test.

use pgvol::{EncodeOptions, ErrorKind, GridSpec, Silent, StorageOptions};

#[test]
fn jobs_over_the_limit_are_refused_before_allocating() {
    let mesh = pgvol::mesh::shapes::octasphere(2);
    let options = EncodeOptions {
        grid: GridSpec::Res(32),
        ..Default::default()
    };
    let encoded = pgvol::encode(&mesh, &options, &Silent).unwrap();
    let (bytes, _) = pgvol::pgv_bytes(&encoded.file, &StorageOptions::default()).unwrap();
    let name = std::path::Path::new("sphere.pgv");

    // 32³ coefficients are 131 kB: a 100 kB limit refuses reading, encoding and remeshing.
    pgvol::set_memory_limit(Some(100_000));
    let read = pgvol::read_pgv_bytes(&bytes, name).unwrap_err();
    let encode = pgvol::encode(&mesh, &options, &Silent).unwrap_err();
    let remesh = pgvol::remesh(
        &mesh,
        &pgvol::RemeshOptions {
            grid: GridSpec::Res(32),
            ..Default::default()
        },
        &Silent,
    )
    .unwrap_err();
    let compare = pgvol::compare(&mesh, &mesh, 10_000, 1).unwrap_err();
    // The lattice of a sphere stores every brick inside it: refused with the brick count.
    let shape = pgvol::Shape::from_file(encoded.file.clone());
    let gyroid = pgvol::Lattice::sheet(pgvol::Tpms::Gyroid, 0.8, 0.2);
    pgvol::set_memory_limit(Some(10_000));
    let lattice = pgvol::lattice(&shape, &gyroid, &Silent).unwrap_err();
    pgvol::set_memory_limit(Some(100_000));
    assert_eq!(lattice.kind(), ErrorKind::ResourceLimit, "{lattice}");
    assert!(lattice.message().contains("a lattice filling"), "{lattice}");
    pgvol::set_memory_limit(None);

    for e in [&read, &encode, &remesh, &compare] {
        assert_eq!(e.kind(), ErrorKind::ResourceLimit, "{e}");
        assert!(e.message().contains("100.0 kB allowed"), "{e}");
    }
    assert_eq!(read.path(), Some(name));
    assert!(read.message().contains("32 x 32 x 32"), "{read}");

    // Under the default limit (the memory available) the same jobs run.
    let back = pgvol::read_pgv_bytes(&bytes, name).unwrap();
    assert_eq!(back.volume.grid, encoded.file.volume.grid);

    // The largest grid is accepted and estimated before any work: a sparse encode at 4096³ is
    // refused under a 1 GB limit with its figure, and a dense remesh (13 bytes a node, 893 GB)
    // under the machine's own.
    let top = pgvol::MAX_RES as usize;
    assert_eq!(top, 4096);
    pgvol::set_memory_limit(Some(1_000_000_000));
    let big = EncodeOptions {
        grid: GridSpec::Res(top),
        ..Default::default()
    };
    let encode = pgvol::encode(&mesh, &big, &Silent).unwrap_err();
    pgvol::set_memory_limit(None);
    assert_eq!(encode.kind(), ErrorKind::ResourceLimit, "{encode}");
    assert!(encode.message().contains("4096 x 4096 x 4096"), "{encode}");
    assert!(encode.message().contains("GB"), "{encode}");
    let dense = pgvol::remesh(
        &mesh,
        &pgvol::RemeshOptions {
            grid: GridSpec::Res(top),
            ..Default::default()
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(dense.kind(), ErrorKind::ResourceLimit, "{dense}");
    assert!(dense.message().contains("893.4 GB"), "{dense}");
}
