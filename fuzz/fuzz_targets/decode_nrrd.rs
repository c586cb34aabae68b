#![no_main]
//! Any bytes read as NRRD, both as a grid and as a coefficient volume: errors name the file; a
//! grid has a finite positive spacing and one value per node; a coefficient volume encodes to a
//! `.pgv` that decodes to the same file.

use std::path::Path;
use std::sync::Once;

use libfuzzer_sys::fuzz_target;
use pgvol_format::nrrd::{decode_coefficients_nrrd, decode_nrrd};

/// The seed corpus: a coefficient volume and a sampled field.
const COEFFICIENTS: &[u8] = include_bytes!("../corpus/decode_nrrd/coefficients.nrrd");
const FIELD: &[u8] = include_bytes!("../corpus/decode_nrrd/field.nrrd");

/// Reads `data` both ways and checks what comes back.
fn check(data: &[u8], path: &Path) {
    match decode_nrrd(data, path) {
        Err(e) => assert!(e.to_string().starts_with("fuzz.nrrd: "), "{e}"),
        Ok((grid, values, _)) => {
            assert!(grid.origin.is_finite() && grid.spacing.is_finite() && grid.spacing > 0.0);
            assert!(grid.dims.iter().all(|&n| n >= 2), "{:?}", grid.dims);
            assert_eq!(values.len(), grid.dims.iter().product::<usize>());
        }
    }
    match decode_coefficients_nrrd(data, path) {
        Err(e) => assert!(e.to_string().starts_with("fuzz.nrrd: "), "{e}"),
        Ok(file) => {
            let bytes = pgvol_format::encode_pgv(&file);
            let back = pgvol_format::decode_pgv(&bytes, Path::new("fuzz.pgv"))
                .expect("the .pgv encoding of a coefficient NRRD decodes");
            assert_eq!(back, file);
        }
    }
}

static SEEDS_READ: Once = Once::new();

fuzz_target!(|data: &[u8]| {
    SEEDS_READ.call_once(|| {
        let path = Path::new("seed.nrrd");
        decode_coefficients_nrrd(COEFFICIENTS, path).expect("the coefficient seed reads");
        decode_nrrd(FIELD, path).expect("the field seed reads");
        assert!(decode_coefficients_nrrd(FIELD, path).is_err());
    });
    check(data, Path::new("fuzz.nrrd"));
});
