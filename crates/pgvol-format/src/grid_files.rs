//! Dense float32 grids as NRRD (readable by pynrrd and 3D Slicer) or NumPy `.npy`.

use std::path::Path;

use pgvol_core::{write_atomic, FileError};
use pgvol_field::Grid;

/// Raw little-endian bytes of `values`.
fn le_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The NRRD header for a float32 grid with x fastest, node-centred samples in world space.
pub fn nrrd_header(grid: &Grid, comment: &str, fields: &[(&str, String)]) -> String {
    let [nx, ny, nz] = grid.dims;
    let h = grid.spacing;
    let o = grid.origin;
    let mut s = String::from("NRRD0004\n");
    for line in comment.lines() {
        s.push_str(&format!("# {line}\n"));
    }
    s.push_str("type: float\ndimension: 3\n");
    s.push_str(&format!("sizes: {nx} {ny} {nz}\n"));
    s.push_str("space dimension: 3\n");
    s.push_str(&format!(
        "space directions: ({h},0,0) (0,{h},0) (0,0,{h})\n"
    ));
    if grid.offset == glam::DVec3::ZERO {
        s.push_str(&format!("space origin: ({},{},{})\n", o.x, o.y, o.z));
    } else {
        // World coordinates, the frame offset added in f64.
        let o = pgvol_core::frame::to_world(o, grid.offset);
        s.push_str(&format!("space origin: ({},{},{})\n", o.x, o.y, o.z));
    }
    s.push_str("centers: node node node\nkinds: domain domain domain\n");
    s.push_str("endian: little\nencoding: raw\n");
    for (k, v) in fields {
        s.push_str(&format!("{k}:={v}\n"));
    }
    s.push('\n');
    s
}

/// Writes `values` (x fastest) as a raw float32 NRRD file, atomically.
pub fn write_nrrd(
    path: &Path,
    grid: &Grid,
    values: &[f32],
    fields: &[(&str, String)],
) -> Result<(), FileError> {
    let header = nrrd_header(grid, "signed distance, negative inside (pgvol)", fields);
    write_atomic(path, |w| {
        w.write_all(header.as_bytes())?;
        w.write_all(&le_bytes(values))
    })
}

/// Writes `values` as a C-ordered `.npy` array of shape `(nz, ny, nx)`, so `a[k, j, i]` is node
/// `(i, j, k)`.
pub fn write_npy(path: &Path, grid: &Grid, values: &[f32]) -> Result<(), FileError> {
    let [nx, ny, nz] = grid.dims;
    let mut dict =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({nz}, {ny}, {nx}), }}");
    // Magic (6) + version (2) + length (2) + dict + newline must be a multiple of 64.
    let unpadded = 10 + dict.len() + 1;
    dict.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    dict.push('\n');
    write_atomic(path, |w| {
        w.write_all(b"\x93NUMPY\x01\x00")?;
        w.write_all(&(dict.len() as u16).to_le_bytes())?;
        w.write_all(dict.as_bytes())?;
        w.write_all(&le_bytes(values))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn nrrd_and_npy_layouts() {
        let dir = tempfile::tempdir().unwrap();
        let grid = Grid {
            origin: Vec3::new(1.0, 2.0, 3.0),
            spacing: 0.5,
            dims: [2, 3, 4],
            offset: Default::default(),
        };
        let values: Vec<f32> = (0..24).map(|v| v as f32).collect();
        let nrrd = dir.path().join("g.nrrd");
        write_nrrd(&nrrd, &grid, &values, &[("pgvol_res", "4".into())]).unwrap();
        let bytes = std::fs::read(&nrrd).unwrap();
        let text_end = bytes.windows(2).position(|w| w == b"\n\n").unwrap() + 2;
        let header = std::str::from_utf8(&bytes[..text_end]).unwrap();
        assert!(header.contains("sizes: 2 3 4") && header.contains("space origin: (1,2,3)"));
        assert_eq!(bytes.len() - text_end, 24 * 4);
        assert_eq!(
            f32::from_le_bytes(bytes[text_end + 4..text_end + 8].try_into().unwrap()),
            1.0
        );

        let npy = dir.path().join("g.npy");
        write_npy(&npy, &grid, &values).unwrap();
        let bytes = std::fs::read(&npy).unwrap();
        let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + hlen) % 64, 0);
        assert!(std::str::from_utf8(&bytes[10..10 + hlen])
            .unwrap()
            .contains("'shape': (4, 3, 2)"));
        assert_eq!(bytes.len(), 10 + hlen + 96);
    }
}
