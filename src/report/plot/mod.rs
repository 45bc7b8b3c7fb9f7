//! PNG plots of a [`Recording`]: the friction coefficient of each event (the seed's Figure 8),
//! the velocities of the dynamic bodies against time (Figures 10–11), and animation frames
//! with each body's rugosity band (Figure 12).
//!
//! Every picture is meant to be read without the code: each names its bodies (their
//! [`Recording::body_name`]), gives each body the one colour of [`body_colour`] (the viewer's
//! too), states its units, and keeps its legend in a column beside the data.
//!
//! Text uses DejaVu Sans, bundled in `assets/fonts/` (Bitstream Vera licence, beside it), so
//! no system font is needed. The charts (friction, velocity) are in `charts.rs`, the frames in
//! `frames.rs`; the shared drawing helpers here.

mod charts;
mod frames;

pub use charts::{plot_friction, plot_velocity};
pub use frames::render_frames;

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use glam::DVec2;
use plotters::coord::Shift;
use plotters::element::ComposedElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rand_distr::{Distribution, Normal};

use super::{BodyInfo, Recording, ReportError, StateSample, body_colour, create_dir};
use crate::components::RigidState;
use crate::events::EventKind;

/// The bundled font, registered with plotters as `sans-serif` on first use.
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
const FONT_FAMILY: &str = "sans-serif";

/// Width of the legend column beside a plot's data (px).
const LEGEND_WIDTH: u32 = 290;
/// Height of a plot's header: its title and a line saying what is drawn (px).
const HEADER_HEIGHT: u32 = 56;
/// Height of one legend line (px).
const LEGEND_LINE: i32 = 21;
/// Grey of secondary text (notes, empty legend entries).
const NOTE_GREY: RGBColor = RGBColor(100, 100, 100);

/// How animation frames are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStyle {
    /// Image width (px); the height follows the scene's aspect ratio, within 300..=900 px, plus
    /// a strip at the top for the time and the scale bar.
    pub width: u32,
    /// Factor applied to the tolerance when drawing the band (1 = true scale). Bands of a few
    /// millimetres are under a pixel wide in a metre-wide view; the factor is printed on the frame.
    pub band_scale: f64,
    /// Outline samples per segment.
    pub samples_per_segment: usize,
    /// Seed of the synthesized surface perturbation.
    pub seed: u64,
}

impl Default for FrameStyle {
    fn default() -> Self {
        Self { width: 1200, band_scale: 4.0, samples_per_segment: 12, seed: 1 }
    }
}

/// Writes `dir/friction.png`, `dir/velocity.png` and `frames` animation frames in
/// `dir/frames/NNNN.png`. Returns the number of frames written.
///
/// # Errors
/// [`ReportError`] naming the file that could not be written.
pub fn write_plots(recording: &Recording, dir: &Path, frames: usize, style: &FrameStyle) -> Result<usize, ReportError> {
    create_dir(dir)?;
    plot_friction(recording, &dir.join("friction.png"))?;
    plot_velocity(recording, &dir.join("velocity.png"))?;
    render_frames(recording, &dir.join("frames"), frames, style)
}

fn register_font() {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    REGISTERED.get_or_init(|| plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT).is_ok());
}

fn plot_error(path: &Path, error: impl std::fmt::Display) -> ReportError {
    ReportError::Plot { path: path.to_owned(), message: error.to_string() }
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// The colour of body `body` of `recording` ([`body_colour`]).
fn colour_of(recording: &Recording, body: usize) -> RGBColor {
    let (r, g, b) = body_colour(body, is_static(recording, body));
    RGBColor(r, g, b)
}

fn is_static(recording: &Recording, body: usize) -> bool {
    recording.bodies.get(body).is_some_and(|b| b.is_static)
}

fn font(size: u32, colour: &RGBColor) -> TextStyle<'_> {
    (FONT_FAMILY, size).into_font().color(colour)
}

/// Draws a title and, under it in grey, what the picture shows; returns the area below.
fn draw_header<'a>(area: &Area<'a>, title: &str, subtitle: &str) -> Result<Area<'a>, Box<dyn std::error::Error>> {
    let (header, rest) = area.split_vertically(HEADER_HEIGHT);
    let centre = i32::try_from(header.dim_in_pixel().0 / 2)?;
    let centred = Pos::new(HPos::Center, VPos::Top);
    header.draw_text(title, &font(22, &BLACK).pos(centred), (centre, 6))?;
    header.draw_text(subtitle, &font(14, &NOTE_GREY).pos(centred), (centre, 34))?;
    Ok(rest)
}

/// A legend drawn line by line down a column of its own, beside the data.
struct Legend<'a, 'b> {
    area: &'a Area<'b>,
    y: i32,
}

impl<'a, 'b> Legend<'a, 'b> {
    fn new(area: &'a Area<'b>) -> Self {
        Self { area, y: 14 }
    }

    /// Whether `lines` more lines fit in the column.
    fn fits(&self, lines: i32) -> bool {
        i64::from(self.y + lines * LEGEND_LINE) <= i64::from(self.area.dim_in_pixel().1)
    }

    /// A heading, with a gap above it unless it is the first line.
    fn heading(&mut self, text: &str) -> DrawResult {
        if self.y > 14 {
            self.y += LEGEND_LINE / 2;
        }
        self.text(text, 0, &BLACK, 15)
    }

    /// An indented line of grey text.
    fn note(&mut self, text: &str) -> DrawResult {
        self.text(text, 8, &NOTE_GREY, 13)
    }

    /// An entry: `swatch` is drawn centred at the given pixel, the text to its right.
    fn entry(
        &mut self,
        text: &str,
        colour: &RGBColor,
        swatch: impl FnOnce(&Area<'b>, (i32, i32)) -> DrawResult,
    ) -> DrawResult {
        swatch(self.area, (22, self.y))?;
        self.text(text, 40, colour, 14)
    }

    fn text(&mut self, text: &str, x: i32, colour: &RGBColor, size: u32) -> DrawResult {
        let style = font(size, colour).pos(Pos::new(HPos::Left, VPos::Center));
        self.area.draw_text(text, &style, (x, self.y))?;
        self.y += LEGEND_LINE;
        Ok(())
    }
}
