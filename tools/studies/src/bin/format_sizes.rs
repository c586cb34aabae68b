//! Bytes of a real field in each encoding.
//!
//! `cargo run --release -p pgvol-studies --bin format_sizes -- MESH N`
//! Encodes MESH on an N³ grid as `pgvol encode --res N` does, and prints the file size of dense
//! f32, of pgvol's own sparse file, and of the sparse encoding for each precision, predictor and
//! compression, with bytes per stored coefficient and the largest coefficient error relative to
//! the spacing.

use std::path::{Path, PathBuf};

use pgvol::{EncodeOptions, Grid, GridSpec, Silent, StorageOptions};
use pgvol_format::{encode_pgv_with, Compression, Precision, Predictor};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mesh_path = PathBuf::from(args.get(1).expect("usage: format_sizes MESH N"));
    let n: usize = args.get(2).map_or(64, |s| s.parse().expect("N"));
    let mesh = pgvol::io::read_mesh(&mesh_path).expect("mesh").mesh;
    let options = EncodeOptions {
        grid: GridSpec::Res(n),
        ..EncodeOptions::default()
    };
    let file = pgvol::encode(&mesh, &options, &Silent)
        .expect("encode")
        .file;
    let grid = file.volume.grid;
    let h = grid.spacing;

    let file_size = |storage: StorageOptions| {
        pgvol::io::pgv_bytes(&file, &storage)
            .expect("pgv bytes")
            .bytes
            .len()
    };
    let dense = file_size(StorageOptions {
        dense: true,
        ..StorageOptions::default()
    });
    let product = file_size(StorageOptions::default());
    println!(
        "{} N={n}: dense-f32 {dense} bytes ({:.1} KB), pgvol encode {product} bytes ({:.1} KB)",
        mesh_path.display(),
        dense as f64 / 1024.0,
        product as f64 / 1024.0
    );
    println!("precision  predictor  shuffle  compression  bytes  KB  stored/total  B/stored-coeff  max-err/h");
    let edge = 8usize;
    for precision in [
        None,
        Some(Precision::F32),
        Some(Precision::F16),
        Some(Precision::Q16),
        Some(Precision::Fixed),
    ] {
        for (predictor, shuffle, compression) in [
            (Predictor::None, false, Compression::None),
            (Predictor::None, false, Compression::Zstd),
            (Predictor::None, true, Compression::Zstd),
            (Predictor::DeltaX, true, Compression::Zstd),
            (Predictor::Lorenzo, true, Compression::Zstd),
            (Predictor::Lorenzo, false, Compression::Zstd),
        ] {
            let storage = pgvol_format::EncodeOptions {
                precision,
                predictor,
                shuffle,
                compression,
                brick: edge,
                ..pgvol_format::EncodeOptions::default()
            };
            let (bytes, r) = encode_pgv_with(&file, &storage).expect("encode");
            let back = pgvol::io::read_pgv_bytes(&bytes, Path::new("mem")).unwrap();
            assert_eq!(back.volume.coeffs.dims(), file.volume.coeffs.dims());
            // Stored coefficients: nodes of stored bricks (edge bricks are partial).
            let stored_coeffs = stored_coefficients(&grid, &bytes, edge);
            println!(
                "{:<10} {:<10} {:<8} {:<12} {:>7} {:>7.1} {:>5}/{:<6} {:>6.3} {:>10.5}",
                precision.map_or("auto", |p| p.name()),
                format!("{predictor:?}"),
                shuffle,
                format!("{compression:?}"),
                bytes.len(),
                bytes.len() as f64 / 1024.0,
                r.bricks_stored,
                r.bricks_total,
                (r.bytes_payload + r.bytes_index) as f64 / stored_coeffs as f64,
                r.max_quantisation_error / h,
            );
        }
    }
}

/// Coefficients in stored bricks, from the index alone.
fn stored_coefficients(grid: &Grid, bytes: &[u8], edge: usize) -> usize {
    let count = grid.dims.map(|n| n.div_ceil(edge));
    let mut total = 0;
    for k in 0..count[2] {
        for j in 0..count[1] {
            for i in 0..count[0] {
                let b = pgvol_format::read_brick(bytes, Path::new("mem"), [i, j, k]).unwrap();
                if b.stored {
                    total += b.coeffs.len();
                }
            }
        }
    }
    total
}
