//! Operations whose result has no inside (or no surface) refuse it with an empty-result error
//! that says why, instead of returning a field that only a later decode refuses.

use pgvol::edit::Restore;
use pgvol::glam::{DVec3, Vec3};
use pgvol::mesh::shapes;
use pgvol::perturbation::PerturbOptions;
use pgvol::{BoolOp, CsgOptions, EncodeOptions, ErrorKind, Field, GridSpec, Mesh, Silent};

fn operands(texts: &[&str]) -> Vec<pgvol::Operand> {
    texts
        .iter()
        .map(|t| pgvol::Operand::parse(t).unwrap())
        .collect()
}

#[track_caller]
fn assert_empty<T: std::fmt::Debug>(result: pgvol::Result<T>, words: &[&str]) {
    let e = result.expect_err("expected an empty-result error");
    assert_eq!(e.kind(), ErrorKind::EmptyResult, "{e}");
    for w in words {
        assert!(e.message().contains(w), "{e} should mention {w:?}");
    }
    // The library names no command-line option.
    assert!(!e.message().contains("--"), "{e}");
}

/// A flat square of `n` × `n` cells in z = 0, two triangles each: an open sheet.
fn sheet(n: u32) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(Vec3::new(i as f32, j as f32, 0.0) / n as f32);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            triangles.push([a, a + 1, a + n + 2]);
            triangles.push([a, a + n + 2, a + n + 1]);
        }
    }
    pgvol::io::mesh_from_parts(positions, triangles)
        .unwrap()
        .mesh
}

/// The sheet tilted: open and without thickness, though not flat along an axis.
fn tilted(n: u32) -> Mesh {
    let mesh = sheet(n);
    let world: Vec<_> = (0..mesh.positions.len())
        .map(|i| {
            let p = mesh.world(i);
            p + DVec3::Z * (0.3 * p.x + 0.2 * p.y)
        })
        .collect();
    pgvol::io::mesh_from_world(&world, mesh.triangles.clone())
        .unwrap()
        .mesh
}

/// Counts the stages a call starts.
#[derive(Default)]
struct Stages(std::sync::Mutex<usize>);

impl pgvol::Progress for Stages {
    fn stage(&self, _name: &str) {
        *self.0.lock().unwrap() += 1;
    }
}

#[test]
fn booleans_with_nothing_inside_are_refused_with_their_reason() {
    let settings = |op| CsgOptions {
        op,
        res: 32,
        ..CsgOptions::default()
    };
    let disjoint = operands(&["sphere:0,0,0,1", "sphere:3,0,0,1"]);
    assert_empty(
        Field::csg(&disjoint, &settings(BoolOp::Intersection), &Silent)
            .map(|f| f.into_file().volume),
        &["the intersection is empty", "do not overlap"],
    );
    let same = operands(&["sphere:0,0,0,1", "sphere:0,0,0,1"]);
    assert_empty(
        Field::csg(&same, &settings(BoolOp::Difference), &Silent).map(|f| f.into_file().volume),
        &["the difference is empty", "cover all of the first"],
    );
    // Overlapping operands still give their intersection, and a smaller ball its difference.
    let overlap = operands(&["sphere:0,0,0,1", "sphere:1,0,0,1"]);
    let v = Field::csg(&overlap, &settings(BoolOp::Intersection), &Silent)
        .map(|f| f.into_file().volume)
        .unwrap();
    assert!(v.value(Vec3::new(0.5, 0.0, 0.0)) < 0.0);
    let smaller = operands(&["sphere:0,0,0,1", "sphere:0,0,0,0.5"]);
    Field::csg(&smaller, &settings(BoolOp::Difference), &Silent)
        .map(|f| f.into_file().volume)
        .unwrap();
}

#[test]
fn a_repair_that_keeps_nothing_is_refused() {
    let options = EncodeOptions {
        grid: GridSpec::Res(32),
        ..EncodeOptions::default()
    };
    let encoded = pgvol::encode(&shapes::octasphere(2), &options, &Silent).unwrap();
    let shape = Field::from_file(encoded.file);
    let (lo, hi) = (shape.volume().grid.origin, shape.volume().grid.max_corner());
    let whole = pgvol::edit::Mask {
        lo: lo - 1.0,
        hi: hi + 1.0,
    };
    let restore = Restore::Protrusion {
        face: pgvol::edit::Face {
            axis: 2,
            upper: false,
        },
        alpha: 1.0,
    };
    assert_empty(
        shape
            .repair(&[whole], restore, &Silent)
            .map(|r| (r.field.into_file().volume, r.masks)),
        &[
            "the restored field",
            "masks around only the parts to restore",
        ],
    );
    // A mask over a cap only keeps the rest.
    let cap = pgvol::edit::Mask {
        lo: Vec3::new(-1.2, -1.2, 0.6),
        hi: Vec3::new(1.2, 1.2, 1.2),
    };
    shape
        .repair(&[cap], restore, &Silent)
        .map(|r| (r.field.into_file().volume, r.masks))
        .unwrap();
}

#[test]
fn sheets_without_thickness_encode_and_perturb_to_an_error_saying_so() {
    let options = EncodeOptions {
        grid: GridSpec::Res(32),
        ..EncodeOptions::default()
    };
    assert_empty(
        pgvol::encode(&sheet(10), &options, &Silent),
        &[
            "the encoded field would be empty",
            "flat",
            "finer grid would not help",
        ],
    );
    // A flat sheet in any orientation is refused before any work, even on the largest grid.
    let stages = Stages::default();
    let finest = EncodeOptions {
        grid: GridSpec::Res(pgvol::limits::MAX_RES as usize),
        ..EncodeOptions::default()
    };
    assert_empty(
        pgvol::encode(&tilted(100), &finest, &stages),
        &[
            "flat",
            "all its vertices lie in one plane",
            "finer grid would not help",
        ],
    );
    assert_eq!(*stages.0.lock().unwrap(), 0, "a stage ran");

    let perturb = PerturbOptions {
        max_functions: 20,
        ..PerturbOptions::default()
    };
    assert_empty(
        pgvol::perturbation::perturb_on(&sheet(6), &perturb, GridSpec::Res(24), &Silent),
        &["the perturbation field is empty", "flat"],
    );
    // A closed mesh encodes as before.
    pgvol::encode(&shapes::octasphere(2), &options, &Silent).unwrap();
}
