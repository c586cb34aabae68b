//! Jobs computed in parts (`pgvol::distributed`) against the single-process jobs on the shared
//! meshes: the same file bytes, the same triangles and the same layers whatever the split.

use pgvol::distributed::{
    assemble_encode, decode_part, decode_part_bricks, part_encode_bytes, plan_decode, plan_encode,
    plan_encode_bytes, plan_slice, slice_part, slice_part_bricks, weld_parts, write_encode_parts,
    write_encode_parts_to, EncodeJob, EncodedPart, PartsWritten,
};
use pgvol::{Basis, DecodeOptions, EncodeOptions, GridSpec, Mesh, Silent, StorageOptions};
use pgvol_tests::load_shared;

/// The parts of `mesh` encoded in `parts` parts.
fn encoded_parts(mesh: &Mesh, options: &EncodeOptions, parts: usize) -> Vec<EncodedPart> {
    let plan = plan_encode(mesh, options, parts).unwrap();
    if parts == 8 {
        // More parts than z layers of groups: the slabs are cut along y too.
        assert!(
            plan.parts.iter().any(|p| p.gy.start > 0),
            "{:?}",
            plan.parts
        );
    }
    let job = EncodeJob::new(mesh, options).unwrap();
    plan.parts
        .iter()
        .map(|p| job.encode_part(p).unwrap())
        .collect()
}

/// The file of `mesh` assembled in memory from `parts` parts.
fn encode_in_parts(mesh: &Mesh, options: &EncodeOptions, parts: usize) -> pgvol::Encoded {
    let results = encoded_parts(mesh, options, parts);
    let bytes: Vec<&[u8]> = results.iter().map(|r| r.bricks.as_slice()).collect();
    assemble_encode(mesh, options, &bytes).unwrap()
}

/// The file of `mesh` written from `parts` parts as they come.
fn streamed_in_parts(mesh: &Mesh, options: &EncodeOptions, parts: usize) -> Vec<u8> {
    let mut out = Vec::new();
    let mut results = encoded_parts(mesh, options, parts).into_iter().map(Ok);
    let got = write_encode_parts_to(&mut out, mesh, options, &mut results).unwrap();
    assert!(matches!(got, PartsWritten::Written(_)), "{got:?}");
    out
}

/// Triangles as sorted triples of vertex bit patterns, sorted: equal for equal meshes in any
/// vertex or triangle order.
fn triangle_set(mesh: &Mesh) -> Vec<[[u32; 3]; 3]> {
    let mut out: Vec<[[u32; 3]; 3]> = mesh
        .triangles
        .iter()
        .map(|t| {
            let mut v = t.map(|i| mesh.positions[i as usize].to_array().map(f32::to_bits));
            // Keep the orientation: rotate the smallest vertex first.
            let m = (0..3).min_by_key(|&i| v[i]).unwrap_or(0);
            v.rotate_left(m);
            v
        })
        .collect();
    out.sort_unstable();
    out
}

#[test]
fn encoding_in_parts_gives_the_same_file_bytes() {
    for (name, res, basis) in [
        ("stanford-bunny", 150, Basis::Bspline3),
        ("fandisk", 80, Basis::Bspline2),
        ("spot", 72, Basis::Trilinear),
    ] {
        let mesh = load_shared(name);
        let options = EncodeOptions {
            grid: GridSpec::Res(res),
            basis,
            ..EncodeOptions::default()
        };
        let whole = pgvol::encode(&mesh, &options, &Silent).unwrap();
        let want = pgvol::io::pgv_bytes(&whole.file, &StorageOptions::default())
            .unwrap()
            .bytes;
        for parts in [1, 2, 8] {
            let got = encode_in_parts(&mesh, &options, parts);
            let bytes = pgvol::io::pgv_bytes(&got.file, &StorageOptions::default())
                .unwrap()
                .bytes;
            assert!(bytes == want, "{name}: {parts} parts give other bytes");
            let streamed = streamed_in_parts(&mesh, &options, parts);
            assert!(
                streamed == want,
                "{name}: {parts} streamed parts give other bytes"
            );
        }
    }
}

#[test]
fn sharp_feature_vertices_in_parts_are_the_single_process_ones() {
    let mesh = load_shared("fandisk");
    let options = EncodeOptions {
        grid: GridSpec::Res(96),
        sharp: pgvol::sharp::SharpOptions {
            enabled: true,
            ..Default::default()
        },
        ..EncodeOptions::default()
    };
    let whole = pgvol::encode(&mesh, &options, &Silent).unwrap();
    assert!(whole.sharp.stored_cells > 1000, "{:?}", whole.sharp);
    let want = pgvol::io::pgv_bytes(&whole.file, &StorageOptions::default())
        .unwrap()
        .bytes;
    for parts in [2, 8] {
        let got = encode_in_parts(&mesh, &options, parts);
        assert_eq!(got.sharp, whole.sharp);
        let bytes = pgvol::io::pgv_bytes(&got.file, &StorageOptions::default())
            .unwrap()
            .bytes;
        assert!(bytes == want, "{parts} parts give other bytes");
        let streamed = streamed_in_parts(&mesh, &options, parts);
        assert!(streamed == want, "{parts} streamed parts give other bytes");
    }
}

#[test]
fn streamed_parts_that_stop_leave_the_file_as_it_was() {
    let mesh = load_shared("spot");
    let options = EncodeOptions {
        grid: GridSpec::Res(72),
        ..EncodeOptions::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("spot.pgv");
    std::fs::write(&path, b"the file before").unwrap();
    let mut parts = encoded_parts(&mesh, &options, 2);
    // A part that failed (a lost worker, say) stops the writing after the first part.
    let failed = pgvol::Error::parameter("the second part failed");
    let mut results = [Ok(parts[0].clone()), Err(failed)].into_iter();
    let err = write_encode_parts(&path, &mesh, &options, &mut results).unwrap_err();
    assert!(err.to_string().contains("the second part failed"), "{err}");
    assert_eq!(std::fs::read(&path).unwrap(), b"the file before");
    // Parts out of order are refused, naming the file.
    parts.swap(0, 1);
    let mut results = parts.clone().into_iter().map(Ok);
    let err = write_encode_parts(&path, &mesh, &options, &mut results).unwrap_err();
    assert!(err.to_string().contains("do not tile"), "{err}");
    assert!(err.to_string().contains("spot.pgv"), "{err}");
    assert_eq!(std::fs::read(&path).unwrap(), b"the file before");
    // In order, the file is the single-process one.
    parts.swap(0, 1);
    let mut results = parts.into_iter().map(Ok);
    let got = write_encode_parts(&path, &mesh, &options, &mut results).unwrap();
    let PartsWritten::Written(report) = got else {
        panic!("{got:?}");
    };
    let whole = pgvol::encode(&mesh, &options, &Silent).unwrap();
    let want = pgvol::io::pgv_bytes(&whole.file, &StorageOptions::default()).unwrap();
    assert!(std::fs::read(&path).unwrap() == want.bytes);
    assert_eq!(Some(report), want.storage);
}

#[test]
fn a_part_that_is_not_its_own_differs() {
    // The assembly refuses parts that do not tile the grid, rather than filling the gap.
    let mesh = load_shared("spot");
    let options = EncodeOptions {
        grid: GridSpec::Res(72),
        ..EncodeOptions::default()
    };
    let plan = plan_encode(&mesh, &options, 2).unwrap();
    assert_eq!(plan.parts.len(), 2);
    let job = EncodeJob::new(&mesh, &options).unwrap();
    let second = job.encode_part(&plan.parts[1]).unwrap();
    let err = assemble_encode(&mesh, &options, &[&second.bricks]).unwrap_err();
    assert!(err.to_string().contains("do not tile"), "{err}");
}

#[test]
fn decoding_and_slicing_in_parts_match_the_whole() {
    let mesh = load_shared("stanford-bunny");
    let options = EncodeOptions {
        grid: GridSpec::Res(96),
        ..EncodeOptions::default()
    };
    let file = pgvol::encode(&mesh, &options, &Silent).unwrap().file;
    let decode_options = DecodeOptions::default();
    let whole = pgvol::Field::from_volume(file.volume.clone())
        .to_mesh(&decode_options, &Silent)
        .unwrap();
    let want = triangle_set(&whole);
    for parts in [1, 2, 8] {
        let pieces: Vec<Mesh> = plan_decode(&file.volume, parts)
            .unwrap()
            .into_iter()
            .map(|cells| {
                let bricks = decode_part_bricks(&file.volume, cells.clone());
                decode_part(&bricks, cells, &decode_options).unwrap()
            })
            .collect();
        let welded =
            weld_parts(pieces, file.volume.grid.spacing, &decode_options, &Silent).unwrap();
        let stats = welded.stats();
        assert_eq!(stats.boundary_edges, 0, "{parts} parts");
        assert!(stats.watertight, "{parts} parts");
        assert_eq!(
            welded.positions.len(),
            whole.positions.len(),
            "{parts} parts"
        );
        assert!(triangle_set(&welded) == want, "{parts} parts");
    }

    let shape = pgvol::Field::from_file(file);
    let settings = pgvol::SliceOptions::new(shape.volume().grid.spacing * 1.7);
    let layers = shape.slice(&settings, &Silent).map(|s| s.layers).unwrap();
    for parts in [1, 3, 8] {
        let mut got = Vec::new();
        for range in plan_slice(&shape, &settings, parts).unwrap() {
            let bricks = slice_part_bricks(&shape, &settings, range.clone()).unwrap();
            got.extend(slice_part(&bricks, shape.bounds(), &settings, range).unwrap());
        }
        assert_eq!(got, layers, "{parts} parts");
    }
}

#[test]
fn a_plans_estimates_in_one_pass_are_each_parts_own() {
    let mesh = load_shared("stanford-bunny");
    let options = EncodeOptions {
        grid: GridSpec::Res(300),
        ..EncodeOptions::default()
    };
    for parts in [1, 3, 40] {
        let plan = plan_encode(&mesh, &options, parts).unwrap();
        let each: Vec<u64> = plan
            .parts
            .iter()
            .map(|p| part_encode_bytes(&mesh, &options, p).unwrap())
            .collect();
        assert_eq!(plan_encode_bytes(&mesh, &options, &plan).unwrap(), each);
        // Parts with and without surface: the figures depend on the part.
        let (least, most) = (each.iter().min().unwrap(), each.iter().max().unwrap());
        assert!(parts == 1 || least < most, "{parts} parts: {each:?}");
    }
}
