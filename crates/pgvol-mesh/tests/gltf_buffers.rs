//! External glTF buffers: only regular files inside the glTF's folder are read, and only the
//! bytes they declare.

use std::path::Path;

/// One triangle whose positions live in the external buffer `uri` of `byte_length` bytes.
fn gltf_with_buffer(uri: &str, byte_length: usize) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},
"buffers":[{{"uri":"{uri}","byteLength":{byte_length}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
  "min":[0,0,0],"max":[1,1,0]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#
    )
}

fn triangle_bytes() -> Vec<u8> {
    [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

fn read_with(dir: &Path, uri: &str, byte_length: usize) -> Result<pgvol_mesh::Mesh, String> {
    let path = dir.join("mesh.gltf");
    std::fs::write(&path, gltf_with_buffer(uri, byte_length)).unwrap();
    pgvol_mesh::read(&path).map_err(|e| e.to_string())
}

#[test]
fn a_buffer_file_beside_the_gltf_is_read() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tri.bin"), triangle_bytes()).unwrap();
    let mesh = read_with(dir.path(), "tri.bin", 36).unwrap();
    assert_eq!(mesh.triangles.len(), 1);
    assert_eq!(mesh.positions.len(), 3);
}

#[test]
fn absolute_and_escaping_paths_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let inner = dir.path().join("inner");
    std::fs::create_dir(&inner).unwrap();
    std::fs::write(dir.path().join("tri.bin"), triangle_bytes()).unwrap();
    for uri in ["/etc/passwd", "../tri.bin", "./../tri.bin"] {
        let e = read_with(&inner, uri, 36).unwrap_err();
        assert!(e.contains("inside the glTF's folder"), "{uri}: {e}");
    }
}

#[cfg(unix)]
#[test]
fn links_out_of_the_folder_and_devices_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.bin")).unwrap();
    let e = read_with(dir.path(), "zero.bin", 36).unwrap_err();
    assert!(e.contains("inside the glTF's folder"), "{e}");
    let outside = tempfile::tempdir().unwrap();
    std::fs::write(outside.path().join("tri.bin"), triangle_bytes()).unwrap();
    std::os::unix::fs::symlink(outside.path().join("tri.bin"), dir.path().join("link.bin"))
        .unwrap();
    let e = read_with(dir.path(), "link.bin", 36).unwrap_err();
    assert!(e.contains("inside the glTF's folder"), "{e}");
}

#[test]
fn a_file_shorter_than_its_declared_length_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tri.bin"), triangle_bytes()).unwrap();
    let e = read_with(dir.path(), "tri.bin", 1 << 40).unwrap_err();
    assert!(e.contains("declares"), "{e}");
}
