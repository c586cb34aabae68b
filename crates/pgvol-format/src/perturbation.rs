//! The `perturbation-f64` encoding: a perturbation field (`docs/perturbation.md`) stored as
//! its function list — the base quadric, then every perturbation's quadric and factor — in
//! the `.pgv` container, each number an IEEE-754 binary64 so the field reads back bit for bit.
//! The header's `grid` and `basis` say where a reader resamples the field to contour it; the
//! boxes of the perturbations are recomputed on reading.

use std::path::Path;

use glam::DVec3;
use pgvol_perturb::{Perturbation, PerturbationField, Quadric};

use crate::container::{container, parse_container};
use crate::error::{err, FormatError};
use crate::header::PgvHeader;
pub use crate::header::ENCODING_PERTURBATION;

/// Bytes of the base quadric: centre (3), scale, ten coefficients.
pub const BASE_BYTES: usize = 8 * 14;

/// Bytes of one perturbation: its quadric and its factor.
pub const TERM_BYTES: usize = 8 * 15;

/// Serialises `field` with `header` (whose `encoding` and `sparse` are replaced).
pub fn encode_perturbation(header: &PgvHeader, field: &PerturbationField) -> Vec<u8> {
    let mut header = header.clone();
    header.encoding = ENCODING_PERTURBATION.to_string();
    header.sparse = None;
    let mut payload = Vec::with_capacity(BASE_BYTES + TERM_BYTES * field.terms().len());
    let words = |q: &Quadric| {
        let c = q.centre;
        [c.x, c.y, c.z, q.scale].into_iter().chain(q.q)
    };
    let mut put = |x: f64| payload.extend_from_slice(&x.to_le_bytes());
    words(field.base()).for_each(&mut put);
    for t in field.terms() {
        words(&t.quadric).chain([t.factor]).for_each(&mut put);
    }
    container(&header, &payload)
}

/// Writes `field` to `path` atomically in the `perturbation-f64` encoding.
pub fn write_perturbation(
    path: &Path,
    header: &PgvHeader,
    field: &PerturbationField,
) -> Result<(), FormatError> {
    let bytes = encode_perturbation(header, field);
    pgvol_core::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| err(path, e.problem))
}

/// Whether `header` describes a stored function list.
pub fn is_perturbation(header: &PgvHeader) -> bool {
    header.encoding == ENCODING_PERTURBATION
}

/// Decodes a `perturbation-f64` file; `path` names the file in errors. Every number is
/// checked finite, every factor ±1 and every perturbation a bounded bump.
pub fn decode_perturbation(
    bytes: &[u8],
    path: &Path,
) -> Result<(PgvHeader, PerturbationField), FormatError> {
    let c = parse_container(bytes, path, true)?;
    if !is_perturbation(&c.header) {
        return Err(err(
            path,
            format!(
                "holds a coefficient volume ('{}'), not a perturbation field",
                c.header.encoding
            ),
        ));
    }
    let p = c.payload;
    if p.len() < BASE_BYTES || !(p.len() - BASE_BYTES).is_multiple_of(TERM_BYTES) {
        return Err(err(
            path,
            format!(
                "the function list holds {} bytes; it must be {BASE_BYTES} (the base quadric) \
                 plus {TERM_BYTES} per perturbation",
                p.len()
            ),
        ));
    }
    let words: Vec<f64> = p
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect();
    let quadric = |w: &[f64]| Quadric {
        centre: DVec3::new(w[0], w[1], w[2]),
        scale: w[3],
        q: w[4..14].try_into().expect("ten coefficients"),
    };
    let base = quadric(&words[..14]);
    let terms = words[14..]
        .chunks_exact(15)
        .map(|w| Perturbation {
            quadric: quadric(w),
            factor: w[14],
        })
        .collect();
    let field = PerturbationField::new(base, terms)
        .map_err(|e| err(path, format!("invalid function list: {e}")))?;
    Ok((c.header, field))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::header::ENCODING_DENSE_F32;
    use glam::Vec3;
    use pgvol_field::{Basis, Grid};
    use std::collections::BTreeMap;

    fn header() -> PgvHeader {
        PgvHeader {
            basis: Basis::Bspline3,
            fit: "perturbation".into(),
            grid: Grid {
                origin: Vec3::splat(-1.5),
                spacing: 0.1,
                dims: [31, 31, 31],
                offset: Default::default(),
            },
            units: "source mesh units".into(),
            encoding: ENCODING_DENSE_F32.into(),
            source_bounds: None,
            source_hash: None,
            metadata: BTreeMap::new(),
            sparse: None,
            sharp: None,
        }
    }

    /// A unit sphere with two bumps of opposite factors, coefficients not round in binary.
    fn field() -> PerturbationField {
        let sphere = Quadric {
            centre: DVec3::ZERO,
            scale: 1.0,
            q: [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        };
        let bump = |c: DVec3, a: f64| Quadric {
            centre: c,
            scale: 0.3 + a / 7.0,
            q: [-1.0, -1.1, -0.9, 0.05, 0.0, -0.02, 0.1, 0.0, 0.0, a],
        };
        let terms = vec![
            Perturbation {
                quadric: bump(DVec3::new(1.0, 0.1, 0.0), 0.37),
                factor: -1.0,
            },
            Perturbation {
                quadric: bump(DVec3::new(-0.2, 0.9, 0.3), 0.21),
                factor: 1.0,
            },
        ];
        PerturbationField::new(sphere, terms).unwrap()
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let f = field();
        let bytes = encode_perturbation(&header(), &f);
        let (h, back) = decode_perturbation(&bytes, Path::new("p.pgv")).unwrap();
        assert_eq!(h.encoding, ENCODING_PERTURBATION);
        assert_eq!(back.base(), f.base());
        assert_eq!(back.terms(), f.terms());
        assert_eq!(encode_perturbation(&h, &back), bytes);
        let p = DVec3::new(0.95, 0.12, 0.01);
        assert_eq!(back.value_f64(p).to_bits(), f.value_f64(p).to_bits());
        assert_eq!(
            bytes.len(),
            28 + 4 + serde_json::to_vec(&h).unwrap().len() + BASE_BYTES + 2 * TERM_BYTES
        );
    }

    #[test]
    fn damaged_lists_are_refused_naming_the_file() {
        let good = encode_perturbation(&header(), &field());
        let name = Path::new("bumps.pgv");
        let msg = |b: &[u8]| decode_perturbation(b, name).unwrap_err().to_string();
        for cut in [0, 10, good.len() / 2, good.len() - 1] {
            let m = msg(&good[..cut]);
            assert!(m.starts_with("bumps.pgv: "), "{m}");
        }
        assert!(msg(&good[..good.len() - 9]).contains("truncated"));
        let mut v = good.clone();
        let last = v.len() - 20;
        v[last] ^= 0x10;
        assert!(msg(&v).contains("checksum"));
        // A coefficient volume is not a function list, and the volume reader refuses a list.
        let volume = pgvol_field::CoefficientVolume::new(
            Grid {
                origin: Vec3::ZERO,
                spacing: 1.0,
                dims: [2, 2, 2],
                offset: Default::default(),
            },
            Basis::Bspline3,
            vec![1.0; 8],
        )
        .unwrap();
        let dense = crate::encode_pgv(&crate::PgvFile {
            header: crate::header_for(&volume, "interp", None),
            volume,
        });
        assert!(msg(&dense).contains("not a perturbation field"));
        let m = crate::decode_pgv(&good, name).unwrap_err().to_string();
        assert!(m.contains("perturbation field"), "{m}");
    }

    #[test]
    fn invalid_contents_are_refused() {
        let f = field();
        // Rebuild the container around an edited payload so the checksums hold.
        let edit = |at: usize, x: f64, len: Option<usize>| {
            let good = encode_perturbation(&header(), &f);
            let hlen = u32::from_le_bytes(good[12..16].try_into().unwrap()) as usize;
            let start = 28 + hlen;
            let mut payload = good[start..good.len() - 4].to_vec();
            payload[at..at + 8].copy_from_slice(&x.to_le_bytes());
            payload.truncate(len.unwrap_or(payload.len()));
            let h: PgvHeader = serde_json::from_slice(&good[16..16 + hlen]).unwrap();
            let bytes = container(&h, &payload);
            decode_perturbation(&bytes, Path::new("e.pgv"))
                .unwrap_err()
                .to_string()
        };
        assert!(edit(0, f64::NAN, None).contains("base quadric"));
        assert!(edit(BASE_BYTES + 14 * 8, 0.5, None).contains("factor of 0.5"));
        // A positive quadratic part is not a bump.
        assert!(edit(BASE_BYTES + 4 * 8, 2.0, None).contains("not a bounded bump"));
        assert!(edit(0, 0.0, Some(BASE_BYTES + 7)).contains("per perturbation"));
        assert!(edit(BASE_BYTES + 3 * 8, 1e300, None).contains("single precision"));
    }

    /// The seed files of the fuzz target `decode_perturbation` decode; run with
    /// `PGVOL_WRITE_CORPUS=1` to rewrite them.
    #[test]
    fn fuzz_seed_corpus_decodes() {
        let dir =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/decode_perturbation");
        let f = field();
        let base_only = PerturbationField::new(*f.base(), Vec::new()).unwrap();
        let seeds = [("bumps.pgv", &f), ("base-only.pgv", &base_only)];
        if std::env::var_os("PGVOL_WRITE_CORPUS").is_some() {
            std::fs::create_dir_all(&dir).unwrap();
            for (name, field) in seeds {
                std::fs::write(dir.join(name), encode_perturbation(&header(), field)).unwrap();
            }
        }
        for (name, field) in seeds {
            let bytes = std::fs::read(dir.join(name)).unwrap();
            let (_, back) = decode_perturbation(&bytes, Path::new(name)).unwrap();
            assert_eq!(back.terms(), field.terms());
        }
    }
}
