//! The page's colours, checked to be `#rrggbb` before they are written into it.

use crate::error::{Error, Result};

/// Colours of the viewer page, each `#rrggbb`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ViewColours {
    /// The surface (default a light grey-blue).
    pub surface: String,
    /// The filled inside of a section (default orange).
    pub section: String,
    /// The background (default white).
    pub background: String,
}

impl Default for ViewColours {
    fn default() -> Self {
        ViewColours {
            surface: "#a8b8cc".into(),
            section: "#e8743b".into(),
            background: "#ffffff".into(),
        }
    }
}

impl ViewColours {
    /// Refuses a colour that is not `#` and six hexadecimal digits.
    pub(crate) fn check(&self) -> Result<()> {
        for (what, value) in [
            ("surface", &self.surface),
            ("section", &self.section),
            ("background", &self.background),
        ] {
            let hex = value.strip_prefix('#').unwrap_or("");
            if hex.len() != 6 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
                return Err(Error::parameter(format!(
                    "the {what} colour {value:?} is not a colour: give # and six hexadecimal \
                     digits, e.g. #e8743b"
                )));
            }
        }
        Ok(())
    }
}
