//! Booleans of fields against analytic truths: the rounded union's fillet radius, its bound
//! against the sharp union, and operands read from files.

use pgvol::glam::{DVec3, Vec3};
use pgvol::mesh::shapes;
use pgvol::{Blend, BoolOp, CoefficientVolume, CsgSettings, EncodeOptions, ErrorKind, GridSpec};
use pgvol::{Operand, Silent};

fn operands(texts: &[&str]) -> Vec<Operand> {
    texts
        .iter()
        .map(|t| pgvol::parse_operand(t).unwrap())
        .collect()
}

/// The zero of the field on the segment from `a` (outside) to `b` (inside), by bisection.
fn zero_between(volume: &CoefficientVolume, mut a: Vec3, mut b: Vec3) -> Vec3 {
    assert!(volume.value(a) > 0.0 && volume.value(b) < 0.0);
    for _ in 0..40 {
        let m = (a + b) * 0.5;
        if volume.value(m) > 0.0 {
            a = m;
        } else {
            b = m;
        }
    }
    (a + b) * 0.5
}

#[test]
fn rounded_union_of_orthogonal_planes_is_a_fillet_of_the_radius() {
    let r = 0.3;
    let settings = CsgSettings {
        op: BoolOp::Union,
        blend: Blend::Round(r),
        res: 96,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        ..CsgSettings::default()
    };
    // The half-spaces x ≤ 0 and y ≤ 0: the fillet fills their concave corner along z.
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0"]);
    let volume = pgvol::csg(&planes, &settings, &Silent).unwrap();
    let centre = Vec3::new(r, r, 0.1);
    // Along rays from the fillet's centre toward the corner the surface lies at the radius.
    let mut worst: f32 = 0.0;
    for k in 1..10 {
        let t = k as f32 / 10.0 * std::f32::consts::FRAC_PI_2;
        let dir = Vec3::new(-t.cos(), -t.sin(), 0.0);
        let p = zero_between(&volume, centre, centre + dir * (2.0 * r));
        worst = worst.max(((p - centre).length() - r).abs() / r);
    }
    assert!(worst <= 0.02, "fillet radius off by {:.2} %", 100.0 * worst);
    // Beyond the fillet the planes are untouched.
    let p = zero_between(&volume, Vec3::new(0.2, 0.7, 0.0), Vec3::new(-0.2, 0.7, 0.0));
    assert!(p.x.abs() < 1e-3 * r, "{p}");
}

#[test]
fn rounded_field_stays_between_the_sharp_one_and_the_radius_below() {
    let spheres = operands(&["sphere:0,0,0,1", "sphere:1.2,0,0,0.8"]);
    let sharp = CsgSettings {
        res: 64,
        bounds: Some((Vec3::splat(-2.0), Vec3::splat(2.0))),
        ..CsgSettings::default()
    };
    let r = 0.25;
    let round = CsgSettings {
        blend: Blend::Round(r),
        ..sharp
    };
    let a = pgvol::csg(&spheres, &sharp, &Silent).unwrap();
    let b = pgvol::csg(&spheres, &round, &Silent).unwrap();
    let h = a.grid.spacing;
    let band = pgvol::ENCODE_BAND * h;
    let mut deepest: f32 = 0.0;
    for i in 0..400 {
        let p = Vec3::new(
            -1.2 + 3.4 * ((i * 37) % 400) as f32 / 400.0,
            -1.0 + 2.0 * ((i * 91) % 400) as f32 / 400.0,
            -0.2 + 0.4 * ((i * 13) % 400) as f32 / 400.0,
        );
        let (va, vb) = (a.value(p), b.value(p));
        // Only where neither field is clamped by the band, with the fit's rounding allowed.
        if va.abs() < band - r && vb.abs() < band - r {
            assert!(
                vb <= va + 0.02 * h && vb >= va - r - 0.02 * h,
                "{p}: {va} {vb}"
            );
            deepest = deepest.max(va - vb);
        }
    }
    assert!(deepest > 0.0);
    // On the circle where the spheres cross, both distances are 0 and the blend is
    // r − √2 r below the sharp field.
    let p = Vec3::new(0.75, 0.75f32.mul_add(-0.75, 1.0).sqrt(), 0.0);
    let drop = a.value(p) - b.value(p);
    let expected = (std::f32::consts::SQRT_2 - 1.0) * r;
    assert!((drop - expected).abs() < 0.1 * r, "{drop} vs {expected}");
}

#[test]
fn a_pgv_operand_too_narrow_for_the_radius_is_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("pgvol-editing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("ball.pgv");
    let options = EncodeOptions {
        grid: GridSpec::Res(32),
        ..EncodeOptions::default()
    };
    let encoded = pgvol::encode(&shapes::octasphere(2), &options, &Silent).unwrap();
    pgvol::write_pgv(&path, &encoded.file, &pgvol::StorageOptions::default()).unwrap();
    let both = vec![
        Operand::File(path.clone()),
        pgvol::parse_operand("sphere:0.5,0,0,0.5").unwrap(),
    ];
    let settings = CsgSettings {
        blend: Blend::Round(0.8),
        res: 32,
        ..CsgSettings::default()
    };
    let e = pgvol::csg(&both, &settings, &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
    assert_eq!(e.path(), Some(path.as_path()), "{e}");
    // The same with a sharp union works, and its surface passes through both balls' far poles.
    let sharp = CsgSettings {
        res: 32,
        ..CsgSettings::default()
    };
    let v = pgvol::csg(&both, &sharp, &Silent).unwrap();
    assert!(v.value(Vec3::new(1.0, 0.0, 0.0)).abs() < 0.02);
    assert!(v.value(Vec3::ZERO) < -0.2);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn liming_rounding_of_orthogonal_planes_crosses_the_bisector_where_predicted() {
    // P₁ = x, P₂ = y, C = (−x − y − 0.6)/√2, λ = ½: on the bisector x = y = −s the blend
    // vanishes where (2s − 0.6)² / 2 = s², s = 0.6 / (2 + √2).
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0"]);
    let operator = pgvol::BlendOperator::Liming {
        cut: pgvol::parse_operand("plane:-1,-1,0,0.6").unwrap(),
        lambda: 0.5,
    };
    let settings = pgvol::BlendSettings {
        res: 64,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        ..pgvol::BlendSettings::default()
    };
    let blended = pgvol::blend(&planes, &operator, &settings, &Silent).unwrap();
    let v = &blended.volume;
    let p = zero_between(v, Vec3::new(0.0, 0.0, 0.1), Vec3::new(-0.5, -0.5, 0.1));
    let s = 0.6 / (2.0 + std::f32::consts::SQRT_2);
    assert!(
        (p.x + s).abs() < 0.01 && (p.y + s).abs() < 0.01,
        "{p} vs −{s}"
    );
    // Renormalised: the gradient has about unit length on the blend surface.
    let g = v.eval(p).1.length();
    assert!((g - 1.0).abs() < 0.15, "gradient {g}");
    // Away from the cut the planes are unchanged.
    let q = zero_between(v, Vec3::new(0.3, -0.8, 0.0), Vec3::new(-0.3, -0.8, 0.0));
    assert!(q.x.abs() < 1e-3, "{q}");
    // Too few operands are refused.
    let e = pgvol::blend(&planes[..1], &operator, &settings, &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter);
}

#[test]
fn an_ipatch_with_fewer_bounds_than_primaries_is_refused() {
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0"]);
    let settings = pgvol::BlendSettings {
        res: 16,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        ..pgvol::BlendSettings::default()
    };
    for weights in [Some((vec![1.0, 1.0], -0.5)), None] {
        let operator = pgvol::BlendOperator::IPatch {
            bounds: operands(&["plane:-1,0,0,1"]),
            points: vec![DVec3::new(-0.5, -0.5, 0.0); 4],
            weights,
        };
        let e = pgvol::blend(&planes, &operator, &settings, &Silent).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
        assert!(e.message().contains("one bound per primary"), "{e}");
        assert!(!e.message().contains("--"), "{e}");
    }
    // Weights that do not pair with the primaries are refused the same way.
    let operator = pgvol::BlendOperator::IPatch {
        bounds: operands(&["plane:-1,0,0,1", "plane:0,-1,0,1"]),
        weights: Some((vec![1.0], -0.5)),
        points: Vec::new(),
    };
    let e = pgvol::blend(&planes, &operator, &settings, &Silent).unwrap_err();
    assert!(e.message().contains("needs 2 weights"), "{e}");
}
