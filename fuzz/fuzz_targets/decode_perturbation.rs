#![no_main]
//! Any bytes read as a perturbation field's function list (`perturbation-f64`): errors name the
//! file; a list that decodes is a field of bounded bumps with factors ±1 that evaluates to
//! finite-or-infinite numbers without panicking, re-encodes to a file that decodes to the same
//! field bit for bit, and is refused by the coefficient-volume reader. The seed files are checked
//! to decode first, so a decoder that refuses everything fails at once.

use std::path::Path;
use std::sync::Once;

use libfuzzer_sys::fuzz_target;
use pgvol_format::{decode_perturbation, encode_perturbation};

/// The valid files of the seed corpus.
const SEEDS: [&[u8]; 2] = [
    include_bytes!("../corpus/decode_perturbation/bumps.pgv"),
    include_bytes!("../corpus/decode_perturbation/base-only.pgv"),
];

static SEEDS_READ: Once = Once::new();

fuzz_target!(|data: &[u8]| {
    SEEDS_READ.call_once(|| {
        for (i, seed) in SEEDS.iter().enumerate() {
            if let Err(e) = decode_perturbation(seed, Path::new("seed.pgv")) {
                panic!("seed {i} does not decode: {e}");
            }
        }
    });
    let path = Path::new("fuzz.pgv");
    let _ = pgvol_format::pgv_info(data, path);
    match decode_perturbation(data, path) {
        Err(e) => assert!(e.to_string().starts_with("fuzz.pgv: "), "{e}"),
        Ok((header, field)) => {
            assert!(pgvol_format::is_perturbation(&header));
            assert!(pgvol_format::decode_pgv(data, path).is_err());
            for (i, t) in field.terms().iter().enumerate() {
                assert!(t.factor == 1.0 || t.factor == -1.0);
                let (lo, hi) = field.term_box(i);
                assert!(lo.is_finite() && hi.is_finite() && lo.cmple(hi).all());
                let _ = field.value_gradient(0.5 * (lo + hi));
            }
            let _ = field.value_gradient(header.grid.origin);
            let bytes = encode_perturbation(&header, &field);
            let (h2, f2) = decode_perturbation(&bytes, path).expect("a re-encoded list decodes");
            assert_eq!(h2, header);
            assert_eq!(f2.base(), field.base());
            assert_eq!(f2.terms(), field.terms());
            assert_eq!(encode_perturbation(&h2, &f2), bytes);
        }
    }
});
