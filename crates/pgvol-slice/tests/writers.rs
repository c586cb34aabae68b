//! Layer files: structure of the SVG and CLI output, exact JSON round trip.

use glam::Vec3;
use pgvol_slice::{
    read_slice_json, slice, write_cli, write_slice_json, write_svg, Axis, Layer, SliceOptions,
};

/// A torus cut twice through its tube (two loops per layer: outer and hole) and once above it.
fn layers() -> Vec<Layer> {
    let torus = |p: Vec3| glam::Vec2::new(p.truncate().length() - 0.5, p.z).length() - 0.2;
    let mut o = SliceOptions::new(Axis::Z, 0.15, 0.02);
    o.first = Some(-0.1);
    let layers = slice(&torus, (Vec3::splat(-0.8), Vec3::new(0.8, 0.8, 0.25)), &o).unwrap();
    assert_eq!(
        layers.iter().map(|l| l.loops.len()).collect::<Vec<_>>(),
        [2, 2, 0]
    );
    layers
}

#[test]
fn svg_has_one_group_per_layer() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layers.svg");
    let layers = layers();
    write_svg(&path, &layers).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("<?xml"));
    assert!(text.contains(r#"<svg xmlns="http://www.w3.org/2000/svg""#));
    assert!(text.trim_end().ends_with("</svg>"));
    assert_eq!(text.matches("<g ").count(), 3);
    assert_eq!(text.matches("</g>").count(), 3);
    for (i, l) in layers.iter().enumerate() {
        assert!(text.contains(&format!(r#"id="layer-{i}" data-height="{}""#, l.height)));
    }
    // One path per non-empty layer, one subpath per loop.
    assert_eq!(text.matches("<path ").count(), 2);
    assert_eq!(text.matches('M').count(), 4);
    assert_eq!(text.matches('<').count(), text.matches('>').count());
}

#[test]
fn cli_header_layers_and_polylines() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layers.cli");
    let layers = layers();
    write_cli(&path, &layers, 1.0).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        &lines[..4],
        ["$$HEADERSTART", "$$ASCII", "$$UNITS/1", "$$VERSION/200"]
    );
    assert!(lines.contains(&"$$LAYERS/3"));
    let end = lines.iter().position(|l| *l == "$$HEADEREND").unwrap();
    assert_eq!(lines[end + 1], "$$GEOMETRYSTART");
    assert_eq!(*lines.last().unwrap(), "$$GEOMETRYEND");
    let layer_lines: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.starts_with("$$LAYER/"))
        .collect();
    assert_eq!(
        layer_lines,
        layers
            .iter()
            .map(|l| format!("$$LAYER/{}", l.height))
            .collect::<Vec<_>>()
    );
    let polylines: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.starts_with("$$POLYLINE/"))
        .collect();
    assert_eq!(polylines.len(), 4);
    let loops: Vec<_> = layers.iter().flat_map(|l| &l.loops).collect();
    for (line, lp) in polylines.iter().zip(loops) {
        let f: Vec<f64> = line["$$POLYLINE/".len()..]
            .split(',')
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(f[0], 1.0);
        assert_eq!(f[1], if lp.hole { 0.0 } else { 1.0 });
        let n = f[2] as usize;
        assert_eq!(n, lp.points.len() + 1);
        assert_eq!(f.len(), 3 + 2 * n);
        // Closed: the last point repeats the first.
        assert_eq!(f[3..5], f[f.len() - 2..]);
        assert_eq!(f[3] as f32, lp.points[0][0]);
    }
    assert!(write_cli(&path, &layers, 0.0).is_err());
}

#[test]
fn json_round_trips_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layers.json");
    let layers = layers();
    write_slice_json(&path, &layers).unwrap();
    assert_eq!(read_slice_json(&path).unwrap(), layers);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(v["layers"].as_array().unwrap().len(), 3);
    assert_eq!(
        v["layers"][0]["loops"][0]["points"][0]
            .as_array()
            .unwrap()
            .len(),
        2
    );
}

#[test]
fn json_layers_carry_their_area_and_perimeter() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layers.json");
    write_slice_json(&path, &layers()).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let layer = |i: usize, key: &str| v["layers"][i][key].as_f64().unwrap();
    // The torus's cut through its tube's middle: an annulus between radii 0.3 and 0.7, its
    // boundary two circles (within the slicing's resolution of 0.02).
    let mid = (0..2)
        .min_by(|&a, &b| {
            let h = |i: usize| layer(i, "height").abs();
            h(a).total_cmp(&h(b))
        })
        .unwrap();
    let z = layer(mid, "height");
    let t = (0.04 - z * z).sqrt();
    let (r0, r1) = (0.5 - t, 0.5 + t);
    let pi = std::f64::consts::PI;
    let area = pi * (r1 * r1 - r0 * r0);
    let perimeter = 2.0 * pi * (r0 + r1);
    assert!(
        (layer(mid, "area") - area).abs() < 0.01 * area,
        "area {}",
        layer(mid, "area")
    );
    assert!(
        (layer(mid, "perimeter") - perimeter).abs() < 0.01 * perimeter,
        "perimeter {}",
        layer(mid, "perimeter")
    );
    // The empty layer above the torus.
    assert_eq!((layer(2, "area"), layer(2, "perimeter")), (0.0, 0.0));
}

#[test]
fn writing_into_a_missing_directory_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("missing").join("layers.json");
    let err = write_slice_json(&path, &layers()).unwrap_err();
    assert_eq!(err.path, path);
    assert!(!path.exists());
}
