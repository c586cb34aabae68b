//! glTF 2.0 (JSON `.gltf` and binary `.glb`). Reading works on the raw JSON document with every
//! index, offset and length checked here, because the `gltf` crate's own accessors assume a
//! validated file and may panic on hostile ones.

use std::borrow::Cow;
use std::io::{self, Read, Write};
use std::path::Path;
use std::rc::Rc;

use glam::{DMat4, DQuat, DVec3, Vec3};
use gltf::json::accessor::{ComponentType, GenericComponentType, Type};
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::{Checked, USize64};
use gltf::json::{self, Root};

use crate::{Mesh, MeshError};
use pgvol_core::base64;

/// Reads glTF or GLB from memory. External buffers are looked up in `base_dir`; without one
/// they are reported as unreadable.
pub(crate) fn read(
    bytes: &[u8],
    name: &Path,
    binary: bool,
    base_dir: Option<&Path>,
) -> Result<Mesh, MeshError> {
    let err = |problem: String| MeshError::new(name, problem);
    let (json_bytes, bin) = if bytes.starts_with(b"glTF") {
        split_glb(bytes).map_err(err)?
    } else if binary {
        return Err(err("not a GLB file (missing 'glTF' magic)".into()));
    } else {
        (bytes, None)
    };
    let root = Root::from_slice(json_bytes).map_err(|e| err(format!("invalid glTF JSON: {e}")))?;
    let mut reader = Reader {
        root: &root,
        bin,
        base_dir,
        buffers: vec![None; root.buffers.len()],
    };
    reader.mesh().map_err(err)
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let u32_at = |o: usize| -> Option<u32> {
        Some(u32::from_le_bytes(bytes.get(o..o + 4)?.try_into().ok()?))
    };
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(format!(
            "truncated GLB: {} bytes, the header alone needs 12",
            bytes.len()
        ));
    };
    if version != 2 {
        return Err(format!("unsupported GLB version {version} (expected 2)"));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(format!(
            "truncated GLB: header says {length} bytes, file holds {}",
            bytes.len()
        ));
    }
    if length < bytes.len() {
        // The header's length is the whole file's; more bytes mean a damaged or joined file.
        return Err(format!(
            "GLB header says {length} bytes, but the file has {} ({} more); a GLB file ends \
             where its header's length says",
            bytes.len(),
            bytes.len() - length
        ));
    }
    let data = bytes;
    let mut pos = 12;
    let mut chunks = Vec::new();
    while pos < data.len() && chunks.len() < 2 {
        let header = data
            .get(pos..pos + 8)
            .ok_or("truncated GLB: chunk header cut off")?;
        let len = u32::from_le_bytes([header[0], header[1], header[2], header[3]]) as usize;
        let kind = [header[4], header[5], header[6], header[7]];
        let body = data
            .get(pos + 8..)
            .and_then(|d| d.get(..len))
            .ok_or_else(|| {
                format!(
                    "truncated GLB: chunk '{}' says {len} bytes, only {} remain",
                    String::from_utf8_lossy(&kind).trim_end_matches('\0'),
                    data.len() - pos - 8
                )
            })?;
        chunks.push((kind, body));
        pos += 8 + len;
    }
    match chunks.as_slice() {
        [([b'J', b'S', b'O', b'N'], json), rest @ ..] => {
            let bin = rest.first().filter(|(k, _)| k == b"BIN\0").map(|c| c.1);
            Ok((json, bin))
        }
        _ => Err("GLB does not start with a JSON chunk".into()),
    }
}

struct Reader<'a> {
    root: &'a Root,
    bin: Option<&'a [u8]>,
    base_dir: Option<&'a Path>,
    /// Resolved buffers, shared so each is decoded or read from disk once.
    buffers: Vec<Option<Rc<[u8]>>>,
}

/// One mesh placed in the world by a node.
struct Instance {
    mesh: usize,
    world: DMat4,
}

impl<'a> Reader<'a> {
    fn mesh(&mut self) -> Result<Mesh, String> {
        let instances = self.instances()?;
        // World positions in f64: node translations may put the mesh far from the origin.
        let mut out = (Vec::new(), Vec::new());
        let mut other_modes = 0;
        for inst in &instances {
            let mesh = self.root.meshes.get(inst.mesh).ok_or_else(|| {
                format!("a node refers to mesh {} which does not exist", inst.mesh)
            })?;
            // A mirroring transform turns counter-clockwise faces clockwise; undo that.
            let flip = inst.world.determinant() < 0.0;
            for (p, prim) in mesh.primitives.iter().enumerate() {
                if !matches!(prim.mode, Checked::Valid(Mode::Triangles)) {
                    other_modes += 1;
                    continue;
                }
                let at = |e: String| format!("mesh {} primitive {p}: {e}", inst.mesh);
                self.primitive(prim, inst.world, flip, &mut out)
                    .map_err(at)?;
            }
        }
        if out.1.is_empty() {
            return Err(if other_modes > 0 {
                format!(
                    "no triangles ({other_modes} primitives use points or lines or strips, \
                     which are skipped)"
                )
            } else {
                "no triangles".into()
            });
        }
        Ok(Mesh::from_world(&out.0, out.1))
    }

    /// Meshes with their world transforms: the default scene, else every scene, else every
    /// root node, else (no nodes at all) every mesh untransformed.
    fn instances(&self) -> Result<Vec<Instance>, String> {
        let root = self.root;
        if root.nodes.is_empty() {
            return Ok((0..root.meshes.len())
                .map(|mesh| Instance {
                    mesh,
                    world: DMat4::IDENTITY,
                })
                .collect());
        }
        let scenes: Vec<Vec<usize>> = match root.scene {
            Some(s) => {
                let scene = root
                    .scenes
                    .get(s.value())
                    .ok_or_else(|| format!("default scene {} does not exist", s.value()))?;
                vec![scene.nodes.iter().map(|n| n.value()).collect()]
            }
            None if !root.scenes.is_empty() => root
                .scenes
                .iter()
                .map(|s| s.nodes.iter().map(|n| n.value()).collect())
                .collect(),
            None => {
                let mut is_child = vec![false; root.nodes.len()];
                for node in &root.nodes {
                    for c in node.children.iter().flatten() {
                        if let Some(flag) = is_child.get_mut(c.value()) {
                            *flag = true;
                        }
                    }
                }
                vec![(0..root.nodes.len()).filter(|&n| !is_child[n]).collect()]
            }
        };
        let mut out = Vec::new();
        for roots in scenes {
            // Each node may be visited once per scene; a second visit means a cycle.
            let mut visited = vec![false; root.nodes.len()];
            let mut stack: Vec<(usize, DMat4)> = roots
                .into_iter()
                .rev()
                .map(|n| (n, DMat4::IDENTITY))
                .collect();
            while let Some((n, parent)) = stack.pop() {
                let node = root
                    .nodes
                    .get(n)
                    .ok_or_else(|| format!("node {n} does not exist"))?;
                if std::mem::replace(&mut visited[n], true) {
                    return Err(format!(
                        "node {n} is reached twice (a cycle or a node with two parents)"
                    ));
                }
                let world = parent * local_transform(node);
                if !world.is_finite() {
                    return Err(format!("node {n} has a non-finite transform"));
                }
                if let Some(m) = node.mesh {
                    out.push(Instance {
                        mesh: m.value(),
                        world,
                    });
                }
                for c in node.children.iter().flatten().rev() {
                    stack.push((c.value(), world));
                }
            }
        }
        Ok(out)
    }

    fn primitive(
        &mut self,
        prim: &json::mesh::Primitive,
        world: DMat4,
        flip: bool,
        out: &mut (Vec<DVec3>, Vec<[u32; 3]>),
    ) -> Result<(), String> {
        let pos_acc = prim
            .attributes
            .get(&Checked::Valid(Semantic::Positions))
            .ok_or("no POSITION attribute")?
            .value();
        let coords = self.accessor(pos_acc, Type::Vec3, "POSITION")?;
        let n = coords.len() / 3;
        let indices = match prim.indices {
            Some(i) => {
                let v = self.accessor(i.value(), Type::Scalar, "indices")?;
                v.into_iter()
                    .map(|x| {
                        let i = x as u64;
                        if x < 0.0 || x.fract() != 0.0 || i >= n as u64 {
                            Err(format!(
                                "index {x} is out of range (POSITION has {n} vertices)"
                            ))
                        } else {
                            Ok(i as u32)
                        }
                    })
                    .collect::<Result<Vec<u32>, String>>()?
            }
            None => (0..n as u32).collect(),
        };
        if indices.len() % 3 != 0 {
            return Err(format!(
                "{} indices is not a multiple of 3 (TRIANGLES mode)",
                indices.len()
            ));
        }
        let base = out.0.len();
        if base + n > u32::MAX as usize {
            return Err("more than 2^32 vertices in total".into());
        }
        let base = base as u32;
        out.0.extend(
            coords
                .chunks_exact(3)
                .map(|c| world.transform_point3(DVec3::new(c[0], c[1], c[2]))),
        );
        out.1.extend(indices.chunks_exact(3).map(|t| {
            let [a, b, c] = [t[0] + base, t[1] + base, t[2] + base];
            if flip {
                [a, c, b]
            } else {
                [a, b, c]
            }
        }));
        Ok(())
    }

    /// The components of accessor `index`, in order, as f64 (exact for every glTF component
    /// type). Checks type, and that every element lies inside its view and buffer.
    fn accessor(&mut self, index: usize, want: Type, role: &str) -> Result<Vec<f64>, String> {
        let root = self.root;
        let acc = root
            .accessors
            .get(index)
            .ok_or_else(|| format!("{role} accessor {index} does not exist"))?;
        let what = format!("{role} accessor {index}");
        if acc.type_ != Checked::Valid(want) {
            return Err(format!(
                "{what} has type {:?}, expected {want:?}",
                acc.type_
            ));
        }
        let Checked::Valid(GenericComponentType(ct)) = acc.component_type else {
            return Err(format!("{what} has an invalid component type"));
        };
        let allowed = if want == Type::Scalar {
            matches!(
                ct,
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32
            )
        } else {
            // Float, or the integer forms KHR_mesh_quantization allows.
            !matches!(ct, ComponentType::U32)
        };
        if !allowed {
            return Err(format!("{what} has unsupported component type {ct:?}"));
        }
        if acc.sparse.is_some() {
            return Err(format!("{what} is sparse, which is not supported"));
        }
        let count = acc.count.0;
        if count == 0 {
            return Ok(Vec::new());
        }
        let view_index = acc
            .buffer_view
            .ok_or_else(|| format!("{what} has no bufferView (not supported)"))?
            .value();
        let view = root.buffer_views.get(view_index).ok_or_else(|| {
            format!("{what} refers to buffer view {view_index} which does not exist")
        })?;
        let comps = if want == Type::Scalar { 1 } else { 3 };
        let comp_size = ct.size();
        let elem = (comps * comp_size) as u64;
        let stride = view.byte_stride.map_or(elem, |s| s.0 as u64);
        if stride < elem {
            return Err(format!(
                "buffer view {view_index} has byteStride {stride}, smaller than the {elem}-byte \
                 elements of {what}"
            ));
        }
        let view_offset = view.byte_offset.map_or(0, |o| o.0);
        let view_len = view.byte_length.0;
        let acc_offset = acc.byte_offset.map_or(0, |o| o.0);
        let needed = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(elem))
            .and_then(|x| x.checked_add(acc_offset));
        if needed.is_none_or(|needed| needed > view_len) {
            return Err(format!(
                "{what} ({count} elements) reads past the end of buffer view {view_index} \
                 ({view_len} bytes)"
            ));
        }
        let buffer_index = view.buffer.value();
        let data = self.buffer(buffer_index)?;
        let view_end = view_offset.checked_add(view_len);
        if view_end.is_none_or(|end| end > data.len() as u64) {
            return Err(format!(
                "buffer view {view_index} (offset {view_offset}, {view_len} bytes) lies outside \
                 buffer {buffer_index} ({} bytes)",
                data.len()
            ));
        }
        // All of these fit in usize now: they are bounded by the buffer's length.
        let start = (view_offset + acc_offset) as usize;
        let (stride, count) = (stride as usize, count as usize);
        let normalized = acc.normalized;
        let mut out = Vec::with_capacity(count * comps);
        for e in 0..count {
            let at = start + e * stride;
            for c in 0..comps {
                let o = at + c * comp_size;
                out.push(component(&data[o..o + comp_size], ct, normalized));
            }
        }
        Ok(out)
    }

    fn buffer(&mut self, index: usize) -> Result<Rc<[u8]>, String> {
        let buffer = self
            .root
            .buffers
            .get(index)
            .ok_or_else(|| format!("buffer {index} does not exist"))?;
        if let Some(Some(data)) = self.buffers.get(index) {
            return Ok(data.clone());
        }
        let data: Rc<[u8]> = match buffer.uri.as_deref() {
            None if index == 0 => self
                .bin
                .ok_or("buffer 0 has no uri and the file has no GLB BIN chunk")?
                .into(),
            None => return Err(format!("buffer {index} has no uri")),
            Some(uri) if uri.starts_with("data:") => decode_data_uri(uri)
                .map_err(|e| format!("buffer {index}: {e}"))?
                .into(),
            Some(uri) => self.external(index, uri)?.into(),
        };
        self.buffers[index] = Some(data.clone());
        Ok(data)
    }

    /// The bytes of an external buffer file. Only a regular file inside the glTF's own folder
    /// is read (no absolute paths, no `..` out of it, no devices or pipes), and only the
    /// `byteLength` bytes the buffer declares, after checking the file holds them.
    fn external(&self, index: usize, uri: &str) -> Result<Vec<u8>, String> {
        let Some(dir) = self.base_dir else {
            return Err(format!(
                "buffer {index} refers to external file '{uri}', which cannot be resolved when \
                 reading from memory"
            ));
        };
        if uri.contains("://") {
            return Err(format!("buffer {index} uri '{uri}' is not a local file"));
        }
        let rel = percent_decode(uri)
            .ok_or_else(|| format!("buffer {index} uri '{uri}' is not valid"))?;
        let outside = || {
            format!("buffer {index} uri '{uri}' is not a relative path inside the glTF's folder")
        };
        let rel_path = Path::new(&rel);
        if rel_path.is_absolute()
            || rel_path
                .components()
                .any(|c| !matches!(c, std::path::Component::Normal(_)))
        {
            return Err(outside());
        }
        let path = dir.join(rel_path);
        let cannot =
            |e: io::Error| format!("cannot read buffer {index} file '{}': {e}", path.display());
        // A symbolic link may still lead out of the folder: compare the resolved paths.
        let resolved = path.canonicalize().map_err(cannot)?;
        let folder = dir.canonicalize().map_err(cannot)?;
        if !resolved.starts_with(&folder) {
            return Err(outside());
        }
        let meta = std::fs::metadata(&resolved).map_err(cannot)?;
        if !meta.is_file() {
            return Err(format!(
                "buffer {index} file '{}' is not a regular file",
                path.display()
            ));
        }
        let declared = self.root.buffers[index].byte_length.0;
        if meta.len() < declared {
            return Err(format!(
                "buffer {index} declares {declared} bytes but its file '{}' holds {}",
                path.display(),
                meta.len()
            ));
        }
        let mut data = Vec::new();
        std::fs::File::open(&resolved)
            .and_then(|f| f.take(declared).read_to_end(&mut data))
            .map_err(cannot)?;
        Ok(data)
    }
}

fn component(raw: &[u8], ct: ComponentType, normalized: bool) -> f64 {
    let v = match ct {
        ComponentType::I8 => f64::from(raw[0] as i8),
        ComponentType::U8 => f64::from(raw[0]),
        ComponentType::I16 => f64::from(i16::from_le_bytes([raw[0], raw[1]])),
        ComponentType::U16 => f64::from(u16::from_le_bytes([raw[0], raw[1]])),
        ComponentType::U32 => f64::from(u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]])),
        ComponentType::F32 => f64::from(f32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]])),
    };
    if !normalized {
        return v;
    }
    match ct {
        ComponentType::I8 => (v / 127.0).max(-1.0),
        ComponentType::U8 => v / 255.0,
        ComponentType::I16 => (v / 32767.0).max(-1.0),
        ComponentType::U16 => v / 65535.0,
        _ => v,
    }
}

fn local_transform(node: &json::Node) -> DMat4 {
    if let Some(m) = node.matrix {
        return DMat4::from_cols_array(&m.map(f64::from));
    }
    let t = DVec3::from_array(node.translation.unwrap_or([0.0; 3]).map(f64::from));
    let s = DVec3::from_array(node.scale.unwrap_or([1.0; 3]).map(f64::from));
    let [x, y, z, w] = node
        .rotation
        .map_or([0.0, 0.0, 0.0, 1.0], |q| q.0)
        .map(f64::from);
    let q = DQuat::from_xyzw(x, y, z, w);
    // The spec demands unit quaternions; normalise slightly-off ones, ignore zero ones.
    let q = if q.length() > 0.0 && q.is_finite() {
        q.normalize()
    } else {
        DQuat::IDENTITY
    };
    DMat4::from_scale_rotation_translation(s, q, t)
}

/// The node holding the mesh, under parents translating it by `offset` when that is not zero.
/// glTF translations are f32, so the offset is split in two: its f32 rounding on an outer node
/// and the remainder on an inner one, which readers compose to within 2^-48 of the offset.
fn frame_nodes(
    root: &mut Root,
    mesh_node: json::Index<json::Node>,
    offset: DVec3,
) -> json::Index<json::Node> {
    if offset == DVec3::ZERO {
        return mesh_node;
    }
    let coarse = offset.as_vec3();
    let fine = (offset - coarse.as_dvec3()).as_vec3();
    let inner = root.push(json::Node {
        children: Some(vec![mesh_node]),
        translation: Some(fine.to_array()),
        ..Default::default()
    });
    root.push(json::Node {
        children: Some(vec![inner]),
        translation: Some(coarse.to_array()),
        ..Default::default()
    })
}

fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let (meta, payload) = uri
        .split_once(',')
        .ok_or("data: URI has no ',' before its payload")?;
    if !meta.ends_with(";base64") {
        return Err("data: URI is not base64-encoded (not supported)".into());
    }
    base64::decode(payload).map_err(|e| format!("data: URI: {e}"))
}

fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// One buffer holding positions, normals and u32 indices, one mesh, node and scene. GLB keeps
/// the buffer in its BIN chunk; `.gltf` embeds it as a base64 `data:` URI so the file stands
/// alone.
pub(crate) fn write(
    w: &mut dyn Write,
    mesh: &Mesh,
    normals: &[Vec3],
    binary: bool,
) -> io::Result<()> {
    let mut bin = Vec::with_capacity(24 * mesh.positions.len() + 12 * mesh.triangles.len());
    for p in &mesh.positions {
        bin.extend(p.to_array().iter().flat_map(|c| c.to_le_bytes()));
    }
    let normals_offset = bin.len();
    for n in normals {
        bin.extend(n.to_array().iter().flat_map(|c| c.to_le_bytes()));
    }
    let indices_offset = bin.len();
    for t in &mesh.triangles {
        bin.extend(t.iter().flat_map(|i| i.to_le_bytes()));
    }

    let mut root = Root::default();
    let uri = (!binary).then(|| {
        format!(
            "data:application/octet-stream;base64,{}",
            base64::encode(&bin)
        )
    });
    let buffer = root.push(json::Buffer {
        byte_length: USize64::from(bin.len()),
        name: None,
        uri,
        extensions: Default::default(),
        extras: Default::default(),
    });
    let view = |root: &mut Root, offset: usize, len: usize, target| {
        root.push(json::buffer::View {
            buffer,
            byte_length: USize64::from(len),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: Some(Checked::Valid(target)),
            extensions: Default::default(),
            extras: Default::default(),
        })
    };
    use json::buffer::Target;
    let pos_view = view(&mut root, 0, normals_offset, Target::ArrayBuffer);
    let nrm_view = view(
        &mut root,
        normals_offset,
        indices_offset - normals_offset,
        Target::ArrayBuffer,
    );
    let idx_view = view(
        &mut root,
        indices_offset,
        bin.len() - indices_offset,
        Target::ElementArrayBuffer,
    );

    let accessor = |root: &mut Root, view, count: usize, ct, ty, min, max| {
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Checked::Valid(GenericComponentType(ct)),
            type_: Checked::Valid(ty),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
            extensions: Default::default(),
            extras: Default::default(),
        })
    };
    // glTF requires min/max on POSITION; they are computed over all stored vertices.
    let (lo, hi) = mesh.positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let bound = |v: Vec3| Some(json::Value::from(v.to_array().to_vec()));
    let n = mesh.positions.len();
    let positions = accessor(
        &mut root,
        pos_view,
        n,
        ComponentType::F32,
        Type::Vec3,
        bound(lo),
        bound(hi),
    );
    let normal_acc = accessor(
        &mut root,
        nrm_view,
        n,
        ComponentType::F32,
        Type::Vec3,
        None,
        None,
    );
    let indices = accessor(
        &mut root,
        idx_view,
        3 * mesh.triangles.len(),
        ComponentType::U32,
        Type::Scalar,
        None,
        None,
    );

    let primitive = json::mesh::Primitive {
        attributes: [
            (Checked::Valid(Semantic::Positions), positions),
            (Checked::Valid(Semantic::Normals), normal_acc),
        ]
        .into_iter()
        .collect(),
        indices: Some(indices),
        material: None,
        mode: Checked::Valid(Mode::Triangles),
        targets: None,
        extensions: Default::default(),
        extras: Default::default(),
    };
    let mesh_index = root.push(json::Mesh {
        primitives: vec![primitive],
        name: None,
        weights: None,
        extensions: Default::default(),
        extras: Default::default(),
    });
    let node = root.push(json::Node {
        mesh: Some(mesh_index),
        ..Default::default()
    });
    let top = frame_nodes(&mut root, node, mesh.offset);
    let scene = root.push(json::Scene {
        nodes: vec![top],
        name: None,
        extensions: Default::default(),
        extras: Default::default(),
    });
    root.scene = Some(scene);
    root.asset = json::Asset {
        version: "2.0".into(),
        generator: Some("pgvol".into()),
        ..Default::default()
    };

    let text = root.to_vec().map_err(io::Error::other)?;
    if !binary {
        return w.write_all(&text);
    }
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            // Recomputed (with padding) by `to_writer`.
            length: 0,
        },
        json: Cow::Owned(text),
        bin: Some(Cow::Owned(bin)),
    };
    glb.to_writer(w).map_err(|e| match e {
        gltf::Error::Io(e) => e,
        other => io::Error::other(other.to_string()),
    })
}
