//! Writing a sparse volume costs in proportion to its stored bricks, not to its grid: a 1024³
//! grid holding a thin shell round a small sphere encodes and decodes in little memory. Alone in
//! its test binary so that the peak memory measured is its own.

use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use pgvol_core::{Background, SparseGrid, BRICK_EDGE, BRICK_NODES};
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_format::{decode_pgv, encode_pgv_with, header_for, EncodeOptions, PgvFile, Precision};

const N: usize = 1024;

/// A sphere of 40 spacings' radius: the grid bricks whose nodes may lie within `clamp` of it
/// are stored with the clamped distance, the others are background, inside or outside.
fn shell() -> (PgvFile, f32) {
    let grid = Grid {
        origin: Vec3::ZERO,
        spacing: 1.0 / (N - 1) as f32,
        dims: [N; 3],
        offset: Default::default(),
    };
    let h = grid.spacing;
    let clamp = 4.0 * h;
    let centre = grid.point(300, 610, 480) + Vec3::new(0.3, 0.7, 0.2) * h;
    let radius = 40.0 * h;
    let distance = |p: Vec3| (p - centre).length() - radius;
    let mut coeffs = SparseGrid::new(grid.dims, Background::clamp(clamp));
    // A brick's nodes lie within 3.5·√3 < 6.1 spacings of its centre.
    let keep = clamp + 6.1 * h;
    let brick_of = |x: f32| (x / h) as usize / BRICK_EDGE;
    let lo = [0, 1, 2].map(|a| brick_of(centre[a] - radius - keep) - 1);
    let hi = [0, 1, 2].map(|a| brick_of(centre[a] + radius + keep) + 1);
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            for i in lo[0]..=hi[0] {
                let b = [i, j, k];
                let mid = grid.point(8 * i, 8 * j, 8 * k) + Vec3::splat(3.5 * h);
                let d = distance(mid);
                if d.abs() < keep {
                    let mut v = Box::new([0.0; BRICK_NODES]);
                    for (at, c) in v.iter_mut().enumerate() {
                        let n = [at % 8, at / 8 % 8, at / 64];
                        let p = grid.point(8 * i + n[0], 8 * j + n[1], 8 * k + n[2]);
                        *c = distance(p).clamp(-clamp, clamp);
                    }
                    coeffs.insert(b, v);
                } else if d < 0.0 {
                    coeffs.set_inside(b, true);
                }
            }
        }
    }
    let volume = CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap();
    let header = header_for(&volume, "interp", None);
    (PgvFile { header, volume }, clamp)
}

/// Peak resident memory of this process so far, in bytes.
#[cfg(target_os = "linux")]
fn peak_memory() -> usize {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmHWM:")).unwrap();
    let kb: usize = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    kb * 1024
}

#[test]
fn a_sparse_1024_cubed_volume_round_trips_in_little_memory() {
    let (f, clamp) = shell();
    let original = &f.volume.coeffs;
    assert!(
        (300..3000).contains(&original.stored_count()),
        "{}",
        original.stored_count()
    );
    let o = EncodeOptions {
        precision: Some(Precision::Fixed),
        free_tolerance: 0.0,
        ..EncodeOptions::default()
    };
    let start = Instant::now();
    let (bytes, report) = encode_pgv_with(&f, &o).unwrap();
    let encoded = start.elapsed();
    let back = decode_pgv(&bytes, Path::new("shell.pgv")).unwrap();
    let decoded = start.elapsed() - encoded;
    eprintln!(
        "1024³, {} stored grid bricks: encode {encoded:?}, decode {decoded:?}, {} bytes, {} of \
         {} file bricks stored",
        original.stored_count(),
        bytes.len(),
        report.bricks_stored,
        report.bricks_total
    );
    #[cfg(target_os = "linux")]
    {
        // A dense pass would take 1 GB for a mask alone and 4 GB for the node values.
        let peak = peak_memory();
        eprintln!("peak resident memory {} MB", peak >> 20);
        assert!(peak < 300 << 20, "peak resident memory {} MB", peak >> 20);
    }
    assert_eq!(report.bricks_total, (N / 16).pow(3));
    assert!(report.bricks_stored > 0 && report.bricks_stored < 2 * original.stored_count());
    let sp = back.header.sparse.clone().unwrap();
    assert_eq!(sp.clamp, clamp);
    let step = sp.fixed.unwrap();
    let back = &back.volume.coeffs;
    // Stored coefficients within half a step; the bricks left out hold the background of
    // their side, and no node near the surface is left out.
    let bound = |a: f32| {
        let s = if a.abs() <= step.knee as f32 * step.step {
            step.step
        } else {
            step.step * step.ratio as f32
        };
        s * 0.5 + 4.0 * f32::EPSILON * a.abs()
    };
    for (b, values) in original.stored() {
        for (at, &a) in values.iter().enumerate() {
            let n = [0, 1, 2].map(|x| 8 * b[x] + [at % 8, at / 8 % 8, at / 64][x]);
            let d = back.get(n);
            if back.is_stored(b) {
                assert!((a - d).abs() <= bound(a), "{n:?}: {a} -> {d}");
            } else {
                assert!(a.abs() > f.volume.grid.spacing, "{n:?}: {a} left out");
                assert_eq!(d, if a < 0.0 { -clamp } else { clamp }, "{n:?}");
            }
        }
    }
    for b in original.all_bricks().filter(|&b| !original.is_stored(b)) {
        let want = original.background_of(b);
        let got = back.get(b.map(|c| c * BRICK_EDGE));
        assert!((got - want).abs() <= bound(want), "{b:?}: {want} -> {got}");
    }
}
