//! `pgvol perturb` through the facade: the field of a bumpy sphere resampled into a `.pgv`
//! file that reads back and contours into a closed manifold mesh of one piece, near the input.

use std::path::Path;

use pgvol::glam::Vec3;
use pgvol::mesh::shapes;
use pgvol::perturbation::PerturbOptions;
use pgvol::{GridSpec, Silent};

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
        ..Default::default()
    };
    let built = pgvol::perturbation::perturb(&mesh, &options, &Silent).unwrap();
    assert!(built.report.functions > 0);
    let file =
        pgvol::perturbation::resample(&built.field, &mesh, GridSpec::Res(48), &Silent).unwrap();
    assert_eq!(file.header.metadata["source"], "perturbation");
    let bytes = pgvol::io::pgv_bytes(&file, &pgvol::StorageOptions::default())
        .unwrap()
        .bytes;
    let back = pgvol::io::read_pgv_bytes(&bytes, Path::new("bumpy.pgv")).unwrap();
    let out = pgvol::perturbation::perturbation_mesh(&back, &Silent).unwrap();
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
fn a_stored_function_list_decodes_as_the_field_in_memory() {
    let mesh = bumpy();
    let options = PerturbOptions {
        max_functions: 60,
        tolerance: 1e-3,
        ..Default::default()
    };
    let built = pgvol::perturbation::perturb(&mesh, &options, &Silent).unwrap();
    let header =
        pgvol::perturbation::perturbation_header(&built.field, &mesh, GridSpec::Res(40)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bumpy.pgv");
    pgvol::perturbation::write_perturbation(&path, &header, &built.field).unwrap();
    let stored = std::fs::read(&path).unwrap();
    // The list, read back, is the field bit for bit.
    match pgvol::io::read_field_source(&path).unwrap() {
        pgvol::io::FieldSource::Perturbation { header: h, field } => {
            assert_eq!(h, header);
            assert_eq!(field.base(), built.field.base());
            assert_eq!(field.terms(), built.field.terms());
        }
        other => panic!("read as a volume: {:?}", other.header()),
    }
    // Decoding the file gives the mesh of the field resampled in memory.
    let from_file = pgvol::io::read_pgv(&path).unwrap();
    assert_eq!(from_file.header.encoding, "perturbation-f64");
    let in_memory =
        pgvol::perturbation::resample(&built.field, &mesh, GridSpec::Res(40), &Silent).unwrap();
    assert_eq!(from_file.volume, in_memory.volume);
    let a = pgvol::perturbation::perturbation_mesh(&from_file, &Silent).unwrap();
    let b = pgvol::perturbation::perturbation_mesh(&in_memory, &Silent).unwrap();
    assert!(!a.triangles.is_empty());
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.triangles, b.triangles);
    // Truncated or corrupted, the file is refused with its name.
    let name = Path::new("bumpy.pgv");
    let e = pgvol::io::read_pgv_bytes(&stored[..stored.len() - 100], name).unwrap_err();
    assert!(
        e.to_string().contains("bumpy.pgv") && e.to_string().contains("truncated"),
        "{e}"
    );
    let mut bad = stored.clone();
    let at = bad.len() - 200;
    bad[at] ^= 4;
    let e = pgvol::io::read_pgv_bytes(&bad, name).unwrap_err();
    assert!(
        e.to_string().contains("bumpy.pgv") && e.to_string().contains("checksum"),
        "{e}"
    );
}

#[test]
fn bad_options_are_refused_with_the_figure() {
    let mesh = bumpy();
    let bad = PerturbOptions {
        max_functions: 10,
        tolerance: -1.0,
        ..Default::default()
    };
    let e = pgvol::perturbation::perturb(&mesh, &bad, &Silent).unwrap_err();
    assert!(e.to_string().contains("-1"), "{e}");
}
