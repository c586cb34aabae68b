//! The perturbation loop on a sphere with bumps: the error falls at every step and ends far
//! below the base quadric's, the vertices end near the zero set, and the field is negative
//! inside and positive outside.

use glam::Vec3;
use pgvol_core::Mesh;
use pgvol_perturb::{build, PerturbOptions, StopReason};

/// Radius of the bumpy sphere along the unit direction `d`: a unit sphere with three smooth
/// bumps of height 0.25 and one dent of depth 0.15.
fn radius(d: Vec3) -> f32 {
    let bump = |axis: Vec3, h: f32| h * (-(1.0 - d.dot(axis.normalize())) * 12.0).exp();
    1.0 + bump(Vec3::X, 0.25) + bump(Vec3::new(-1.0, 1.0, 0.3), 0.25) + bump(Vec3::Z, 0.25)
        - bump(Vec3::new(0.2, -1.0, -1.0), 0.15)
}

/// A latitude–longitude mesh of the bumpy sphere, counter-clockwise seen from outside.
fn bumpy_sphere(rings: u32, sectors: u32) -> Mesh {
    let dir = |i: u32, j: u32| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = std::f32::consts::TAU * j as f32 / sectors as f32;
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    };
    let mut positions = vec![Vec3::Z * radius(Vec3::Z)];
    for i in 1..rings {
        for j in 0..sectors {
            let d = dir(i, j);
            positions.push(d * radius(d));
        }
    }
    positions.push(-Vec3::Z * radius(-Vec3::Z));
    let south = positions.len() as u32 - 1;
    let at = |i: u32, j: u32| 1 + (i - 1) * sectors + j % sectors;
    let mut triangles = Vec::new();
    for j in 0..sectors {
        triangles.push([0, at(1, j), at(1, j + 1)]);
        triangles.push([south, at(rings - 1, j + 1), at(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..sectors {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    Mesh::new(positions, triangles)
}

/// Points on a lattice around the bumpy sphere with half their radial gap to the surface, an
/// underestimate of their distance with the right sign.
fn sign_points() -> Vec<(Vec3, f32)> {
    let mut out = Vec::new();
    for k in 0..16 {
        for j in 0..16 {
            for i in 0..16 {
                let p = (Vec3::new(i as f32, j as f32, k as f32) / 15.0 - 0.5) * 3.0;
                let r = p.length();
                if r > 1e-3 {
                    let gap = 0.5 * (r - radius(p / r));
                    if gap.abs() > 0.1 {
                        out.push((p, gap));
                    }
                }
            }
        }
    }
    out
}

#[test]
fn error_falls_monotonically_on_a_sphere_with_bumps() {
    let mesh = bumpy_sphere(40, 80);
    let options = PerturbOptions {
        max_functions: 400,
        tolerance: 1e-3,
        ..Default::default()
    };
    let (field, report) = build(&mesh, &sign_points(), &options, &mut |_| true).unwrap();
    eprintln!(
        "functions {} base mean {:.5} max {:.5} -> mean {:.5} max {:.5} stop {:?} trials {} set aside {} exact {} in {:.2} s",
        report.functions, report.base_mean, report.base_max, report.mean, report.max,
        report.stop, report.trials, report.seeds_set_aside, report.exact_solves, report.seconds
    );
    assert!(report.functions > 10, "{report:?}");
    // The optimisation step runs and, like every accepted step, never raises the functional.
    assert!(report.descent_steps > 0, "{report:?}");
    assert_eq!(report.history.len(), report.loop_functions);
    let mut previous = report.base_functional;
    for (k, &e) in report.history.iter().enumerate() {
        assert!(
            e <= previous * (1.0 + 1e-9),
            "step {k}: {e} after {previous}"
        );
        previous = e;
    }
    // The bumps are far from a quadric; the perturbations must take most of that away.
    assert!(report.base_mean > 0.02, "{}", report.base_mean);
    assert!(report.mean < 0.1 * report.base_mean, "{report:?}");
    let functional = mesh
        .positions
        .iter()
        .map(|&p| field.value_f64(p.as_dvec3()).abs())
        .sum::<f64>()
        / mesh.positions.len() as f64;
    assert!((functional - report.history.last().unwrap()).abs() < 1e-9 * report.diagonal);
    assert!(functional < 0.1 * report.base_functional);
    // Sign: the centre and the bump tips' insides are inside, points beyond them outside.
    assert!(field.value(Vec3::ZERO) < 0.0);
    for d in [
        Vec3::X,
        Vec3::Z,
        Vec3::new(-1.0, 1.0, 0.3).normalize(),
        -Vec3::Y,
    ] {
        let r = radius(d);
        assert!(field.value(d * (r - 0.05)) < 0.0, "inside along {d}");
        assert!(field.value(d * (r + 0.05)) > 0.0, "outside along {d}");
    }
    // The vertices lie near the zero set (first-order distance).
    let worst = mesh
        .positions
        .iter()
        .map(|&p| field.distance_estimate(p).0.abs())
        .fold(0.0f32, f32::max);
    assert!(
        (worst as f64 - report.max).abs() < 1e-3,
        "{worst} vs {}",
        report.max
    );
    assert_ne!(report.stop, StopReason::Cancelled);
    assert_eq!(report.wrong_side_after, 0, "{report:?}");
    for (p, d) in sign_points() {
        assert_eq!(field.value(p) > 0.0, d > 0.0, "sign at {p}");
    }
}

#[test]
fn the_budget_and_cancellation_stop_the_loop() {
    let mesh = bumpy_sphere(20, 40);
    let options = PerturbOptions {
        max_functions: 5,
        tolerance: 0.0,
        ..Default::default()
    };
    let (_, report) = build(&mesh, &[], &options, &mut |_| true).unwrap();
    assert_eq!(report.stop, StopReason::MaxFunctions);
    assert_eq!(report.functions, 5);
    let mut calls = 0;
    let (field, report) = build(&mesh, &[], &options, &mut |_| {
        calls += 1;
        calls <= 2
    })
    .unwrap();
    assert_eq!(report.stop, StopReason::Cancelled);
    assert_eq!(field.terms().len(), 2);
}

#[test]
fn too_few_vertices_are_refused() {
    let mesh = Mesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    );
    let e = build(&mesh, &[], &PerturbOptions::default(), &mut |_| true).unwrap_err();
    assert!(e.to_string().contains("4 vertices"), "{e}");
}
