//! Text in plots needs a font; one is read at run time from the usual system places (or the
//! file named by `PGVOL_PLOT_FONT`). Without one, plots are drawn without text.

use plotters::style::{register_font, FontStyle};

const CANDIDATES: [&str; 4] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// Registers a system font as `sans-serif`; returns whether text can be drawn. When
/// `PGVOL_PLOT_FONT` is set only that file is tried (set it to nothing to draw without text).
pub fn load() -> bool {
    let chosen = std::env::var("PGVOL_PLOT_FONT").ok();
    let paths: Vec<&str> = match &chosen {
        Some(p) => vec![p.as_str()],
        None => CANDIDATES.to_vec(),
    };
    for path in paths {
        if let Ok(bytes) = std::fs::read(path) {
            // plotters keeps fonts for the life of the program.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            if register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                return true;
            }
        }
    }
    eprintln!("no font found: plots are drawn without text (set PGVOL_PLOT_FONT to a .ttf)");
    false
}
