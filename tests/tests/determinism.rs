//! Results must not depend on the number of threads: the same input gives the same bits.

use pgvol::sdf::{MeshSdf, SignMode};
use pgvol::Grid;
use pgvol_tests::{decode, encode, load_shared, with_threads};

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn distance_grid_is_identical_with_one_and_two_threads() {
    let mesh = load_shared("stanford-bunny");
    let (lo, hi) = mesh.bounds().unwrap();
    let grid = Grid::cube_res(lo, hi, 32).unwrap();
    let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
    let one = with_threads(1, || sdf.sample_grid(&grid, &|_| {}));
    let two = with_threads(2, || sdf.sample_grid(&grid, &|_| {}));
    assert_eq!(one.len(), grid.len());
    // Sanity: the grid straddles the surface, otherwise the comparison would prove little.
    assert!(one.iter().any(|&d| d < 0.0) && one.iter().any(|&d| d > 0.0));
    assert!(
        bits(&one) == bits(&two),
        "distance grids differ between 1 and 2 threads"
    );
}

#[test]
fn pipeline_output_is_identical_with_one_and_two_threads() {
    let mesh = load_shared("stanford-bunny");
    let run = |threads| {
        with_threads(threads, || {
            let encoded = encode(&mesh, 32);
            let bytes = pgvol::io::pgv_bytes(&encoded.file, &pgvol::StorageOptions::default())
                .expect("file bytes")
                .bytes;
            (
                bits(&encoded.file.volume.dense_coeffs()),
                bytes,
                decode(&encoded.file.volume),
            )
        })
    };
    let (c1, f1, m1) = run(1);
    let (c2, f2, m2) = run(2);
    assert!(c1 == c2, "coefficients differ between 1 and 2 threads");
    assert!(f1 == f2, "file bytes differ between 1 and 2 threads");
    assert!(
        m1.triangles.len() > 1000,
        "{} triangles",
        m1.triangles.len()
    );
    assert_eq!(
        m1.triangles, m2.triangles,
        "triangles differ between 1 and 2 threads"
    );
    let pos = |m: &pgvol::Mesh| {
        m.positions
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert!(
        pos(&m1) == pos(&m2),
        "vertex positions differ between 1 and 2 threads"
    );
}
