//! A mesh to a `.pgv` file and back to a mesh through the library.
//!
//! `cargo run --release -p pgvol --example encode_decode -- MESH RES OUT_STEM`
//! writes OUT_STEM.pgv (the field on a RES³ grid) and OUT_STEM.glb (its zero level set).

use std::path::PathBuf;

use pgvol::{DecodeOptions, EncodeOptions, GridSpec, Silent, StorageOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [mesh_path, res, stem] = args.as_slice() else {
        return Err("usage: encode_decode MESH RES OUT_STEM".into());
    };
    let mesh = pgvol::io::read_mesh(mesh_path)?.mesh;

    let options = EncodeOptions {
        grid: GridSpec::Res(res.parse()?),
        ..EncodeOptions::default()
    };
    let encoded = pgvol::encode(&mesh, &options, &Silent)?;
    let pgv_path = PathBuf::from(format!("{stem}.pgv"));
    pgvol::io::write_pgv(&pgv_path, &encoded.file, &StorageOptions::default())?;

    let file = pgvol::io::read_pgv(&pgv_path)?;
    let surface = pgvol::Field::from_volume(file.volume.clone())
        .to_mesh(&DecodeOptions::default(), &Silent)?;
    let glb_path = PathBuf::from(format!("{stem}.glb"));
    pgvol::io::write_mesh(&glb_path, &surface)?;

    for path in [mesh_path.as_ref(), pgv_path.as_path(), glb_path.as_path()] {
        println!(
            "{:>12} bytes  {}",
            std::fs::metadata(path)?.len(),
            path.display()
        );
    }
    println!(
        "{} triangles in, {} out",
        mesh.triangles.len(),
        surface.triangles.len()
    );
    Ok(())
}
