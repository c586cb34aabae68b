//! File size of one volume re-encoded with the `fixed` precision at several steps, predictors
//! and free tolerances, next to f16 and q16; optionally writes each file for decoding and
//! comparison (`docs/format.md`, "Sizes measured").
//!
//! `cargo run --release -p pgvol-studies --bin fixed_study -- FILE.pgv STEPS PREDICTORS
//! TOLERANCES [OUT_PREFIX [BRICK]]`: STEPS are denominators K of the step h/K (e.g. 256,1024),
//! each optionally with a knee in grid spacings and a coarse/fine ratio (`512:1:8`; default
//! one step throughout),
//! PREDICTORS from none,delta-x,lorenzo, TOLERANCES free tolerances in grid spacings (e.g.
//! 0,0.5). With OUT_PREFIX (`-` for none), writes OUT_PREFIX-PREDICTOR-K-TOLERANCE.pgv (and
//! -f16, -q16). An optional seventh argument sets the brick edge (default 8).

use std::path::PathBuf;

use pgvol_format::{decode_pgv, encode_pgv_with, EncodeOptions, Precision, Predictor};

fn list<T>(
    arg: Option<&String>,
    what: &str,
    parse: impl Fn(&str) -> Option<T>,
) -> Result<Vec<T>, String> {
    arg.ok_or(format!("missing {what}"))?
        .split(',')
        .map(|s| parse(s).ok_or(format!("{what}: cannot read '{s}'")))
        .collect()
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path =
        PathBuf::from(args.get(1).ok_or(
            "usage: fixed_study FILE.pgv STEPS PREDICTORS TOLERANCES [OUT_PREFIX [BRICK]]",
        )?);
    let steps = list(args.get(2), "STEPS", |s| {
        let mut parts = s.split(':').map(str::parse::<f32>);
        let k = parts.next()?.ok()?;
        let knee = parts.next().map_or(Some(1e9), |p| p.ok())?;
        let ratio = parts.next().map_or(Some(1.0), |p| p.ok())?;
        Some((k, knee, ratio as u32))
    })?;
    let predictors = list(args.get(3), "PREDICTORS", |s| match s {
        "none" => Some(Predictor::None),
        "delta-x" => Some(Predictor::DeltaX),
        "lorenzo" => Some(Predictor::Lorenzo),
        _ => None,
    })?;
    let tolerances = list(args.get(4), "TOLERANCES", |s| s.parse::<f32>().ok())?;
    let prefix = args.get(5).filter(|p| p.as_str() != "-");
    let brick: usize = match args.get(6) {
        Some(s) => s.parse().map_err(|e| format!("BRICK '{s}': {e}"))?,
        None => 8,
    };
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let file = decode_pgv(&bytes, &path).map_err(|e| e.to_string())?;
    let band = file.header.sparse.as_ref().map_or(3.0, |sp| sp.band);
    let base = EncodeOptions {
        band,
        brick,
        ..EncodeOptions::default()
    };
    let mut runs = vec![(
        "f16".to_string(),
        EncodeOptions {
            precision: Some(Precision::F16),
            ..base.clone()
        },
    )];
    runs.push((
        "q16".to_string(),
        EncodeOptions {
            precision: Some(Precision::Q16),
            ..base.clone()
        },
    ));
    for &p in &predictors {
        for &(k, knee, ratio) in &steps {
            for &t in &tolerances {
                let name = if ratio == 1 {
                    format!("{}-{k}-{t}", predictor_name(p))
                } else {
                    format!("{}-{k}:{knee}:{ratio}-{t}", predictor_name(p))
                };
                runs.push((
                    name,
                    EncodeOptions {
                        precision: Some(Precision::Fixed),
                        predictor: p,
                        fixed_step: 1.0 / k,
                        fixed_knee: knee,
                        fixed_ratio: ratio,
                        free_tolerance: t,
                        ..base.clone()
                    },
                ));
            }
        }
    }
    println!("encoding  bytes  brick-bytes  max-error/h");
    for (name, opts) in runs {
        let (encoded, report) = encode_pgv_with(&file, &opts).map_err(|e| e.to_string())?;
        println!(
            "{name}  {}  {}  {:.5}",
            encoded.len(),
            report.bytes_payload,
            report.max_quantisation_error / file.volume.grid.spacing
        );
        if let Some(prefix) = prefix {
            let out = format!("{prefix}-{name}.pgv");
            std::fs::write(&out, &encoded).map_err(|e| format!("{out}: {e}"))?;
        }
    }
    Ok(())
}

fn predictor_name(p: Predictor) -> &'static str {
    match p {
        Predictor::None => "none",
        Predictor::DeltaX => "delta-x",
        Predictor::Lorenzo => "lorenzo",
    }
}

fn main() {
    if let Err(e) = run() {
        eprintln!("fixed_study: {e}");
        std::process::exit(1);
    }
}
