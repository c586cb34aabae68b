//! `pgvol perturb` through the facade: the field of a bumpy sphere resampled into a `.pgv`
//! file that reads back and contours into a closed manifold mesh of one piece, near the input.

use std::path::Path;

use pgvol::glam::Vec3;
use pgvol::mesh::shapes;
use pgvol::{GridSpec, PerturbOptions, Silent};

fn bumpy() -> pgvol::Mesh {
    let mut mesh = shapes::octasphere(4);
    for p in &mut mesh.positions {
        let d = p.normalize();
        let bump = (-(1.0 - d.dot(Vec3::X)) * 10.0).exp();
        *p = d * (1.0 + 0.25 * bump);
    }
    mesh
}

#[test]
fn a_resampled_field_reads_back_and_contours_closed() {
    let mesh = bumpy();
    let options = PerturbOptions {
        max_functions: 200,
        tolerance: 1e-3,
    };
    let built = pgvol::perturb(&mesh, &options, &Silent).unwrap();
    assert!(built.report.functions > 0);
    let file = pgvol::resample(&built.field, &mesh, GridSpec::Res(48), &Silent).unwrap();
    assert_eq!(file.header.metadata["source"], "perturbation");
    let bytes = pgvol::pgv_bytes(&file, &pgvol::StorageOptions::default())
        .unwrap()
        .0;
    let back = pgvol::read_pgv_bytes(&bytes, Path::new("bumpy.pgv")).unwrap();
    let out = pgvol::perturbation_mesh(&back, &Silent).unwrap();
    let stats = out.stats();
    assert!(
        stats.watertight && stats.non_manifold_edges == 0,
        "{stats:?}"
    );
    assert_eq!(stats.components, 1);
    let c = pgvol::compare(&mesh, &out, 20_000, 1).unwrap();
    // The grid spacing is 0.05: the zero set lies within a fraction of it on average.
    assert!(c.chamfer_l1 < 0.02, "Chamfer {}", c.chamfer_l1);
    assert!(c.vertex_deviation.mean < 0.02, "{:?}", c.vertex_deviation);
}

#[test]
fn bad_options_are_refused_with_the_figure() {
    let mesh = bumpy();
    let bad = PerturbOptions {
        max_functions: 10,
        tolerance: -1.0,
    };
    let e = pgvol::perturb(&mesh, &bad, &Silent).unwrap_err();
    assert!(e.to_string().contains("-1"), "{e}");
}
