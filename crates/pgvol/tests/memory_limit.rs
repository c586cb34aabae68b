//! Jobs are refused before they allocate when their estimate exceeds the memory limit. The
//! limit is global to the process, so the tests take turns through one lock.

use std::sync::{Mutex, MutexGuard};

use pgvol::glam::Vec3;
use pgvol::{EncodeOptions, ErrorKind, GridSpec, Silent, StorageOptions};

static LIMIT: Mutex<()> = Mutex::new(());

/// Holds the memory limit for one test; the default returns when it is dropped.
struct Limit(#[allow(dead_code)] MutexGuard<'static, ()>);

impl Limit {
    fn take() -> Self {
        Limit(LIMIT.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

impl Drop for Limit {
    fn drop(&mut self) {
        pgvol::set_memory_limit(None);
    }
}

fn sphere_shape(res: usize) -> pgvol::Shape {
    let options = EncodeOptions {
        grid: GridSpec::Res(res),
        ..Default::default()
    };
    let encoded = pgvol::encode(&pgvol::mesh::shapes::octasphere(3), &options, &Silent).unwrap();
    pgvol::Shape::from_file(encoded.file)
}

#[test]
fn jobs_over_the_limit_are_refused_before_allocating() {
    let _limit = Limit::take();
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
}

#[test]
fn denoising_lattices_are_range_checked_and_estimated_before_work() {
    let _limit = Limit::take();
    let shape = sphere_shape(48);
    let mask = pgvol::parse_mask("-0.5,-0.5,0.5,0.5,0.5,1.2").unwrap();
    // Lattices finer than the field's grid are refused by their range, however large.
    for coarse in [3000, 100_000_000] {
        let restore = pgvol::Restore::Denoise { coarse };
        let e = pgvol::repair(&shape, &[mask], restore, &Silent).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
        assert!(
            e.message().contains("the coarse resolution must be 4 to"),
            "{e}"
        );
    }
    // A lattice in range but over the limit is refused with its figure.
    let restore = pgvol::Restore::Denoise { coarse: 20 };
    pgvol::set_memory_limit(Some(10_000));
    let e = pgvol::repair(&shape, &[mask], restore, &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::ResourceLimit, "{e}");
    assert!(
        e.message().contains("restoring 1 mask(s) needs about"),
        "{e}"
    );
    assert!(e.message().contains("10.0 kB allowed"), "{e}");
    pgvol::set_memory_limit(None);
    let (repaired, _) = pgvol::repair(&shape, &[mask], restore, &Silent).unwrap();
    assert!(repaired.value(Vec3::ZERO) < 0.0);
}
