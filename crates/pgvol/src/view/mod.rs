//! The viewer page: one self-contained HTML file showing a field's surface, lit and turnable,
//! and an axis-aligned section computed in the browser from the field's coefficients.
//!
//! Rust prepares everything the page needs (`payload`: the decoded surface and the field's
//! bricks, quantised and base64'd) and inlines it with the committed script bundle (`page`);
//! the page never reads `.pgv` bytes itself, so it does not depend on the file layout.

mod colour;
mod options;
mod page;
mod payload;

use std::path::Path;

use crate::error::{FileResult, Result};
use crate::field_value::Field;
use crate::progress::Progress;

pub use colour::ViewColours;
pub use options::{ViewOptions, MAX_VIEW_RES, VIEW_RES};

impl Field {
    /// The viewer page of this field as one HTML document with everything inlined.
    pub fn view_html(&self, options: &ViewOptions, progress: &dyn Progress) -> Result<String> {
        options.check()?;
        if options.iso != 0.0 {
            self.check_reach(options.iso)?;
        }
        if let Some((axis, height)) = options.section {
            options::check_section(self, axis, height)?;
        }
        let data = payload::Payload::of(self, options, progress)?;
        page::html(&data, options)
    }

    /// Writes the viewer page to `path` atomically (see [`Field::view_html`]).
    pub fn write_view(
        &self,
        path: impl AsRef<Path>,
        options: &ViewOptions,
        progress: &dyn Progress,
    ) -> Result<()> {
        let path = path.as_ref();
        let html = self.view_html(options, progress)?;
        pgvol_core::write_atomic(path, |w| w.write_all(html.as_bytes())).writing()
    }
}
