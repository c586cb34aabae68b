//! Booleans of fields against analytic truths: the rounded union's fillet radius, its bound
//! against the sharp union, and operands read from files.

use pgvol::edit::{Continuity, IPatchWeights};
use pgvol::glam::{DVec3, Vec3};
use pgvol::mesh::shapes;
use pgvol::{Blend, BoolOp, CoefficientVolume, CsgOptions, EncodeOptions, ErrorKind, GridSpec};
use pgvol::{Operand, Silent};

fn operands(texts: &[&str]) -> Vec<Operand> {
    texts.iter().map(|t| Operand::parse(t).unwrap()).collect()
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
    let settings = CsgOptions {
        op: BoolOp::Union,
        blend: Blend::Round(r),
        res: 96,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        ..CsgOptions::default()
    };
    // The half-spaces x ≤ 0 and y ≤ 0: the fillet fills their concave corner along z.
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0"]);
    let volume = pgvol::Field::csg(&planes, &settings, &Silent)
        .map(|f| f.into_file().volume)
        .unwrap();
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
    let sharp = CsgOptions {
        res: 64,
        bounds: Some((Vec3::splat(-2.0), Vec3::splat(2.0))),
        ..CsgOptions::default()
    };
    let r = 0.25;
    let round = CsgOptions {
        blend: Blend::Round(r),
        ..sharp
    };
    let a = pgvol::Field::csg(&spheres, &sharp, &Silent)
        .map(|f| f.into_file().volume)
        .unwrap();
    let b = pgvol::Field::csg(&spheres, &round, &Silent)
        .map(|f| f.into_file().volume)
        .unwrap();
    let h = a.grid.spacing;
    let band = pgvol::limits::ENCODE_BAND * h;
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
    pgvol::io::write_pgv(&path, &encoded.file, &pgvol::StorageOptions::default()).unwrap();
    let both = vec![
        Operand::File(path.clone()),
        Operand::parse("sphere:0.5,0,0,0.5").unwrap(),
    ];
    let settings = CsgOptions {
        blend: Blend::Round(0.8),
        res: 32,
        ..CsgOptions::default()
    };
    let e = pgvol::Field::csg(&both, &settings, &Silent)
        .map(|f| f.into_file().volume)
        .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
    assert_eq!(e.path(), Some(path.as_path()), "{e}");
    // The same with a sharp union works, and its surface passes through both balls' far poles.
    let sharp = CsgOptions {
        res: 32,
        ..CsgOptions::default()
    };
    let v = pgvol::Field::csg(&both, &sharp, &Silent)
        .map(|f| f.into_file().volume)
        .unwrap();
    assert!(v.value(Vec3::new(1.0, 0.0, 0.0)).abs() < 0.02);
    assert!(v.value(Vec3::ZERO) < -0.2);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn liming_rounding_of_orthogonal_planes_crosses_the_bisector_where_predicted() {
    // P₁ = x, P₂ = y, C = (−x − y − 0.6)/√2, λ = ½: on the bisector x = y = −s the blend
    // vanishes where (2s − 0.6)² / 2 = s², s = 0.6 / (2 + √2).
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0"]);
    let operator = pgvol::edit::BlendOperator::Liming {
        cut: Operand::parse("plane:-1,-1,0,0.6").unwrap(),
        lambda: 0.5,
    };
    let settings = pgvol::edit::BlendOptions {
        res: 64,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        ..pgvol::edit::BlendOptions::default()
    };
    let blended = pgvol::edit::blend(&planes, &operator, &settings, &Silent).unwrap();
    let v = blended.field.volume();
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
    let e = pgvol::edit::blend(&planes[..1], &operator, &settings, &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter);
}

#[test]
fn an_ipatch_with_fewer_bounds_than_primaries_is_refused() {
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0"]);
    let settings = pgvol::edit::BlendOptions {
        res: 16,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        ..pgvol::edit::BlendOptions::default()
    };
    for weights in [
        IPatchWeights::Given(vec![1.0, 1.0], -0.5),
        IPatchWeights::Fitted(vec![DVec3::new(-0.5, -0.5, 0.0); 4]),
    ] {
        let operator = pgvol::edit::BlendOperator::IPatch {
            bounds: operands(&["plane:-1,0,0,1"]),
            weights,
            continuity: Continuity::G1,
        };
        let e = pgvol::edit::blend(&planes, &operator, &settings, &Silent).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
        assert!(e.message().contains("one bound per primary"), "{e}");
        assert!(!e.message().contains("--"), "{e}");
    }
    // Weights that do not pair with the primaries are refused the same way.
    let operator = pgvol::edit::BlendOperator::IPatch {
        bounds: operands(&["plane:-1,0,0,1", "plane:0,-1,0,1"]),
        weights: IPatchWeights::Given(vec![1.0], -0.5),
        continuity: Continuity::G1,
    };
    let e = pgvol::edit::blend(&planes, &operator, &settings, &Silent).unwrap_err();
    assert!(e.message().contains("needs 2 weights"), "{e}");
}

fn blend_settings(res: usize) -> pgvol::edit::BlendOptions {
    pgvol::edit::BlendOptions {
        res,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        ..pgvol::edit::BlendOptions::default()
    }
}

#[test]
fn g1_blends_keep_the_values_they_had_before_orders_and_more_operands() {
    // Bit patterns of the re-fitted fields at four points, recorded before I-patches took an
    // order and functional splines any number of operands: the defaults must not move. (The
    // I-patch's were recorded again once results with planes were cut at the box: its last
    // point lies 0.3 inside the box's face, where the cut takes over.)
    let primaries = operands(&["plane:1,0,0,0", "sphere:0.2,0.1,0,0.9"]);
    let bounds = operands(&["plane:-1,0,0,0.8", "plane:0,-1,0.2,0.7"]);
    let ipatch = pgvol::edit::BlendOperator::IPatch {
        bounds: bounds.clone(),
        weights: IPatchWeights::Given(vec![1.0, 1.5], -0.7),
        continuity: Continuity::default(),
    };
    let spline = pgvol::edit::BlendOperator::Spline {
        bounds,
        lambda: 0.4,
    };
    let points = [
        Vec3::new(-0.3, -0.2, 0.1),
        Vec3::new(-0.5, -0.6, 0.0),
        Vec3::new(0.1, 0.05, -0.2),
        Vec3::new(-0.7, 0.3, 0.4),
    ];
    for (operator, before) in [
        (ipatch, [3194681295u32, 1022253451, 3200331359, 3197839876]),
        (spline, [3196500120, 1033848309, 1047626734, 1038211911]),
    ] {
        let v = pgvol::edit::blend(&primaries, &operator, &blend_settings(24), &Silent)
            .unwrap()
            .field
            .into_file()
            .volume;
        let now = points.map(|p| v.value(p).to_bits());
        assert_eq!(now, before, "{operator:?}");
    }
}

/// The zero of the analytic I-patch of the planes x = 0, y = 0 with bounds −x − 0.8, −y − 0.8
/// and weights (1, 1, w) on the diagonal x = y = −s, by bisection in f64; there
/// `|B|ᵉ = (0.8 − s)ᵉ`.
fn diagonal_zero(order: u32, w0: f64) -> f64 {
    let e = order as i32 + 1;
    let f = |s: f64| 2.0 * -s * (0.8 - s).powi(e) + w0 * (0.8 - s).powi(2 * e);
    let (mut a, mut b) = (0.0f64, 0.79f64);
    assert!(f(a).signum() != f(b).signum(), "order {order}");
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if f(m).signum() == f(a).signum() {
            a = m
        } else {
            b = m
        }
    }
    0.5 * (a + b)
}

#[test]
fn higher_order_ipatches_cross_the_diagonal_where_their_formula_does() {
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0"]);
    let bounds = operands(&["plane:-1,0,0,0.8", "plane:0,-1,0,0.8"]);
    let mut crossings = Vec::new();
    for order in 1..=3 {
        let operator = pgvol::edit::BlendOperator::IPatch {
            bounds: bounds.clone(),
            weights: IPatchWeights::Given(vec![1.0, 1.0], 0.5),
            continuity: Continuity::new(order).unwrap(),
        };
        let v = pgvol::edit::blend(&planes, &operator, &blend_settings(48), &Silent)
            .unwrap()
            .field
            .into_file()
            .volume;
        let p = zero_between(&v, Vec3::new(-0.02, -0.02, 0.0), Vec3::new(-0.7, -0.7, 0.0));
        let s = diagonal_zero(order, 0.5) as f32;
        assert!(
            (p.x + s).abs() < 0.01 && (p.y + s).abs() < 0.01,
            "order {order}: {p} vs −{s}"
        );
        crossings.push(s);
    }
    // The orders give different surfaces: the test sees the exponent.
    assert!((crossings[0] - crossings[2]).abs() > 0.03, "{crossings:?}");
}

#[test]
fn an_ipatch_through_a_point_passes_through_it_at_every_order() {
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0"]);
    let bounds = operands(&["plane:-1,0,0,0.8", "plane:0,-1,0,0.8"]);
    let through = Vec3::new(-0.25, -0.35, 0.1);
    for order in [1, 2, 4] {
        let operator = pgvol::edit::BlendOperator::IPatch {
            bounds: bounds.clone(),
            weights: IPatchWeights::Through(vec![1.0, 1.0], through.as_dvec3()),
            continuity: Continuity::new(order).unwrap(),
        };
        let blended = pgvol::edit::blend(&planes, &operator, &blend_settings(48), &Silent).unwrap();
        let v = blended.field.volume().value(through);
        assert!(v.abs() < 0.01, "order {order}: {v} at {through}");
        // The weight is the formula's, computed here independently in f64.
        let e = order as i32 + 1;
        let (x, y) = (through.x as f64, through.y as f64);
        let (b1, b2) = ((-x - 0.8).abs(), (-y - 0.8).abs());
        let want = -(x * b2.powi(e) + y * b1.powi(e)) / (b1 * b2).powi(e);
        let (_, w0) = blended.weights.unwrap();
        assert!(
            (w0 as f64 - want).abs() < 1e-5 * want.abs(),
            "{w0} vs {want}"
        );
    }
    // A point on a bound fixes no weight; one far away is refused before any work.
    for point in [DVec3::new(-0.8, -0.3, 0.0), DVec3::new(1e9, 0.0, 0.0)] {
        let operator = pgvol::edit::BlendOperator::IPatch {
            bounds: bounds.clone(),
            weights: IPatchWeights::Through(vec![1.0, 1.0], point),
            continuity: Continuity::G1,
        };
        let e = pgvol::edit::blend(&planes, &operator, &blend_settings(16), &Silent).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
        assert!(!e.message().contains("--"), "{e}");
    }
}

#[test]
fn a_functional_spline_of_three_planes_rounds_their_vertex() {
    // The octant x, y, z ≤ 0 with the one bound (−x − y − z − 1.2)/√3 (planes are normalised),
    // λ = ½: on the diagonal x = y = z = −s the blend vanishes where (3s − 1.2)²/3 = s³.
    let planes = operands(&["plane:1,0,0,0", "plane:0,1,0,0", "plane:0,0,1,0"]);
    let operator = pgvol::edit::BlendOperator::Spline {
        bounds: operands(&["plane:-1,-1,-1,1.2"]),
        lambda: 0.5,
    };
    let v = pgvol::edit::blend(&planes, &operator, &blend_settings(48), &Silent)
        .unwrap()
        .field
        .into_file()
        .volume;
    let p = zero_between(&v, Vec3::splat(-0.01), Vec3::splat(-0.6));
    let cubic = |s: f64| (3.0 * s - 1.2).powi(2) / 3.0 - s.powi(3);
    let (mut a, mut b) = (0.0f64, 0.4f64);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if cubic(m) > 0.0 {
            a = m
        } else {
            b = m
        }
    }
    let s = (0.5 * (a + b)) as f32;
    assert!(
        (p - Vec3::splat(-s)).abs().max_element() < 0.01,
        "{p} vs −{s}"
    );
    // Away from the bound the faces are unchanged; beyond two faces is outside.
    let q = zero_between(&v, Vec3::new(0.3, -0.7, -0.7), Vec3::new(-0.3, -0.7, -0.7));
    assert!(q.x.abs() < 1e-3, "{q}");
    assert!(v.value(Vec3::new(0.2, 0.2, -0.3)) > 0.0);
    // One primary has no edge to round.
    let e = pgvol::edit::blend(&planes[..1], &operator, &blend_settings(16), &Silent).unwrap_err();
    assert!(e.message().contains("two or more primaries"), "{e}");
}
