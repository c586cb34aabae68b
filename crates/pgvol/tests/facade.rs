//! The library's entry points: in-memory and path I/O agree, the encoding band is recorded and
//! enforced, errors carry their kind and file, and progress reports stages and can cancel.

use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use pgvol::edit::ShellSide;
use pgvol::glam::Vec3;
use pgvol::mesh::{shapes, MeshFormat};
use pgvol::{
    Basis, DecodeOptions, EncodeOptions, ErrorKind, Field, FitMethod, GridSpec, Mesh, Method,
    Progress, RemeshField, RemeshOptions, SdfOptions, ShellKind, SignMode, Silent, StorageOptions,
};

fn sphere() -> Mesh {
    shapes::octasphere(2)
}

fn encode_options(res: usize) -> EncodeOptions {
    EncodeOptions {
        grid: GridSpec::Res(res),
        ..EncodeOptions::default()
    }
}

fn encoded(res: usize) -> pgvol::Encoded {
    pgvol::encode(&sphere(), &encode_options(res), &Silent).unwrap()
}

/// The error's kind and, when given, the file it names.
#[track_caller]
fn assert_error<T: std::fmt::Debug>(
    result: pgvol::Result<T>,
    kind: ErrorKind,
    path: Option<&Path>,
) -> pgvol::Error {
    let e = result.expect_err("expected an error");
    assert_eq!(e.kind(), kind, "{e}");
    if let Some(path) = path {
        assert_eq!(e.path(), Some(path), "{e}");
    }
    e
}

// ---------------------------------------------------------------------------------------------
// I/O: bytes, readers and writers against paths.

#[test]
fn pgv_bytes_writers_and_paths_give_the_same_file() {
    let dir = tempfile::tempdir().unwrap();
    let file = encoded(24).file;
    for storage in [
        StorageOptions::default(),
        StorageOptions {
            dense: true,
            ..StorageOptions::default()
        },
    ] {
        let pgvol::io::PgvBytes {
            bytes,
            storage: report,
        } = pgvol::io::pgv_bytes(&file, &storage).unwrap();
        assert_eq!(report.is_none(), storage.dense);

        let path = dir.path().join("s.pgv");
        let written = pgvol::io::write_pgv(&path, &file, &storage).unwrap();
        assert_eq!(written, report);
        assert_eq!(std::fs::read(&path).unwrap(), bytes);

        let mut sink = Vec::new();
        let streamed = pgvol::io::write_pgv_to(&mut sink, &file, &storage).unwrap();
        assert_eq!(streamed, report);
        assert_eq!(sink, bytes);

        let from_path = pgvol::io::read_pgv(&path).unwrap();
        let name = Path::new("memory.pgv");
        assert_eq!(pgvol::io::read_pgv_bytes(&bytes, name).unwrap(), from_path);
        assert_eq!(
            pgvol::io::read_pgv_from(&mut bytes.as_slice(), name).unwrap(),
            from_path
        );
        if storage.dense {
            // Dense storage is f32 throughout: the file comes back as it was.
            assert_eq!(from_path, file);
        }
    }
}

#[test]
fn mesh_bytes_writers_and_paths_agree_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = sphere();
    for format in [
        MeshFormat::Obj,
        MeshFormat::Gltf,
        MeshFormat::Glb,
        MeshFormat::Stl,
        MeshFormat::Ply,
    ] {
        let path = dir.path().join(format!("m.{}", format.extension()));
        pgvol::io::write_mesh(&path, &mesh).unwrap();
        assert_eq!(pgvol::io::mesh_format(&path).unwrap(), format);
        let on_disk = std::fs::read(&path).unwrap();
        let mut sink = Vec::new();
        pgvol::io::write_mesh_to(&mut sink, &mesh, format, &path).unwrap();
        assert_eq!(sink, on_disk, "{format:?}");

        let pgvol::io::ReadMesh {
            mesh: from_path,
            cleaned: report,
        } = pgvol::io::read_mesh(&path).unwrap();
        let pgvol::io::ReadMesh {
            mesh: from_bytes,
            cleaned: report_bytes,
        } = pgvol::io::read_mesh_bytes(&on_disk, format, Path::new("memory")).unwrap();
        assert_eq!(from_bytes, from_path, "{format:?}");
        assert_eq!(report_bytes, report, "{format:?}");
        assert_eq!(
            from_path.triangles.len(),
            mesh.triangles.len(),
            "{format:?}"
        );
    }
}

#[test]
fn in_memory_readers_name_the_given_file_in_errors() {
    let name = Path::new("in/memory.pgv");
    assert_error(
        pgvol::io::read_pgv_bytes(b"not a pgv file", name),
        ErrorKind::InputFile,
        Some(name),
    );

    struct Failing;
    impl Read for Failing {
        fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
            Err(io::Error::other("the disk went away"))
        }
    }
    let e = assert_error(
        pgvol::io::read_pgv_from(&mut Failing, name),
        ErrorKind::InputFile,
        Some(name),
    );
    assert!(e.to_string().contains("the disk went away"), "{e}");

    let mesh_name = Path::new("in/memory.stl");
    assert_error(
        pgvol::io::read_mesh_bytes(b"solid nothing\n", MeshFormat::Stl, mesh_name),
        ErrorKind::InputFile,
        Some(mesh_name),
    );

    struct Full;
    impl io::Write for Full {
        fn write(&mut self, _: &[u8]) -> io::Result<usize> {
            Err(io::Error::other("no space left"))
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }
    let file = encoded(16).file;
    assert_error(
        pgvol::io::write_pgv_to(&mut Full, &file, &StorageOptions::default()),
        ErrorKind::OutputFile,
        None,
    );
    let out = Path::new("out/memory.obj");
    assert_error(
        pgvol::io::write_mesh_to(&mut Full, &sphere(), MeshFormat::Obj, out),
        ErrorKind::OutputFile,
        Some(out),
    );
}

// ---------------------------------------------------------------------------------------------
// The band: recorded by encode, kept by the file, enforced by offsets and shells.

#[test]
fn encode_records_its_band_and_the_file_keeps_it() {
    let dir = tempfile::tempdir().unwrap();
    for band in [pgvol::limits::ENCODE_BAND, 6.5] {
        let options = EncodeOptions {
            band,
            ..encode_options(24)
        };
        let file = pgvol::encode(&sphere(), &options, &Silent).unwrap().file;
        let h = file.volume.grid.spacing;
        let recorded = pgvol::io::recorded_band(&file).expect("a recorded band");
        assert!((recorded - band * h).abs() <= 1e-6 * recorded, "{recorded}");

        let path = dir.path().join("b.pgv");
        pgvol::io::write_pgv(&path, &file, &StorageOptions::default()).unwrap();
        let back = pgvol::io::read_pgv(&path).unwrap();
        assert_eq!(pgvol::io::recorded_band(&back), Some(recorded));
        let stored = Field::from_file(back);
        assert_eq!(stored.band(), Some(recorded));

        // The sparse file keeps what an offset to the edge of the band reads: it moves the
        // surface as the in-memory field does, up to the storage's quantisation.
        let amount = 0.9 * (band - 2.0) * h;
        let from_file = stored.offset(amount).map(|f| f.into_file().volume).unwrap();
        let in_memory = Field::from_file(file)
            .offset(amount)
            .map(|f| f.into_file().volume)
            .unwrap();
        for p in [
            Vec3::X,
            -Vec3::Y,
            Vec3::new(0.6, 0.6, 0.5),
            Vec3::splat(-0.57),
        ] {
            for q in [p * 0.9, p, p * 1.1] {
                let (a, b) = (from_file.eval(q).0, in_memory.eval(q).0);
                assert!((a - b).abs() <= 0.02 * h, "{a} against {b} at {q}");
            }
        }
    }
}

#[test]
fn offsets_and_shells_within_the_band_succeed_and_beyond_it_are_refused() {
    for band in [pgvol::limits::ENCODE_BAND, 8.0] {
        let options = EncodeOptions {
            band,
            ..encode_options(24)
        };
        let file = pgvol::encode(&sphere(), &options, &Silent).unwrap().file;
        let h = file.volume.grid.spacing;
        // The cubic B-spline reaches two spacings past the level set it shapes.
        let reach = (band - 2.0) * h;
        // What `pgvol info` shows as the usable reach is the one the operations enforce.
        let shown = pgvol::checks::exact_reach(&file);
        assert!(
            (shown - reach).abs() <= 1e-5 * reach,
            "{shown} against {reach}"
        );
        let shape = Field::from_file(file);
        assert_eq!(shape.exact_band(), shown);
        for amount in [0.5 * reach, -0.5 * reach, 0.95 * reach] {
            let grown = shape.offset(amount).map(|f| f.into_file().volume).unwrap();
            // The surface moved: the old surface point is now `amount` inside.
            let value = grown.eval(Vec3::new(0.0, 0.0, 1.0)).0;
            assert!((value + amount).abs() < 0.25 * h, "{value} after {amount}");
        }
        for amount in [1.05 * reach, -1.05 * reach, 3.0 * reach] {
            assert_error(
                shape.offset(amount).map(|f| f.into_file().volume),
                ErrorKind::BadParameter,
                None,
            );
        }
        for kind in [
            ShellKind::Hollow,
            ShellKind::Wall(ShellSide::Outer),
            ShellKind::Wall(ShellSide::Centred),
        ] {
            let built = shape
                .shell(
                    &pgvol::ShellOptions {
                        thickness: 0.5 * reach,
                        kind,
                        drains: [].to_vec(),
                    },
                    &Silent,
                )
                .map(|f| f.into_file().volume);
            if 0.5 * reach < pgvol::limits::MIN_WALL_SPACINGS * h {
                // Within the band, but a wall thinner than the grid holds.
                assert_error(built, ErrorKind::Unresolved, None);
            } else {
                built.unwrap();
            }
            assert_error(
                shape
                    .shell(
                        &pgvol::ShellOptions {
                            thickness: 1.05 * reach,
                            kind,
                            drains: [].to_vec(),
                        },
                        &Silent,
                    )
                    .map(|f| f.into_file().volume),
                ErrorKind::BadParameter,
                None,
            );
        }
    }
}

#[test]
fn derived_files_are_sparse_and_keep_the_band_they_are_exact_in() {
    let options = EncodeOptions {
        band: 8.0,
        ..encode_options(96)
    };
    let file = pgvol::encode(&sphere(), &options, &Silent).unwrap().file;
    let h = file.volume.grid.spacing;
    let encoded = pgvol::io::pgv_bytes(&file, &StorageOptions::default())
        .unwrap()
        .bytes;
    let shape = Field::from_file(file);
    let band = shape.band().unwrap();
    let dense = StorageOptions {
        dense: true,
        ..StorageOptions::default()
    };
    for (kind, amount) in [
        (None, 1.5 * h),
        (None, -3.0 * h),
        (Some(ShellKind::Hollow), 2.5 * h),
        (Some(ShellKind::Wall(ShellSide::Centred)), 3.0 * h),
    ] {
        let result = match kind {
            None => shape.offset(amount),
            Some(kind) => {
                let options = pgvol::ShellOptions {
                    thickness: amount,
                    kind,
                    drains: Vec::new(),
                };
                shape.shell(&options, &Silent)
            }
        };
        let derived = result.unwrap().into_file();
        let volume = derived.volume.clone();
        let what = format!("{kind:?} {amount}");
        // How far the operation reads the shape's field beyond its surface.
        let shift = match kind {
            Some(ShellKind::Wall(ShellSide::Centred)) => amount / 2.0,
            _ => amount.abs(),
        };
        // The band it is exact in: the shape's less how far the operation reads beyond it.
        let recorded = pgvol::io::recorded_band(&derived).unwrap();
        assert!((recorded - (band - shift)).abs() <= 1e-6 * band, "{what}");

        // Sparse and quantised as `encode` writes, about as small.
        let pgvol::io::PgvBytes {
            bytes,
            storage: report,
        } = pgvol::io::pgv_bytes(&derived, &StorageOptions::default()).unwrap();
        let report = report.expect("a sparse file");
        assert_eq!(report.precision, pgvol::Precision::Fixed, "{what}");
        assert!(
            report.bricks_stored < report.bricks_total,
            "{what}: {report:?}"
        );
        assert!(
            bytes.len() <= 3 * encoded.len(),
            "{what}: {} bytes against encode's {}",
            bytes.len(),
            encoded.len()
        );
        // Dense on request, every coefficient as it is.
        let pgvol::io::PgvBytes {
            bytes: full,
            storage: none,
        } = pgvol::io::pgv_bytes(&derived, &dense).unwrap();
        assert!(none.is_none() && full.len() > 4 * bytes.len(), "{what}");
        let name = Path::new("d.pgv");
        let exact = pgvol::io::read_pgv_bytes(&full, name).unwrap();
        assert_eq!(exact.header.encoding, "dense-f32");
        assert_eq!(exact.volume.dense_coeffs(), volume.dense_coeffs(), "{what}");

        // Within the band the stored bricks keep (the recorded band less a spacing), the sparse
        // file's field is the dense one's up to the quantisation.
        let back = pgvol::io::read_pgv_bytes(&bytes, name).unwrap();
        let grid = volume.grid;
        let (want, got) = (volume.sample(&grid), back.volume.sample(&grid));
        let mut checked = 0;
        for (a, b) in want.iter().zip(&got) {
            if a.abs() <= recorded - h {
                let bound = report.max_quantisation_error + 1e-6 * h;
                assert!((a - b).abs() <= bound, "{what}: {a} -> {b}");
                checked += 1;
            }
        }
        assert!(checked > 1000, "{what}: {checked}");
        // Read back, the file keeps its band; written again, it is the same file.
        let reread = Field::from_file(back.clone());
        assert_eq!(reread.band(), Some(recorded));
        assert!((reread.exact_band() - (recorded - 2.0 * h)).abs() <= 1e-5 * band);
        let again = pgvol::io::pgv_bytes(&back, &StorageOptions::default())
            .unwrap()
            .bytes;
        assert!(again == bytes, "{what}: writing the read file changed it");
    }
}

// ---------------------------------------------------------------------------------------------
// Errors: kind and file.

#[test]
fn missing_inputs_are_input_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["missing.obj", "missing.pgv"] {
        let path = dir.path().join(name);
        if name.ends_with(".pgv") {
            assert_error(
                pgvol::io::read_pgv(&path),
                ErrorKind::InputFile,
                Some(&path),
            );
        } else {
            assert_error(
                pgvol::io::read_mesh(&path),
                ErrorKind::InputFile,
                Some(&path),
            );
        }
        let e = Field::open(
            &path,
            &pgvol::OpenOptions {
                res: 16,
                grow: 0.0,
                reach: 0.0,
                wall: None,
                sign: SignMode::Auto,
                ..Default::default()
            },
            &Silent,
        )
        .unwrap_err();
        assert_eq!((e.kind(), e.path()), (ErrorKind::InputFile, Some(&*path)));
    }
}

#[test]
fn unknown_or_unwritable_outputs_are_output_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = sphere();
    let unknown = dir.path().join("m.xyz");
    assert_error(
        pgvol::io::write_mesh(&unknown, &mesh),
        ErrorKind::OutputFile,
        Some(&unknown),
    );
    assert_error(
        pgvol::io::mesh_format(&unknown),
        ErrorKind::OutputFile,
        Some(&unknown),
    );
    assert!(!unknown.exists());

    let not_pgv = dir.path().join("v.obj");
    assert_error(
        pgvol::io::check_pgv_name(&not_pgv),
        ErrorKind::OutputFile,
        Some(&not_pgv),
    );
    let grid_name = dir.path().join("g.txt");
    assert_error(
        pgvol::io::GridFormat::from_path(&grid_name),
        ErrorKind::OutputFile,
        Some(&grid_name),
    );

    let no_dir = dir.path().join("no/such/dir/v.pgv");
    let file = encoded(16).file;
    assert_error(
        pgvol::io::write_pgv(&no_dir, &file, &StorageOptions::default()),
        ErrorKind::OutputFile,
        Some(&no_dir),
    );
}

#[test]
fn bad_options_are_parameter_errors() {
    let mesh = sphere();
    for band in [1.5, 0.0, -4.0, f32::NAN, f32::INFINITY] {
        let options = EncodeOptions {
            band,
            ..encode_options(16)
        };
        assert_error(
            pgvol::encode(&mesh, &options, &Silent),
            ErrorKind::BadParameter,
            None,
        );
    }
    let bad_basis = EncodeOptions {
        basis: Basis::Pg { n: 9, r: 1.5 },
        ..encode_options(16)
    };
    assert_error(
        pgvol::encode(&mesh, &bad_basis, &Silent),
        ErrorKind::BadParameter,
        None,
    );
    for z in [0.0, 1.5, 2.0] {
        let bad_step = EncodeOptions {
            fit: FitMethod::Iso { z_step: Some(z) },
            ..encode_options(16)
        };
        let e = pgvol::encode(&mesh, &bad_step, &Silent).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
        assert!(e.to_string().contains("(0, 1] grid spacings"), "{e}");
    }
    assert_error(
        pgvol::encode(&mesh, &encode_options(1), &Silent),
        ErrorKind::BadParameter,
        None,
    );

    let volume = encoded(16).file.volume;
    for iso in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let options = DecodeOptions {
            iso,
            ..DecodeOptions::default()
        };
        assert_error(
            Field::from_volume(volume.clone()).to_mesh(&options, &Silent),
            ErrorKind::BadParameter,
            None,
        );
    }
    // A level set the field never reaches is empty.
    let far = DecodeOptions {
        iso: -10.0,
        ..DecodeOptions::default()
    };
    assert_error(
        Field::from_volume(volume.clone()).to_mesh(&far, &Silent),
        ErrorKind::BadParameter,
        None,
    );

    let shape = Field::from_file(encoded(16).file);
    for distance in [0.0, -0.0, f32::NAN, f32::INFINITY] {
        assert_error(
            shape.offset(distance).map(|f| f.into_file().volume),
            ErrorKind::BadParameter,
            None,
        );
    }
    for thickness in [0.0, -0.01, f32::NAN] {
        assert_error(
            shape
                .shell(
                    &pgvol::ShellOptions {
                        thickness,
                        kind: ShellKind::Hollow,
                        drains: [].to_vec(),
                    },
                    &Silent,
                )
                .map(|f| f.into_file().volume),
            ErrorKind::BadParameter,
            None,
        );
    }
    for band in [0.0, -1.0, f32::NAN] {
        let options = SdfOptions {
            grid: GridSpec::Res(8),
            band: Some(band),
            ..SdfOptions::default()
        };
        assert_error(
            pgvol::distances::signed_distance(&mesh, &options, &Silent),
            ErrorKind::BadParameter,
            None,
        );
    }
    assert_error(
        pgvol::compare(&mesh, &mesh, 0, 1),
        ErrorKind::BadParameter,
        None,
    );
}

#[test]
fn grids_beyond_the_node_limit_are_resource_errors() {
    let mesh = sphere();
    // 9000³ and a spacing of 1e-4 over a side of 2.2 both exceed the 2³⁹ nodes (8192³) a
    // grid may have.
    for grid in [GridSpec::Res(9000), GridSpec::Voxel(1e-4)] {
        let options = EncodeOptions {
            grid,
            ..EncodeOptions::default()
        };
        assert_error(
            pgvol::encode(&mesh, &options, &Silent),
            ErrorKind::ResourceLimit,
            None,
        );
        let options = RemeshOptions {
            grid,
            ..RemeshOptions::default()
        };
        assert_error(
            pgvol::remesh(&mesh, &options, &Silent),
            ErrorKind::ResourceLimit,
            None,
        );
    }
    let volume = encoded(16).file.volume;
    let options = DecodeOptions {
        res: Some(3000),
        ..DecodeOptions::default()
    };
    assert_error(
        Field::from_volume(volume.clone()).to_mesh(&options, &Silent),
        ErrorKind::ResourceLimit,
        None,
    );
}

#[test]
fn a_resampling_too_coarse_to_hold_a_surface_is_refused_as_such() {
    let volume = encoded(16).file.volume;
    for res in [0, 1, 3] {
        let options = DecodeOptions {
            res: Some(res),
            ..DecodeOptions::default()
        };
        let e = assert_error(
            Field::from_volume(volume.clone()).to_mesh(&options, &Silent),
            ErrorKind::BadParameter,
            None,
        );
        assert!(
            e.message().contains(&format!(
                "resolution must be at least 4 nodes along the longest side, got {res}"
            )),
            "{e}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Progress: stages and cancellation.

/// Records what a call reports, and cancels once the stage `cancel_in` has begun (from the
/// start when it is `Some("")`).
#[derive(Default)]
struct Recorder {
    stages: Mutex<Vec<String>>,
    updates: Mutex<Vec<f64>>,
    /// Each update with the stage it came in.
    staged: Mutex<Vec<(String, f64)>>,
    finished: Mutex<usize>,
    cancel_in: Option<&'static str>,
}

impl Recorder {
    fn cancelling_in(stage: &'static str) -> Self {
        Self {
            cancel_in: Some(stage),
            ..Self::default()
        }
    }

    fn stages(&self) -> Vec<String> {
        self.stages.lock().unwrap().clone()
    }

    /// The fractions reported while `stage` ran.
    fn fractions_of(&self, stage: &str) -> Vec<f64> {
        self.staged
            .lock()
            .unwrap()
            .iter()
            .filter(|(s, _)| s == stage)
            .map(|&(_, f)| f)
            .collect()
    }
}

/// Asserts that `stage` of `recorder` reported several fractions, rising, ending near 1.
fn assert_fractions_rise_to_one(recorder: &Recorder, stage: &str, what: &str) {
    let f = recorder.fractions_of(stage);
    assert!(f.len() >= 5, "{what}: {stage} reported {f:?}");
    assert!(
        f.windows(2).all(|w| w[0] <= w[1]),
        "{what}: {stage} went back: {f:?}"
    );
    assert!(f.iter().all(|f| (0.0..=1.0).contains(f)), "{what}: {f:?}");
    assert!(*f.last().unwrap() > 0.99, "{what}: {stage} ended at {f:?}");
}

impl Progress for Recorder {
    fn stage(&self, name: &str) {
        self.stages.lock().unwrap().push(name.to_string());
    }
    fn update(&self, done: f64) {
        self.updates.lock().unwrap().push(done);
        let stage = self
            .stages
            .lock()
            .unwrap()
            .last()
            .cloned()
            .unwrap_or_default();
        self.staged.lock().unwrap().push((stage, done));
    }
    fn finish(&self) {
        *self.finished.lock().unwrap() += 1;
    }
    fn cancelled(&self) -> bool {
        match self.cancel_in {
            Some("") => true,
            Some(stage) => self.stages.lock().unwrap().iter().any(|s| s == stage),
            None => false,
        }
    }
}

/// The stages each fit reports: `Iso` queries distances as its points move, inside the fit.
const FITS: [(FitMethod, &[&str]); 3] = [
    (FitMethod::Interp, &["distance", "fit"]),
    (FitMethod::Wls, &["distance", "fit"]),
    (FitMethod::Iso { z_step: Some(0.5) }, &["fit"]),
];

#[test]
fn encode_reports_its_stages_and_fractions() {
    for (fit, stages) in FITS {
        let recorder = Recorder::default();
        let options = EncodeOptions {
            fit,
            ..encode_options(16)
        };
        pgvol::encode(&sphere(), &options, &recorder).unwrap();
        assert_eq!(recorder.stages(), stages, "{fit:?}");
        assert_eq!(*recorder.finished.lock().unwrap(), stages.len(), "{fit:?}");
        let updates = recorder.updates.lock().unwrap();
        assert!(
            updates.iter().all(|u| (0.0..=1.0).contains(u)),
            "{updates:?}"
        );
        if stages.contains(&"distance") {
            assert!(!updates.is_empty(), "{fit:?}: no fractions reported");
        }
    }
}

#[test]
fn remesh_and_decode_report_their_stages() {
    let recorder = Recorder::default();
    let options = RemeshOptions {
        grid: GridSpec::Res(24),
        ..RemeshOptions::default()
    };
    pgvol::remesh(&sphere(), &options, &recorder).unwrap();
    assert_eq!(recorder.stages(), ["distance", "contour"]);

    let recorder = Recorder::default();
    let options = RemeshOptions {
        field: RemeshField::Decoded(Basis::Bspline3),
        ..options
    };
    pgvol::remesh(&sphere(), &options, &recorder).unwrap();
    assert_eq!(recorder.stages(), ["distance", "fit", "contour"]);

    let recorder = Recorder::default();
    Field::from_volume(encoded(16).file.volume.clone())
        .to_mesh(&DecodeOptions::default(), &recorder)
        .unwrap();
    assert_eq!(recorder.stages(), ["contour"]);
}

#[test]
fn contouring_and_the_solving_fits_report_rising_fractions() {
    // Updates come from the worker threads and may overtake each other; on one thread they
    // arrive in order, so the check can ask for rising fractions.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        for fit in [FitMethod::Wls, FitMethod::Iso { z_step: None }] {
            let recorder = Recorder::default();
            let options = EncodeOptions {
                fit,
                ..encode_options(20)
            };
            pgvol::encode(&sphere(), &options, &recorder).unwrap();
            assert_fractions_rise_to_one(&recorder, "fit", &format!("{fit:?}"));
        }
        let recorder = Recorder::default();
        let options = RemeshOptions {
            grid: GridSpec::Res(40),
            ..RemeshOptions::default()
        };
        pgvol::remesh(&sphere(), &options, &recorder).unwrap();
        assert_fractions_rise_to_one(&recorder, "contour", "remesh");
        for method in [
            Method::MarchingCubes,
            Method::SurfaceNets,
            Method::DualContouring,
        ] {
            let recorder = Recorder::default();
            let options = DecodeOptions {
                method,
                res: Some(48),
                ..DecodeOptions::default()
            };
            Field::from_volume(encoded(32).file.volume.clone())
                .to_mesh(&options, &recorder)
                .unwrap();
            assert_fractions_rise_to_one(&recorder, "contour", &format!("decode {method:?}"));
        }
    });
}

#[test]
fn a_cancelled_encode_stops_with_cancelled() {
    let mesh = sphere();
    for (fit, stages) in FITS {
        let options = EncodeOptions {
            fit,
            ..encode_options(16)
        };
        let from_start = Recorder::cancelling_in("");
        assert_error(
            pgvol::encode(&mesh, &options, &from_start),
            ErrorKind::Cancelled,
            None,
        );
        assert!(from_start.stages().is_empty(), "{fit:?}: a stage began");
        for &stage in stages {
            let midway = Recorder::cancelling_in(stage);
            assert_error(
                pgvol::encode(&mesh, &options, &midway),
                ErrorKind::Cancelled,
                None,
            );
            // No stage begins once the caller has asked to stop.
            assert_eq!(
                midway.stages().last().map(String::as_str),
                Some(stage),
                "{fit:?}"
            );
        }
    }
}

#[test]
fn a_cancelled_remesh_stops_with_cancelled() {
    let mesh = sphere();
    let cases = [
        (RemeshField::Exact, &["", "distance", "contour"][..]),
        (
            RemeshField::Decoded(Basis::Bspline3),
            &["", "distance", "fit", "contour"][..],
        ),
    ];
    for (field, stages) in cases {
        let options = RemeshOptions {
            grid: GridSpec::Res(16),
            field,
            ..RemeshOptions::default()
        };
        for &stage in stages {
            let progress = Recorder::cancelling_in(stage);
            assert_error(
                pgvol::remesh(&mesh, &options, &progress),
                ErrorKind::Cancelled,
                None,
            );
        }
    }
}

#[test]
fn load_names_the_mesh_when_encoding_it_fails() {
    // A cancelled on-the-fly encode keeps its kind and gains the mesh's name.
    let dir = tempfile::tempdir().unwrap();
    let path: PathBuf = dir.path().join("s.obj");
    pgvol::io::write_mesh(&path, &sphere()).unwrap();
    let e = Field::open(
        &path,
        &pgvol::OpenOptions {
            res: 16,
            grow: 0.0,
            reach: 0.0,
            wall: None,
            sign: SignMode::Auto,
            ..Default::default()
        },
        &Recorder::cancelling_in(""),
    )
    .unwrap_err();
    assert_eq!((e.kind(), e.path()), (ErrorKind::Cancelled, Some(&*path)));
    let shape = Field::open(
        &path,
        &pgvol::OpenOptions {
            res: 16,
            grow: 0.0,
            reach: 0.1,
            wall: None,
            sign: SignMode::Auto,
            ..Default::default()
        },
        &Silent,
    )
    .unwrap();
    assert!(shape.band().is_some() && shape.mesh().is_some());
}

// ---------------------------------------------------------------------------------------------
// Meshes and grids given in memory (as the Python bindings give them).

#[test]
fn meshes_from_parts_are_checked_and_cleaned_like_read_meshes() {
    let s = sphere();
    // A triangle soup: every triangle with its own corners, plus one degenerate triangle.
    let mut positions: Vec<Vec3> = (0..s.triangles.len()).flat_map(|t| s.triangle(t)).collect();
    let mut triangles: Vec<[u32; 3]> = (0..s.triangles.len() as u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    positions.push(Vec3::ZERO);
    let last = positions.len() as u32 - 1;
    triangles.push([last, last, 0]);
    let pgvol::io::ReadMesh {
        mesh,
        cleaned: report,
    } = pgvol::io::mesh_from_parts(positions, triangles).unwrap();
    assert_eq!(report.degenerate_dropped, 1);
    assert_eq!(mesh.triangles.len(), s.triangles.len());
    assert!(mesh.stats().watertight);

    let bad = [
        (
            vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            vec![[0, 1, 3]],
            "refers to vertex 3",
        ),
        (vec![Vec3::ZERO, Vec3::X, Vec3::NAN], vec![[0, 1, 2]], "NaN"),
        (
            vec![Vec3::ZERO, Vec3::X * 1e9, Vec3::Y],
            vec![[0, 1, 2]],
            "out of range",
        ),
        (
            vec![Vec3::ZERO, Vec3::X * 1e-8, Vec3::Y * 1e-8],
            vec![[0, 1, 2]],
            "too small",
        ),
        (vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![], "no triangles"),
        (
            vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            vec![[0, 1, 1]],
            "no triangles left",
        ),
    ];
    for (positions, triangles, problem) in bad {
        let e = assert_error(
            pgvol::io::mesh_from_parts(positions, triangles),
            ErrorKind::BadParameter,
            None,
        );
        assert!(e.to_string().contains(problem), "{e}");
    }
}

#[test]
fn sampling_a_grid_gives_the_field_at_its_nodes_x_fastest() {
    let volume = encoded(24).file.volume;
    let grid = pgvol::Grid {
        origin: Vec3::new(-0.5, -0.25, 0.0),
        spacing: 0.125,
        dims: [3, 4, 5],
        offset: Default::default(),
    };
    let values = Field::from_volume(volume.clone())
        .sample_grid(&grid)
        .unwrap();
    assert_eq!(values.len(), 60);
    for (k, j, i) in [(0, 0, 0), (4, 3, 2), (2, 1, 0), (1, 3, 1)] {
        let p = grid.origin + grid.spacing * Vec3::new(i as f32, j as f32, k as f32);
        assert_eq!(values[i + 3 * (j + 4 * k)], volume.value(p));
    }
    let nodes: Vec<Vec3> = (0..60)
        .map(|n| {
            grid.origin
                + grid.spacing * Vec3::new((n % 3) as f32, (n / 3 % 4) as f32, (n / 12) as f32)
        })
        .collect();
    assert_eq!(volume.values_many(&nodes), values);
    for (spacing, dims) in [(0.0, [2, 2, 2]), (f32::NAN, [2, 2, 2]), (0.1, [2, 0, 2])] {
        let grid = pgvol::Grid {
            spacing,
            dims,
            ..grid
        };
        assert_error(
            Field::from_volume(volume.clone()).sample_grid(&grid),
            ErrorKind::BadParameter,
            None,
        );
    }
    let huge = pgvol::Grid {
        dims: [1 << 12, 1 << 12, 1 << 12],
        ..grid
    };
    assert_error(
        Field::from_volume(volume.clone()).sample_grid(&huge),
        ErrorKind::ResourceLimit,
        None,
    );
}

#[test]
fn a_file_sliced_slab_by_slab_gives_the_layers_of_the_whole_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.pgv");
    let file = encoded(72).file;
    pgvol::io::write_pgv(&path, &file, &StorageOptions::default()).unwrap();
    let shape = Field::from_file(pgvol::io::read_pgv(&path).unwrap());
    for axis in [pgvol::Axis::X, pgvol::Axis::Y, pgvol::Axis::Z] {
        for height in [0.013, 0.2] {
            let settings = pgvol::SliceOptions {
                axis,
                ..pgvol::SliceOptions::new(height)
            };
            let whole = shape.slice(&settings, &Silent).map(|s| s.layers).unwrap();
            let streamed = pgvol::stream::slice_file(&path, &settings, &Silent).unwrap();
            assert!(whole.iter().filter(|l| !l.loops.is_empty()).count() >= 4);
            assert_eq!(streamed.layers, whole, "{axis:?} every {height}");
            assert_eq!(
                streamed.frame,
                shape.slice(&settings, &Silent).unwrap().frame
            );
        }
    }
    // A damaged file is refused, naming it.
    let mut bytes = std::fs::read(&path).unwrap();
    let n = bytes.len();
    bytes[n / 2] ^= 0x10;
    std::fs::write(&path, &bytes).unwrap();
    let e = pgvol::stream::slice_file(&path, &pgvol::SliceOptions::new(0.05), &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InputFile);
    assert!(e.to_string().contains("s.pgv"), "{e}");
}

/// `file` written to `path` with the default storage and read back: the coefficients a
/// streamed decode of `path` reads.
fn written_and_read(path: &Path, file: &pgvol::PgvFile) -> Field {
    pgvol::io::write_pgv(path, file, &StorageOptions::default()).unwrap();
    Field::from_file(pgvol::io::read_pgv(path).unwrap())
}

/// Levels and resamplings a streamed decode is checked at: the surface, an offset of one
/// spacing, and the surface on another grid.
fn stream_cases(shape: &Field) -> [(f32, Option<usize>); 3] {
    let h = shape.volume().grid.spacing;
    [(0.0, None), (h, None), (0.0, Some(97))]
}

/// The unit normals a binary little-endian PLY of `pgvol`'s writer stores, one per vertex.
fn ply_normals(bytes: &[u8]) -> Vec<Vec3> {
    let end = b"end_header\n";
    let body = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = std::str::from_utf8(&bytes[..body]).unwrap();
    assert!(header.contains("property float nx"), "{header}");
    let count: usize = header
        .split("element vertex ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .unwrap()
        .parse()
        .unwrap();
    let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    (0..count)
        .map(|i| {
            let at = body + 24 * i + 12;
            Vec3::new(float(at), float(at + 4), float(at + 8))
        })
        .collect()
}

#[test]
fn decoded_vertices_carry_the_fields_normals_through_speck_removal_into_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("n.pgv");
    // A small box below the sphere: its vertices come first, so removing it renumbers every
    // vertex of the sphere.
    let mut mesh = sphere();
    let speck = shapes::cuboid(Vec3::new(-0.2, -0.2, -1.6), Vec3::new(0.0, 0.0, -1.4));
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(speck.positions);
    mesh.triangles
        .extend(speck.triangles.iter().map(|t| t.map(|i| i + base)));
    let file = pgvol::encode(&mesh, &encode_options(150), &Silent)
        .unwrap()
        .file;
    let shape = written_and_read(&path, &file);
    for (iso, res) in stream_cases(&shape) {
        let options = DecodeOptions {
            iso,
            res,
            min_component: Some(0.05),
            ..Default::default()
        };
        let streamed = pgvol::stream::decode_file(&path, &options, &Silent).unwrap();
        let whole = shape.to_mesh(&options, &Silent).unwrap();
        assert_eq!(streamed.normals, whole.normals, "iso {iso} res {res:?}");
        // Only the sphere is left.
        assert!(
            streamed.positions.iter().all(|p| p.z > -1.3),
            "iso {iso} res {res:?}"
        );
        let n = streamed.positions.len();
        assert_eq!(streamed.normals.len(), n, "iso {iso} res {res:?}");
        // Each normal is the field's gradient direction at its own vertex.
        let points: Vec<_> = (0..n).map(|i| streamed.world(i)).collect();
        for (i, e) in shape.eval(&points).iter().enumerate() {
            let want = Vec3::from_array(e.gradient).normalize();
            let got = streamed.normals[i];
            assert!(
                (got.length() - 1.0).abs() < 1e-5 && got.dot(want) > 0.9999,
                "iso {iso} res {res:?}: vertex {i} at {}: {got} against {want}",
                streamed.positions[i]
            );
        }
        // The file stores them.
        let out = dir.path().join("n.ply");
        pgvol::io::write_mesh(&out, &streamed).unwrap();
        let written = ply_normals(&std::fs::read(&out).unwrap());
        assert_eq!(written, streamed.normals, "iso {iso} res {res:?}");
    }
}

#[test]
fn a_file_decoded_window_by_window_gives_the_mesh_of_the_whole_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d.pgv");
    // 150 layers along z: three runs of contouring, each from its own window of slabs.
    let file = encoded(150).file;
    let shape = written_and_read(&path, &file);
    for (iso, res) in stream_cases(&shape) {
        let options = DecodeOptions {
            iso,
            res,
            ..Default::default()
        };
        let whole = shape.to_mesh(&options, &Silent).unwrap();
        let streamed = pgvol::stream::decode_file(&path, &options, &Silent).unwrap();
        assert_eq!(streamed.positions, whole.positions, "iso {iso} res {res:?}");
        assert_eq!(streamed.triangles, whole.triangles, "iso {iso} res {res:?}");
        let s = streamed.stats();
        assert!(s.watertight && s.winding_consistent, "{s:?}");
        // The offset surface encloses the mesh's volume plus about its area times the level.
        let mesh = sphere().stats();
        let exact = mesh.volume + mesh.area * f64::from(iso);
        assert!(
            (s.volume - exact).abs() < 0.01 * exact,
            "{} vs {exact}",
            s.volume
        );
    }
    // A level past the recorded band is refused, as for the whole field.
    let far = DecodeOptions {
        iso: 0.4,
        ..Default::default()
    };
    let e = pgvol::stream::decode_file(&path, &far, &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
    assert!(shape.to_mesh(&far, &Silent).is_err());
    // A damaged file is refused, naming it.
    let mut bytes = std::fs::read(&path).unwrap();
    let n = bytes.len();
    bytes[n / 2] ^= 0x10;
    std::fs::write(&path, &bytes).unwrap();
    let e = pgvol::stream::decode_file(&path, &Default::default(), &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InputFile);
    assert!(e.to_string().contains("d.pgv"), "{e}");
}
