//! Walls thinner than the grid resolves are refused before the work, with the grid that would
//! hold them; a result broken into far more pieces than its input is refused after it.

use std::path::PathBuf;
use std::sync::Mutex;

use pgvol::edit::ShellSide;
use pgvol::{ErrorKind, Field, OpenOptions, Progress, ShellKind, SignMode, Silent};

/// The shared mesh corpus: `PGVOL_SHARED_MESHES`, or `../shared/meshes` beside the repository.
fn shared_mesh(name: &str) -> PathBuf {
    let folder = std::env::var_os("PGVOL_SHARED_MESHES").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes"),
        PathBuf::from,
    );
    let path = folder.join(format!("{name}.obj"));
    assert!(path.is_file(), "shared mesh missing: {}", path.display());
    path
}

/// The rocker arm scaled to 100 units along its longest side.
fn rocker_mesh() -> pgvol::Mesh {
    let mut mesh = pgvol::io::read_mesh(shared_mesh("rocker-arm"))
        .unwrap()
        .mesh;
    let (lo, hi) = mesh.bounds().unwrap();
    let scale = 100.0 / (hi - lo).max_element();
    mesh.positions.iter_mut().for_each(|p| *p *= scale);
    mesh
}

/// The 100-unit rocker arm encoded at the default 128 nodes per axis (spacing 0.86) with
/// distances exact `reach` out.
fn rocker(reach: f32) -> Field {
    Field::for_operations(
        rocker_mesh(),
        &OpenOptions {
            res: 128,
            grow: 0.0,
            reach,
            wall: None,
            sign: SignMode::Auto,
            ..OpenOptions::default()
        },
        &Silent,
    )
    .unwrap()
}

/// The stages a call began.
#[derive(Default)]
struct Stages(Mutex<Vec<String>>);

impl Progress for Stages {
    fn stage(&self, name: &str) {
        self.0.lock().unwrap().push(name.to_string());
    }
}

#[test]
fn a_mesh_is_not_encoded_for_a_wall_its_grid_cannot_hold() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rocker.stl");
    pgvol::io::write_mesh(&path, &rocker_mesh()).unwrap();
    let stages = Stages::default();
    let walled = |res| OpenOptions {
        res,
        reach: 0.5,
        wall: Some(0.5),
        ..OpenOptions::default()
    };
    let e = Field::open(&path, &walled(128), &stages).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Unresolved, "{e}");
    assert_eq!(e.path(), Some(path.as_path()));
    assert!(stages.0.lock().unwrap().is_empty(), "work began");
    // At the grid it names the mesh is encoded.
    let nodes = e.resolution().unwrap();
    let shape = Field::open(&path, &walled(nodes), &stages).unwrap();
    assert!(shape.volume().grid.spacing <= 0.25);
    assert!(!stages.0.lock().unwrap().is_empty());
}

#[test]
fn a_wall_thinner_than_two_spacings_is_refused_with_the_grid_that_holds_it() {
    let shape = rocker(2.0);
    let spacing = shape.volume().grid.spacing;
    assert!((spacing - 0.866).abs() < 0.01, "{spacing}");
    for kind in [
        ShellKind::Wall(ShellSide::Inner),
        ShellKind::Wall(ShellSide::Centred),
        ShellKind::Hollow,
    ] {
        let e = shape
            .shell(
                &pgvol::ShellOptions {
                    thickness: 0.5,
                    kind,
                    drains: [].to_vec(),
                },
                &Silent,
            )
            .map(|f| f.into_file().volume)
            .unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Unresolved, "{e}");
        assert!(e.message().contains("0.25"), "{e}");
        // The grid named holds the wall: spacing 0.25 over the same box.
        let nodes = e.resolution().unwrap();
        let finer = 0.866 * 127.0 / (nodes - 1) as f32;
        assert!(
            finer <= 0.25 && finer > 0.24,
            "{nodes} nodes: spacing {finer}"
        );
    }
    // Two spacings and more are built, in one piece.
    let wall = shape
        .shell(
            &pgvol::ShellOptions {
                thickness: 2.0,
                kind: ShellKind::Wall(ShellSide::Inner),
                drains: [].to_vec(),
            },
            &Silent,
        )
        .map(|f| f.into_file().volume)
        .unwrap();
    pgvol::checks::check_pieces("the shell", shape.volume(), &wall).unwrap();
}

#[test]
fn a_result_broken_into_pieces_is_refused() {
    let shape = rocker(0.5);
    // The 0.5 wall built without the check before: it falls apart on the nodes.
    let shredded = pgvol::ops::shell(
        shape.volume(),
        0.5,
        ShellSide::Inner,
        pgvol_core::progress::QUIET,
    )
    .unwrap();
    let e = pgvol::checks::check_pieces("the shell", shape.volume(), &shredded).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Unresolved, "{e}");
    assert!(e.message().contains("where the shape has 1"), "{e}");
    assert_eq!(e.resolution(), Some(255), "{e}");
}
