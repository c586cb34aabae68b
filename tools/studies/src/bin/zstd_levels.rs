//! File size, write time and read time of one volume re-encoded at several zstd levels.
//!
//! `cargo run --release -p pgvol-studies --bin zstd_levels -- FILE.pgv [RUNS] [LEVELS]`
//! Decodes FILE, re-encodes it with the file's precision and brick settings at each level
//! (default 1,3,6,9,15,19,22), and prints the size and the minimum over RUNS (default 5) of
//! `encode_pgv_with` and of `decode_pgv`. Re-encoding requantises, so sizes can differ
//! slightly from the original file at its own level.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use pgvol_format::sparse::basis_weight_bound;
use pgvol_format::{decode_pgv, encode_pgv_with, EncodeOptions, PgvFile};

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = PathBuf::from(
        args.get(1)
            .ok_or("usage: zstd_levels FILE.pgv [RUNS] [LEVELS]")?,
    );
    let runs: usize = match args.get(2) {
        Some(s) => s.parse().map_err(|e| format!("RUNS '{s}': {e}"))?,
        None => 5,
    };
    let levels: Vec<i32> = args
        .get(3)
        .map_or("1,3,6,9,15,19,22", String::as_str)
        .split(',')
        .map(|s| s.parse().map_err(|e| format!("level '{s}': {e}")))
        .collect::<Result<_, _>>()?;
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let file = decode_pgv(&bytes, &path).map_err(|e| e.to_string())?;
    let sp = file
        .header
        .sparse
        .clone()
        .ok_or("the file is not in the sparse-bricks encoding")?;
    println!("level  bytes  encode_pgv  decode_pgv");
    for level in levels {
        let opts = EncodeOptions {
            precision: Some(sp.precision),
            band: sp.band,
            brick: sp.brick,
            predictor: sp.predictor,
            shuffle: sp.shuffle,
            compression: sp.compression,
            zstd_level: level,
            ..fixed_options(&file)
        };
        let mut write = Duration::MAX;
        let mut encoded = Vec::new();
        for _ in 0..runs {
            let t = Instant::now();
            encoded = encode_pgv_with(&file, &opts).map_err(|e| e.to_string())?.0;
            write = write.min(t.elapsed());
        }
        let mut whole = Duration::MAX;
        for _ in 0..runs {
            let t = Instant::now();
            std::hint::black_box(decode_pgv(&encoded, &path).map_err(|e| e.to_string())?);
            whole = whole.min(t.elapsed());
        }
        println!(
            "{level:5}  {:8}  {:8.1} ms  {:8.2} ms",
            encoded.len(),
            write.as_secs_f64() * 1e3,
            whole.as_secs_f64() * 1e3
        );
    }
    Ok(())
}

/// The default options with the file's `fixed` scale, if it has one.
fn fixed_options(file: &PgvFile) -> EncodeOptions {
    let defaults = EncodeOptions::default();
    let Some(f) = file.header.sparse.as_ref().and_then(|sp| sp.fixed) else {
        return defaults;
    };
    // The encoder divides the step by the basis weight bound; undo that.
    let unit = file.volume.grid.spacing / basis_weight_bound(file.volume.basis);
    EncodeOptions {
        fixed_step: f.step / unit,
        fixed_knee: f.knee as f32 * f.step / unit,
        fixed_ratio: f.ratio,
        ..defaults
    }
}

fn main() {
    if let Err(e) = run() {
        eprintln!("zstd_levels: {e}");
        std::process::exit(1);
    }
}
