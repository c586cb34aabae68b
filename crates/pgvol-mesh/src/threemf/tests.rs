//! The reader on small packages written here: transforms, units, parts, and the limits.

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use super::{read_with, Limits};
use crate::{DeclaredUnit, LengthUnit, UnitChoice};

fn read(bytes: &[u8], name: &Path) -> Result<(crate::Mesh, DeclaredUnit), crate::MeshError> {
    super::read(bytes, name, UnitChoice::Millimetres)
}

const CORE: &str = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02";
const PRODUCTION: &str = "http://schemas.microsoft.com/3dmanufacturing/production/2015/06";

fn rels(target: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?><Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel" Target="{target}" Id="r0"/></Relationships>"#
    )
}

/// A zip package of `entries`, deflated.
fn package(entries: &[(&str, &[u8])]) -> Vec<u8> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, bytes) in entries {
        zip.start_file(*name, options).unwrap();
        zip.write_all(bytes).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

/// A package whose start part is `/3D/3dmodel.model` holding `model`.
fn single(model: &str) -> Vec<u8> {
    package(&[
        ("_rels/.rels", rels("/3D/3dmodel.model").as_bytes()),
        ("3D/3dmodel.model", model.as_bytes()),
    ])
}

/// A unit tetrahedron, counter-clockwise seen from outside, as a mesh object.
fn tetra(id: u32, kind: &str) -> String {
    format!(
        r#"<object id="{id}" type="{kind}"><mesh><vertices><vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/><vertex x="0" y="0" z="1"/></vertices><triangles><triangle v1="0" v2="2" v3="1"/><triangle v1="0" v2="1" v3="3"/><triangle v1="0" v2="3" v3="2"/><triangle v1="1" v2="2" v3="3"/></triangles></mesh></object>"#
    )
}

fn model(unit: &str, resources: &str, build: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?><model unit="{unit}" xmlns="{CORE}" xmlns:p="{PRODUCTION}"><resources>{resources}</resources><build>{build}</build></model>"#
    )
}

fn name() -> &'static Path {
    Path::new("part.3mf")
}

fn world(mesh: &crate::Mesh) -> Vec<DVec3> {
    (0..mesh.positions.len()).map(|i| mesh.world(i)).collect()
}

fn signed_volume(mesh: &crate::Mesh) -> f64 {
    let p = world(mesh);
    mesh.triangles
        .iter()
        .map(|&[a, b, c]| p[a as usize].dot(p[b as usize].cross(p[c as usize])) / 6.0)
        .sum()
}

fn error(bytes: &[u8], limits: &Limits) -> String {
    let e = read_with(bytes, name(), UnitChoice::Millimetres, limits).unwrap_err();
    assert!(e.to_string().starts_with("part.3mf"), "{e}");
    e.problem
}

#[test]
fn component_transforms_apply_before_the_build_item_transform() {
    // Object 2 places the tetrahedron moved by (1, 0, 0); the item scales by 2 and moves z by
    // 10. The corner (1, 0, 0) must land at ((1 + 1)·2, 0, 10) = (4, 0, 10).
    let resources = format!(
        r#"{}<object id="2"><components><component objectid="1" transform="1 0 0 0 1 0 0 0 1 1 0 0"/></components></object>"#,
        tetra(1, "model")
    );
    let bytes = single(&model(
        "millimeter",
        &resources,
        r#"<item objectid="2" transform="2 0 0 0 2 0 0 0 2 0 0 10"/>"#,
    ));
    let (mesh, unit) = read(&bytes, name()).unwrap();
    assert_eq!(unit.unit, LengthUnit::Millimetre);
    let p = world(&mesh);
    assert_eq!(p.len(), 4);
    assert_eq!(p[1], DVec3::new(4.0, 0.0, 10.0));
    assert_eq!(p[0], DVec3::new(2.0, 0.0, 10.0));
    assert!((signed_volume(&mesh) - 8.0 / 6.0).abs() < 1e-9);
}

#[test]
fn several_items_are_merged_and_a_mirror_keeps_the_outside_out() {
    let bytes = single(&model(
        "millimeter",
        &tetra(1, "model"),
        r#"<item objectid="1"/><item objectid="1" transform="-1 0 0 0 1 0 0 0 1 -5 0 0"/>"#,
    ));
    let (mesh, _) = read(&bytes, name()).unwrap();
    assert_eq!(mesh.triangles.len(), 8);
    // Two tetrahedra of volume 1/6, both outward: a mirror without the corner swap would
    // cancel them to zero.
    assert!((signed_volume(&mesh) - 2.0 / 6.0).abs() < 1e-9);
}

#[test]
fn inches_become_millimetres_and_the_unit_is_reported() {
    let bytes = single(&model(
        "inch",
        &tetra(1, "model"),
        r#"<item objectid="1"/>"#,
    ));
    let (mesh, report) =
        crate::read_bytes_clean(&bytes, crate::MeshFormat::ThreeMf, name()).unwrap();
    assert_eq!(
        report.unit,
        Some(DeclaredUnit {
            unit: LengthUnit::Inch,
            converted: true
        })
    );
    let p = world(&mesh);
    assert!(p
        .iter()
        .any(|q| (*q - DVec3::new(25.4, 0.0, 0.0)).length() < 1e-5));
    // Kept as declared on request: the corner stays at 1.
    let (kept, unit) = super::read(&bytes, name(), UnitChoice::AsDeclared).unwrap();
    assert!(!unit.converted);
    assert!(world(&kept).contains(&DVec3::new(1.0, 0.0, 0.0)));
    let e = error(
        &single(&model(
            "furlong",
            &tetra(1, "model"),
            r#"<item objectid="1"/>"#,
        )),
        &Limits::DEFAULT,
    );
    assert!(e.contains("'furlong'") && e.contains("inch"), "{e}");
}

#[test]
fn objects_in_another_part_are_found_through_p_path() {
    let root = model(
        "millimeter",
        r#"<object id="5"><components><component objectid="1" p:path="/3D/Objects/o.model" transform="1 0 0 0 1 0 0 0 1 0 0 3"/></components></object>"#,
        r#"<item objectid="5"/>"#,
    );
    let other = model("millimeter", &tetra(1, "model"), "");
    let bytes = package(&[
        ("_rels/.rels", rels("3D/3dmodel.model").as_bytes()),
        ("3D/3dmodel.model", root.as_bytes()),
        ("3D/Objects/o.model", other.as_bytes()),
    ]);
    let (mesh, _) = read(&bytes, name()).unwrap();
    assert_eq!(world(&mesh)[3], DVec3::new(0.0, 0.0, 4.0));

    // The same reference to a part the package lacks.
    let bytes = package(&[
        ("_rels/.rels", rels("3D/3dmodel.model").as_bytes()),
        ("3D/3dmodel.model", root.as_bytes()),
    ]);
    let e = error(&bytes, &Limits::DEFAULT);
    assert!(e.contains("part /3D/Objects/o.model is missing"), "{e}");
}

#[test]
fn supports_are_left_out_and_a_build_of_only_supports_is_refused() {
    let resources = format!("{}{}", tetra(1, "model"), tetra(2, "support"));
    let bytes = single(&model(
        "millimeter",
        &resources,
        r#"<item objectid="1"/><item objectid="2"/>"#,
    ));
    assert_eq!(read(&bytes, name()).unwrap().0.triangles.len(), 4);
    let bytes = single(&model(
        "millimeter",
        &tetra(2, "support"),
        r#"<item objectid="2"/>"#,
    ));
    let e = error(&bytes, &Limits::DEFAULT);
    assert!(e.contains("no build item places a mesh"), "{e}");
}

#[test]
fn component_cycles_and_deep_nesting_are_refused() {
    let cycle = r#"<object id="1"><components><component objectid="2"/></components></object><object id="2"><components><component objectid="3"/></components></object><object id="3"><components><component objectid="1"/></components></object>"#;
    let e = error(
        &single(&model("millimeter", cycle, r#"<item objectid="1"/>"#)),
        &Limits::DEFAULT,
    );
    assert!(e.contains("objects 1 → 2 → 3 → 1"), "{e}");

    // A chain of 70 objects, each placing the next, ending at a mesh.
    let mut chain = tetra(100, "model");
    for id in 0..70 {
        let next = if id == 69 { 100 } else { id + 1 };
        chain.push_str(&format!(
            r#"<object id="{id}"><components><component objectid="{next}"/></components></object>"#
        ));
    }
    let bytes = single(&model("millimeter", &chain, r#"<item objectid="0"/>"#));
    let e = error(&bytes, &Limits::DEFAULT);
    assert!(e.contains("nested more than 64 deep"), "{e}");
    let deep = Limits {
        component_depth: 80,
        ..Limits::DEFAULT
    };
    assert_eq!(
        read_with(&bytes, name(), UnitChoice::Millimetres, &deep)
            .unwrap()
            .0
            .triangles
            .len(),
        4
    );
}

#[test]
fn instancing_past_the_triangle_limit_is_refused_before_placing() {
    // Each level places the one below ten times: 4·10^12 triangles at level 12.
    let mut resources = tetra(0, "model");
    for level in 1..=12 {
        let uses = format!(r#"<component objectid="{}"/>"#, level - 1).repeat(10);
        resources.push_str(&format!(
            r#"<object id="{level}"><components>{uses}</components></object>"#
        ));
    }
    let bytes = single(&model("millimeter", &resources, r#"<item objectid="12"/>"#));
    let e = error(&bytes, &Limits::DEFAULT);
    assert!(e.contains("triangles allowed"), "{e}");
}

#[test]
fn a_zip_bomb_is_refused_before_inflating_and_when_its_header_lies() {
    // 20 MB of spaces deflate to about 20 KB: a thousandfold expansion.
    let padding = " ".repeat(20 << 20);
    let bomb = model(
        "millimeter",
        &format!("{}{padding}", tetra(1, "model")),
        r#"<item objectid="1"/>"#,
    );
    let bytes = single(&bomb);
    assert!(bytes.len() < 100_000, "{}", bytes.len());
    let e = error(&bytes, &Limits::DEFAULT);
    assert!(
        e.contains("part /3D/3dmodel.model: declares") && e.contains("a zip bomb"),
        "{e}"
    );
    // The same with the sizes in its headers rewritten to 100 bytes.
    let e = error(&understate("3D/3dmodel.model", &bytes), &Limits::DEFAULT);
    assert!(e.contains("part /3D/3dmodel.model"), "{e}");
}

/// `bytes` with the uncompressed size of `entry` set to 100 in its local and central headers.
fn understate(entry: &str, bytes: &[u8]) -> Vec<u8> {
    let mut lying = bytes.to_vec();
    let mut patched = 0;
    for (sig, at, name_at) in [(b"PK\x03\x04", 22, 30), (b"PK\x01\x02", 24, 46)] {
        let mut i = 0;
        while let Some(k) = lying[i..].windows(4).position(|w| w == sig) {
            let start = i + k;
            if lying[start + name_at..].starts_with(entry.as_bytes()) {
                lying[start + at..start + at + 4].copy_from_slice(&100u32.to_le_bytes());
                patched += 1;
            }
            i = start + 4;
        }
    }
    assert_eq!(patched, 2);
    lying
}

#[test]
fn parts_larger_than_the_limit_are_refused_declared_or_not() {
    let limits = Limits {
        part_bytes: 2_000,
        ..Limits::DEFAULT
    };
    let padding = " ".repeat(10_000);
    let big = model(
        "millimeter",
        &format!("{}{padding}", tetra(1, "model")),
        r#"<item objectid="1"/>"#,
    );
    let bytes = single(&big);
    let e = error(&bytes, &limits);
    assert!(e.contains("part /3D/3dmodel.model: declares"), "{e}");

    // The same archive with its declared sizes rewritten to 100 bytes: inflating must stop at
    // the limit, not trust the header.
    let lying = understate("3D/3dmodel.model", &bytes);
    let e = error(&lying, &limits);
    assert!(e.contains("part /3D/3dmodel.model"), "{e}");

    let few = Limits {
        parts: 1,
        ..Limits::DEFAULT
    };
    assert!(error(&bytes, &few).contains("2 entries"));
}

#[test]
fn bad_content_is_refused_with_the_part_and_the_place() {
    let bad = |resources: &str, build: &str| {
        error(
            &single(&model("millimeter", resources, build)),
            &Limits::DEFAULT,
        )
    };
    let e = bad(
        &tetra(1, "model").replace(r#"y="1" z="0""#, r#"y="1e999" z="0""#),
        r#"<item objectid="1"/>"#,
    );
    assert!(
        e.contains("part /3D/3dmodel.model")
            && e.contains("object 1, vertex 2")
            && e.contains("1e999"),
        "{e}"
    );
    let e = bad(
        &tetra(1, "model").replace(r#"v3="3"/></triangles>"#, r#"v3="9"/></triangles>"#),
        r#"<item objectid="1"/>"#,
    );
    assert!(e.contains("object 1, triangle 3: vertex index 9"), "{e}");
    let e = bad(&tetra(1, "model"), r#"<item objectid="7"/>"#);
    assert!(e.contains("object 7"), "{e}");
    let e = bad(
        &tetra(1, "model"),
        r#"<item objectid="1" transform="1 0 0"/>"#,
    );
    assert!(e.contains("3 numbers"), "{e}");
    let e = bad(&format!("{}{}", tetra(1, "model"), tetra(1, "model")), "");
    assert!(e.contains("used twice"), "{e}");
    let e = bad(&tetra(1, "model"), "");
    assert!(e.contains("no items"), "{e}");
    let e = error(&single("<model"), &Limits::DEFAULT);
    assert!(e.contains("malformed XML"), "{e}");

    let e = error(b"solid not a zip", &Limits::DEFAULT);
    assert!(e.contains("not a 3MF file"), "{e}");
    let e = error(
        &package(&[("3D/3dmodel.model", b"<model/>".as_slice())]),
        &Limits::DEFAULT,
    );
    assert!(e.contains("part /_rels/.rels is missing"), "{e}");
}
