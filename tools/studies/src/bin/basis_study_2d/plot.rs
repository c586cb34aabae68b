//! PNG panels of 2D fields: banded heat map of the field (blue inside, orange outside, one band
//! per half spacing), the true shape (green), the field's zero isoline (black), the grid nodes
//! (grey) and, for isoline fits, the interpolation points (red).

use plotters::prelude::*;

use super::basis2d::Field2;
use super::isoline::Isoline;
use super::shapes::{Shape, P2};

pub struct Panel<'a> {
    pub title: String,
    pub field: &'a Field2,
    pub iso: &'a Isoline,
    pub shape: &'a Shape,
    pub points: Option<&'a [P2]>,
}

const SIDE: u32 = 208;
const TITLE: u32 = 18;

fn band_colour(v: f64) -> RGBColor {
    let band = (v / 0.5).floor().clamp(-8.0, 7.0);
    let t = if band < 0.0 {
        (-band - 1.0) / 8.0
    } else {
        band / 8.0
    };
    let fade = |full: f64, light: f64| (light + (full - light) * t) as u8;
    if v < 0.0 {
        RGBColor(fade(40.0, 200.0), fade(90.0, 220.0), fade(180.0, 250.0))
    } else {
        RGBColor(fade(210.0, 255.0), fade(110.0, 235.0), fade(30.0, 200.0))
    }
}

/// Draws `panels` in a grid of `columns` and writes the PNG.
pub fn write(path: &str, panels: &[Panel], columns: usize, text: bool) -> Result<(), String> {
    let columns = columns.max(1);
    let rows = panels.len().div_ceil(columns);
    let size = (SIDE * columns as u32, (SIDE + TITLE) * rows as u32);
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let areas = root.split_evenly((rows, columns));
    for (area, panel) in areas.iter().zip(panels) {
        // A white gutter between panels.
        let area = area.margin(0, 2, 2, 2);
        draw_panel(&area, panel, text).map_err(|e| format!("{path}: {e}"))?;
    }
    root.present().map_err(|e| format!("{path}: {e}"))
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    panel: &Panel,
    text: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let g = panel.field.grid;
    let (lo, hi) = (g.origin, g.hi());
    let (w, h) = area.dim_in_pixel();
    let side = w.min(h.saturating_sub(TITLE)).max(2);
    let to_px = |p: P2| -> (i32, i32) {
        let s = (side - 1) as f64 / (hi - lo);
        (
            ((p[0] - lo) * s).round() as i32,
            (TITLE as f64 + (hi - p[1]) * s).round() as i32,
        )
    };
    // The heat map in 2 × 2 pixel blocks: half the detail is plenty for bands of half a
    // spacing, and repeated rows keep the PNG small.
    for py in (0..side).step_by(2) {
        for px in (0..side).step_by(2) {
            let x = lo + (hi - lo) * (px as f64 + 1.0) / side as f64;
            let y = hi - (hi - lo) * (py as f64 + 1.0) / side as f64;
            let colour = band_colour(panel.field.value([x, y]) / g.spacing);
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                if px + dx < side && py + dy < side {
                    let at = ((px + dx) as i32, (py + dy + TITLE) as i32);
                    area.draw_pixel(at, &colour)?;
                }
            }
        }
    }
    for idx in 0..g.len() {
        area.draw(&Circle::new(
            to_px(g.node(idx)),
            1,
            RGBColor(90, 90, 90).filled(),
        ))?;
    }
    let boundary = panel.shape.boundary(400);
    let mut closed: Vec<(i32, i32)> = boundary.iter().map(|&p| to_px(p)).collect();
    closed.push(closed[0]);
    area.draw(&PathElement::new(
        closed,
        RGBColor(0, 150, 60).stroke_width(2),
    ))?;
    for (seg, _) in &panel.iso.segments {
        area.draw(&PathElement::new(
            vec![to_px(seg[0]), to_px(seg[1])],
            BLACK.stroke_width(1),
        ))?;
    }
    if let Some(points) = panel.points {
        for &p in points {
            area.draw(&Circle::new(to_px(p), 1, RED.filled()))?;
        }
    }
    if text {
        area.draw(&Text::new(
            panel.title.clone(),
            (4, 4),
            ("sans-serif", 12).into_font(),
        ))?;
    }
    Ok(())
}
