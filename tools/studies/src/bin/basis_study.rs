//! Measures every basis × fit on exact signed distances of a sphere, a rotated box and a torus
//! at several resolutions. Errors are in grid spacings; prints markdown tables and writes the
//! rows as CSV to `target/basis-study.csv`.
//!
//! `cargo run --release -p pgvol-studies --bin basis_study [-- 16,32,64]`

use std::fmt::Write as _;

use glam::{EulerRot, Quat, Vec3};
use pgvol_field::analytic::{RotatedBox, Sphere, Torus};
use pgvol_field::{
    fit, Basis, CoefficientVolume, FitMethod, FitOptions, FitReport, Grid, SignedDistance,
};
use rayon::prelude::*;

/// Deterministic xorshift, so every run measures the same points.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn in_box(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        lo + (hi - lo) * Vec3::new(self.unit(), self.unit(), self.unit())
    }
}

struct Probes {
    surface: Vec<(Vec3, Vec3)>,
    band: Vec<(Vec3, f32)>,
    whole: Vec<(Vec3, f32)>,
}

fn probes(sdf: &dyn SignedDistance, grid: &Grid, n: usize) -> Probes {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (lo, hi) = (grid.origin, grid.max_corner());
    let k = grid.spacing;
    let mut surface = Vec::new();
    let mut band = Vec::new();
    let mut whole = Vec::new();
    while surface.len() < n || band.len() < n || whole.len() < n {
        let p = rng.in_box(lo, hi);
        let (d, g) = sdf.distance_gradient(p);
        if whole.len() < n {
            whole.push((p, d));
        }
        if d.abs() < 2.0 * k && band.len() < n {
            band.push((p, d));
        }
        if d.abs() < 3.0 * k && surface.len() < n {
            let mut s = p - d * g;
            for _ in 0..3 {
                let (ds, gs) = sdf.distance_gradient(s);
                s -= ds * gs;
            }
            let (ds, gs) = sdf.distance_gradient(s);
            if ds.abs() < 1e-5 {
                surface.push((s, gs));
            }
        }
    }
    Probes {
        surface,
        band,
        whole,
    }
}

#[derive(Clone, Debug)]
struct Row {
    shape: &'static str,
    res: usize,
    basis: Basis,
    method: String,
    surf_rms: f32,
    surf_max: f32,
    band_rms: f32,
    box_max: f32,
    angle_mean: f32,
    angle_p95: f32,
    report: FitReport,
}

fn measure(vol: &CoefficientVolume, pr: &Probes) -> [f32; 6] {
    let k = vol.grid.spacing;
    let surf: Vec<(f32, f32)> = pr
        .surface
        .par_iter()
        .map(|&(p, n)| {
            let (v, g) = vol.eval(p);
            let cos = (g.dot(n) / g.length().max(1e-30)).clamp(-1.0, 1.0);
            (v.abs() / k, cos.acos().to_degrees())
        })
        .collect();
    let rms = |v: &mut dyn Iterator<Item = f32>| {
        let (s, c) = v.fold((0.0f64, 0usize), |(s, c), x| {
            (s + (x as f64).powi(2), c + 1)
        });
        (s / c.max(1) as f64).sqrt() as f32
    };
    let surf_rms = rms(&mut surf.iter().map(|s| s.0));
    let surf_max = surf.iter().map(|s| s.0).fold(0.0, f32::max);
    let mut angles: Vec<f32> = surf.iter().map(|s| s.1).collect();
    angles.sort_by(|a, b| a.total_cmp(b));
    let angle_mean = angles.iter().sum::<f32>() / angles.len() as f32;
    let angle_p95 = angles[(angles.len() * 95 / 100).min(angles.len() - 1)];
    let err = |set: &[(Vec3, f32)]| -> Vec<f32> {
        set.par_iter()
            .map(|&(p, d)| (vol.value(p) - d).abs() / k)
            .collect()
    };
    let band = err(&pr.band);
    let band_rms = rms(&mut band.iter().copied());
    let box_max = err(&pr.whole).into_iter().fold(0.0, f32::max);
    [surf_rms, surf_max, band_rms, box_max, angle_mean, angle_p95]
}

fn main() {
    let resolutions: Vec<usize> = std::env::args()
        .nth(1)
        .map(|s| s.split(',').filter_map(|v| v.parse().ok()).collect())
        .unwrap_or_else(|| vec![16, 32, 64]);
    let shapes: Vec<(&'static str, Box<dyn SignedDistance>)> = vec![
        (
            "sphere",
            Box::new(Sphere {
                centre: Vec3::new(0.03, -0.05, 0.07),
                radius: 0.6,
            }),
        ),
        (
            "rotated box",
            Box::new(RotatedBox {
                centre: Vec3::new(0.02, 0.03, -0.01),
                half: Vec3::new(0.55, 0.4, 0.3),
                rotation: Quat::from_euler(EulerRot::XYZ, 0.3, 0.5, 0.2),
            }),
        ),
        (
            "torus",
            Box::new(Torus {
                centre: Vec3::new(0.02, 0.01, -0.03),
                major: 0.55,
                minor: 0.22,
            }),
        ),
    ];
    let bases = [
        Basis::Trilinear,
        Basis::Bspline2,
        Basis::Bspline3,
        Basis::Pg { n: 3, r: 1.5 },
        Basis::Pg { n: 4, r: 1.5 },
        Basis::Pg { n: 3, r: 2.0 },
    ];
    let opts = FitOptions {
        max_iterations: 200,
        ..FitOptions::default()
    };
    let mut rows = Vec::new();
    for &res in &resolutions {
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), res).unwrap();
        for (shape, sdf) in &shapes {
            let pr = probes(sdf.as_ref(), &grid, 20_000);
            for basis in bases {
                let mut methods = vec![
                    FitMethod::Interp,
                    FitMethod::Iso { z_step: Some(0.5) },
                    FitMethod::Wls,
                ];
                if res <= 32 {
                    methods.push(FitMethod::Iso { z_step: None });
                }
                for method in methods {
                    let (vol, report) = match fit(
                        grid,
                        basis,
                        method,
                        sdf.as_ref(),
                        &opts,
                        pgvol_core::progress::QUIET,
                    ) {
                        Ok(v) => v,
                        Err(e) => {
                            eprintln!("{shape} {res} {basis} {}: {e}", method.name());
                            continue;
                        }
                    };
                    let [surf_rms, surf_max, band_rms, box_max, angle_mean, angle_p95] =
                        measure(&vol, &pr);
                    let label = match method {
                        FitMethod::Iso { z_step: Some(z) } => format!("iso z={z}"),
                        FitMethod::Iso { z_step: None } => {
                            format!("iso z*={:.3}", report.z_step.unwrap_or(f32::NAN))
                        }
                        m => m.name().to_string(),
                    };
                    eprintln!(
                        "{shape:12} {res:3} {basis:12} {label:14} surf {surf_rms:.4} box {box_max:.3} it {} {:.2}s",
                        report.iterations, report.seconds
                    );
                    rows.push(Row {
                        shape,
                        res,
                        basis,
                        method: label,
                        surf_rms,
                        surf_max,
                        band_rms,
                        box_max,
                        angle_mean,
                        angle_p95,
                        report,
                    });
                }
            }
        }
    }
    print!("{}", markdown(&rows));
    let mut csv = String::from(
        "shape,res,basis,fit,bytes,surf_rms,surf_max,band_rms,box_max,angle_mean,angle_p95,spurious,iterations,converged,seconds\n",
    );
    for r in &rows {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3}",
            r.shape,
            r.res,
            r.basis,
            r.method,
            4 * r.res.pow(3),
            r.surf_rms,
            r.surf_max,
            r.band_rms,
            r.box_max,
            r.angle_mean,
            r.angle_p95,
            r.report.spurious_sign_changes,
            r.report.iterations,
            r.report.converged,
            r.report.seconds
        );
    }
    let _ = std::fs::create_dir_all("target");
    if let Err(e) = std::fs::write("target/basis-study.csv", csv) {
        eprintln!("could not write target/basis-study.csv: {e}");
    }
}

/// Four decimals, or two significant digits below 0.001 (B-splines at N = 64 reach 1e-6 k).
fn small(v: f32) -> String {
    if v != 0.0 && v.abs() < 1e-3 {
        format!("{v:.1e}")
    } else {
        format!("{v:.4}")
    }
}

fn markdown(rows: &[Row]) -> String {
    let mut out = String::new();
    let mut last = ("", 0);
    for r in rows {
        if (r.shape, r.res) != last {
            last = (r.shape, r.res);
            let _ = writeln!(
                out,
                "\n### {}, N = {} ({} KiB)\n\n| basis | fit | surface rms / max | band rms | box max | angle mean / p95 (°) | spurious | iterations | s |\n|---|---|---|---|---|---|---|---|---|",
                r.shape, r.res, 4 * r.res.pow(3) / 1024
            );
        }
        let _ = writeln!(
            out,
            "| {} | {} | {} / {} | {} | {:.3} | {:.2} / {:.2} | {} | {}{} | {:.2} |",
            r.basis,
            r.method,
            small(r.surf_rms),
            small(r.surf_max),
            small(r.band_rms),
            r.box_max,
            r.angle_mean,
            r.angle_p95,
            r.report.spurious_sign_changes,
            r.report.iterations,
            if r.report.converged {
                ""
            } else {
                " (not converged)"
            },
            r.report.seconds
        );
    }
    out
}
