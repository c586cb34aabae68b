//! The HTML document: the payload and the committed script bundle inlined, nothing loaded.

use super::options::ViewOptions;
use super::payload::Payload;
use crate::error::Result;

/// The page's script: tools/viewer built and minified (rebuilt from its lock file by the
/// checks and compared byte for byte).
const BUNDLE: &str = include_str!("viewer.min.js");

/// The document holding `data` and the script that draws it.
pub(crate) fn html(data: &Payload, options: &ViewOptions) -> Result<String> {
    let title = escape_text(options.title.as_deref().unwrap_or("pgvol view"));
    let background = &options.colours.background;
    let json = data.to_json();
    let mut page = String::with_capacity(json.len() + BUNDLE.len() + 2048);
    page.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    page.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    page.push_str(&format!("<title>{title}</title>\n"));
    page.push_str(&format!(
        "<style>html,body{{margin:0;height:100%;overflow:hidden;background:{background};\
         font:13px/1.4 system-ui,sans-serif}}</style>\n"
    ));
    page.push_str("</head>\n<body data-status=\"loading\">\n");
    page.push_str("<script type=\"application/json\" id=\"pgvol-data\">");
    page.push_str(&json);
    page.push_str("</script>\n<script>");
    page.push_str(BUNDLE);
    page.push_str("</script>\n</body>\n</html>\n");
    Ok(page)
}

/// `text` safe as HTML element content.
fn escape_text(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_bundle_cannot_end_its_script_element_early() {
        assert!(!super::BUNDLE.to_ascii_lowercase().contains("</script"));
        assert!(!super::BUNDLE.is_empty());
    }
}
