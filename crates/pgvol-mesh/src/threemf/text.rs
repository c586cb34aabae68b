//! Small text helpers shared by the part parsers: numbers, namespaces, and messages that point
//! into the XML.

use quick_xml::name::ResolveResult;

/// A finite decimal number of a coordinate or transform.
pub(super) fn number(word: &str) -> Result<f64, String> {
    match word.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{}' is not a finite number", clip(word))),
    }
}

pub(super) fn in_namespace(ns: &ResolveResult, uri: &str) -> bool {
    matches!(ns, ResolveResult::Bound(n) if n.as_ref() == uri)
}

pub(super) fn xml_error(text: &str, position: u64, e: &quick_xml::Error) -> String {
    format!("line {}: malformed XML: {e}", line_of(text, position))
}

/// The first characters of an attribute, for messages about long or binary values.
pub(super) fn clip(text: &str) -> String {
    match text.char_indices().nth(60) {
        Some((end, _)) => format!("{}…", &text[..end]),
        None => text.to_string(),
    }
}

/// The 1-based line of byte `position` in `text`.
pub(super) fn line_of(text: &str, position: u64) -> usize {
    let end = (position as usize).min(text.len());
    1 + text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}
