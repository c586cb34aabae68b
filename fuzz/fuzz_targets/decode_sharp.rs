#![no_main]
//! Any bytes read as a `.pgv` file and then its optional `sharp` section: errors name the file;
//! a section that decodes names distinct cells of the file's grid in ascending order, each
//! position within half a cell of its cell, and re-encodes to a section that decodes to the same cells. The
//! seed file is checked to decode with its section first, so a reader that refuses everything
//! fails at once.

use std::path::Path;
use std::sync::Once;

use libfuzzer_sys::fuzz_target;
use pgvol_format::decode_pgv;
use pgvol_format::sharp::{cell_count, decode_sharp, encode_sharp, read_sharp};

/// The valid file of the seed corpus: a cube with four stored cells.
const SEED: &[u8] = include_bytes!("../corpus/decode_sharp/cube-sharp.pgv");

static SEED_READ: Once = Once::new();

fuzz_target!(|data: &[u8]| {
    SEED_READ.call_once(|| {
        let seed = decode_pgv(SEED, Path::new("seed.pgv")).expect("the seed decodes");
        match read_sharp(
            seed.header.sharp.as_ref(),
            seed.volume.grid.dims,
            Path::new("seed.pgv"),
        ) {
            Ok(Some(cells)) => assert!(!cells.keys.is_empty()),
            other => panic!("the seed's section does not decode: {other:?}"),
        }
    });
    let path = Path::new("fuzz.pgv");
    let Ok(file) = decode_pgv(data, path) else {
        return;
    };
    match read_sharp(file.header.sharp.as_ref(), file.volume.grid.dims, path) {
        Err(e) => assert!(e.to_string().starts_with("fuzz.pgv: "), "{e}"),
        Ok(None) => assert!(file.header.sharp.is_none()),
        Ok(Some(cells)) => {
            let dims = file.volume.grid.dims;
            let total = cell_count(dims).expect("a decoded grid's cells fit in u64");
            assert_eq!(cells.keys.len(), cells.positions.len());
            assert!(cells.keys.windows(2).all(|w| w[0] < w[1]));
            assert!(cells.keys.iter().all(|&k| k < total));
            for i in 0..cells.keys.len() {
                assert!(cells.position(i).iter().all(|x| (-0.5..1.5).contains(x)));
            }
            let again = encode_sharp(&cells);
            assert_eq!(
                decode_sharp(&again, dims).expect("a re-encoded section decodes"),
                cells
            );
        }
    }
});
