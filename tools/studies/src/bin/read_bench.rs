//! Time to read a `.pgv` file into an evaluable `CoefficientVolume`.
//!
//! `cargo run --release -p pgvol-studies --bin read_bench -- FILE.pgv [RUNS]`
//! Prints the minimum over RUNS (default 9) of: reading the file's bytes; and `decode_pgv` on one
//! thread and on every thread of the global pool (`RAYON_NUM_THREADS` sets it). The machine is
//! rarely idle, so the minimum is the figure to quote.

use std::path::PathBuf;
use std::time::{Duration, Instant};

fn ms(d: Duration) -> String {
    format!("{:8.2} ms", d.as_secs_f64() * 1e3)
}

/// Runs `f` `runs` times and keeps the smallest time.
fn min_time<T>(
    runs: usize,
    mut f: impl FnMut() -> Result<T, String>,
) -> Result<(Duration, T), String> {
    let mut best: Option<(Duration, T)> = None;
    for _ in 0..runs {
        let t = Instant::now();
        let out = f()?;
        let d = t.elapsed();
        if best.as_ref().is_none_or(|(b, _)| d < *b) {
            best = Some((d, out));
        }
    }
    best.ok_or_else(|| "RUNS must be at least 1".to_string())
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = PathBuf::from(args.get(1).ok_or("usage: read_bench FILE.pgv [RUNS]")?);
    let runs: usize = match args.get(2) {
        Some(s) => s.parse().map_err(|e| format!("RUNS '{s}': {e}"))?,
        None => 9,
    };
    let read = || std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()));
    let bytes = read()?;
    let info = pgvol_format::pgv_info(&bytes, &path).map_err(|e| e.to_string())?;
    let g = info.header.grid;
    println!(
        "{}: {} bytes, {:?} nodes, {}, {} of {} bricks stored, {:?}; min of {runs} runs",
        path.display(),
        bytes.len(),
        g.dims,
        info.header.encoding,
        info.bricks_stored.unwrap_or(0),
        info.bricks_total.unwrap_or(0),
        info.precision,
    );

    let (t_read, _) = min_time(runs, read)?;
    println!("read the bytes                 {}", ms(t_read));
    let decode = || pgvol_format::decode_pgv(&bytes, &path).map_err(|e| e.to_string());
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| e.to_string())?;
    let (t_one, file_one) = one.install(|| min_time(runs, decode))?;
    let (t_all, file) = min_time(runs, decode)?;
    if file != file_one {
        return Err("one thread and all threads decoded different volumes".into());
    }
    println!("decode_pgv, 1 thread           {}", ms(t_one));
    println!(
        "decode_pgv, {} threads          {}",
        rayon::current_num_threads(),
        ms(t_all)
    );
    println!("file to volume (read + decode) {}", ms(t_read + t_all));

    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("read_bench: {e}");
        std::process::exit(1);
    }
}
