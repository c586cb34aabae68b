//! The reader decodes brick layers in parallel: the volume, and the error on a damaged file,
//! must not depend on the number of threads, and must equal what reading brick by brick gives.

use std::path::Path;

use glam::Vec3;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_format::{
    decode_pgv, encode_pgv, encode_pgv_with, header_for, pgv_info, read_brick, Compression,
    EncodeOptions, PgvFile, Precision, Predictor,
};

fn p() -> &'static Path {
    Path::new("t.pgv")
}

/// Two banded spheres on a grid whose sides are not multiples of the brick edges, so that the
/// far bricks are partial and there are many brick layers.
fn two_spheres() -> PgvFile {
    spheres_on(Grid {
        origin: Vec3::new(-1.0, -0.8, -1.2),
        spacing: 0.05,
        dims: [41, 33, 50],
        offset: Default::default(),
    })
}

fn spheres_on(grid: Grid) -> PgvFile {
    let clamp = 4.0 * grid.spacing;
    let mut samples = Vec::with_capacity(grid.len());
    for k in 0..grid.dims[2] {
        for j in 0..grid.dims[1] {
            for i in 0..grid.dims[0] {
                let q = grid.point(i, j, k);
                let a = (q - Vec3::new(-0.3, 0.0, -0.4)).length() - 0.4;
                let b = (q - Vec3::new(0.4, 0.1, 0.5)).length() - 0.3;
                samples.push(a.min(b).clamp(-clamp, clamp));
            }
        }
    }
    let volume = CoefficientVolume::new(grid, Basis::Trilinear, samples).unwrap();
    PgvFile {
        header: header_for(&volume, "interp", None),
        volume,
    }
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The volume assembled from `read_brick`, which decodes each brick on its own.
fn brick_by_brick(bytes: &[u8], dims: [usize; 3], edge: usize) -> Vec<f32> {
    let mut out = vec![f32::NAN; dims.iter().product()];
    let count = dims.map(|n| n.div_ceil(edge));
    for bk in 0..count[2] {
        for bj in 0..count[1] {
            for bi in 0..count[0] {
                let b = read_brick(bytes, p(), [bi, bj, bk]).unwrap();
                let mut at = 0;
                for k in 0..b.dims[2] {
                    for j in 0..b.dims[1] {
                        for i in 0..b.dims[0] {
                            let [x, y, z] = [0, 1, 2].map(|a| b.first_node[a]);
                            out[x + i + dims[0] * (y + j + dims[1] * (z + k))] = b.coeffs[at];
                            at += 1;
                        }
                    }
                }
            }
        }
    }
    out
}

fn variants() -> Vec<EncodeOptions> {
    let mut all = Vec::new();
    for (brick, precision, predictor, compression) in [
        (8, Precision::Q16, Predictor::DeltaX, Compression::Zstd),
        (8, Precision::F16, Predictor::DeltaX, Compression::Zstd),
        (5, Precision::F32, Predictor::Lorenzo, Compression::Zstd),
        (3, Precision::Q16, Predictor::None, Compression::None),
        (32, Precision::F16, Predictor::Lorenzo, Compression::None),
        (8, Precision::Fixed, Predictor::DeltaX, Compression::Zstd),
        (6, Precision::Fixed, Predictor::Lorenzo, Compression::None),
    ] {
        all.push(EncodeOptions {
            precision: Some(precision),
            brick,
            predictor,
            compression,
            band: 2.0,
            zstd_level: 3,
            ..EncodeOptions::default()
        });
    }
    all
}

#[test]
fn thread_count_does_not_change_the_volume() {
    let f = two_spheres();
    let dims = f.volume.grid.dims;
    for o in variants() {
        let (bytes, report) = encode_pgv_with(&f, &o).unwrap();
        assert!(report.bricks_stored > 0 && report.bricks_stored < report.bricks_total);
        let one = in_pool(1, || decode_pgv(&bytes, p()).unwrap());
        let want = bits(&one.volume.dense_coeffs());
        for threads in [2, 3, 8] {
            let many = in_pool(threads, || decode_pgv(&bytes, p()).unwrap());
            assert_eq!(
                bits(&many.volume.dense_coeffs()),
                want,
                "{o:?}, {threads} threads"
            );
            assert_eq!(many.header, one.header);
        }
        let alone = brick_by_brick(&bytes, dims, o.brick);
        assert_eq!(bits(&alone), want, "{o:?}: brick by brick");
    }
}

#[test]
fn thin_grids_in_small_bricks_read_the_same() {
    // Two nodes across x and bricks of 2: one brick per row, many rows per layer.
    let f = spheres_on(Grid {
        origin: Vec3::new(-0.3, -0.9, -1.0),
        spacing: 0.05,
        dims: [2, 37, 41],
        offset: Default::default(),
    });
    let o = EncodeOptions {
        precision: Some(Precision::F16),
        brick: 2,
        band: 1.0,
        zstd_level: 3,
        ..EncodeOptions::default()
    };
    let (bytes, report) = encode_pgv_with(&f, &o).unwrap();
    assert!(report.bricks_stored > 0 && report.bricks_stored < report.bricks_total);
    let want = bits(&brick_by_brick(&bytes, f.volume.grid.dims, 2));
    for threads in [1, 2, 6] {
        let back = in_pool(threads, || decode_pgv(&bytes, p()).unwrap());
        assert_eq!(bits(&back.volume.dense_coeffs()), want, "{threads} threads");
    }
}

#[test]
fn dense_files_read_the_same_on_any_thread_count() {
    let f = two_spheres();
    let bytes = encode_pgv(&f);
    for threads in [1, 2, 5] {
        let back = in_pool(threads, || decode_pgv(&bytes, p()).unwrap());
        assert_eq!(
            bits(&back.volume.dense_coeffs()),
            bits(&f.volume.dense_coeffs())
        );
    }
    // A non-finite value is found, and named, whichever chunk holds it.
    let mut bad = bytes.clone();
    let hlen = u32::from_le_bytes(bad[12..16].try_into().unwrap()) as usize;
    let payload = 28 + hlen;
    let index = f.volume.grid.len() - 3;
    bad[payload + 4 * index..payload + 4 * index + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let end = bad.len() - 4;
    let crc = crc32fast::hash(&bad[payload..end]);
    bad[end..].copy_from_slice(&crc.to_le_bytes());
    for threads in [1, 3] {
        let e = in_pool(threads, || decode_pgv(&bad, p()).unwrap_err().to_string());
        assert!(e.contains(&format!("value {index} is not finite")), "{e}");
    }
}

#[test]
fn damaged_bricks_give_the_same_error_on_any_thread_count() {
    let f = two_spheres();
    let o = &variants()[0];
    // In the version 1 layout, whose payload CRC the damage is made to agree with, so that the
    // bricks' own CRCs are what finds it.
    let good = pgvol_format::sparse_pgv(&f, o).unwrap().0.to_bytes_v1();
    let info = pgv_info(&good, p()).unwrap();
    let (total, stored) = (info.bricks_total.unwrap(), info.bricks_stored.unwrap());
    let hlen = u32::from_le_bytes(good[12..16].try_into().unwrap()) as usize;
    let payload = 28 + hlen;
    let map = total.div_ceil(8);
    let data = payload + 2 * map + 16 * stored + 4;
    let entry_offset = |e: usize| {
        let at = payload + 2 * map + 16 * e;
        u64::from_le_bytes(good[at..at + 8].try_into().unwrap()) as usize
    };
    let stored_bricks: Vec<usize> = (0..total)
        .filter(|&b| good[payload + b / 8] >> (b % 8) & 1 == 1)
        .collect();
    let count = info.header.sparse.as_ref().unwrap().bricks;
    let coords = |b: usize| {
        [
            b % count[0],
            b / count[0] % count[1],
            b / (count[0] * count[1]),
        ]
    };
    // Damage a late brick and an early one; the error names the earlier in brick order.
    let (early, late) = (stored.div_ceil(3), stored - 1);
    let mut bad = good.clone();
    for e in [late, early] {
        bad[data + entry_offset(e)] ^= 0x5a;
    }
    let end = bad.len() - 4;
    let crc = crc32fast::hash(&bad[payload..end]);
    bad[end..].copy_from_slice(&crc.to_le_bytes());
    let want = format!("brick {:?} checksum mismatch", coords(stored_bricks[early]));
    for threads in [1, 2, 7] {
        let e = in_pool(threads, || decode_pgv(&bad, p()).unwrap_err().to_string());
        assert!(e.contains(&want), "{threads} threads: {e}");
    }
    let e = read_brick(&bad, p(), coords(stored_bricks[early]))
        .unwrap_err()
        .to_string();
    assert!(e.contains(&want), "brick by brick: {e}");
}
