//! The sparse-bricks encoding: round trips, the band rule, random access, and damaged files.

use std::path::Path;

use glam::Vec3;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_format::pgv::MAGIC;
use pgvol_format::{
    decode_pgv, encode_pgv, encode_pgv_with, header_for, pgv_info, read_brick, read_pgv,
    sparse_pgv, write_pgv_with, Compression, EncodeOptions, PgvFile, Precision, Predictor,
};
use proptest::prelude::*;

/// A banded sphere distance (clamped at 4 spacings, as `pgvol encode` samples) interpolated by
/// `basis` on an n³ grid; the sphere sits off-centre so some bricks are background.
fn sphere_file(n: usize, basis: Basis) -> PgvFile {
    let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), n).unwrap();
    let clamp = 4.0 * grid.spacing;
    let mut samples = Vec::with_capacity(grid.len());
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = grid.point(i, j, k);
                let d = (p - Vec3::new(0.3, -0.2, 0.1)).length() - 0.45;
                samples.push(d.clamp(-clamp, clamp));
            }
        }
    }
    let volume = CoefficientVolume::interpolate(grid, basis, samples).unwrap();
    let header = header_for(&volume, "interp", None);
    PgvFile { header, volume }
}

fn opts(precision: Option<Precision>) -> EncodeOptions {
    EncodeOptions {
        precision,
        ..EncodeOptions::default()
    }
}

fn p() -> &'static Path {
    Path::new("s.pgv")
}

/// Node index sets of every brick of edge `e`, with their brick coordinates.
fn bricks(dims: [usize; 3], e: usize) -> Vec<([usize; 3], Vec<usize>)> {
    let c = dims.map(|n| n.div_ceil(e));
    let mut out = Vec::new();
    for bk in 0..c[2] {
        for bj in 0..c[1] {
            for bi in 0..c[0] {
                let mut idx = Vec::new();
                for k in bk * e..((bk + 1) * e).min(dims[2]) {
                    for j in bj * e..((bj + 1) * e).min(dims[1]) {
                        for i in bi * e..((bi + 1) * e).min(dims[0]) {
                            idx.push(i + dims[0] * (j + dims[1] * k));
                        }
                    }
                }
                out.push(([bi, bj, bk], idx));
            }
        }
    }
    out
}

#[test]
fn f32_round_trip_is_exact_on_stored_bricks_and_constant_elsewhere() {
    let f = sphere_file(30, Basis::Bspline3);
    let o = EncodeOptions {
        brick: 8,
        ..opts(Some(Precision::F32))
    };
    let (bytes, r) = encode_pgv_with(&f, &o).unwrap();
    assert_eq!(r.precision, Precision::F32);
    assert_eq!(r.max_quantisation_error, 0.0);
    assert_eq!(r.bricks_total, 64);
    assert!(
        r.bricks_stored > 0 && r.bricks_stored < r.bricks_total,
        "{r:?}"
    );
    assert_eq!(
        r.bytes_header + r.bytes_index + r.bytes_payload,
        bytes.len()
    );
    assert!(bytes.len() < encode_pgv(&f).len());
    let back = decode_pgv(&bytes, p()).unwrap();
    assert_eq!(back.header.encoding, "sparse-bricks");
    let mut stored = 0;
    for (coords, idx) in bricks(f.volume.grid.dims, 8) {
        let b = read_brick(&bytes, p(), coords).unwrap();
        assert_eq!(b.coeffs.len(), idx.len());
        for (&i, &c) in idx.iter().zip(&b.coeffs) {
            assert_eq!(back.volume.coeffs.get_index(i).to_bits(), c.to_bits());
            if b.stored {
                assert_eq!(c.to_bits(), f.volume.coeffs.get_index(i).to_bits());
            } else {
                assert_eq!(c.abs(), r.clamp);
                // Background keeps the side of the surface.
                assert_eq!(c < 0.0, f.volume.coeffs.get_index(i) < 0.0);
            }
        }
        stored += b.stored as usize;
    }
    assert_eq!(stored, r.bricks_stored);
}

#[test]
fn the_field_near_the_surface_is_unchanged() {
    // Every cell with a corner within the band must evaluate exactly as before: the basis
    // support of such points lies in stored bricks.
    for basis in [
        Basis::Trilinear,
        Basis::Bspline2,
        Basis::Bspline3,
        Basis::Pg { n: 2, r: 1.7 },
    ] {
        let f = sphere_file(22, basis);
        let o = EncodeOptions {
            precision: Some(Precision::F32),
            band: 1.5,
            brick: 4,
            ..EncodeOptions::default()
        };
        let (bytes, r) = encode_pgv_with(&f, &o).unwrap();
        assert!(r.bricks_stored < r.bricks_total, "{basis:?} {r:?}");
        let back = decode_pgv(&bytes, p()).unwrap().volume;
        let g = f.volume.grid;
        let nodes = f.volume.sample(&g);
        let mut checked = 0;
        for n in 0..4000u32 {
            let t = Vec3::new(
                (n as f32 * 0.7548).fract(),
                (n as f32 * 0.5698).fract(),
                (n as f32 * 0.3141).fract(),
            );
            let u = t * (g.dims[0] - 1) as f32;
            let c = u.floor().as_uvec3();
            let near = (0..8).any(|m| {
                let (i, j, k) = (
                    (c.x + (m & 1)).min(g.dims[0] as u32 - 1) as usize,
                    (c.y + (m >> 1 & 1)).min(g.dims[1] as u32 - 1) as usize,
                    (c.z + (m >> 2 & 1)).min(g.dims[2] as u32 - 1) as usize,
                );
                nodes[g.index(i, j, k)].abs() <= 1.5 * g.spacing
            });
            if near {
                let x = g.origin + u * g.spacing;
                assert_eq!(back.value(x), f.volume.value(x), "{basis:?} at {x}");
                checked += 1;
            }
        }
        assert!(checked > 100, "{basis:?}: {checked}");
    }
}

#[test]
fn auto_precision_stays_within_one_percent_of_the_spacing() {
    let f = sphere_file(40, Basis::Bspline3);
    let h = f.volume.grid.spacing;
    let (auto, r) = encode_pgv_with(&f, &opts(None)).unwrap();
    assert_ne!(r.precision, Precision::F32);
    assert!(r.max_quantisation_error <= 0.01 * h, "{r:?}");
    for p16 in [Precision::F16, Precision::Q16] {
        let (b, r16) = encode_pgv_with(&f, &opts(Some(p16))).unwrap();
        assert!(auto.len() <= b.len(), "auto picked the bigger one");
        assert!(r16.max_quantisation_error > 0.0);
    }
    let (b32, _) = encode_pgv_with(&f, &opts(Some(Precision::F32))).unwrap();
    assert!(auto.len() < b32.len());
    // A field too large for f16 cannot be written as f16, and auto avoids it.
    let mut big = f.clone();
    big.volume.coeffs.map_values(|c| c * 1e6);
    let wide = |precision| EncodeOptions {
        precision,
        band: 1e12,
        ..EncodeOptions::default()
    };
    let Err(e) = encode_pgv_with(&big, &wide(Some(Precision::F16))) else {
        panic!("f16 overflow accepted");
    };
    let e = e.to_string();
    assert!(e.contains("f16"), "{e}");
    let (_, r) = encode_pgv_with(&big, &wide(None)).unwrap();
    assert_eq!(r.bricks_stored, r.bricks_total);
    assert_ne!(r.precision, Precision::F16);
}

/// `fixed` keeps the coefficients the band needs within half a step and moves the others by
/// at most the free tolerance (plus half a coarse step), which makes the file smaller.
#[test]
fn fixed_moves_only_coefficients_the_band_does_not_need() {
    let f = sphere_file(40, Basis::Bspline3);
    let h = f.volume.grid.spacing;
    let values = f.volume.sample(&f.volume.grid);
    let fixed = |free_tolerance| EncodeOptions {
        precision: Some(Precision::Fixed),
        free_tolerance,
        ..EncodeOptions::default()
    };
    let (strict, rs) = encode_pgv_with(&f, &fixed(0.0)).unwrap();
    let (loose, rl) = encode_pgv_with(&f, &fixed(0.5)).unwrap();
    assert!(
        loose.len() < strict.len(),
        "{} {}",
        loose.len(),
        strict.len()
    );
    assert_eq!(rs.max_quantisation_error, rl.max_quantisation_error);
    let file = decode_pgv(&loose, p()).unwrap();
    let s = file.header.sparse.as_ref().unwrap().fixed.unwrap();
    let coarse = s.step * s.ratio as f32;
    let clamp = file.header.sparse.as_ref().unwrap().clamp;
    assert!(rl.max_quantisation_error <= coarse / 2.0 * 1.001, "{rl:?}");
    let [nx, ny, nz] = f.volume.grid.dims;
    let (mut moved, mut checked) = (0, 0);
    for (idx, (&a, &d)) in f
        .volume
        .dense_coeffs()
        .iter()
        .zip(&file.volume.dense_coeffs())
        .enumerate()
    {
        let at = [idx % nx, (idx / nx) % ny, idx / (nx * ny)];
        // Needed: within 2 nodes (the cubic reach) of a node within the band.
        let mut needed = false;
        for k in at[2].saturating_sub(2)..=(at[2] + 2).min(nz - 1) {
            for j in at[1].saturating_sub(2)..=(at[1] + 2).min(ny - 1) {
                for i in at[0].saturating_sub(2)..=(at[0] + 2).min(nx - 1) {
                    needed |= values[i + nx * (j + ny * k)].abs() <= 3.0 * h;
                }
            }
        }
        if needed {
            assert!((a - d).abs() <= coarse / 2.0 * 1.001, "{at:?}: {a} -> {d}");
            checked += 1;
        } else if d.abs() != clamp {
            // Not in a background brick (whose value is the clamp).
            assert!(
                (a - d).abs() <= 0.5 * h + coarse / 2.0 * 1.001,
                "{at:?}: {a} -> {d}"
            );
            moved += ((a - d).abs() > coarse) as usize;
        }
    }
    assert!(checked > 1000 && moved > 100, "{checked} {moved}");
    // Free coefficients move only towards zero, so the largest node value, which `pgvol offset`
    // reads as the stored band, is no larger than without them.
    let largest = |bytes: &[u8]| {
        let v = decode_pgv(bytes, p()).unwrap().volume;
        let values = v.sample(&v.grid);
        values.iter().fold(0.0f32, |m, x| m.max(x.abs()))
    };
    assert!(largest(&loose) <= largest(&strict));
}

#[test]
fn every_option_decodes_the_same_coefficients() {
    let f = sphere_file(19, Basis::Bspline3);
    let reference = {
        let (b, _) = encode_pgv_with(&f, &opts(Some(Precision::Q16))).unwrap();
        decode_pgv(&b, p()).unwrap().volume.coeffs
    };
    for predictor in [Predictor::None, Predictor::DeltaX, Predictor::Lorenzo] {
        for shuffle in [false, true] {
            for compression in [Compression::None, Compression::Zstd] {
                let o = EncodeOptions {
                    precision: Some(Precision::Q16),
                    predictor,
                    shuffle,
                    compression,
                    zstd_level: 3,
                    ..EncodeOptions::default()
                };
                let (b, _) = encode_pgv_with(&f, &o).unwrap();
                let got = decode_pgv(&b, p()).unwrap().volume.coeffs;
                assert_eq!(got, reference, "{predictor:?} {shuffle} {compression:?}");
            }
        }
    }
}

#[test]
fn info_reads_header_and_index_and_files_round_trip_on_disk() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.pgv");
    let f = sphere_file(20, Basis::Bspline3);
    let r = write_pgv_with(&path, &f, &opts(None)).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let info = pgv_info(&bytes, &path).unwrap();
    assert_eq!(info.bricks_total, Some(r.bricks_total));
    assert_eq!(info.bricks_stored, Some(r.bricks_stored));
    assert_eq!(info.precision, r.precision);
    assert_eq!(
        (info.bytes_header, info.bytes_index, info.bytes_payload),
        (r.bytes_header, r.bytes_index, r.bytes_payload)
    );
    // Info does not touch brick data: a damaged brick still gives info, but not a decode.
    let mut bad = bytes.clone();
    let at = bytes.len() - 4 - r.bytes_payload / 2;
    bad[at] ^= 0x10;
    assert!(pgv_info(&bad, &path).is_ok());
    assert!(decode_pgv(&bad, &path).is_err());
    let back = read_pgv(&path).unwrap();
    assert_eq!(back.volume.grid, f.volume.grid);

    let dense = encode_pgv(&f);
    let di = pgv_info(&dense, &path).unwrap();
    assert_eq!((di.bricks_total, di.precision), (None, Precision::F32));
    assert_eq!(di.bytes_payload, 4 * f.volume.grid.len());
    let e = read_brick(&dense, &path, [0, 0, 0])
        .unwrap_err()
        .to_string();
    assert!(e.contains("sparse-bricks"), "{e}");
}

#[test]
fn dense_files_written_before_still_read() {
    let f = sphere_file(6, Basis::Trilinear);
    let bytes = encode_pgv(&f);
    // The dense header carries no sparse field: byte-compatible with files written earlier.
    let text = String::from_utf8_lossy(&bytes);
    assert!(text.contains("\"encoding\":\"dense-f32\"") && !text.contains("sparse"));
    assert_eq!(decode_pgv(&bytes, p()).unwrap(), f);
}

// ---- damaged files -------------------------------------------------------------------------

/// A sparse file taken apart: header JSON, payload before the data, the blobs.
struct Parts {
    header: serde_json::Value,
    maps: Vec<u8>,
    blobs: Vec<Vec<u8>>,
}

/// The header, the payload (version 1) or the index and the brick data (version 2) of a file.
fn sections(bytes: &[u8]) -> (serde_json::Value, Vec<u8>, Vec<u8>) {
    let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap());
    if version == 1 {
        let hlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let header = serde_json::from_slice(&bytes[16..16 + hlen]).unwrap();
        let payload = bytes[16 + hlen + 12..bytes.len() - 4].to_vec();
        return (header, payload, Vec::new());
    }
    let n = bytes.len();
    let dlen = u64::from_le_bytes(bytes[n - 32..n - 24].try_into().unwrap()) as usize;
    let ilen = u64::from_le_bytes(bytes[n - 24..n - 16].try_into().unwrap()) as usize;
    let hlen = u32::from_le_bytes(bytes[n - 16..n - 12].try_into().unwrap()) as usize;
    let header = serde_json::from_slice(&bytes[12 + dlen + ilen..12 + dlen + ilen + hlen]).unwrap();
    (
        header,
        bytes[12 + dlen..12 + dlen + ilen].to_vec(),
        bytes[12..12 + dlen].to_vec(),
    )
}

fn split(bytes: &[u8]) -> Parts {
    let (header, index, data) = sections(bytes);
    let sp = &header["sparse"];
    let nb: u64 = sp["bricks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .product();
    let map = nb.div_ceil(8) as usize;
    let stored = sp["stored"].as_u64().unwrap() as usize;
    let data = if data.is_empty() {
        index[2 * map + 16 * stored + 4..].to_vec()
    } else {
        data
    };
    let blobs = (0..stored)
        .map(|e| {
            let at = 2 * map + 16 * e;
            let off = u64::from_le_bytes(index[at..at + 8].try_into().unwrap()) as usize;
            let len = u32::from_le_bytes(index[at + 8..at + 12].try_into().unwrap()) as usize;
            data[off..off + len].to_vec()
        })
        .collect();
    Parts {
        header,
        maps: index[..2 * map].to_vec(),
        blobs,
    }
}

/// The brick maps and index of `parts` with their CRC; `entry` may rewrite index entries.
fn index_of(parts: &Parts, entry: impl Fn(usize, u64, u32) -> (u64, u32)) -> Vec<u8> {
    let mut meta = parts.maps.clone();
    let mut off = 0u64;
    for (e, b) in parts.blobs.iter().enumerate() {
        let (o, l) = entry(e, off, b.len() as u32);
        meta.extend_from_slice(&o.to_le_bytes());
        meta.extend_from_slice(&l.to_le_bytes());
        meta.extend_from_slice(&crc32fast::hash(b).to_le_bytes());
        off += b.len() as u64;
    }
    let icrc = crc32fast::hash(&meta);
    meta.extend_from_slice(&icrc.to_le_bytes());
    meta
}

/// Frames the parts again in the version 2 layout with correct checksums; `entry` may rewrite
/// index entries.
fn join(parts: &Parts, entry: impl Fn(usize, u64, u32) -> (u64, u32)) -> Vec<u8> {
    let index = index_of(parts, entry);
    let data: Vec<u8> = parts.blobs.concat();
    let header = serde_json::to_vec(&parts.header).unwrap();
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&data);
    out.extend_from_slice(&index);
    out.extend_from_slice(&header);
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    out.extend_from_slice(&(index.len() as u64).to_le_bytes());
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(&header).to_le_bytes());
    out.extend_from_slice(MAGIC);
    out
}

/// As [`join`], in the version 1 layout.
fn join_v1(parts: &Parts, entry: impl Fn(usize, u64, u32) -> (u64, u32)) -> Vec<u8> {
    let mut meta = index_of(parts, entry);
    for b in &parts.blobs {
        meta.extend_from_slice(b);
    }
    let header = serde_json::to_vec(&parts.header).unwrap();
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&crc32fast::hash(&header).to_le_bytes());
    out.extend_from_slice(&(meta.len() as u64).to_le_bytes());
    out.extend_from_slice(&meta);
    out.extend_from_slice(&crc32fast::hash(&meta).to_le_bytes());
    out
}

fn msg(bytes: &[u8]) -> String {
    let e = decode_pgv(bytes, p()).unwrap_err().to_string();
    assert!(e.starts_with("s.pgv: "), "{e}");
    e
}

#[test]
fn damaged_sparse_files_give_clear_errors() {
    let f = sphere_file(20, Basis::Bspline3);
    let (good, _) = encode_pgv_with(&f, &opts(None)).unwrap();
    let good_v1 = sparse_pgv(&f, &opts(None)).unwrap().0.to_bytes_v1();
    let parts = split(&good);
    // The test's own framing (JSON keys re-ordered) gives a valid file, in either layout.
    assert!(decode_pgv(&join(&parts, |_, o, l| (o, l)), p()).is_ok());
    assert!(decode_pgv(&join_v1(&parts, |_, o, l| (o, l)), p()).is_ok());
    assert!(decode_pgv(&good, p()).is_ok());
    assert_eq!(pgv_info(&good, p()).unwrap().version, 2);
    assert_eq!(pgv_info(&good_v1, p()).unwrap().version, 1);
    assert_eq!(
        pgv_info(&good, p()).unwrap().header,
        pgv_info(&good_v1, p()).unwrap().header
    );
    assert_eq!(
        decode_pgv(&good_v1, p()).unwrap().volume.dense_coeffs(),
        decode_pgv(&good, p()).unwrap().volume.dense_coeffs()
    );

    for file in [&good, &good_v1] {
        assert!(msg(&file[..file.len() / 2]).contains("truncated"));
        assert!(msg(&file[..file.len() - 1]).contains("truncated"));
        let mut v = file.clone();
        v[0] = b'X';
        assert!(msg(&v).contains("magic"));
        let mut v = file.clone();
        v[8] = 3;
        assert!(msg(&v).contains("version 3"));
    }
    // A version 1 file read as version 2 has no trailer.
    let mut v = good_v1.clone();
    v[8] = 2;
    assert!(msg(&v).contains("version 2"));
    // Version 2 trailer sizes that do not add up, and a damaged header.
    let n = good.len();
    for at in [n - 32, n - 24, n - 16] {
        let mut v = good.clone();
        v[at] ^= 1;
        let e = msg(&v);
        assert!(e.contains("add up"), "{e}");
    }
    let mut v = good.clone();
    v[n - 40] ^= 1;
    assert!(msg(&v).contains("header checksum"));
    // Version 2 holds only the sparse encoding.
    let mut h = split(&good);
    h.header["encoding"] = serde_json::json!("dense-f32");
    assert!(msg(&join(&h, |_, o, l| (o, l))).contains("version 2 file holds"));

    // Version 1: the whole-payload CRC catches a flipped data byte; the brick CRC catches it
    // when the payload CRC is made to agree, and so does read_brick, which skips the payload
    // CRC.
    let mut bad = split(&good);
    bad.blobs[0][3] ^= 0x20;
    let framed = join_v1(&bad, |_, o, l| (o, l));
    let hlen = u32::from_le_bytes(framed[12..16].try_into().unwrap()) as usize;
    let mut v = framed.clone();
    // Restore the old brick CRC in the index (the one for the undamaged blob), fix the rest.
    let map = parts.maps.len();
    let at = 16 + hlen + 12 + map + 12;
    v[at..at + 4].copy_from_slice(&crc32fast::hash(&parts.blobs[0]).to_le_bytes());
    let stored = bad.blobs.len();
    let meta_end = 16 + hlen + 12 + map + 16 * stored;
    let icrc = crc32fast::hash(&v[16 + hlen + 12..meta_end]);
    v[meta_end..meta_end + 4].copy_from_slice(&icrc.to_le_bytes());
    let plen = v.len() - 4 - (16 + hlen + 12);
    let pcrc = crc32fast::hash(&v[16 + hlen + 12..16 + hlen + 12 + plen]);
    let n = v.len();
    v[n - 4..].copy_from_slice(&pcrc.to_le_bytes());
    let e = msg(&v);
    assert!(
        e.contains("brick") && e.contains("checksum mismatch"),
        "{e}"
    );
    let mut v = good_v1.clone();
    v[n / 2] ^= 1;
    assert!(msg(&v).contains("checksum mismatch"));
    // Version 2 has no payload CRC: the brick's own finds the flipped byte.
    let mut v = good.clone();
    v[12 + 3] ^= 0x20;
    let e = msg(&v);
    assert!(
        e.contains("brick") && e.contains("checksum mismatch"),
        "{e}"
    );

    // Index CRC, in either layout.
    let mut v = good_v1.clone();
    let at = 16 + hlen + 12 + map + 20;
    v[at] ^= 1;
    let n = v.len();
    let pcrc = crc32fast::hash(&v[16 + hlen + 12..n - 4]);
    v[n - 4..].copy_from_slice(&pcrc.to_le_bytes());
    let e = msg(&v);
    assert!(e.contains("index checksum"), "{e}");
    let data: usize = parts.blobs.iter().map(Vec::len).sum();
    let mut v = good.clone();
    v[12 + data + map + 20] ^= 1;
    let e = msg(&v);
    assert!(e.contains("index checksum"), "{e}");

    // Index entries pointing outside the brick data.
    let e = msg(&join(&parts, |e, o, l| {
        if e == 1 {
            (o + 1_000_000, l)
        } else {
            (o, l)
        }
    }));
    assert!(e.contains("index entry 1"), "{e}");
    let e = msg(&join(
        &parts,
        |e, o, l| if e == 0 { (o, l + 7) } else { (o, l) },
    ));
    assert!(
        e.contains("index entry 1") || e.contains("brick data"),
        "{e}"
    );

    // Brick counts inconsistent with the grid.
    let mut h = split(&good);
    h.header["sparse"]["bricks"] = serde_json::json!([3, 3, 4]);
    assert!(msg(&join(&h, |_, o, l| (o, l))).contains("bricks"));
    let mut h = split(&good);
    h.header["sparse"]["stored"] = serde_json::json!(1);
    let e = msg(&join_v1(&h, |_, o, l| (o, l)));
    assert!(e.contains("index checksum"), "{e}");
    let e = msg(&join(&h, |_, o, l| (o, l)));
    assert!(e.contains("the file gives them"), "{e}");
    let mut h = split(&good);
    h.header["sparse"]["stored"] = serde_json::json!(1_000_000);
    let e = msg(&join(&h, |_, o, l| (o, l)));
    assert!(e.contains("stored bricks claimed"), "{e}");
    // The map disagreeing with the count, all checksums right.
    let mut h = split(&good);
    let first = h.maps.iter().position(|&b| b != 0).unwrap();
    let low = h.maps[first].trailing_zeros();
    h.maps[first] &= !(1 << low);
    let e = msg(&join(&h, |_, o, l| (o, l)));
    assert!(e.contains("brick map marks"), "{e}");
    let mut h = split(&good);
    h.header["sparse"]["brick"] = serde_json::json!(1000);
    assert!(msg(&join(&h, |_, o, l| (o, l))).contains("brick edge"));

    // Absurd dimensions are refused before anything is allocated from them.
    let mut h = split(&good);
    h.header["grid"]["dims"] = serde_json::json!([1u64 << 40, 1u64 << 40, 4]);
    assert!(msg(&join(&h, |_, o, l| (o, l))).contains("too large"));

    // A brick that decompresses to more than a brick holds.
    let mut h = split(&good);
    h.blobs[0] = zstd::bulk::compress(&vec![7u8; 1 << 16], 1).unwrap();
    let e = msg(&join(&h, |_, o, l| (o, l)));
    assert!(e.contains("does not decompress"), "{e}");
    // One that decompresses to fewer.
    let mut h = split(&good);
    h.blobs[0] = zstd::bulk::compress(&[1u8; 10], 1).unwrap();
    let e = msg(&join(&h, |_, o, l| (o, l)));
    assert!(e.contains("needs"), "{e}");
    // Non-finite clamp.
    let mut h = split(&good);
    h.header["sparse"]["clamp"] = serde_json::json!(-1.0);
    assert!(msg(&join(&h, |_, o, l| (o, l))).contains("clamp"));
    // The fixed scale: the automatic choice here, checked before any brick is decoded.
    assert_eq!(parts.header["sparse"]["precision"], "fixed");
    for (key, value) in [
        ("ratio", serde_json::json!(0)),
        ("ratio", serde_json::json!(1 << 20)),
        ("step", serde_json::json!(-1.0)),
        ("step", serde_json::json!(0.0)),
    ] {
        let mut h = split(&good);
        h.header["sparse"]["fixed"][key] = value;
        let e = msg(&join(&h, |_, o, l| (o, l)));
        assert!(e.contains("fixed scale"), "{key}: {e}");
    }
    let mut h = split(&good);
    h.header["sparse"].as_object_mut().unwrap().remove("fixed");
    assert!(msg(&join(&h, |_, o, l| (o, l))).contains("fixed scale"));
    let mut h = split(&good);
    h.header["sparse"]["precision"] = serde_json::json!("f16");
    assert!(msg(&join(&h, |_, o, l| (o, l))).contains("fixed scale"));
    // A valid but huge step makes the words overflow f32.
    let mut h = split(&good);
    h.header["sparse"]["fixed"]["step"] = serde_json::json!(1e38);
    assert!(msg(&join(&h, |_, o, l| (o, l))).contains("non-finite"));

    // read_brick outside the grid.
    let e = read_brick(&good, p(), [0, 9, 0]).unwrap_err().to_string();
    assert!(e.contains("outside"), "{e}");
}

// ---- properties ----------------------------------------------------------------------------

/// A small sparse file in bricks of 4, every stored coefficient within the precision (free
/// ones are tested apart), and the file it was written from.
fn tiny_sparse(precision: Precision) -> (PgvFile, Vec<u8>) {
    let f = sphere_file(12, Basis::Bspline3);
    let o = EncodeOptions {
        precision: Some(precision),
        brick: 4,
        zstd_level: 3,
        free_tolerance: 0.0,
        ..EncodeOptions::default()
    };
    let bytes = encode_pgv_with(&f, &o).unwrap().0;
    (f, bytes)
}

/// Checks that `bytes`, written from `f` in bricks of `edge` with no free tolerance, decode to
/// the written coefficients: in stored bricks within half a quantisation step of the precision
/// (exact for f32), elsewhere `±clamp`; and that each brick read alone matches the whole.
/// Returns the largest error in stored bricks.
fn assert_round_trip(f: &PgvFile, bytes: &[u8], edge: usize) -> f32 {
    let decoded = decode_pgv(bytes, p()).unwrap();
    let sp = decoded.header.sparse.clone().unwrap();
    let (precision, fixed) = (sp.precision, sp.fixed);
    assert_eq!(fixed.is_some(), precision == Precision::Fixed);
    let back = decoded.volume.dense_coeffs();
    let mut worst = 0.0f32;
    for (coords, idx) in bricks(f.volume.grid.dims, edge) {
        let b = read_brick(bytes, p(), coords).unwrap();
        for (&i, c) in idx.iter().zip(&b.coeffs) {
            assert_eq!(back[i].to_bits(), c.to_bits(), "{coords:?}");
        }
        if !b.stored {
            for &i in &idx {
                assert_eq!(back[i].abs(), sp.clamp);
            }
            continue;
        }
        let lo = idx
            .iter()
            .map(|&i| f.volume.coeffs.get_index(i))
            .fold(f32::INFINITY, f32::min);
        let hi = idx
            .iter()
            .map(|&i| f.volume.coeffs.get_index(i))
            .fold(f32::NEG_INFINITY, f32::max);
        for &i in &idx {
            let (a, d) = (f.volume.coeffs.get_index(i), back[i]);
            let bound = match precision {
                Precision::F32 => 0.0,
                // Half an f16 ulp: relative 2^-11, absolute 2^-25 among subnormals.
                Precision::F16 => a.abs() * 2f32.powi(-11) + 2f32.powi(-25),
                // Half a step, plus f32 rounding of lo + q·step.
                Precision::Q16 => {
                    (hi - lo) / 65535.0 * 0.5 + 4.0 * f32::EPSILON * lo.abs().max(hi.abs())
                }
                // Half the step where |a| lies (fine up to the knee, coarse beyond), plus
                // f32 rounding.
                Precision::Fixed => {
                    let s = fixed.unwrap();
                    let step = if a.abs() <= s.knee as f32 * s.step {
                        s.step
                    } else {
                        s.step * s.ratio as f32
                    };
                    step * 0.5 + 4.0 * f32::EPSILON * a.abs()
                }
            };
            if precision == Precision::F32 {
                assert_eq!(a.to_bits(), d.to_bits());
            }
            assert!((a - d).abs() <= bound, "{a} -> {d}, bound {bound}");
            worst = worst.max((a - d).abs());
        }
    }
    worst
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn corrupted_sparse_files_never_panic(
        which in 0usize..4,
        edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..4),
        cut in any::<usize>(),
    ) {
        let (f, good) = tiny_sparse(Precision::ALL[which]);
        // The valid file reads back: a decoder that refuses everything fails here.
        assert_round_trip(&f, &good, 4);
        let coords = [cut % 3, 1, 2];
        let clean = decode_pgv(&good, p()).unwrap();
        let clean_info = pgv_info(&good, p()).unwrap();
        let clean_brick = read_brick(&good, p(), coords).unwrap();
        let mut bytes = good.clone();
        let n = bytes.len();
        for (pos, val) in edits {
            bytes[pos % n] = val;
        }
        bytes.truncate(cut % (n + 1));
        // Every byte is checked or covered by a CRC (the header, the index, each brick, the
        // payload), so whatever still reads is what the valid file gives.
        if let Ok(back) = decode_pgv(&bytes, p()) {
            prop_assert_eq!(back, clean);
        }
        if let Ok(info) = pgv_info(&bytes, p()) {
            prop_assert_eq!(info, clean_info);
        }
        if let Ok(brick) = read_brick(&bytes, p(), coords) {
            prop_assert_eq!(brick, clean_brick);
        }
    }

    #[test]
    fn round_trip_keeps_stored_coefficients_within_the_precision(
        dims in proptest::array::uniform3(2usize..14),
        seed in any::<u64>(),
        scale in 1e-3f32..1e3,
        which in 0usize..4,
        brick in 2usize..9,
        band in 0.0f32..3.0,
        predictor in 0usize..3,
    ) {
        let grid = Grid { origin: Vec3::ZERO, spacing: 0.1, dims, offset: Default::default() };
        let mut s = seed | 1;
        let coeffs: Vec<f32> = (0..grid.len())
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                ((s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) as f32 * scale
            })
            .collect();
        let volume = CoefficientVolume::new(grid, Basis::Bspline3, coeffs).unwrap();
        let f = PgvFile { header: header_for(&volume, "interp", None), volume };
        let precision = Precision::ALL[which];
        let o = EncodeOptions {
            precision: Some(precision),
            brick,
            band,
            predictor: [Predictor::None, Predictor::DeltaX, Predictor::Lorenzo][predictor],
            zstd_level: 1,
            // Every stored coefficient within the precision (free ones are tested apart).
            free_tolerance: 0.0,
            ..EncodeOptions::default()
        };
        let (bytes, r) = encode_pgv_with(&f, &o).unwrap();
        prop_assert_eq!(pgv_info(&bytes, p()).unwrap().precision, precision);
        let worst = assert_round_trip(&f, &bytes, brick);
        // The report counts the coefficients the band needs, a subset of the stored ones.
        prop_assert!(r.max_quantisation_error <= worst);
    }
}

/// The fuzzing seed corpus (`fuzz/corpus/decode_pgv`) holds valid tiny files of each encoding
/// (the sparse ones in both layouts);
/// `PGVOL_WRITE_CORPUS=1` rewrites it.
#[test]
fn fuzz_seed_corpus_decodes() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/decode_pgv");
    if std::env::var_os("PGVOL_WRITE_CORPUS").is_some() {
        std::fs::create_dir_all(&dir).unwrap();
        let f = sphere_file(10, Basis::Bspline3);
        std::fs::write(dir.join("dense.pgv"), encode_pgv(&f)).unwrap();
        for (name, precision, predictor, compression) in [
            (
                "sparse-f32.pgv",
                Precision::F32,
                Predictor::None,
                Compression::None,
            ),
            (
                "sparse-f16.pgv",
                Precision::F16,
                Predictor::DeltaX,
                Compression::Zstd,
            ),
            (
                "sparse-q16.pgv",
                Precision::Q16,
                Predictor::Lorenzo,
                Compression::Zstd,
            ),
            (
                "sparse-fixed.pgv",
                Precision::Fixed,
                Predictor::DeltaX,
                Compression::Zstd,
            ),
        ] {
            let o = EncodeOptions {
                precision: Some(precision),
                predictor,
                compression,
                brick: 4,
                band: 1.0,
                ..EncodeOptions::default()
            };
            std::fs::write(dir.join(name), encode_pgv_with(&f, &o).unwrap().0).unwrap();
            let v1 = sparse_pgv(&f, &o).unwrap().0.to_bytes_v1();
            std::fs::write(dir.join(name.replace(".pgv", "-v1.pgv")), v1).unwrap();
        }
    }
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.len() < 10_000, "{}", path.display());
        decode_pgv(&bytes, &path).unwrap();
        seen += 1;
    }
    assert!(seen >= 9);
}
