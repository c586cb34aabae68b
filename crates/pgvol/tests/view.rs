//! The viewer page's payload read back: the surface is the decode's, the field's node values are
//! the file's coefficients (or, above the cap, the field's values at the capped grid's nodes,
//! absent bricks included) within the int16 quantisation step.

use glam::{EulerRot, Quat, Vec3};
use pgvol::view::ViewOptions;
use pgvol::{EncodeOptions, Field, GridSpec, Silent};
use serde_json::Value;

fn sphere_field(res: usize) -> Field {
    let options = EncodeOptions {
        grid: GridSpec::Res(res),
        ..EncodeOptions::default()
    };
    Field::from_mesh(&pgvol::mesh::shapes::octasphere(4), &options, &Silent).unwrap()
}

fn payload(page: &str) -> Value {
    let start = page.find("id=\"pgvol-data\">").unwrap() + "id=\"pgvol-data\">".len();
    let end = start + page[start..].find("</script>").unwrap();
    serde_json::from_str(&page[start..end]).unwrap()
}

/// Standard base64, written here apart from the library's encoder.
fn unbase64(text: &str) -> Vec<u8> {
    let digit = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let mut out = Vec::new();
    for quad in text.as_bytes().chunks(4) {
        let n = quad
            .iter()
            .take_while(|&&c| c != b'=')
            .fold((0u32, 0), |(acc, k), &c| {
                (acc | u32::from(digit(c)) << (18 - 6 * k), k + 1)
            });
        for i in 0..n.1 - 1 {
            out.push((n.0 >> (16 - 8 * i)) as u8);
        }
    }
    out
}

fn dims(v: &Value) -> [usize; 3] {
    [0, 1, 2].map(|a| v[a].as_u64().unwrap() as usize)
}

/// Node values of the page's brick grid, whether each lies in a stored brick, and the largest
/// quantisation error.
fn node_values(field: &Value) -> (Vec<f32>, Vec<bool>, f32) {
    let [nx, ny, nz] = dims(&field["dims"]);
    let [bx, by, _] = dims(&field["bricks"]);
    let states = unbase64(field["states"].as_str().unwrap());
    let values: Vec<i16> = unbase64(field["values"].as_str().unwrap())
        .chunks(2)
        .map(|b| i16::from_le_bytes([b[0], b[1]]))
        .collect();
    let scale = field["scale"].as_f64().unwrap() as f32;
    let (inside, outside) = (
        field["inside"].as_f64().unwrap() as f32,
        field["outside"].as_f64().unwrap() as f32,
    );
    let mut slots = Vec::new();
    let mut next = 0;
    for &s in &states {
        slots.push(if s == 2 {
            next += 1;
            Some(next - 1)
        } else {
            None
        });
    }
    assert_eq!(values.len(), next * 512);
    let mut out = Vec::with_capacity(nx * ny * nz);
    let mut stored = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let b = i / 8 + bx * (j / 8 + by * (k / 8));
                stored.push(slots[b].is_some());
                out.push(match (slots[b], states[b]) {
                    (Some(s), _) => {
                        values[s * 512 + i % 8 + 8 * (j % 8) + 64 * (k % 8)] as f32 * scale
                    }
                    (None, 1) => inside,
                    _ => outside,
                });
            }
        }
    }
    (out, stored, scale / 2.0)
}

#[test]
fn the_page_holds_the_decoded_surface_and_the_files_coefficients() {
    let field = sphere_field(40);
    let page = field.view_html(&ViewOptions::default(), &Silent).unwrap();
    let data = payload(&page);
    let mesh = field
        .to_mesh(&pgvol::DecodeOptions::default(), &Silent)
        .unwrap();
    let surface = &data["surface"];
    assert_eq!(
        surface["triangles"].as_u64().unwrap() as usize,
        mesh.triangles.len()
    );
    let positions = unbase64(surface["positions"].as_str().unwrap());
    let lo = [0, 1, 2].map(|a| surface["lo"][a].as_f64().unwrap() as f32);
    let hi = [0, 1, 2].map(|a| surface["hi"][a].as_f64().unwrap() as f32);
    for (v, p) in mesh.positions.iter().enumerate() {
        for a in 0..3 {
            let q = u16::from_le_bytes([positions[6 * v + 2 * a], positions[6 * v + 2 * a + 1]]);
            let back = lo[a] + f32::from(q) * (hi[a] - lo[a]) / 65535.0;
            assert!((back - p[a]).abs() <= (hi[a] - lo[a]) / 65535.0, "{v} {a}");
        }
    }
    let f = &data["field"];
    assert_eq!(
        (f["source"].as_str(), f["basis"].as_str()),
        (Some("coefficients"), Some("bspline3"))
    );
    let volume = field.volume();
    assert_eq!(dims(&f["dims"]), volume.grid.dims);
    let (values, _, step) = node_values(f);
    let [nx, ny, nz] = volume.grid.dims;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let want = volume.coeffs.get([i, j, k]);
                let got = values[i + nx * (j + ny * k)];
                assert!(
                    (got - want).abs() <= step * 1.01,
                    "node {i},{j},{k}: {got} for {want}"
                );
            }
        }
    }
}

#[test]
fn above_the_cap_the_page_holds_the_fields_values_at_the_coarser_nodes() {
    let field = sphere_field(96);
    let options = ViewOptions {
        max_res: 40,
        ..ViewOptions::default()
    };
    let data = payload(&field.view_html(&options, &Silent).unwrap());
    let f = &data["field"];
    assert_eq!(
        (f["source"].as_str(), f["basis"].as_str()),
        (Some("samples"), Some("trilinear"))
    );
    let [nx, ny, nz] = dims(&f["dims"]);
    assert_eq!(nx.max(ny).max(nz), 40);
    assert_eq!(dims(&data["surface"]["grid"]), [nx, ny, nz]);
    let origin = [0, 1, 2].map(|a| f["origin"][a].as_f64().unwrap() as f32);
    let h = f["spacing"].as_f64().unwrap() as f32;
    let (values, stored, step) = node_values(f);
    let mut absent_checked = 0;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = Vec3::new(origin[0], origin[1], origin[2])
                    + h * Vec3::new(i as f32, j as f32, k as f32);
                let want = field.volume().value(p);
                let n = i + nx * (j + ny * k);
                let got = values[n];
                // Absent bricks hold the side's value: the field there must be that value.
                assert!(
                    (got - want).abs() <= step * 1.01 + 1e-5,
                    "node {i},{j},{k}: {got} for {want}"
                );
                absent_checked += usize::from(!stored[n]);
            }
        }
    }
    assert!(absent_checked > 0);
}

#[test]
fn choices_out_of_range_are_refused_with_what_would_work() {
    let field = sphere_field(24);
    let refuse = |options: ViewOptions, words: &str| {
        let e = field.view_html(&options, &Silent).unwrap_err();
        assert!(e.to_string().contains(words), "{e}");
    };
    refuse(
        ViewOptions {
            max_res: 3,
            ..ViewOptions::default()
        },
        "4 to 1024",
    );
    refuse(
        ViewOptions {
            iso: f32::NAN,
            ..ViewOptions::default()
        },
        "finite",
    );
    refuse(
        ViewOptions {
            iso: 1.0,
            ..ViewOptions::default()
        },
        "exact distance only within",
    );
    refuse(
        ViewOptions {
            iso: 5.0,
            ..ViewOptions::default()
        },
        "reaches beyond the field's grid",
    );
    refuse(
        ViewOptions {
            section: Some((pgvol::Axis::X, 9.0)),
            ..ViewOptions::default()
        },
        "spans x from",
    );
    let mut colours = ViewOptions::default();
    colours.colours.background = "white\"><script>".into();
    refuse(colours, "six hexadecimal digits");
}

#[test]
fn a_basis_the_page_does_not_evaluate_is_sampled_at_its_own_nodes() {
    let options = EncodeOptions {
        grid: GridSpec::Res(32),
        basis: pgvol::Basis::Bspline2,
        ..EncodeOptions::default()
    };
    let field = Field::from_mesh(&pgvol::mesh::shapes::octasphere(4), &options, &Silent).unwrap();
    let data = payload(&field.view_html(&ViewOptions::default(), &Silent).unwrap());
    let f = &data["field"];
    assert_eq!(f["source"].as_str(), Some("samples"));
    assert_eq!(dims(&f["dims"]), field.volume().grid.dims);
    let (values, _, step) = node_values(f);
    let grid = field.volume().grid;
    let [nx, ny, _] = grid.dims;
    for (n, got) in values.iter().enumerate() {
        let (i, j, k) = (n % nx, n / nx % ny, n / (nx * ny));
        let want = field.volume().value(grid.point(i, j, k));
        assert!((got - want).abs() <= step * 1.01 + 1e-5, "node {i},{j},{k}");
    }
}

#[test]
fn a_file_with_sharp_vertices_is_drawn_with_them() {
    // A box turned off the grid axes: its edges are creases.
    let mut cube = pgvol::mesh::shapes::cuboid(Vec3::splat(-0.5), Vec3::splat(0.5));
    let turn = Quat::from_euler(EulerRot::XYZ, 0.5, 0.4, 0.0);
    for p in &mut cube.positions {
        *p = turn * *p;
    }
    let options = EncodeOptions {
        grid: GridSpec::Res(40),
        ..EncodeOptions::default()
    };
    let mut file = pgvol::encode(&cube, &options, &Silent).unwrap().file;
    let sharp = pgvol::sharp::SharpOptions {
        enabled: true,
        ..Default::default()
    };
    let report =
        pgvol::sharp::attach(&mut file, &cube, pgvol::SignMode::Auto, &sharp, &Silent).unwrap();
    assert!(report.stored_cells > 0, "{report:?}");
    let field = Field::from_file(file);
    let data = payload(&field.view_html(&ViewOptions::default(), &Silent).unwrap());
    let dc = pgvol::DecodeOptions {
        method: pgvol::Method::DualContouring,
        ..Default::default()
    };
    let placed = field.to_mesh(&dc, &Silent).unwrap();
    let smooth = field
        .to_mesh(&pgvol::DecodeOptions::default(), &Silent)
        .unwrap();
    assert_ne!(placed.triangles.len(), smooth.triangles.len());
    assert_eq!(
        data["surface"]["triangles"].as_u64().unwrap() as usize,
        placed.triangles.len()
    );
}
