//! `pgvol view`: one self-contained HTML page showing a field's surface and its sections.

use std::time::Instant;

use anyhow::Result;
use clap::Args;

use super::args::{at_input, OutputArgs, PathArg};
use crate::output::outln;
use crate::progress::Bars;
use crate::report::{self, Seconds};

#[derive(Args)]
#[command(
    after_help = "Example: pgvol view spot.pgv -o spot.html --section z:0.1 --color \
                        section=#d04020\n\nOpening spot.html#section=x:0.2 shows that section \
                        instead of the one written in."
)]
pub struct ViewArgs {
    /// A .pgv file, or a mesh (encoded first at --res).
    pub input: PathArg,
    /// Output page (.html), everything inlined: it opens from disk with no server or network.
    #[arg(short, long)]
    pub output: PathArg,
    /// The section shown on opening, AXIS:HEIGHT in the model's own coordinates (e.g. z:0.25)
    /// [default: none; the page's controls turn one on].
    #[arg(long, value_name = "AXIS:HEIGHT", value_parser = parse_section, allow_hyphen_values = true)]
    pub section: Option<(pgvol::Axis, f64)>,
    /// The level set drawn and contoured in sections; levels beyond the band the file stores
    /// as exact distances are refused.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub iso: f32,
    /// A colour, PART=#rrggbb with PART surface, section or background (repeatable)
    /// [defaults: surface=#a8b8cc, section=#e8743b, background=#ffffff].
    #[arg(long = "color", value_name = "PART=#RRGGBB", value_parser = parse_colour)]
    pub colours: Vec<(String, String)>,
    /// Nodes per axis above which the page holds the surface and the field resampled onto a
    /// coarser grid over the same box, so a large file opens in seconds.
    #[arg(long, default_value_t = pgvol::view::VIEW_RES as u32, value_parser = clap::value_parser!(u32).range(pgvol::limits::MIN_RES as i64..=pgvol::view::MAX_VIEW_RES as i64))]
    pub max_res: u32,
    /// Grid nodes per axis when the input is a mesh.
    #[arg(long, default_value_t = pgvol::limits::DEFAULT_RES as u32, value_parser = clap::value_parser!(u32).range(pgvol::limits::MIN_RES as i64..=pgvol::limits::MAX_RES as i64))]
    pub res: u32,
    /// Title shown on the page [default: the input's file name].
    #[arg(long)]
    pub title: Option<String>,
    #[command(flatten)]
    pub out: OutputArgs,
}

fn parse_section(text: &str) -> std::result::Result<(pgvol::Axis, f64), String> {
    let bad =
        || format!("'{text}' is not a section: give AXIS:HEIGHT with AXIS x, y or z, e.g. z:0.25");
    let (axis, height) = text.split_once(':').ok_or_else(bad)?;
    let axis = match axis.trim() {
        "x" | "X" => pgvol::Axis::X,
        "y" | "Y" => pgvol::Axis::Y,
        "z" | "Z" => pgvol::Axis::Z,
        _ => return Err(bad()),
    };
    match height.trim().parse::<f64>() {
        Ok(h) if h.is_finite() => Ok((axis, h)),
        _ => Err(bad()),
    }
}

fn parse_colour(text: &str) -> std::result::Result<(String, String), String> {
    let bad = || {
        format!(
            "'{text}' is not a colour: give PART=#rrggbb with PART surface, section or \
             background, e.g. section=#e8743b"
        )
    };
    let (part, value) = text.split_once('=').ok_or_else(bad)?;
    let hex = value.strip_prefix('#').unwrap_or("");
    if !["surface", "section", "background"].contains(&part)
        || hex.len() != 6
        || !hex.bytes().all(|b| b.is_ascii_hexdigit())
    {
        return Err(bad());
    }
    Ok((part.to_string(), value.to_string()))
}

pub fn run(a: ViewArgs) -> Result<()> {
    let start = Instant::now();
    let html_name = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("html") || e.eq_ignore_ascii_case("htm"));
    if !html_name {
        anyhow::bail!(
            "{}: the page is written as .html; name the output e.g. view.html",
            a.output.display()
        );
    }
    let bars = Bars::new(a.out.silent());
    // A mesh is encoded with exact distances out to the level drawn.
    let open = pgvol::OpenOptions {
        res: a.res as usize,
        reach: a.iso.abs(),
        ..Default::default()
    };
    let field = pgvol::Field::open(&a.input, &open, &bars).map_err(|e| at_input(e, &a.input))?;
    let mut options = pgvol::view::ViewOptions {
        section: a.section,
        iso: a.iso,
        max_res: a.max_res as usize,
        title: Some(a.title.clone().unwrap_or_else(|| {
            a.input
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        })),
        ..Default::default()
    };
    for (part, value) in &a.colours {
        match part.as_str() {
            "surface" => options.colours.surface = value.clone(),
            "section" => options.colours.section = value.clone(),
            _ => options.colours.background = value.clone(),
        }
    }
    let t = Instant::now();
    field
        .write_view(&a.output, &options, &bars)
        .map_err(|e| at_input(e, &a.input))?;
    let seconds = t.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&a.output).map(|m| m.len()).unwrap_or(0);
    if a.out.json {
        return report::print(
            &serde_json::json!({ "output": a.output, "bytes": bytes }),
            &Seconds::since(start).stage("view", seconds),
        );
    }
    if !a.out.quiet {
        outln!(
            "{}: {} bytes in {:.2} s",
            a.output.display(),
            bytes,
            seconds
        );
    }
    Ok(())
}
