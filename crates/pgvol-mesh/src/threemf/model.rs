//! One 3MF model part (`.model` XML): its unit, the objects of `<resources>` that hold a mesh or
//! components, and the items of `<build>`. Only elements of the core namespace are read;
//! extension elements (slices, beams, level sets, vendor metadata) are passed over.

use std::collections::HashMap;

use glam::{DAffine3, DVec3};
use quick_xml::events::{BytesStart, Event};
use quick_xml::name::ResolveResult;
use quick_xml::NsReader;

use super::limits::Limits;
use super::text::{clip, in_namespace, line_of, number, xml_error};
use super::transform;
use super::unit::LengthUnit;

const CORE_NS: &str = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02";
const PRODUCTION_NS: &str = "http://schemas.microsoft.com/3dmanufacturing/production/2015/06";

/// An object's or build item's reference to an object, placed by a transform.
#[derive(Clone, Debug)]
pub(super) struct Reference {
    pub object: u32,
    /// The model part holding the object (production extension `p:path`); `None` for the part
    /// the reference is in.
    pub path: Option<String>,
    pub transform: DAffine3,
}

#[derive(Debug, Default)]
pub(super) enum Content {
    #[default]
    Empty,
    Mesh {
        vertices: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
    },
    Components(Vec<Reference>),
}

#[derive(Debug)]
pub(super) struct Object {
    /// The `type` attribute: `model` unless given (others: `support`, `solidsupport`,
    /// `surface`, `other`).
    pub kind: String,
    pub content: Content,
}

#[derive(Debug)]
pub(super) struct Model {
    pub unit: LengthUnit,
    pub objects: HashMap<u32, Object>,
    pub build: Vec<Reference>,
}

/// Where the parser is: only the core elements that matter are told apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Element {
    Model,
    Resources,
    Object,
    Mesh,
    Vertices,
    Triangles,
    Components,
    Build,
    /// Any other element, core or not, whose content is passed over.
    Other,
}

/// Parses the model part `xml`. Errors say where (line) and what; the caller adds the part.
pub(super) fn parse(xml: &[u8], limits: &Limits) -> Result<Model, String> {
    let text = std::str::from_utf8(xml).map_err(|e| format!("not UTF-8 text: {e}"))?;
    let mut reader = NsReader::from_str(text);
    let mut parser = Parser {
        model: Model {
            unit: LengthUnit::Millimetre,
            objects: HashMap::new(),
            build: Vec::new(),
        },
        stack: Vec::new(),
        object: None,
        seen_model: false,
    };
    loop {
        let position = reader.buffer_position();
        let at = |problem: String| format!("line {}: {problem}", line_of(text, position));
        let (core, event) = match reader.read_resolved_event() {
            Ok((ns, event)) => (in_namespace(&ns, CORE_NS), event),
            Err(e) => return Err(xml_error(text, reader.error_position(), &e)),
        };
        match event {
            Event::Start(e) => {
                let element = parser.start(&e, core, &reader).map_err(at)?;
                if parser.stack.len() >= limits.xml_depth {
                    return Err(at(format!(
                        "elements nested more than {} deep",
                        limits.xml_depth
                    )));
                }
                parser.stack.push(element);
            }
            Event::Empty(e) => {
                parser.start(&e, core, &reader).map_err(at)?;
                parser.end().map_err(at)?;
            }
            Event::End(_) => {
                parser.stack.pop();
                parser.end().map_err(at)?;
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if !parser.seen_model {
        return Err("no <model> element in the core 3MF namespace".into());
    }
    Ok(parser.model)
}

struct Parser {
    model: Model,
    stack: Vec<Element>,
    /// The object being read and its id.
    object: Option<(u32, Object)>,
    seen_model: bool,
}

impl Parser {
    /// Handles the start of an element; returns what it is, for the stack.
    fn start(
        &mut self,
        e: &BytesStart,
        core: bool,
        reader: &NsReader<&[u8]>,
    ) -> Result<Element, String> {
        let parent = self.stack.last().copied();
        if !core || parent == Some(Element::Other) {
            return Ok(Element::Other);
        }
        let element = match (parent, e.local_name().as_ref()) {
            (None, "model") => {
                self.seen_model = true;
                if let Some(unit) = attribute(e, reader, "unit", false)? {
                    self.model.unit = LengthUnit::from_3mf(&unit).ok_or_else(|| {
                        format!(
                            "unit '{}' is not a 3MF unit (expected one of {})",
                            clip(&unit),
                            LengthUnit::expected()
                        )
                    })?;
                }
                Element::Model
            }
            (Some(Element::Model), "resources") => Element::Resources,
            (Some(Element::Model), "build") => Element::Build,
            (Some(Element::Resources), "object") => {
                let id = id(e, reader, "id")?;
                let kind = attribute(e, reader, "type", false)?.unwrap_or_else(|| "model".into());
                self.object = Some((
                    id,
                    Object {
                        kind,
                        content: Content::Empty,
                    },
                ));
                Element::Object
            }
            (Some(Element::Object), "mesh") => {
                self.set_content(Content::Mesh {
                    vertices: Vec::new(),
                    triangles: Vec::new(),
                })?;
                Element::Mesh
            }
            (Some(Element::Object), "components") => {
                self.set_content(Content::Components(Vec::new()))?;
                Element::Components
            }
            (Some(Element::Mesh), "vertices") => Element::Vertices,
            (Some(Element::Mesh), "triangles") => Element::Triangles,
            (Some(Element::Vertices), "vertex") => {
                let mut p = [0.0; 3];
                for (c, key) in p.iter_mut().zip(["x", "y", "z"]) {
                    *c = required(e, reader, key)
                        .and_then(|v| number(&v))
                        .map_err(|m| format!("{}: {m}", self.vertex_label()))?;
                }
                if let Some((
                    _,
                    Object {
                        content: Content::Mesh { vertices, .. },
                        ..
                    },
                )) = &mut self.object
                {
                    vertices.push(DVec3::from_array(p));
                }
                Element::Other
            }
            (Some(Element::Triangles), "triangle") => {
                let mut t = [0u32; 3];
                for (v, key) in t.iter_mut().zip(["v1", "v2", "v3"]) {
                    *v = id(e, reader, key)
                        .map_err(|m| format!("{}: {m}", self.triangle_label()))?;
                }
                if let Some((
                    _,
                    Object {
                        content: Content::Mesh { triangles, .. },
                        ..
                    },
                )) = &mut self.object
                {
                    triangles.push(t);
                }
                Element::Other
            }
            (Some(Element::Components), "component") => {
                let reference = reference(e, reader)?;
                if let Some((
                    _,
                    Object {
                        content: Content::Components(list),
                        ..
                    },
                )) = &mut self.object
                {
                    list.push(reference);
                }
                Element::Other
            }
            (Some(Element::Build), "item") => {
                let reference = reference(e, reader)?;
                self.model.build.push(reference);
                Element::Other
            }
            _ => Element::Other,
        };
        Ok(element)
    }

    /// Handles the end of the element now off the stack: an object is complete at its end.
    fn end(&mut self) -> Result<(), String> {
        if self.stack.last() != Some(&Element::Resources) {
            return Ok(());
        }
        let Some((id, object)) = self.object.take() else {
            return Ok(());
        };
        if let Content::Mesh {
            vertices,
            triangles,
        } = &object.content
        {
            let n = vertices.len();
            if let Some((t, v)) = triangles
                .iter()
                .enumerate()
                .find_map(|(t, tri)| tri.iter().find(|&&v| v as usize >= n).map(|&v| (t, v)))
            {
                return Err(format!(
                    "object {id}, triangle {t}: vertex index {v} but the mesh has {n} vertices"
                ));
            }
        }
        if self.model.objects.insert(id, object).is_some() {
            return Err(format!("object id {id} is used twice"));
        }
        Ok(())
    }

    fn set_content(&mut self, content: Content) -> Result<(), String> {
        let Some((id, object)) = &mut self.object else {
            return Ok(());
        };
        if !matches!(object.content, Content::Empty) {
            return Err(format!(
                "object {id} has more than one <mesh> or <components>"
            ));
        }
        object.content = content;
        Ok(())
    }

    fn vertex_label(&self) -> String {
        match &self.object {
            Some((
                id,
                Object {
                    content: Content::Mesh { vertices, .. },
                    ..
                },
            )) => {
                format!("object {id}, vertex {}", vertices.len())
            }
            _ => "vertex".into(),
        }
    }

    fn triangle_label(&self) -> String {
        match &self.object {
            Some((
                id,
                Object {
                    content: Content::Mesh { triangles, .. },
                    ..
                },
            )) => {
                format!("object {id}, triangle {}", triangles.len())
            }
            _ => "triangle".into(),
        }
    }
}

/// A component's or build item's reference: `objectid`, optional `transform`, optional
/// production `p:path`.
fn reference(e: &BytesStart, reader: &NsReader<&[u8]>) -> Result<Reference, String> {
    let object = id(e, reader, "objectid")?;
    let transform = match attribute(e, reader, "transform", false)? {
        Some(text) => transform::parse(&text)?,
        None => DAffine3::IDENTITY,
    };
    let path = attribute(e, reader, "path", true)?;
    Ok(Reference {
        object,
        path,
        transform,
    })
}

/// A non-negative integer attribute (ids and vertex indices).
fn id(e: &BytesStart, reader: &NsReader<&[u8]>, key: &str) -> Result<u32, String> {
    let text = required(e, reader, key)?;
    text.trim().parse::<u32>().map_err(|_| {
        format!(
            "{} '{}' is not a whole number from 0 to {}",
            key,
            clip(&text),
            u32::MAX
        )
    })
}

fn required(e: &BytesStart, reader: &NsReader<&[u8]>, key: &str) -> Result<String, String> {
    attribute(e, reader, key, false)?.ok_or_else(|| {
        format!(
            "<{}> has no {} attribute",
            e.local_name().as_ref() as &str,
            key
        )
    })
}

/// The value of the attribute `key`: without a namespace, or in the production namespace when
/// `production` is set.
fn attribute(
    e: &BytesStart,
    reader: &NsReader<&[u8]>,
    key: &str,
    production: bool,
) -> Result<Option<String>, String> {
    for attr in e.attributes() {
        let attr = attr.map_err(|e| format!("bad attribute: {e}"))?;
        let (ns, local) = reader.resolver().resolve_attribute(attr.key);
        let wanted = match &ns {
            ResolveResult::Unbound => !production,
            ns => production && in_namespace(ns, PRODUCTION_NS),
        };
        if wanted && local.as_ref() == key {
            let value = attr
                .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                .map_err(|e| format!("bad attribute value: {e}"))?;
            return Ok(Some(value.into_owned()));
        }
    }
    Ok(None)
}
