//! The 3MF package: a zip archive of parts (Open Packaging Conventions) with relationship parts
//! that lead from the package to its start part. Every part is inflated under the size limits,
//! so a small archive cannot expand into gigabytes.

use std::collections::HashMap;
use std::io::{Cursor, Read};

use quick_xml::events::Event;
use quick_xml::NsReader;
use zip::ZipArchive;

use super::limits::Limits;
use super::text::{in_namespace, xml_error};

/// The relationship type of a 3D model part (3MF core specification).
pub(super) const MODEL_RELATIONSHIP: &str =
    "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel";
const RELATIONSHIPS_NS: &str = "http://schemas.openxmlformats.org/package/2006/relationships";

pub(super) struct Package<'a> {
    archive: ZipArchive<Cursor<&'a [u8]>>,
    /// Entry index by part name in ASCII lower case, without the leading '/': OPC part names
    /// compare case-insensitively.
    entries: HashMap<String, usize>,
    limits: Limits,
    inflated: u64,
}

impl<'a> Package<'a> {
    pub(super) fn open(bytes: &'a [u8], limits: Limits) -> Result<Package<'a>, String> {
        let archive = ZipArchive::new(Cursor::new(bytes))
            .map_err(|e| format!("not a 3MF file (a 3MF file is a zip package): {e}"))?;
        if archive.len() > limits.parts {
            return Err(format!(
                "the package has {} entries, more than the {} allowed",
                archive.len(),
                limits.parts
            ));
        }
        let mut entries = HashMap::with_capacity(archive.len());
        for (i, raw) in archive.file_names_raw().enumerate() {
            if let Ok(name) = std::str::from_utf8(raw) {
                entries.insert(key(name), i);
            }
        }
        Ok(Package {
            archive,
            entries,
            limits,
            inflated: 0,
        })
    }

    /// The part named `part` (absolute, as `/3D/3dmodel.model`) inflated, refused before
    /// inflating when its declared size is over the limits and while inflating when it turns
    /// out larger than declared.
    pub(super) fn read_part(&mut self, part: &str) -> Result<Vec<u8>, String> {
        let index = *self
            .entries
            .get(&key(part))
            .ok_or_else(|| format!("part {part} is missing from the package"))?;
        // Fuzz builds accept every CRC-32, so mutated parts reach the XML parsing behind them.
        let options = zip::read::ZipReadOptions::new().ignore_crc32(cfg!(fuzzing));
        let mut file = self
            .archive
            .by_index_with_options(index, options)
            .map_err(|e| format!("part {part}: cannot open it: {e}"))?;
        let compressed = file.compressed_size();
        let limits = self.limits;
        let part_limit = limits
            .part_bytes
            .min(limits.package_bytes.saturating_sub(self.inflated))
            .min(
                compressed
                    .saturating_mul(limits.inflation)
                    .saturating_add(limits.slack),
            );
        let refuse = |size: String| {
            format!(
                "part {part}: {size} uncompressed from {compressed} compressed, over the \
                 {part_limit} allowed (at most {} bytes a part, {} for all parts read, and \
                 {} times the compressed size past the first {}); a zip bomb or a model too \
                 large to read",
                limits.part_bytes, limits.package_bytes, limits.inflation, limits.slack
            )
        };
        let declared = file.size();
        if declared > part_limit {
            return Err(refuse(format!("declares {declared} bytes")));
        }
        // The declared size may lie: inflate at most one byte past the limit to find out.
        let mut bytes = Vec::with_capacity(declared.min(1 << 26) as usize);
        (&mut file)
            .take(part_limit + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| format!("part {part}: cannot inflate it: {e}"))?;
        if bytes.len() as u64 > part_limit {
            return Err(refuse(format!(
                "declares {declared} bytes but inflates to more than {part_limit}"
            )));
        }
        self.inflated += bytes.len() as u64;
        Ok(bytes)
    }

    /// The start part: the target of the package relationship of the 3D model type.
    pub(super) fn start_part(&mut self) -> Result<String, String> {
        let rels_part = "/_rels/.rels";
        let xml = self.read_part(rels_part)?;
        let rels = relationships(&xml).map_err(|e| format!("part {rels_part}: {e}"))?;
        rels.into_iter()
            .find(|(kind, _)| kind == MODEL_RELATIONSHIP)
            .map(|(_, target)| resolve("/", &target))
            .ok_or_else(|| {
                format!(
                    "part {rels_part} has no relationship of type {MODEL_RELATIONSHIP}, so the \
                     package names no 3D model"
                )
            })
    }
}

/// The lookup key of a part name: lower case, no leading '/'.
fn key(part: &str) -> String {
    part.trim_start_matches('/').to_ascii_lowercase()
}

/// The absolute part name of a relationship target, relative to the folder of `source` (its
/// part name up to the last '/'), with `%XX` escapes decoded and `.`/`..` segments resolved.
pub(super) fn resolve(source: &str, target: &str) -> String {
    let target = percent_decode(target);
    let joined = if target.starts_with('/') {
        target
    } else {
        let folder = &source[..source.rfind('/').map_or(0, |i| i + 1)];
        format!("{folder}{target}")
    };
    let mut segments: Vec<&str> = Vec::new();
    for s in joined.split('/') {
        match s {
            "" | "." => {}
            ".." => {
                segments.pop();
            }
            s => segments.push(s),
        }
    }
    format!("/{}", segments.join("/"))
}

fn percent_decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The (type, target) pairs of a relationships part.
pub(super) fn relationships(xml: &[u8]) -> Result<Vec<(String, String)>, String> {
    let text = std::str::from_utf8(xml).map_err(|e| format!("not UTF-8 text: {e}"))?;
    let mut reader = NsReader::from_str(text);
    let mut found = Vec::new();
    loop {
        let (in_rels, event) = match reader.read_resolved_event() {
            Ok((ns, event)) => (in_namespace(&ns, RELATIONSHIPS_NS), event),
            Err(e) => return Err(xml_error(text, reader.error_position(), &e)),
        };
        match event {
            Event::Start(e) | Event::Empty(e)
                if in_rels && e.local_name().as_ref() == "Relationship" =>
            {
                let (mut kind, mut target) = (None, None);
                for attr in e.attributes() {
                    let attr = attr.map_err(|e| format!("bad attribute: {e}"))?;
                    let value = attr
                        .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                        .map_err(|e| format!("bad attribute value: {e}"))?;
                    match attr.key.as_ref() {
                        "Type" => kind = Some(value.into_owned()),
                        "Target" => target = Some(value.into_owned()),
                        _ => {}
                    }
                }
                if let (Some(kind), Some(target)) = (kind, target) {
                    found.push((kind, target));
                }
            }
            Event::Eof => return Ok(found),
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_resolve_against_the_source_folder() {
        assert_eq!(resolve("/", "/3D/3dmodel.model"), "/3D/3dmodel.model");
        assert_eq!(resolve("/", "3D/3dmodel.model"), "/3D/3dmodel.model");
        assert_eq!(
            resolve("/3D/3dmodel.model", "Objects/a.model"),
            "/3D/Objects/a.model"
        );
        assert_eq!(resolve("/3D/3dmodel.model", "../x%20y.model"), "/x y.model");
        assert_eq!(resolve("/", "%zz%4"), "/%zz%4");
        assert_eq!(key("/3D/3DModel.model"), "3d/3dmodel.model");
    }
}
