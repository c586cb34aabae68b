//! The optional `sharp` header section in whole files: it survives writing and reading in every
//! encoding, a reader that does not know it still reads the coefficients, and the fuzz seed of
//! `decode_sharp` is such a file.

use std::path::Path;

use glam::Vec3;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_format::sharp::{encode_sharp, read_sharp, SharpCells};
use pgvol_format::{decode_pgv, encode_pgv, encode_pgv_with, header_for, EncodeOptions, PgvFile};

fn cube_file(n: usize) -> PgvFile {
    let grid = Grid {
        origin: Vec3::splat(-1.0),
        spacing: 2.0 / (n - 1) as f32,
        dims: [n, n, n],
        offset: Default::default(),
    };
    let mut values = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = grid.origin + Vec3::new(i as f32, j as f32, k as f32) * grid.spacing;
                values.push(p.abs().max_element() - 0.5);
            }
        }
    }
    let volume = CoefficientVolume::new(grid, Basis::Bspline3, values).unwrap();
    let mut header = header_for(&volume, "interp", None);
    let cells = SharpCells {
        keys: vec![0, 7, 8, 100],
        // Each in its cell but the last, which lies past two faces.
        positions: [
            [0.5, 0.5, 0.5],
            [0.0, 1.0, 0.01],
            [0.04, 0.8, 0.3],
            [1.25, 0.0, -0.25],
        ]
        .map(SharpCells::quantise)
        .to_vec(),
    };
    header.sharp = Some(encode_sharp(&cells));
    PgvFile { header, volume }
}

#[test]
fn the_section_round_trips_dense_and_sparse() {
    let file = cube_file(10);
    let path = Path::new("cube.pgv");
    let want = read_sharp(file.header.sharp.as_ref(), file.volume.grid.dims, path)
        .unwrap()
        .unwrap();
    for bytes in [
        encode_pgv(&file),
        encode_pgv_with(&file, &EncodeOptions::default()).unwrap().0,
    ] {
        let back = decode_pgv(&bytes, path).unwrap();
        assert_eq!(back.header.sharp, file.header.sharp);
        assert_eq!(
            read_sharp(back.header.sharp.as_ref(), back.volume.grid.dims, path)
                .unwrap()
                .unwrap(),
            want
        );
    }
}

#[test]
fn a_reader_without_the_section_reads_the_coefficients() {
    // The header as a reader that predates the section sees it: unknown keys are ignored.
    #[derive(serde::Deserialize)]
    struct OlderHeader {
        encoding: String,
        grid: Grid,
    }
    let bytes = encode_pgv(&cube_file(6));
    let hlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let header: OlderHeader = serde_json::from_slice(&bytes[16..16 + hlen]).unwrap();
    assert_eq!(header.encoding, "dense-f32");
    assert_eq!(header.grid.dims, [6, 6, 6]);
    assert!(String::from_utf8_lossy(&bytes[16..16 + hlen]).contains("\"sharp\""));
}

#[test]
fn a_corrupt_section_is_refused_naming_the_file() {
    let mut file = cube_file(6);
    file.header.sharp.as_mut().unwrap().data = "AAAA".into();
    let e = read_sharp(
        file.header.sharp.as_ref(),
        file.volume.grid.dims,
        Path::new("bad.pgv"),
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("bad.pgv: the sharp-feature section"),
        "{e}"
    );
}

#[test]
fn fuzz_seed_corpus_decodes() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/decode_sharp");
    let seed = dir.join("cube-sharp.pgv");
    if std::env::var_os("PGVOL_WRITE_CORPUS").is_some() {
        std::fs::create_dir_all(&dir).unwrap();
        let o = EncodeOptions {
            brick: 4,
            band: 1.0,
            ..EncodeOptions::default()
        };
        std::fs::write(&seed, encode_pgv_with(&cube_file(6), &o).unwrap().0).unwrap();
    }
    let bytes = std::fs::read(&seed).unwrap();
    let file = decode_pgv(&bytes, &seed).unwrap();
    assert_eq!(
        read_sharp(file.header.sharp.as_ref(), file.volume.grid.dims, &seed)
            .unwrap()
            .unwrap()
            .keys
            .len(),
        4
    );
}
