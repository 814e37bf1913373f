//! Figures as PNG and SVG, with an embedded font (no system fonts, no fontconfig).
//!
//! A figure implements [`Figure`] once, generically over the plotters backend, and
//! [`save_figure`] renders it to a PNG and, optionally, an SVG of the same layout. Text uses
//! DejaVu Sans, embedded through the `dejavu` crate and registered with plotters' `ab_glyph`
//! font backend by [`register_fonts`] (called by [`save_figure`]).
//!
//! - [`lines`]: generic line-chart panels ([`lines::LinePanel`], [`lines::LineFigure`]).
//!
//! Figures of a study live with it (one jump's in `sandjumper_study::jump_figure`, the
//! sweep's in `sandjumper_study::sweep::plot`).

pub mod lines;

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Font family every figure uses; registered from embedded bytes.
pub const FONT: &str = "sans-serif";

/// A figure could not be drawn or written.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotError {
    /// File being written, if known.
    pub path: Option<PathBuf>,
    /// What went wrong.
    pub reason: String,
}

/// A figure that cannot be drawn is our failure (exit 1).
impl crate::Blamed for PlotError {
    fn blame(&self) -> crate::Blame {
        crate::Blame::Internal
    }
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.path {
            Some(p) => write!(f, "cannot draw figure `{}`: {}", p.display(), self.reason),
            None => write!(f, "cannot draw figure: {}", self.reason),
        }
    }
}

impl std::error::Error for PlotError {}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for PlotError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        Self {
            path: None,
            reason: e.to_string(),
        }
    }
}

/// Result of drawing operations.
pub type PlotResult<T> = Result<T, PlotError>;

/// Something that can draw itself on any plotters backend.
pub trait Figure {
    /// Size in pixels (PNG) or SVG user units.
    fn size(&self) -> (u32, u32);
    /// Draw onto the whole area (already filled white).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult<()>;
}

static FONTS: Once = Once::new();

/// Register DejaVu Sans (embedded) as the `sans-serif` family in all styles. Idempotent.
pub fn register_fonts() {
    FONTS.call_once(|| {
        let regular = dejavu::sans::regular();
        let bold = dejavu::sans::bold();
        let oblique = dejavu::sans::oblique();
        for (style, bytes) in [
            (FontStyle::Normal, regular),
            (FontStyle::Bold, bold),
            (FontStyle::Italic, oblique),
            (FontStyle::Oblique, oblique),
        ] {
            // The bytes are a valid TrueType font shipped by the `dejavu` crate; a failure
            // here would only mean missing text, so it is not fatal.
            let _ = plotters::style::register_font(FONT, style, bytes);
        }
    });
}

fn with_path(path: &Path) -> impl Fn(PlotError) -> PlotError + '_ {
    move |mut e| {
        e.path = Some(path.to_path_buf());
        e
    }
}

fn render<DB: DrawingBackend>(fig: &impl Figure, root: DrawingArea<DB, Shift>) -> PlotResult<()> {
    root.fill(&WHITE)?;
    fig.draw(&root)?;
    root.present()?;
    Ok(())
}

/// Render `fig` to `png` and, if given, to `svg` (same layout).
pub fn save_figure(fig: &impl Figure, png: &Path, svg: Option<&Path>) -> PlotResult<()> {
    register_fonts();
    let size = fig.size();
    // Drawn into memory and encoded with `png`, as the `image` crate the rest of the
    // workspace uses encodes it (fast compression, adaptive filter: the same bytes), without
    // building `image` for a jump (plotters' own encoder would build a second, older `image`).
    let (w, h) = size;
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    render(
        fig,
        BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area(),
    )
    .map_err(with_path(png))?;
    write_png(png, &rgb, w, h).map_err(|e| PlotError {
        path: Some(png.to_path_buf()),
        reason: e.to_string(),
    })?;
    if let Some(svg) = svg {
        render(fig, SVGBackend::new(svg, size).into_drawing_area()).map_err(with_path(svg))?;
    }
    Ok(())
}

/// Write `rgb` (8-bit RGB, `w` x `h`) to `path` as a PNG.
fn write_png(path: &Path, rgb: &[u8], w: u32, h: u32) -> Result<(), png::EncodingError> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut encoder = png::Encoder::new(file, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()
}

/// The symbol of a legend entry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LegendMark {
    /// A line segment, solid or dashed.
    Line {
        /// Colour.
        color: RGBColor,
        /// Dashed.
        dashed: bool,
    },
    /// A filled patch (for shaded regions).
    Patch(RGBColor),
}

/// One entry of a legend.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    /// Text.
    pub label: String,
    /// Symbol.
    pub mark: LegendMark,
}

impl LegendEntry {
    /// A solid or dashed line entry.
    pub fn line(label: impl Into<String>, color: RGBColor, dashed: bool) -> Self {
        Self {
            label: label.into(),
            mark: LegendMark::Line { color, dashed },
        }
    }

    /// A shaded-region entry.
    pub fn patch(label: impl Into<String>, color: RGBColor) -> Self {
        Self {
            label: label.into(),
            mark: LegendMark::Patch(color),
        }
    }
}

/// Row height of legend entries, pixels.
pub const LEGEND_ROW: i32 = 28;

/// Draw `entries` as a legend column into `area` (typically a strip beside a chart),
/// starting `top` pixels from its top. Entries never cover data.
pub fn draw_legend_column<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    top: i32,
) -> PlotResult<()> {
    let font = (FONT, 18).into_font().color(&BLACK);
    for (i, e) in entries.iter().enumerate() {
        let y = top + i as i32 * LEGEND_ROW + LEGEND_ROW / 2;
        match e.mark {
            LegendMark::Line { color, dashed } => {
                let style = color.stroke_width(3);
                if dashed {
                    for x in [6, 20] {
                        area.draw(&PathElement::new(vec![(x, y), (x + 9, y)], style))?;
                    }
                } else {
                    area.draw(&PathElement::new(vec![(6, y), (35, y)], style))?;
                }
            }
            LegendMark::Patch(color) => {
                area.draw(&Rectangle::new([(6, y - 9), (35, y + 9)], color.filled()))?;
                area.draw(&Rectangle::new(
                    [(6, y - 9), (35, y + 9)],
                    RGBColor(150, 150, 150).stroke_width(1),
                ))?;
            }
        }
        area.draw(&Text::new(
            e.label.clone(),
            (44, y),
            font.clone().pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    Ok(())
}

/// A chart with f64 axes.
pub type XyChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Split a polyline into pieces that plotters can stroke thickly without artefacts.
///
/// plotters joins thick segments with unbounded inner mitres, so a turn sharper than 90
/// degrees (a force that jumps and returns, an added mass that drops to zero) draws a long
/// spike. This maps the points to pixels, drops points that fall on the pixel of the previous
/// one, and starts a new piece (sharing the corner point) wherever the path turns by more than
/// 90 degrees.
pub fn stroke_pieces<DB: DrawingBackend>(
    chart: &XyChart<'_, DB>,
    points: impl IntoIterator<Item = (f64, f64)>,
) -> Vec<Vec<(f64, f64)>> {
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut piece: Vec<(f64, f64)> = Vec::new();
    let mut pix: Vec<(i32, i32)> = Vec::new();
    for p in points {
        if !(p.0.is_finite() && p.1.is_finite()) {
            continue;
        }
        let c = chart.backend_coord(&p);
        if pix.last() == Some(&c) {
            continue;
        }
        if let [.., a, b] = pix[..] {
            let (u, v) = ((b.0 - a.0, b.1 - a.1), (c.0 - b.0, c.1 - b.1));
            if i64::from(u.0) * i64::from(v.0) + i64::from(u.1) * i64::from(v.1) < 0 {
                let corner = *piece.last().expect("a piece has as many points as pixels");
                pieces.push(std::mem::replace(&mut piece, vec![corner]));
                pix = vec![b];
            }
        }
        piece.push(p);
        pix.push(c);
    }
    if !piece.is_empty() {
        pieces.push(piece);
    }
    pieces
}

/// Tick label without float noise or needless zeros: `0.1`, `25`, `-2.5`, `1e-5`.
pub fn tick_label(v: &f64) -> String {
    let v = *v;
    if v == 0.0 {
        return "0".into();
    }
    if v.abs() < 1e-3 || v.abs() >= 1e6 {
        return format!("{v:.2e}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

/// Ten well-separated colours (the "tab10" cycle), for lines keyed by an index.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Colour number `i` of [`PALETTE`], cycling.
pub fn palette(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// `(lo, hi)` padded by `pad` of the span; a degenerate or empty span becomes a unit-ish
/// window around the value so axes are always drawable.
pub fn padded_range(values: impl IntoIterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (lo, hi) = values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span <= f64::EPSILON * lo.abs().max(1.0) {
        let half = (lo.abs() * 0.1).max(1e-3);
        return (lo - half, hi + half);
    }
    (lo - pad * span, hi + pad * span)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn padded_range_handles_degenerate_inputs() {
        assert_eq!(padded_range([], 0.05), (0.0, 1.0));
        let (lo, hi) = padded_range([2.0, 2.0], 0.05);
        assert!(lo < 2.0 && hi > 2.0);
        let (lo, hi) = padded_range([0.0, 10.0, f64::NAN], 0.1);
        assert_eq!((lo, hi), (-1.0, 11.0));
    }

    #[test]
    fn thick_lines_are_split_at_sharp_turns_only() {
        register_fonts();
        let mut buf = vec![0u8; 200 * 200 * 3];
        let root = BitMapBackend::with_buffer(&mut buf, (200, 200)).into_drawing_area();
        let chart = ChartBuilder::on(&root)
            .build_cartesian_2d(0.0..10.0, 0.0..10.0)
            .unwrap();
        // A spike up and straight back down: two pieces sharing the apex.
        let spike = stroke_pieces(&chart, [(0.0, 0.0), (5.0, 10.0), (5.2, 0.0), (10.0, 0.0)]);
        assert_eq!(spike.len(), 2, "{spike:?}");
        assert_eq!(spike[0].last(), spike[1].first());
        // A gentle curve, with repeated points on the same pixel: one piece, repeats dropped.
        let smooth: Vec<_> = (0..=100)
            .map(|i| (i as f64 / 10.0, (i as f64 / 10.0).sqrt()))
            .collect();
        let with_repeats = smooth.iter().flat_map(|&p| [p, p]);
        let pieces = stroke_pieces(&chart, with_repeats);
        assert_eq!(pieces.len(), 1);
        assert!(pieces[0].len() <= smooth.len());
        // Non-finite points are skipped, not drawn.
        let gaps = stroke_pieces(&chart, [(0.0, 0.0), (1.0, f64::NAN), (2.0, 2.0)]);
        assert_eq!(gaps, vec![vec![(0.0, 0.0), (2.0, 2.0)]]);
    }

    #[test]
    fn tick_labels_have_no_float_noise() {
        assert_eq!(tick_label(&0.30000000000000004), "0.3");
        assert_eq!(tick_label(&25.0), "25");
        assert_eq!(tick_label(&-2.5), "-2.5");
        assert_eq!(tick_label(&0.0), "0");
        assert_eq!(tick_label(&-0.00001), "-1.00e-5");
    }

    #[test]
    fn embedded_font_measures_text() {
        register_fonts();
        let style = TextStyle::from((FONT, 20).into_font());
        let (w, h) = style
            .font
            .box_size("jump height")
            .expect("the embedded font is registered");
        assert!(w > 50 && h > 5, "{w}x{h}");
    }
}
