//! NRRD exchange of coefficient volumes and sampled fields, and a strict reader for the NRRD files
//! pgvol writes (float32, 3-D, raw, little-endian, axis-aligned cubic voxels).
//!
//! A coefficient NRRD holds the coefficient grid itself; the basis and the rest of the `.pgv`
//! header travel in `key:=value` fields so `pgvol encode --from` can rebuild the `.pgv` exactly.

use std::collections::BTreeMap;
use std::path::Path;

use glam::DVec3;
use pgvol_field::{Basis, CoefficientVolume, Grid};

use crate::error::{err, FormatError};
use crate::grid_files::nrrd_header;
use crate::header::{header_for, PgvFile};

/// Version of the `pgvol_*` key/value fields.
pub const NRRD_FIELDS_VERSION: u32 = 1;
/// Headers longer than this are refused (ours are a few hundred bytes plus the metadata).
const MAX_HEADER: usize = 1 << 20;

/// NRRD escapes backslashes and newlines in key/value pairs.
fn escape(v: &str) -> String {
    v.replace('\\', "\\\\").replace('\n', "\\n")
}

fn unescape(v: &str) -> String {
    let mut out = String::with_capacity(v.len());
    let mut chars = v.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some(o) => out.push(o),
                None => out.push('\\'),
            }
        } else {
            out.push(c);
        }
    }
    out
}

fn write(
    path: &Path,
    grid: &Grid,
    values: &[f32],
    comment: &str,
    fields: &[(&str, String)],
) -> Result<(), FormatError> {
    let fields: Vec<(&str, String)> = fields.iter().map(|(k, v)| (*k, escape(v))).collect();
    let header = nrrd_header(grid, comment, &fields);
    pgvol_core::write_atomic(path, |w| {
        w.write_all(header.as_bytes())?;
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        w.write_all(&bytes)
    })
    .map_err(|e| err(path, e.problem))
}

/// Writes the coefficients of `file` with everything needed to rebuild it: basis, fit, units,
/// source box and hash, metadata.
pub fn write_coefficients_nrrd(path: &Path, file: &PgvFile) -> Result<(), FormatError> {
    let h = &file.header;
    let json = |v: serde_json::Result<String>| v.expect("plain data serialises");
    let fields = [
        ("pgvol_content", "coefficients".to_string()),
        ("pgvol_format_version", NRRD_FIELDS_VERSION.to_string()),
        ("pgvol_basis", file.volume.basis.name().to_string()),
        (
            "pgvol_basis_params",
            json(serde_json::to_string(&file.volume.basis)),
        ),
        ("pgvol_fit", h.fit.clone()),
        ("pgvol_units", h.units.clone()),
        (
            "pgvol_source_bounds",
            json(serde_json::to_string(&h.source_bounds)),
        ),
        (
            "pgvol_source_hash",
            json(serde_json::to_string(&h.source_hash)),
        ),
        ("pgvol_metadata", json(serde_json::to_string(&h.metadata))),
    ];
    write(
        path,
        &file.volume.grid,
        &file.volume.dense_coeffs(),
        "pgvol coefficient volume: these are basis coefficients, not field values;\n\
         the field is sum_j c_j B((x - g_j) / h) with B given by pgvol_basis_params",
        &fields,
    )
}

/// Writes field values sampled on `grid` (x fastest).
pub fn write_field_nrrd(
    path: &Path,
    grid: &Grid,
    values: &[f32],
    basis: Basis,
) -> Result<(), FormatError> {
    let fields = [
        ("pgvol_content", "sdf".to_string()),
        ("pgvol_format_version", NRRD_FIELDS_VERSION.to_string()),
        ("pgvol_basis", basis.name().to_string()),
    ];
    write(
        path,
        grid,
        values,
        "signed distance sampled from a pgvol coefficient volume, negative inside",
        &fields,
    )
}

/// A NRRD's grid, its values (x fastest) and its key/value fields.
pub type NrrdGrid = (Grid, Vec<f32>, BTreeMap<String, String>);

/// Reads a NRRD file written as above (or any NRRD of the same shape) and returns its grid,
/// values (x fastest) and key/value fields. Anything this reader does not support is refused
/// with the file and the field named.
pub fn read_nrrd(path: &Path) -> Result<NrrdGrid, FormatError> {
    let bytes = pgvol_core::read_input(path).map_err(|e| err(path, e.problem))?;
    decode_nrrd(&bytes, path)
}

/// Parses `(x,y,z)`.
fn vector(s: &str) -> Option<[f64; 3]> {
    let inner = s.trim().strip_prefix('(')?.strip_suffix(')')?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|c| c.trim().parse::<f64>().ok())
        .collect::<Option<_>>()?;
    (v.len() == 3 && v.iter().all(|c| c.is_finite())).then(|| [v[0], v[1], v[2]])
}

/// [`read_nrrd`] on bytes; `path` names the file in errors.
pub fn decode_nrrd(bytes: &[u8], path: &Path) -> Result<NrrdGrid, FormatError> {
    let bad = |field: &str, problem: String| err(path, format!("NRRD field '{field}': {problem}"));
    if bytes.len() < 8 || !bytes.starts_with(b"NRRD000") || !(b'1'..=b'5').contains(&bytes[7]) {
        return Err(err(path, "not a NRRD file (no NRRD0001..NRRD0005 magic)"));
    }
    let scan = &bytes[..bytes.len().min(MAX_HEADER)];
    let end = scan.windows(2).position(|w| w == b"\n\n").ok_or_else(|| {
        err(
            path,
            "NRRD header has no blank line ending it within 1 MiB (or the file is truncated)",
        )
    })?;
    let header = std::str::from_utf8(&bytes[..end])
        .map_err(|_| err(path, "NRRD header is not UTF-8 text"))?;
    let data = &bytes[end + 2..];

    let mut fields: BTreeMap<String, String> = BTreeMap::new();
    let mut keyvalues = BTreeMap::new();
    for line in header.lines().skip(1) {
        if line.starts_with('#') {
            continue;
        }
        let (colon_eq, colon_sp) = (line.find(":="), line.find(": "));
        match (colon_eq, colon_sp) {
            (Some(a), b) if b.is_none_or(|b| a < b) => {
                keyvalues.insert(unescape(&line[..a]), unescape(&line[a + 2..]));
            }
            (_, Some(b)) => {
                let key = line[..b].to_ascii_lowercase();
                if fields
                    .insert(key.clone(), line[b + 2..].trim().to_string())
                    .is_some()
                {
                    return Err(bad(&key, "given twice".into()));
                }
            }
            _ => {
                return Err(err(
                    path,
                    format!("NRRD header line is not a field: '{line}'"),
                ))
            }
        }
    }
    let get = |k: &str| {
        fields
            .get(k)
            .map(String::as_str)
            .ok_or_else(|| err(path, format!("NRRD field '{k}' is missing")))
    };
    let ty = get("type")?;
    if ty != "float" {
        return Err(bad("type", format!("'{ty}' is not supported (only float)")));
    }
    let dimension = get("dimension")?;
    if dimension != "3" {
        return Err(bad(
            "dimension",
            format!("'{dimension}': only 3 is supported"),
        ));
    }
    let encoding = get("encoding")?;
    if encoding != "raw" {
        return Err(bad(
            "encoding",
            format!("'{encoding}': only raw is supported"),
        ));
    }
    let endian = get("endian")?;
    if endian != "little" {
        return Err(bad(
            "endian",
            format!("'{endian}': only little is supported"),
        ));
    }
    for k in ["data file", "datafile"] {
        if fields.contains_key(k) {
            return Err(bad(k, "detached data files are not supported".into()));
        }
    }
    for k in ["line skip", "lineskip", "byte skip", "byteskip"] {
        if let Some(v) = fields.get(k) {
            if v != "0" {
                return Err(bad(k, format!("'{v}': only 0 is supported")));
            }
        }
    }
    if let Some(c) = fields.get("centers").or(fields.get("centerings")) {
        if c.split_whitespace().any(|c| c != "node" && c != "???") {
            return Err(bad(
                "centers",
                format!("'{c}': only node-centred samples are supported"),
            ));
        }
    }
    if let Some(k) = fields.get("kinds") {
        if k.split_whitespace()
            .any(|k| !matches!(k, "domain" | "space" | "???"))
        {
            return Err(bad(
                "kinds",
                format!("'{k}': every axis must be a space axis"),
            ));
        }
    }
    if let Some(d) = fields.get("space dimension") {
        if d != "3" {
            return Err(bad(
                "space dimension",
                format!("'{d}': only 3 is supported"),
            ));
        }
    } else if !fields.contains_key("space") {
        return Err(err(
            path,
            "NRRD field 'space dimension' (or 'space') is missing",
        ));
    }

    let sizes_text = get("sizes")?;
    let sizes: Vec<usize> = sizes_text
        .split_whitespace()
        .map(|s| s.parse::<usize>().ok())
        .collect::<Option<_>>()
        .ok_or_else(|| {
            bad(
                "sizes",
                format!("'{sizes_text}' is not three whole numbers"),
            )
        })?;
    if sizes.len() != 3 || sizes.iter().any(|&n| n < 2) {
        return Err(bad(
            "sizes",
            format!("'{sizes_text}': need three sizes, each at least 2"),
        ));
    }
    let dims = [sizes[0], sizes[1], sizes[2]];

    let dirs_text = get("space directions")?;
    let dirs: Vec<[f64; 3]> = dirs_text
        .split(')')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| vector(&format!("{s})")))
        .collect::<Option<_>>()
        .ok_or_else(|| {
            bad(
                "space directions",
                format!("'{dirs_text}' is not three (x,y,z) vectors"),
            )
        })?;
    if dirs.len() != 3 {
        return Err(bad(
            "space directions",
            format!("'{dirs_text}': need three vectors"),
        ));
    }
    let diagonal = (0..3).all(|a| (0..3).all(|b| a == b || dirs[a][b] == 0.0));
    let h = dirs[0][0];
    let equal = (1..3).all(|a| (dirs[a][a] - h).abs() <= 1e-6 * h.abs());
    // `vector` only accepts finite numbers, so `h <= 0.0` covers every bad spacing.
    if !diagonal || !equal || h <= 0.0 {
        return Err(bad(
            "space directions",
            format!("'{dirs_text}': only axis-aligned, equal, positive spacings are supported"),
        ));
    }
    let origin_text = get("space origin")?;
    let o = vector(origin_text).ok_or_else(|| {
        bad(
            "space origin",
            format!("'{origin_text}' is not an (x,y,z) vector"),
        )
    })?;
    let world_origin = DVec3::from_array(o);
    let extent = DVec3::from_array(dims.map(|n| h * (n - 1) as f64));
    // A grid far from the origin is held relative to a nearby point, as meshes are.
    let offset = pgvol_core::frame::recentring_offset(world_origin, world_origin + extent);
    let grid = Grid {
        origin: pgvol_core::frame::to_local(world_origin, offset),
        spacing: h as f32,
        dims,
        offset,
    };
    if !(grid.origin.is_finite() && grid.spacing.is_finite() && grid.spacing > 0.0) {
        return Err(bad(
            "space origin",
            "origin or spacing does not fit in f32".into(),
        ));
    }
    // The .pgv header holds the same offset and refuses it beyond this; refused here first, so
    // no file is written that cannot be read.
    let max = crate::container::MAX_OFFSET;
    if offset.abs().max_element() >= max {
        return Err(bad(
            "space origin",
            format!("'{origin_text}' puts the grid {max:e} or more from the origin"),
        ));
    }

    // Sizes against the data before anything is allocated from them.
    let nodes = dims
        .iter()
        .try_fold(1u128, |acc, &n| acc.checked_mul(n as u128))
        .filter(|&n| n <= pgvol_field::MAX_GRID_NODES)
        .ok_or_else(|| bad("sizes", format!("{dims:?} is too large")))?;
    let want = nodes * 4;
    if data.len() as u128 != want {
        return Err(err(
            path,
            format!(
                "NRRD data holds {} bytes but sizes {:?} of float need {want}",
                data.len(),
                dims
            ),
        ));
    }
    let values = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok((grid, values, keyvalues))
}

/// Rebuilds a `.pgv` file from a coefficient NRRD written by [`write_coefficients_nrrd`].
pub fn read_coefficients_nrrd(path: &Path) -> Result<PgvFile, FormatError> {
    let bytes = pgvol_core::read_input(path).map_err(|e| err(path, e.problem))?;
    decode_coefficients_nrrd(&bytes, path)
}

/// [`read_coefficients_nrrd`] on bytes; `path` names the file in errors.
pub fn decode_coefficients_nrrd(bytes: &[u8], path: &Path) -> Result<PgvFile, FormatError> {
    let (grid, coeffs, kv) = decode_nrrd(bytes, path)?;
    let need = |k: &str| {
        kv.get(k).ok_or_else(|| {
            err(
                path,
                format!(
                    "NRRD key '{k}' is missing: not a coefficient volume written by `pgvol export --what coefficients`"
                ),
            )
        })
    };
    let content = need("pgvol_content")?;
    if content != "coefficients" {
        return Err(err(
            path,
            format!("NRRD holds '{content}', not coefficients (pgvol_content)"),
        ));
    }
    let version = need("pgvol_format_version")?;
    if version != &NRRD_FIELDS_VERSION.to_string() {
        return Err(err(
            path,
            format!("pgvol_format_version {version} is not supported (this reader knows {NRRD_FIELDS_VERSION})"),
        ));
    }
    let params = need("pgvol_basis_params")?;
    let basis: Basis = serde_json::from_str(params)
        .map_err(|e| err(path, format!("pgvol_basis_params '{params}': {e}")))?;
    basis
        .validate()
        .map_err(|e| err(path, format!("pgvol_basis_params: {e}")))?;
    let name = need("pgvol_basis")?;
    if name != basis.name() {
        return Err(err(
            path,
            format!("pgvol_basis '{name}' disagrees with pgvol_basis_params '{params}'"),
        ));
    }
    let fit = need("pgvol_fit")?.clone();
    let volume = CoefficientVolume::new(grid, basis, coeffs)
        .map_err(|e| err(path, format!("invalid coefficients: {e}")))?;
    let mut header = header_for(&volume, &fit, None);
    let parse = |k: &str| -> Result<Option<serde_json::Value>, FormatError> {
        kv.get(k)
            .map(|v| {
                serde_json::from_str(v)
                    .map_err(|e| err(path, format!("{k} '{v}' is not JSON: {e}")))
            })
            .transpose()
    };
    if let Some(u) = kv.get("pgvol_units") {
        header.units = u.clone();
    }
    fn typed<T: serde::de::DeserializeOwned>(
        path: &Path,
        k: &str,
        v: serde_json::Value,
    ) -> Result<T, FormatError> {
        serde_json::from_value(v).map_err(|e| err(path, format!("{k}: {e}")))
    }
    if let Some(v) = parse("pgvol_source_bounds")? {
        let bounds: Option<[[f32; 3]; 2]> = typed(path, "pgvol_source_bounds", v)?;
        // A decimal beyond f32's range parses as infinity, which a .pgv header cannot hold.
        if bounds.is_some_and(|b| b.iter().flatten().any(|c| !c.is_finite())) {
            return Err(err(
                path,
                "pgvol_source_bounds holds a coordinate beyond single precision; \
                 give finite bounds or drop the key"
                    .to_string(),
            ));
        }
        header.source_bounds = bounds;
    }
    if let Some(v) = parse("pgvol_source_hash")? {
        header.source_hash = typed(path, "pgvol_source_hash", v)?;
    }
    if let Some(v) = parse("pgvol_metadata")? {
        header.metadata = typed(path, "pgvol_metadata", v)?;
    }
    Ok(PgvFile { header, volume })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sample_file(basis: Basis) -> PgvFile {
        let grid = Grid {
            origin: glam::Vec3::new(-1.25, 0.1, 2.0),
            spacing: 0.3,
            dims: [3, 4, 5],
            offset: Default::default(),
        };
        // Values that do not survive a decimal round trip unless written exactly.
        let coeffs = (0..60).map(|i| (i as f32 * 0.37 - 3.0) / 7.0).collect();
        let volume = CoefficientVolume::new(grid, basis, coeffs).unwrap();
        let mut header = header_for(&volume, "wls", None);
        header.source_bounds = Some([[0.1, 0.2, 0.3], [1.0, 2.0, 3.0]]);
        header.source_hash = Some("0123456789abcdef".into());
        header
            .metadata
            .insert("note".into(), "line one\nline \\two ünï".into());
        PgvFile { header, volume }
    }

    #[test]
    fn coefficient_round_trip_is_bit_exact() {
        let dir = tempfile::tempdir().unwrap();
        for basis in [
            Basis::Bspline3,
            Basis::Trilinear,
            Basis::Pg { n: 2, r: 1.7 },
        ] {
            let f = sample_file(basis);
            let p = dir.path().join("c.nrrd");
            write_coefficients_nrrd(&p, &f).unwrap();
            let back = read_coefficients_nrrd(&p).unwrap();
            assert_eq!(back, f);
            let bits = |v: &[f32]| v.iter().map(|c| c.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&back.volume.dense_coeffs()),
                bits(&f.volume.dense_coeffs())
            );
            // And through .pgv bytes.
            assert_eq!(crate::pgv::encode_pgv(&back), crate::pgv::encode_pgv(&f));
        }
    }

    #[test]
    fn source_bounds_beyond_single_precision_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.nrrd");
        write_coefficients_nrrd(&p, &sample_file(Basis::Bspline3)).unwrap();
        let text = std::fs::read(&p).unwrap();
        let good = b"[[0.1,0.2,0.3],[1.0,2.0,3.0]]";
        let at = text.windows(good.len()).position(|w| w == good).unwrap();
        let mut bad = text[..at].to_vec();
        bad.extend_from_slice(b"[[0.1,0.2,0.3],[1.0,2.0,3e39]]");
        bad.extend_from_slice(&text[at + good.len()..]);
        let e = decode_coefficients_nrrd(&bad, &p).unwrap_err().to_string();
        assert!(
            e.contains("pgvol_source_bounds") && e.contains("single precision"),
            "{e}"
        );
    }

    #[test]
    fn an_origin_a_pgv_header_could_not_hold_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.nrrd");
        write_coefficients_nrrd(&p, &sample_file(Basis::Bspline3)).unwrap();
        let text = std::fs::read(&p).unwrap();
        let good = b"space origin: (-1.25,";
        let at = text.windows(good.len()).position(|w| w == good).unwrap();
        // Found by fuzzing: read, then written as a .pgv whose header refuses the offset.
        let mut far = text[..at].to_vec();
        far.extend_from_slice(b"space origin: (-100000000000000.25,");
        far.extend_from_slice(&text[at + good.len()..]);
        let e = decode_coefficients_nrrd(&far, &p).unwrap_err().to_string();
        assert!(e.contains("space origin") && e.contains("1e8"), "{e}");
        // Just inside the limit the file reads and its .pgv bytes decode.
        let mut near = text[..at].to_vec();
        near.extend_from_slice(b"space origin: (-90000000.25,");
        near.extend_from_slice(&text[at + good.len()..]);
        let file = decode_coefficients_nrrd(&near, &p).unwrap();
        let pgv = crate::pgv::encode_pgv(&file);
        assert_eq!(crate::pgv::decode_pgv(&pgv, &p).unwrap(), file);
    }

    #[test]
    fn field_nrrd_is_refused_as_coefficients() {
        let dir = tempfile::tempdir().unwrap();
        let f = sample_file(Basis::Bspline3);
        let p = dir.path().join("s.nrrd");
        write_field_nrrd(
            &p,
            &f.volume.grid,
            &f.volume.dense_coeffs(),
            Basis::Bspline3,
        )
        .unwrap();
        let (grid, values, kv) = read_nrrd(&p).unwrap();
        assert_eq!(grid, f.volume.grid);
        assert_eq!(values, f.volume.dense_coeffs());
        assert_eq!(kv["pgvol_content"], "sdf");
        let e = read_coefficients_nrrd(&p).unwrap_err().to_string();
        assert!(e.contains("not coefficients"), "{e}");
        // A plain NRRD (as `pgvol sdf` writes) lacks the basis.
        let plain = dir.path().join("plain.nrrd");
        crate::grid_files::write_nrrd(&plain, &grid, &values, &[]).unwrap();
        let e = read_coefficients_nrrd(&plain).unwrap_err().to_string();
        assert!(e.contains("plain.nrrd") && e.contains("is missing"), "{e}");
    }

    fn good_bytes() -> Vec<u8> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.nrrd");
        write_coefficients_nrrd(&p, &sample_file(Basis::Bspline3)).unwrap();
        std::fs::read(p).unwrap()
    }

    #[test]
    fn unsupported_headers_name_the_field() {
        let good = String::from_utf8_lossy(&good_bytes()).into_owned();
        let p = Path::new("x.nrrd");
        let msg = |s: String| decode_nrrd(s.as_bytes(), p).unwrap_err().to_string();
        let cases = [
            ("type: float", "type: double", "'type'"),
            ("dimension: 3", "dimension: 4", "'dimension'"),
            ("encoding: raw", "encoding: gzip", "'encoding'"),
            ("endian: little", "endian: big", "'endian'"),
            ("sizes: 3 4 5", "sizes: 3 4", "'sizes'"),
            ("(0,0.3,0)", "(0,0.6,0)", "'space directions'"),
            ("(0,0.3,0)", "(0.1,0.3,0)", "'space directions'"),
            ("space origin: (", "space origin: (x", "'space origin'"),
            ("centers: node", "centers: cell", "'centers'"),
        ];
        for (from, to, want) in cases {
            assert!(good.contains(from), "{from}");
            let e = msg(good.replacen(from, to, 1));
            assert!(e.starts_with("x.nrrd: ") && e.contains(want), "{to}: {e}");
        }
        assert!(msg("NRRD0004\ntype: float\n".into()).contains("blank line"));
        assert!(msg("P6 not nrrd".into()).contains("magic"));
        let e = msg(good.replacen("sizes: 3 4 5", "sizes: 3 4 6", 1));
        assert!(e.contains("need"), "{e}");
        let e = msg(good.replacen("sizes: 3 4 5", "sizes: 100000 100000 100000", 1));
        assert!(e.contains("too large"), "{e}");
    }

    /// The uncorrupted file decodes to the coefficients written, bit for bit: without this a
    /// decoder that refuses everything would pass the tests below.
    fn assert_good_bytes_decode(good: &[u8]) {
        let f = sample_file(Basis::Bspline3);
        let (grid, values, _) = decode_nrrd(good, Path::new("g.nrrd")).unwrap();
        assert_eq!(grid, f.volume.grid);
        let bits = |v: &[f32]| v.iter().map(|c| c.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&values), bits(&f.volume.dense_coeffs()));
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            assert_good_bytes_decode(&good_bytes());
            let _ = decode_nrrd(&bytes, Path::new("r.nrrd"));
        }

        #[test]
        fn random_headers_never_panic(tail in proptest::collection::vec(any::<u8>(), 0..200)) {
            assert_good_bytes_decode(&good_bytes());
            let mut bytes = b"NRRD0004\n".to_vec();
            bytes.extend(tail);
            let _ = decode_nrrd(&bytes, Path::new("h.nrrd"));
        }

        #[test]
        fn corrupted_files_never_panic(pos in 0usize..10_000, val in any::<u8>(), cut in 0usize..10_000) {
            let good = good_bytes();
            assert_good_bytes_decode(&good);
            let mut bytes = good.clone();
            let n = bytes.len();
            bytes[pos % n] = val;
            bytes.truncate(cut % (n + 1));
            let _ = decode_nrrd(&bytes, Path::new("c.nrrd"));
        }
    }
}
