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
        pgvol::limits::set_memory_limit(None);
    }
}

fn sphere_shape(res: usize) -> pgvol::Field {
    let options = EncodeOptions {
        grid: GridSpec::Res(res),
        ..Default::default()
    };
    let encoded = pgvol::encode(&pgvol::mesh::shapes::octasphere(3), &options, &Silent).unwrap();
    pgvol::Field::from_file(encoded.file)
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
    let bytes = pgvol::io::pgv_bytes(&encoded.file, &StorageOptions::default())
        .unwrap()
        .bytes;
    let name = std::path::Path::new("sphere.pgv");

    // 32³ coefficients are 131 kB: a 100 kB limit refuses reading, encoding and remeshing.
    pgvol::limits::set_memory_limit(Some(100_000));
    let read = pgvol::io::read_pgv_bytes(&bytes, name).unwrap_err();
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
    let shape = pgvol::Field::from_file(encoded.file.clone());
    let gyroid = pgvol::Lattice::sheet(pgvol::lattices::Tpms::Gyroid, 0.8, 0.2);
    pgvol::limits::set_memory_limit(Some(10_000));
    let lattice = shape
        .lattice(&gyroid, &Silent)
        .map(|l| pgvol::lattices::LatticeSolid {
            volume: l.field.into_file().volume,
            solid: l.solid,
            part: l.part,
        })
        .unwrap_err();
    pgvol::limits::set_memory_limit(Some(100_000));
    assert_eq!(lattice.kind(), ErrorKind::ResourceLimit, "{lattice}");
    assert!(lattice.message().contains("a lattice filling"), "{lattice}");
    pgvol::limits::set_memory_limit(None);

    for e in [&read, &encode, &remesh, &compare] {
        assert_eq!(e.kind(), ErrorKind::ResourceLimit, "{e}");
        assert!(e.message().contains("100.0 kB allowed"), "{e}");
    }
    assert_eq!(read.path(), Some(name));
    assert!(read.message().contains("32 x 32 x 32"), "{read}");

    // Under the default limit (the memory available) the same jobs run.
    let back = pgvol::io::read_pgv_bytes(&bytes, name).unwrap();
    assert_eq!(back.volume.grid, encoded.file.volume.grid);

    // The largest grid is accepted and estimated before any work: a sparse encode at 8192³ is
    // refused under a 1 GB limit with its figure, and a dense remesh (13 bytes a node, 7.1 TB)
    // under the machine's own.
    let top = pgvol::limits::MAX_RES as usize;
    assert_eq!(top, 8192);
    pgvol::limits::set_memory_limit(Some(1_000_000_000));
    let big = EncodeOptions {
        grid: GridSpec::Res(top),
        ..Default::default()
    };
    let encode = pgvol::encode(&mesh, &big, &Silent).unwrap_err();
    pgvol::limits::set_memory_limit(None);
    assert_eq!(encode.kind(), ErrorKind::ResourceLimit, "{encode}");
    assert!(encode.message().contains("8192 x 8192 x 8192"), "{encode}");
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
    assert!(dense.message().contains("7.1 TB"), "{dense}");
}

#[test]
fn denoising_lattices_are_range_checked_and_estimated_before_work() {
    let _limit = Limit::take();
    let shape = sphere_shape(48);
    let mask = pgvol::edit::Mask {
        lo: Vec3::new(-0.5, -0.5, 0.5),
        hi: Vec3::new(0.5, 0.5, 1.2),
    };
    // Lattices finer than the field's grid are refused by their range, however large.
    for coarse in [3000, 100_000_000] {
        let restore = pgvol::edit::Restore::Denoise { coarse };
        let e = shape
            .repair(&[mask], restore, &Silent)
            .map(|r| (r.field.into_file().volume, r.masks))
            .unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
        assert!(
            e.message().contains("the coarse resolution must be 4 to"),
            "{e}"
        );
    }
    // A lattice in range but over the limit is refused with its figure.
    let restore = pgvol::edit::Restore::Denoise { coarse: 20 };
    pgvol::limits::set_memory_limit(Some(10_000));
    let e = shape
        .repair(&[mask], restore, &Silent)
        .map(|r| (r.field.into_file().volume, r.masks))
        .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::ResourceLimit, "{e}");
    assert!(
        e.message().contains("restoring 1 mask(s) needs about"),
        "{e}"
    );
    assert!(e.message().contains("10.0 kB allowed"), "{e}");
    pgvol::limits::set_memory_limit(None);
    let (repaired, _) = shape
        .repair(&[mask], restore, &Silent)
        .map(|r| (r.field.into_file().volume, r.masks))
        .unwrap();
    assert!(repaired.value(Vec3::ZERO) < 0.0);
}

/// Records the stages a call starts: none means it was refused before any work.
#[derive(Default)]
struct Stages(Mutex<Vec<String>>);

impl pgvol::Progress for Stages {
    fn stage(&self, name: &str) {
        self.0.lock().unwrap().push(name.to_string());
    }
}

/// The bytes a refusal says the job needs ("needs about 2.6 GB of memory").
fn needed_bytes(message: &str) -> f64 {
    let rest = &message[message.find("needs about ").expect(message) + 12..];
    let mut words = rest.split_whitespace();
    let value: f64 = words.next().unwrap().parse().unwrap();
    let unit = match words.next().unwrap() {
        "B" => 1.0,
        "kB" => 1e3,
        "MB" => 1e6,
        "GB" => 1e9,
        "TB" => 1e12,
        other => panic!("unit {other}"),
    };
    value * unit
}

#[test]
fn edits_count_their_output_and_refuse_before_any_work() {
    let _limit = Limit::take();
    let dir = tempfile::tempdir().unwrap();
    let ball = dir.path().join("ball.stl");
    pgvol::io::write_mesh(&ball, &pgvol::mesh::shapes::octasphere(3)).unwrap();
    let operands: Vec<pgvol::Operand> = vec![
        pgvol::Operand::File(ball.clone()),
        pgvol::Primary::Sphere(pgvol::field::analytic::Sphere {
            centre: Vec3::new(0.5, 0.0, 0.0),
            radius: 0.8,
        })
        .into(),
    ];
    // Written dense, every node of a 600³ grid costs its coefficient three times over.
    let dense = pgvol::CsgOptions {
        res: 600,
        result: pgvol::ResultUse::DenseFile,
        ..Default::default()
    };
    pgvol::limits::set_memory_limit(Some(100_000_000));
    let stages = Stages::default();
    let e = pgvol::Field::csg(&operands, &dense, &stages)
        .map(|f| f.into_file().volume)
        .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::ResourceLimit, "{e}");
    assert!(
        e.message().contains("a Boolean on a 600 x 600 x 600 grid"),
        "{e}"
    );
    assert!(e.message().contains("100.0 MB allowed"), "{e}");
    assert!(needed_bytes(e.message()) >= 600f64.powi(3) * 12.0, "{e}");
    assert!(stages.0.lock().unwrap().is_empty(), "{:?}", stages.0);

    // Blends of unbounded primaries at 2048³: the dense file alone is 100 GB, and even kept
    // as a volume the sampling's bookkeeping of 256³ bricks exceeds 1 GB.
    let planes: Vec<pgvol::Operand> = vec![plane(1.0, 0.0, 0.0), plane(0.0, 1.0, 0.0)];
    let operator = pgvol::edit::BlendOperator::Liming {
        cut: pgvol::Primary::Plane(pgvol::field::analytic::Plane {
            normal: Vec3::new(-1.0, -1.0, 0.0).normalize(),
            offset: 0.5 / 2f32.sqrt(),
        })
        .into(),
        lambda: 0.5,
    };
    pgvol::limits::set_memory_limit(Some(1_000_000_000));
    let mut needed = std::collections::HashMap::new();
    for (result, at_least) in [
        (pgvol::ResultUse::DenseFile, 2048f64.powi(3) * 12.0),
        (pgvol::ResultUse::File, 256f64.powi(3) * 64.0),
        (pgvol::ResultUse::Volume, 256f64.powi(3) * 64.0),
        (pgvol::ResultUse::Mesh, 256f64.powi(3) * 64.0),
    ] {
        let settings = pgvol::edit::BlendOptions {
            res: 2048,
            bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
            result,
            ..Default::default()
        };
        let stages = Stages::default();
        let e = pgvol::edit::blend(&planes, &operator, &settings, &stages).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::ResourceLimit, "{e}");
        assert!(
            e.message().contains("a blend on a 2048 x 2048 x 2048 grid"),
            "{e}"
        );
        assert!(needed_bytes(e.message()) >= at_least, "{result:?}: {e}");
        assert!(stages.0.lock().unwrap().is_empty(), "{:?}", stages.0);
        needed.insert(format!("{result:?}"), needed_bytes(e.message()));
    }
    // A sparse file adds its stored bricks, not the grid: far less than a dense one.
    let added = |result: &str| needed[result] - needed["Volume"];
    assert!(
        0.0 < added("File") && added("File") < 0.1 * added("DenseFile"),
        "{needed:?}"
    );

    // Within the limit the same jobs run.
    let small = pgvol::CsgOptions { res: 48, ..dense };
    let v = pgvol::Field::csg(&operands, &small, &Silent)
        .map(|f| f.into_file().volume)
        .unwrap();
    assert!(v.value(Vec3::new(1.2, 0.0, 0.0)) < 0.0);
}

#[test]
fn clouds_of_isolated_points_on_a_fine_grid_are_refused_before_work() {
    let _limit = Limit::take();
    // 3000 points scattered through the unit cube, 0.04 apart, on a grid of spacing 0.002: each
    // point would hold its own blob of band bricks (the fit passes 1.7 GB within 20 seconds),
    // and the band would have holes between them.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let points: Vec<Vec3> = (0..3000)
        .map(|_| Vec3::new(next(), next(), next()))
        .collect();
    let cloud = pgvol::reconstruct::PointCloud {
        points,
        normals: None,
    };
    let options = pgvol::PointsOptions {
        grid: GridSpec::Voxel(0.002),
        ..Default::default()
    };
    pgvol::limits::set_memory_limit(Some(1000));
    let stages = Stages::default();
    let e = pgvol::reconstruct::points(&cloud, &options, &stages).unwrap_err();
    assert!(stages.0.lock().unwrap().is_empty(), "{:?}", stages.0);
    // Refused for its spacing, which comes before the memory estimate, with the grid that works.
    assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
    assert!(e.message().contains("too sparse for the grid"), "{e}");
    assert!(e.message().contains("grid spacing of at least"), "{e}");
}

/// The half-space `n·p ≤ 0` of unit normal along `(x, y, z)`.
fn plane(x: f32, y: f32, z: f32) -> pgvol::Operand {
    pgvol::Primary::Plane(pgvol::field::analytic::Plane {
        normal: Vec3::new(x, y, z).normalize(),
        offset: 0.0,
    })
    .into()
}

#[test]
fn a_shell_is_refused_before_its_work_with_the_figure_of_its_stored_bricks() {
    let _limit = Limit::take();
    // A band of 8 spacings (0.37) holds a wall of 0.2.
    let options = EncodeOptions {
        grid: GridSpec::Res(48),
        band: 8.0,
        ..Default::default()
    };
    let encoded = pgvol::encode(&pgvol::mesh::shapes::octasphere(3), &options, &Silent).unwrap();
    let shape = pgvol::Field::from_file(encoded.file);
    let bricks = shape.volume().coeffs.stored_count() as u64;
    let options = pgvol::ShellOptions {
        thickness: 0.2,
        ..Default::default()
    };
    // Just under what the shell's node values, brick list and result take for these bricks.
    pgvol::limits::set_memory_limit(Some(bricks * 3584 - 1));
    let refused = shape.shell(&options, &Silent).unwrap_err();
    pgvol::limits::set_memory_limit(None);
    assert_eq!(refused.kind(), ErrorKind::ResourceLimit, "{refused}");
    assert!(
        refused.message().starts_with("the shell needs about"),
        "{refused}"
    );
    let walls = shape.shell(&options, &Silent).unwrap();
    assert!(walls.volume().coeffs.stored_count() > 0);
}

/// Finding creases holds every half-edge of the mesh, so asking for sharp features raises the
/// estimate of an encode of many triangles: a limit between the two refuses only that one.
#[test]
fn finding_creases_counts_in_the_encodes_estimate() {
    let _limit = Limit::take();
    // 131,072 triangles on a 16³ grid: the triangles are nearly all of the estimate, 400
    // bytes each without creases to find and 464 with them.
    let mesh = pgvol::mesh::shapes::octasphere(7);
    let plain = EncodeOptions {
        grid: GridSpec::Res(16),
        ..Default::default()
    };
    let sharp = EncodeOptions {
        sharp: pgvol::sharp::SharpOptions {
            enabled: true,
            ..Default::default()
        },
        ..plain
    };
    pgvol::limits::set_memory_limit(Some(mesh.triangles.len() as u64 * 430));
    let without = pgvol::encode(&mesh, &plain, &Silent).map(|_| ());
    let with = pgvol::encode(&mesh, &sharp, &Silent).map(|_| ());
    pgvol::limits::set_memory_limit(None);
    assert!(without.is_ok(), "{without:?}");
    let refused = with.unwrap_err();
    assert_eq!(refused.kind(), ErrorKind::ResourceLimit, "{refused}");
    assert!(
        refused
            .message()
            .contains("encoding on a 16 x 16 x 16 grid"),
        "{refused}"
    );
}
