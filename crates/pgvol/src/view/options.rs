//! What the viewer page shows first and how it draws it, with the checks of those choices.

use pgvol_slice::Axis;

use super::colour::ViewColours;
use crate::error::{Error, Result};
use crate::field_value::Field;

/// Default cap on the nodes per axis of what the page holds: the surface is decoded, and the
/// field's bricks shipped, at the file's own grid up to this size and resampled above it.
pub const VIEW_RES: usize = 256;

/// Largest cap accepted: above it a page of a large file grows past what a browser opens
/// in seconds.
pub const MAX_VIEW_RES: usize = 1024;

/// What the page shows first and how it draws it.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewOptions {
    /// The section shown when the page opens: an axis and a height in the model's own
    /// coordinates (default none; the page's controls or `#section=z:H` in its address turn
    /// one on).
    pub section: Option<(Axis, f64)>,
    /// The level set drawn as the surface and contoured in sections (default 0).
    pub iso: f32,
    /// Colours of the surface, the section and the background.
    pub colours: ViewColours,
    /// Nodes per axis above which the surface and the field are resampled (default
    /// [`VIEW_RES`], at most [`MAX_VIEW_RES`]).
    pub max_res: usize,
    /// Title shown on the page (default: none, the page says "pgvol view").
    pub title: Option<String>,
}

impl Default for ViewOptions {
    fn default() -> Self {
        ViewOptions {
            section: None,
            iso: 0.0,
            colours: ViewColours::default(),
            max_res: VIEW_RES,
            title: None,
        }
    }
}

impl ViewOptions {
    /// Refuses a cap out of range or a level that is not a number.
    pub(crate) fn check(&self) -> Result<()> {
        let min = crate::grid::MIN_RES as usize;
        if !(min..=MAX_VIEW_RES).contains(&self.max_res) {
            return Err(Error::parameter(format!(
                "the viewer's resolution cap must be {min} to {MAX_VIEW_RES} nodes per axis, \
                 got {}",
                self.max_res
            )));
        }
        if !self.iso.is_finite() {
            return Err(Error::parameter("the level must be a finite number"));
        }
        if let Some((_, h)) = self.section {
            if !h.is_finite() {
                return Err(Error::parameter(
                    "the section height must be a finite number",
                ));
            }
        }
        self.colours.check()
    }
}

/// Refuses a section height outside the field's grid, naming the range that would work.
pub(crate) fn check_section(field: &Field, axis: Axis, height: f64) -> Result<()> {
    let grid = field.grid();
    let a = axis.indices()[0];
    let lo = f64::from(grid.origin[a]) + grid.offset[a];
    let hi = f64::from(grid.max_corner()[a]) + grid.offset[a];
    if !(lo..=hi).contains(&height) {
        let name = ["x", "y", "z"][a];
        return Err(Error::parameter(format!(
            "the section height {height} lies outside the field, whose grid spans {name} from \
             {lo:.6} to {hi:.6}"
        )));
    }
    Ok(())
}
