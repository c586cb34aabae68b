//! Writing what a file decodes to: the bytes come back unchanged, and the decoded coefficients
//! are within the file's quantisation of those written.

use std::path::Path;

use glam::Vec3;
use pgvol_core::{Background, SparseGrid, BRICK_NODES};
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_format::sparse::basis_weight_bound;
use pgvol_format::{
    decode_pgv, encode_pgv, encode_pgv_with, header_for, EncodeOptions, EncodeReport, PgvFile,
    Precision, Predictor,
};
use proptest::prelude::*;

fn p() -> &'static Path {
    Path::new("r.pgv")
}

const PRECISIONS: [Option<Precision>; 5] = [
    None,
    Some(Precision::Fixed),
    Some(Precision::Q16),
    Some(Precision::F16),
    Some(Precision::F32),
];

const BASES: [Basis; 4] = [
    Basis::Trilinear,
    Basis::Bspline2,
    Basis::Bspline3,
    Basis::Pg { n: 3, r: 1.5 },
];

fn random(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        ((s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) as f32
    }
}

fn file(volume: CoefficientVolume) -> PgvFile {
    PgvFile {
        header: header_for(&volume, "interp", None),
        volume,
    }
}

/// A banded sphere distance (clamped at 4 spacings, as `pgvol encode` samples) interpolated by
/// `basis` on an n³ grid, off-centre so that some bricks are background.
fn sphere(n: usize, basis: Basis) -> PgvFile {
    let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), n).unwrap();
    let clamp = 4.0 * grid.spacing;
    let mut samples = Vec::with_capacity(grid.len());
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let d = (grid.point(i, j, k) - Vec3::new(0.3, -0.2, 0.1)).length() - 0.45;
                samples.push(d.clamp(-clamp, clamp));
            }
        }
    }
    file(CoefficientVolume::interpolate(grid, basis, samples).unwrap())
}

/// A sparse volume of background `±clamp` with some stored bricks of random values in
/// ±`scale` (offset by `shift`) and some bricks inside.
fn sparse(dims: [usize; 3], basis: Basis, seed: u64, scale: f32, shift: f32) -> CoefficientVolume {
    let grid = Grid {
        origin: Vec3::new(0.2, -0.1, 0.0),
        spacing: 0.1,
        dims,
        offset: Default::default(),
    };
    let mut r = random(seed);
    let mut coeffs = SparseGrid::new(dims, Background::clamp(0.35));
    for b in coeffs.all_bricks().collect::<Vec<_>>() {
        let pick = r();
        if pick > 0.3 {
            let mut v = Box::new([0.0; BRICK_NODES]);
            v.iter_mut().for_each(|c| *c = r() * scale + shift);
            coeffs.insert(b, v);
        } else if pick < -0.4 {
            coeffs.set_inside(b, true);
        }
    }
    CoefficientVolume::from_sparse(grid, basis, coeffs).unwrap()
}

/// Per coefficient (x fastest): whether the band needs it, by the rule `docs/format.md` gives:
/// within the basis reach per axis of a node whose value is within `band` spacings of zero.
fn needed(volume: &CoefficientVolume, band: f32) -> Vec<bool> {
    let g = volume.grid;
    let reach = match volume.basis {
        Basis::Trilinear => 1,
        Basis::Bspline2 | Basis::Bspline3 => 2,
        Basis::Pg { r, .. } => r.ceil().max(1.0) as usize,
    };
    let near: Vec<bool> = pgvol_field::fit::node_values(volume)
        .iter()
        .map(|v| v.abs() <= band * g.spacing)
        .collect();
    let [nx, ny, nz] = g.dims;
    let mut out = vec![false; near.len()];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let mut any = false;
                for c in k.saturating_sub(reach)..=(k + reach).min(nz - 1) {
                    for b in j.saturating_sub(reach)..=(j + reach).min(ny - 1) {
                        for a in i.saturating_sub(reach)..=(i + reach).min(nx - 1) {
                            any |= near[a + nx * (b + ny * c)];
                        }
                    }
                }
                out[i + nx * (j + ny * k)] = any;
            }
        }
    }
    out
}

/// Encodes `f`, decodes it and encodes the result: the same bytes, and the decoded coefficients
/// within the file's quantisation of `f`'s: the coefficients the band needs within the reported
/// error, the other stored ones within half the precision's step (for `fixed`, moved towards
/// zero by at most the free tolerance besides), every other one the file's `±clamp`.
fn assert_reencodes(f: &PgvFile, o: &EncodeOptions) -> EncodeReport {
    let (bytes, report) = encode_pgv_with(f, o).unwrap();
    let decoded = decode_pgv(&bytes, p()).unwrap();
    let (again, second) = encode_pgv_with(&decoded, o).unwrap();
    assert!(again == bytes, "{o:?}: re-encoding changed the file");
    assert_eq!(second.max_quantisation_error, 0.0, "{o:?}");
    assert_eq!(decode_pgv(&again, p()).unwrap(), decoded);

    let sp = decoded.header.sparse.clone().unwrap();
    let g = f.volume.grid;
    let [nx, ny, _] = g.dims;
    let needed = needed(&f.volume, o.band);
    let mut worst_needed = 0.0f32;
    for bk in 0..sp.bricks[2] {
        for bj in 0..sp.bricks[1] {
            for bi in 0..sp.bricks[0] {
                let brick = pgvol_format::read_brick(&bytes, p(), [bi, bj, bk]).unwrap();
                let [x0, y0, z0] = brick.first_node;
                let [ex, ey, ez] = brick.dims;
                let mut nodes = Vec::with_capacity(brick.coeffs.len());
                for k in z0..z0 + ez {
                    for j in y0..y0 + ey {
                        nodes.extend((x0..x0 + ex).map(|i| i + nx * (j + ny * k)));
                    }
                }
                let written: Vec<f32> = nodes
                    .iter()
                    .map(|&i| f.volume.coeffs.get_index(i))
                    .collect();
                let what = format!("{o:?}, brick {bi} {bj} {bk}");
                if !brick.stored {
                    assert!(
                        nodes.iter().all(|&i| !needed[i]),
                        "{what}: needed but not stored"
                    );
                    assert!(brick.coeffs.iter().all(|c| c.abs() == sp.clamp), "{what}");
                    continue;
                }
                let lo = written.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = written.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                for ((&i, &a), &d) in nodes.iter().zip(&written).zip(&brick.coeffs) {
                    let err = (a - d).abs();
                    if needed[i] {
                        worst_needed = worst_needed.max(err);
                        continue;
                    }
                    // The precision's half step where `a` lies, plus f32 rounding; `fixed` may
                    // also move the coefficient by the free tolerance.
                    let rounding = 4.0 * f32::EPSILON * lo.abs().max(hi.abs());
                    let bound = match sp.precision {
                        Precision::F32 => 0.0,
                        Precision::F16 => a.abs() * 2f32.powi(-11) + 2f32.powi(-25),
                        Precision::Q16 => (hi - lo) / 65535.0 * 0.5 * 1.001 + rounding,
                        Precision::Fixed => {
                            let s = sp.fixed.unwrap();
                            let coarse = s.step * s.ratio as f32;
                            coarse / 2.0 * 1.001 + o.free_tolerance * g.spacing + rounding
                        }
                    };
                    assert!(
                        err <= bound,
                        "{what}: free coefficient {i}: {a} -> {d}, bound {bound}"
                    );
                }
            }
        }
    }
    assert_eq!(worst_needed, report.max_quantisation_error, "{o:?}");
    report
}

/// The field at every node within the band, read from the decoded file, is within the basis
/// weight bound times the reported error of the field written.
fn assert_band_values(f: &PgvFile, o: &EncodeOptions, report: &EncodeReport) {
    let (bytes, _) = encode_pgv_with(f, o).unwrap();
    let back = decode_pgv(&bytes, p()).unwrap().volume;
    let h = f.volume.grid.spacing;
    let weight = basis_weight_bound(f.volume.basis);
    let before = pgvol_field::fit::node_values(&f.volume);
    let after = pgvol_field::fit::node_values(&back);
    let mut checked = 0;
    for (a, d) in before.iter().zip(&after) {
        if a.abs() <= o.band * h {
            let bound = weight * report.max_quantisation_error * 1.001 + 8.0 * f32::EPSILON * h;
            assert!(
                (a - d).abs() <= bound,
                "{o:?}: node {a} -> {d}, bound {bound}"
            );
            checked += 1;
        }
    }
    assert!(checked > 0);
}

#[test]
fn an_encoded_sphere_reencodes_to_the_same_bytes_in_every_precision() {
    for basis in BASES {
        let f = sphere(40, basis);
        for precision in PRECISIONS {
            let o = EncodeOptions {
                precision,
                ..EncodeOptions::default()
            };
            let r = assert_reencodes(&f, &o);
            assert!(r.bricks_stored < r.bricks_total, "{basis} {precision:?}");
            assert_band_values(&f, &o, &r);
        }
        // Dense files hold every coefficient bit for bit.
        let dense = encode_pgv(&f);
        assert_eq!(dense, encode_pgv(&decode_pgv(&dense, p()).unwrap()));
    }
}

#[test]
fn a_decoded_file_written_in_its_own_precision_under_auto_stays_in_it() {
    // Auto picks `fixed` for a distance; a file written in another precision keeps it when
    // written again with no precision asked for, since it holds every stored value exactly.
    let f = sphere(30, Basis::Bspline3);
    for precision in [Precision::Q16, Precision::F16, Precision::F32] {
        let asked = EncodeOptions {
            precision: Some(precision),
            ..EncodeOptions::default()
        };
        let (bytes, _) = encode_pgv_with(&f, &asked).unwrap();
        let decoded = decode_pgv(&bytes, p()).unwrap();
        let (again, r) = encode_pgv_with(&decoded, &EncodeOptions::default()).unwrap();
        assert_eq!(r.precision, precision);
        assert!(again == bytes, "{precision:?}");
        // Another band is another layout: the band rule applies again.
        let wider = EncodeOptions {
            band: 3.5,
            ..EncodeOptions::default()
        };
        let (_, r) = encode_pgv_with(&decoded, &wider).unwrap();
        assert_eq!(r.precision, Precision::Fixed, "{precision:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_volumes_reencode_to_the_same_bytes(
        dims in proptest::array::uniform3(2usize..26),
        seed in any::<u64>(),
        scale_exp in -3i32..4,
        shift in -1.0f32..1.0,
        which in 0usize..5,
        basis in 0usize..4,
        brick in prop_oneof![Just(8usize), Just(16), Just(24)],
        band in 0.0f32..4.0,
        predictor in 0usize..3,
        free_tolerance in prop_oneof![Just(0.0f32), Just(0.5), 0.0f32..2.0],
        as_sparse in any::<bool>(),
    ) {
        let basis = BASES[basis];
        let scale = 10f32.powi(scale_exp);
        let volume = if as_sparse {
            sparse(dims, basis, seed, scale, shift * scale)
        } else {
            let grid = Grid { origin: Vec3::ZERO, spacing: 0.1, dims, offset: Default::default() };
            let mut r = random(seed);
            let coeffs = (0..grid.len()).map(|_| r() * scale + shift * scale).collect();
            CoefficientVolume::new(grid, basis, coeffs).unwrap()
        };
        let o = EncodeOptions {
            precision: PRECISIONS[which],
            brick,
            band,
            predictor: [Predictor::None, Predictor::DeltaX, Predictor::Lorenzo][predictor],
            zstd_level: 1,
            free_tolerance,
            ..EncodeOptions::default()
        };
        assert_reencodes(&file(volume), &o);
    }
}
