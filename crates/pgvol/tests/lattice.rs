//! Lattices through the facade: parameters the grid cannot hold are refused with the figure, an
//! infill leaves the two labyrinths of a sheet as enclosed voids until a drain opens each.

use glam::Vec3;
use pgvol::lattices::Tpms;
use pgvol::{ErrorKind, Field, Lattice, OpenOptions, SignMode, Silent};

const WALL: f32 = 0.1;

fn sphere() -> Field {
    let mesh = pgvol::mesh::shapes::octasphere(5);
    Field::for_operations(
        mesh,
        &OpenOptions {
            res: 96,
            grow: 0.0,
            reach: WALL,
            wall: None,
            sign: SignMode::Auto,
            ..OpenOptions::default()
        },
        &Silent,
    )
    .unwrap()
}

fn solid(solid: &pgvol::Latticed) -> pgvol::SolidReport {
    let mesh = solid
        .field
        .to_mesh(&pgvol::DecodeOptions::default(), &Silent)
        .unwrap();
    let s = mesh.stats();
    assert!(
        s.watertight && s.winding_consistent && s.non_manifold_edges == 0,
        "{s:?}"
    );
    let on_mesh = solid.report(Some(&mesh), &Silent);
    // The estimate from node values agrees with the contoured solid.
    let on_field = solid.report(None, &Silent);
    assert!(
        (on_field.volume / on_mesh.volume - 1.0).abs() < 0.01,
        "{on_field:?} {on_mesh:?}"
    );
    assert!(
        (on_field.area / on_mesh.area - 1.0).abs() < 0.03,
        "{on_field:?} {on_mesh:?}"
    );
    on_mesh
}

#[test]
fn lattices_the_grid_cannot_hold_are_refused_with_the_figure() {
    let shape = sphere();
    let thin = Lattice::sheet(Tpms::Gyroid, 0.5, 0.01);
    let e = shape.lattice(&thin, &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter);
    assert!(e.message().contains("under two grid spacings"), "{e}");
    let fine = Lattice::sheet(Tpms::Gyroid, 0.1, 0.049);
    let e = shape.lattice(&fine, &Silent).unwrap_err();
    assert!(e.message().contains("under eight grid spacings"), "{e}");
    let too_thick = Lattice::sheet(Tpms::Gyroid, 0.5, 0.3);
    let e = shape.lattice(&too_thick, &Silent).unwrap_err();
    assert!(e.message().contains("under half the cell"), "{e}");
}

#[test]
fn drains_open_the_labyrinths_of_an_infill() {
    let shape = sphere();
    let gyroid = Lattice::sheet(Tpms::Gyroid, 0.6, 0.08);
    let closed = shape.infill(WALL, &gyroid, &[], &Silent).unwrap();
    let sealed = solid(&closed);
    assert!(sealed.enclosed_voids.unwrap() >= 2, "{sealed:?}");
    assert!(sealed.fraction > 0.2 && sealed.fraction < 0.6, "{sealed:?}");

    // One drain from a point deep in each labyrinth, out through the top.
    let labyrinth = |sign: f32| {
        let points = (0..1000).map(|i| glam::UVec3::new(i % 10, (i / 10) % 10, i / 100).as_vec3());
        points
            .map(|p| (p - Vec3::splat(4.5)) * 0.1)
            .max_by(|&a, &b| {
                let d = |p| sign * gyroid.surface_distance(p, -1.0);
                d(a).total_cmp(&d(b))
            })
            .unwrap()
    };
    let drains: Vec<pgvol::edit::Drain> = [1.0, -1.0]
        .map(|sign| pgvol::edit::Drain {
            point: labyrinth(sign),
            direction: Vec3::Z,
            diameter: 0.08,
        })
        .to_vec();
    let open = shape.infill(WALL, &gyroid, &drains, &Silent).unwrap();
    let drained = solid(&open);
    assert!(
        drained.enclosed_voids.unwrap() + 2 <= sealed.enclosed_voids.unwrap(),
        "{sealed:?} then {drained:?}"
    );
    assert!(drained.volume < sealed.volume);
    // A drain point in the wall opens nothing and is refused.
    let wall = pgvol::edit::Drain {
        point: Vec3::new(0.0, 0.0, 0.95),
        ..drains[0]
    };
    let e = shape.infill(WALL, &gyroid, &[wall], &Silent).unwrap_err();
    assert!(e.message().contains("in the wall"), "{e}");
}
