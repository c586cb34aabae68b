//! Placing the build: every build item's object, through its components, with the transforms
//! composed (component first, then its parent's, then the item's), into one triangle soup in
//! model units. Sizes are counted over the whole component graph before anything is placed,
//! so a few objects instanced many times cannot claim more memory than the limits allow.

use std::collections::HashMap;

use glam::{DAffine3, DVec3};

use super::limits::Limits;
use super::model::{Content, Model, Reference};

/// The object a reference names: its part and id.
type Key<'a> = (&'a str, u32);

/// The parsed model parts by part name.
pub(super) type Parts = HashMap<String, Model>;

/// What the build places, in model units.
pub(super) struct Placed {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Places the build of the model in part `root`.
pub(super) fn place(parts: &Parts, root: &str, limits: &Limits) -> Result<Placed, String> {
    let build = &parts[root].build;
    if build.is_empty() {
        return Err(format!(
            "part {root}: the <build> has no items, so nothing is printed"
        ));
    }
    let mut counter = Counter {
        parts,
        limits,
        sizes: HashMap::new(),
        stack: Vec::new(),
    };
    let mut total = Size::default();
    for item in build {
        let key = counter.target(root, item)?;
        total = total.add(counter.size(key)?);
    }
    if total.triangles == 0 {
        return Err(format!(
            "part {root}: no build item places a mesh of type model ({} support or other \
             objects left out)",
            total.skipped
        ));
    }
    limits.check(total)?;
    let mut placed = Placed {
        positions: Vec::with_capacity(total.vertices as usize),
        triangles: Vec::with_capacity(total.triangles as usize),
    };
    for item in build {
        let key = counter.target(root, item)?;
        emit(parts, key, item.transform, &mut placed);
    }
    Ok(placed)
}

#[derive(Clone, Copy, Debug, Default)]
struct Size {
    vertices: u64,
    triangles: u64,
    skipped: u64,
}

impl Size {
    fn add(self, other: Size) -> Size {
        Size {
            vertices: self.vertices.saturating_add(other.vertices),
            triangles: self.triangles.saturating_add(other.triangles),
            skipped: self.skipped.saturating_add(other.skipped),
        }
    }
}

impl Limits {
    fn check(&self, size: Size) -> Result<(), String> {
        if size.vertices > self.vertices || size.triangles > self.triangles {
            return Err(format!(
                "the build places {} vertices and {} triangles (components counted once per \
                 use), over the {} vertices and {} triangles allowed",
                size.vertices, size.triangles, self.vertices, self.triangles
            ));
        }
        Ok(())
    }
}

/// Counts what each object places, once per object, refusing cycles, references to missing
/// objects and nesting past the limit.
struct Counter<'a> {
    parts: &'a Parts,
    limits: &'a Limits,
    sizes: HashMap<Key<'a>, Size>,
    /// The objects being counted, outermost first: a key met again is a cycle.
    stack: Vec<Key<'a>>,
}

impl<'a> Counter<'a> {
    /// The object `reference`, written in part `from`, names; checked to exist.
    fn target(&self, from: &'a str, reference: &'a Reference) -> Result<Key<'a>, String> {
        let part = reference.path.as_deref().unwrap_or(from);
        let model = self
            .parts
            .get(part)
            .ok_or_else(|| format!("part {part} is not a model part of the package"))?;
        if !model.objects.contains_key(&reference.object) {
            return Err(format!(
                "part {from}: object {} is referenced but part {part} has no object with that id",
                reference.object
            ));
        }
        Ok((part, reference.object))
    }

    fn size(&mut self, key: Key<'a>) -> Result<Size, String> {
        if let Some(&size) = self.sizes.get(&key) {
            return Ok(size);
        }
        if let Some(start) = self.stack.iter().position(|&k| k == key) {
            let chain: Vec<String> = self.stack[start..]
                .iter()
                .chain([&key])
                .map(|(_, id)| id.to_string())
                .collect();
            return Err(format!(
                "part {}: components refer back to themselves (objects {})",
                key.0,
                chain.join(" → ")
            ));
        }
        if self.stack.len() >= self.limits.component_depth {
            return Err(format!(
                "part {}: components nested more than {} deep",
                key.0, self.limits.component_depth
            ));
        }
        let object = &self.parts[key.0].objects[&key.1];
        let size = if object.kind != "model" {
            Size {
                skipped: 1,
                ..Size::default()
            }
        } else {
            match &object.content {
                Content::Empty => {
                    return Err(format!(
                        "part {}: object {} has neither a <mesh> nor <components> (a slice \
                         stack, level set or other extension object, which is not read as a \
                         mesh)",
                        key.0, key.1
                    ))
                }
                Content::Mesh {
                    vertices,
                    triangles,
                } => Size {
                    vertices: vertices.len() as u64,
                    triangles: triangles.len() as u64,
                    skipped: 0,
                },
                Content::Components(components) => {
                    self.stack.push(key);
                    let mut sum = Size::default();
                    for c in components {
                        let child = self.target(key.0, c)?;
                        sum = sum.add(self.size(child)?);
                        // Stop early: a graph that doubles at every level overflows long
                        // before its end.
                        self.limits.check(sum)?;
                    }
                    self.stack.pop();
                    sum
                }
            }
        };
        self.sizes.insert(key, size);
        Ok(size)
    }
}

/// Appends the object `key` placed by `to_world`; the references were checked by counting.
fn emit(parts: &Parts, key: Key, to_world: DAffine3, placed: &mut Placed) {
    let object = &parts[key.0].objects[&key.1];
    if object.kind != "model" {
        return;
    }
    match &object.content {
        Content::Empty => {}
        Content::Mesh {
            vertices,
            triangles,
        } => {
            let base = placed.positions.len() as u32;
            placed
                .positions
                .extend(vertices.iter().map(|&p| to_world.transform_point3(p)));
            // A mirroring transform turns the outward side inward: swap two corners back.
            let mirrored = to_world.matrix3.determinant() < 0.0;
            placed.triangles.extend(triangles.iter().map(|&[a, b, c]| {
                if mirrored {
                    [base + a, base + c, base + b]
                } else {
                    [base + a, base + b, base + c]
                }
            }));
        }
        Content::Components(components) => {
            for c in components {
                let part = c.path.as_deref().unwrap_or(key.0);
                emit(parts, (part, c.object), to_world * c.transform, placed);
            }
        }
    }
}
