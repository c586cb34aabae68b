//! The `.vdb` writer against the layout of OpenVDB's file format (file version 224): a sphere
//! level set is written, then walked here byte by byte as `io::File`, `RootNode`,
//! `InternalNode` and `LeafNode` read it, and every voxel's value is checked.

use std::collections::HashMap;
use std::io::Read;

use pgvol_format::vdb::write::{write_level_set, LevelSetGrid, VdbCompression, VdbLeafValues};
use pgvol_format::vdb::{UniformScaleTranslate, LEAF_VOXELS};

const CENTRE: [f64; 3] = [64.0, 64.0, 64.0];
const RADIUS: f64 = 120.0;
const VOXEL: f64 = 0.1;
const BAND: f32 = 0.3;

/// The sphere's signed distance at voxel `ijk`, in world units.
fn sphere(ijk: [i32; 3]) -> f32 {
    let d: f64 = (0..3)
        .map(|a| (ijk[a] as f64 - CENTRE[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    ((d - RADIUS) * VOXEL) as f32
}

/// Leaf origins over the sphere's box, and each leaf's values: tiles where a leaf is clearly
/// on one side, samples near the surface.
fn sphere_leaves() -> Vec<[i32; 3]> {
    let lo = ((CENTRE[0] - RADIUS - 8.0) / 8.0).floor() as i32 * 8;
    let hi = ((CENTRE[0] + RADIUS + 8.0) / 8.0).ceil() as i32 * 8;
    let mut out = Vec::new();
    for x in (lo..hi).step_by(8) {
        for y in (lo..hi).step_by(8) {
            for z in (lo..hi).step_by(8) {
                out.push([x, y, z]);
            }
        }
    }
    out
}

fn leaf_values(o: [i32; 3]) -> VdbLeafValues {
    let centre = o.map(|c| c as f64 + 3.5);
    let d = (0..3)
        .map(|a| (centre[a] - CENTRE[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    let half_diagonal = 3.5 * 3f64.sqrt();
    let band = BAND as f64 / VOXEL;
    if d + half_diagonal < RADIUS - band - 1.0 {
        return VdbLeafValues::Inside;
    }
    if d - half_diagonal > RADIUS + band + 1.0 {
        return VdbLeafValues::Outside;
    }
    let mut values = Box::new([0f32; LEAF_VOXELS]);
    for (n, v) in values.iter_mut().enumerate() {
        *v = sphere([
            o[0] + (n >> 6) as i32,
            o[1] + (n >> 3 & 7) as i32,
            o[2] + (n & 7) as i32,
        ]);
    }
    VdbLeafValues::Sampled(values)
}

/// A cursor over the file's bytes.
struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    fn take(&mut self, n: usize) -> &'a [u8] {
        let s = &self.data[self.at..self.at + n];
        self.at += n;
        s
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let n = self.u32() as usize;
        String::from_utf8(self.take(n).to_vec()).unwrap()
    }
    fn coord(&mut self) -> [i32; 3] {
        [self.i32(), self.i32(), self.i32()]
    }
    fn mask(&mut self, bits: usize) -> Vec<bool> {
        let words: Vec<u64> = (0..bits / 64)
            .map(|_| u64::from_le_bytes(self.take(8).try_into().unwrap()))
            .collect();
        (0..bits)
            .map(|n| words[n / 64] >> (n % 64) & 1 == 1)
            .collect()
    }
}

struct Settings {
    half: bool,
    zip: bool,
    background: f32,
}

/// `io::readCompressedValues` with active-mask compression: the tag, the selection mask,
/// then the active values (zipped or raw, half or full floats).
fn read_values(b: &mut Bytes, s: &Settings, active: &[bool]) -> Vec<f32> {
    let tag = b.u8();
    assert!([0, 1, 3].contains(&tag), "unexpected chunk tag {tag}");
    let selection = if tag == 3 {
        b.mask(active.len())
    } else {
        vec![false; active.len()]
    };
    let count = active.iter().filter(|&&a| a).count();
    let width = if s.half { 2 } else { 4 };
    let raw: Vec<u8> = if s.half && count == 0 {
        Vec::new()
    } else if s.zip {
        let n = b.i64();
        if n <= 0 {
            b.take((-n) as usize).to_vec()
        } else {
            let mut out = Vec::new();
            flate2::read::ZlibDecoder::new(b.take(n as usize))
                .read_to_end(&mut out)
                .unwrap();
            out
        }
    } else {
        b.take(count * width).to_vec()
    };
    assert_eq!(raw.len(), count * width);
    let mut stored = raw.chunks(width).map(|c| {
        if s.half {
            half::f16::from_le_bytes([c[0], c[1]]).to_f32()
        } else {
            f32::from_le_bytes(c.try_into().unwrap())
        }
    });
    let inactive0 = if tag == 0 {
        s.background
    } else {
        -s.background
    };
    (0..active.len())
        .map(|n| match (active[n], selection[n]) {
            (true, _) => stored.next().unwrap(),
            (false, true) => s.background,
            (false, false) => inactive0,
        })
        .collect()
}

/// What the tree holds: voxel values of the leaves (with their active state) and tile values by
/// (origin, edge).
#[derive(Default)]
struct Tree {
    voxels: HashMap<[i32; 3], (f32, bool)>,
    tiles: HashMap<([i32; 3], i32), f32>,
}

impl Tree {
    fn value(&self, ijk: [i32; 3], background: f32) -> (f32, bool) {
        if let Some(&v) = self.voxels.get(&ijk) {
            return v;
        }
        for edge in [8, 128] {
            if let Some(&v) = self
                .tiles
                .get(&(ijk.map(|c| c.div_euclid(edge) * edge), edge))
            {
                return (v, false);
            }
        }
        (background, false)
    }
}

fn child_origin(parent: [i32; 3], log2: u32, child_span: i32, n: usize) -> [i32; 3] {
    let dim = 1usize << log2;
    let xyz = [n >> (2 * log2), (n >> log2) & (dim - 1), n & (dim - 1)];
    std::array::from_fn(|a| parent[a] + xyz[a] as i32 * child_span)
}

/// Parses the whole file as OpenVDB does; returns the settings and the tree.
fn parse(data: &[u8], name: &str) -> (Settings, UniformScaleTranslate, Tree) {
    let mut b = Bytes { data, at: 0 };
    assert_eq!(b.take(8), b" BDV\0\0\0\0", "magic");
    assert_eq!(b.u32(), 224, "file version");
    assert_eq!((b.u32(), b.u32()), (10, 0), "library version");
    assert_eq!(b.u8(), 1, "grid offsets present");
    let uuid = String::from_utf8(b.take(36).to_vec()).unwrap();
    assert_eq!(uuid.matches('-').count(), 4, "{uuid}");
    assert_eq!(b.i32(), 0, "file metadata count");
    assert_eq!(b.i32(), 1, "grid count");
    assert_eq!(b.string(), name);
    let grid_type = b.string();
    let half = grid_type.ends_with("_HalfFloat");
    assert_eq!(grid_type.trim_end_matches("_HalfFloat"), "Tree_float_5_4_3");
    assert_eq!(b.string(), "", "instance parent");
    let (grid_pos, block_pos, end_pos) = (b.i64(), b.i64(), b.i64());
    assert_eq!(grid_pos as usize, b.at);
    assert_eq!(end_pos as usize, data.len());
    let compression = b.u32();
    assert_eq!(compression & 0x2, 0x2, "active-mask compression");
    assert_eq!(compression & 0x4, 0, "no blosc");
    let mut meta = HashMap::new();
    for _ in 0..b.i32() {
        let key = b.string();
        let kind = b.string();
        let size = b.u32() as usize;
        meta.insert(key, (kind, b.take(size).to_vec()));
    }
    assert_eq!(meta["class"], ("string".into(), b"level set".to_vec()));
    assert_eq!(meta["name"], ("string".into(), name.as_bytes().to_vec()));
    assert_eq!(meta.contains_key("is_saved_as_half_float"), half);
    assert_eq!(b.string(), "UniformScaleTranslateMap");
    let mut rows = [[0f64; 3]; 6];
    for row in &mut rows {
        *row = [b.f64(), b.f64(), b.f64()];
    }
    let s = rows[1][0];
    assert_eq!(rows[2], [s; 3], "voxel size");
    assert_eq!(rows[3], [1.0 / s; 3]);
    assert_eq!(rows[4], [1.0 / (s * s); 3]);
    assert_eq!(rows[5], [0.5 / s; 3]);
    let transform = UniformScaleTranslate {
        voxel_size: s,
        translation: rows[0],
    };

    assert_eq!(b.i32(), 1, "buffer count");
    let settings = Settings {
        half,
        zip: compression & 0x1 != 0,
        background: b.f32(),
    };
    let (tiles, children) = (b.u32(), b.u32());
    assert_eq!(tiles, 0);
    let mut tree = Tree::default();
    // Leaves in the order their buffers follow, with their active masks.
    let mut leaves: Vec<([i32; 3], Vec<bool>)> = Vec::new();
    let mut last_root: Option<[i32; 3]> = None;
    for _ in 0..children {
        let upper = b.coord();
        assert!(upper.iter().all(|c| c.rem_euclid(4096) == 0), "{upper:?}");
        assert!(last_root < Some(upper), "root children in coordinate order");
        last_root = Some(upper);
        let upper_children = b.mask(32768);
        let upper_active = b.mask(32768);
        assert!(
            !upper_active.iter().any(|&a| a),
            "level-set tiles are inactive"
        );
        let values = read_values(&mut b, &settings, &upper_active);
        for n in 0..32768 {
            if !upper_children[n] && values[n] != settings.background {
                assert_eq!(values[n], -settings.background);
                tree.tiles
                    .insert((child_origin(upper, 5, 128, n), 128), values[n]);
            }
        }
        for n in (0..32768).filter(|&n| upper_children[n]) {
            let lower = child_origin(upper, 5, 128, n);
            let lower_children = b.mask(4096);
            let lower_active = b.mask(4096);
            assert!(!lower_active.iter().any(|&a| a));
            let values = read_values(&mut b, &settings, &lower_active);
            for m in 0..4096 {
                if !lower_children[m] && values[m] != settings.background {
                    assert_eq!(values[m], -settings.background);
                    tree.tiles
                        .insert((child_origin(lower, 4, 8, m), 8), values[m]);
                }
            }
            for m in (0..4096).filter(|&m| lower_children[m]) {
                leaves.push((child_origin(lower, 4, 8, m), b.mask(512)));
            }
        }
    }
    assert_eq!(
        b.at, block_pos as usize,
        "buffers start where the descriptor says"
    );
    for (origin, topology_mask) in leaves {
        let active = b.mask(512);
        assert_eq!(active, topology_mask);
        let values = read_values(&mut b, &settings, &active);
        for n in 0..512 {
            let ijk = child_origin(origin, 3, 1, n);
            tree.voxels.insert(ijk, (values[n], active[n]));
        }
    }
    assert_eq!(b.at, data.len());
    (settings, transform, tree)
}

fn write(half: bool, compression: VdbCompression) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sphere.vdb");
    let grid = LevelSetGrid {
        name: "surface",
        transform: UniformScaleTranslate {
            voxel_size: VOXEL,
            translation: [1.0, -2.0, 3.5],
        },
        background: BAND,
        half,
        compression,
    };
    write_level_set(&path, &grid, &sphere_leaves(), leaf_values).unwrap();
    std::fs::read(path).unwrap()
}

#[test]
fn sphere_reads_back_voxel_by_voxel() {
    for half in [false, true] {
        for compression in [VdbCompression::None, VdbCompression::Zip] {
            let data = write(half, compression);
            let (s, transform, tree) = parse(&data, "surface");
            assert_eq!(transform.voxel_size, VOXEL);
            assert_eq!(transform.translation, [1.0, -2.0, 3.5]);
            let tolerance = if half { 2e-4 } else { 0.0 };
            assert!((s.background - BAND).abs() <= tolerance);
            // The sphere's inside holds a whole lower node (128³ voxels from the origin): it
            // is one tile of the upper node, not 4096 leaf tiles.
            assert_eq!(tree.tiles.get(&([0, 0, 0], 128)), Some(&-s.background));
            assert!(tree.voxels.keys().any(|v| v.iter().any(|&c| c < 0)));
            let mut active = 0;
            let mut check = |ijk: [i32; 3]| {
                let f = sphere(ijk);
                let (v, on) = tree.value(ijk, s.background);
                if f.abs() < s.background - 1e-6 {
                    assert!(on, "{ijk:?} lies in the band");
                    assert!((v - f).abs() <= tolerance * 2.0, "{ijk:?}: {v} for {f}");
                    active += 1;
                } else if f.abs() > s.background + 1e-6 {
                    assert!(!on, "{ijk:?} lies beyond the band");
                    assert_eq!(v, s.background.copysign(f), "{ijk:?}: {v} for {f}");
                }
            };
            for &ijk in tree.voxels.keys() {
                check(ijk);
            }
            // A lattice over the whole box, tiles and background included.
            for x in (-70..200).step_by(7) {
                for y in (-70..200).step_by(5) {
                    for z in (-70..200).step_by(3) {
                        check([x, y, z]);
                    }
                }
            }
            // About the band's shell: 4π R² · 2 · 3 voxels.
            assert!(active > 500_000, "{active} active voxels");
        }
    }
}

#[test]
fn zip_is_smaller_and_half_smaller_still() {
    let zip = write(false, VdbCompression::Zip).len();
    let raw = write(false, VdbCompression::None).len();
    let half = write(true, VdbCompression::Zip).len();
    assert!(zip < raw, "{zip} >= {raw}");
    assert!(half < zip * 7 / 10, "{half} vs {zip}");
}

#[test]
fn bad_settings_are_refused_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.vdb");
    let good = LevelSetGrid {
        name: "surface",
        transform: UniformScaleTranslate {
            voxel_size: 0.1,
            translation: [0.0; 3],
        },
        background: 0.3,
        half: false,
        compression: VdbCompression::Zip,
    };
    let cases = [
        LevelSetGrid {
            background: 0.0,
            ..good
        },
        LevelSetGrid {
            transform: UniformScaleTranslate {
                voxel_size: f64::NAN,
                translation: [0.0; 3],
            },
            ..good
        },
        LevelSetGrid { name: "", ..good },
    ];
    for grid in cases {
        let e = write_level_set(&path, &grid, &[[0, 0, 0]], leaf_values).unwrap_err();
        assert!(e.to_string().contains("bad.vdb"), "{e}");
        assert!(!path.exists());
    }
    let e = write_level_set(&path, &good, &[[3, 0, 0]], leaf_values).unwrap_err();
    assert!(e.to_string().contains("multiple of 8"), "{e}");
    let inside = |_| VdbLeafValues::Inside;
    let e = write_level_set(&path, &good, &[[8, 0, 0], [8, 0, 0]], inside).unwrap_err();
    assert!(e.to_string().contains("listed twice"), "{e}");
    assert!(!path.exists());
}
