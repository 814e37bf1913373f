//! PIV figures: a colour map of a field with arrows (speed, the paper's Fig. 4 velocity
//! panels) or with the foot drawn in (max shear strain rate), and added mass against depth
//! with the model's equation 6 (Fig. 6a).

use plotters::coord::Shift;
use plotters::prelude::*;

use sandjumper_output::plot::{FONT, Figure, PlotResult};

/// A colour map of one quantity on the vector grid, in image pixel coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct MapFigure {
    /// Title.
    pub title: String,
    /// Colour bar label.
    pub label: String,
    /// Image size, px.
    pub image: (usize, usize),
    /// Grid centres, px.
    pub xs: Vec<f64>,
    /// Grid centres, px (y down).
    pub ys: Vec<f64>,
    /// Values, row-major (NaN: not drawn).
    pub values: Vec<f64>,
    /// Arrows `(x, y, dx, dy)` in px, already scaled for drawing.
    pub arrows: Vec<(f64, f64, f64, f64)>,
    /// Outlines to draw (the foot), px.
    pub outlines: Vec<Vec<(f64, f64)>>,
}

/// A perceptually ordered colour map (dark blue to yellow, viridis-like), `t` in 0..=1.
pub fn colour(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = t.clamp(0.0, 1.0) * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |x: f64, y: f64| (x + (y - x) * f) as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

impl Figure for MapFigure {
    fn size(&self) -> (u32, u32) {
        let (w, h) = self.image;
        let scale = (900.0 / w.max(h) as f64).min(2.0);
        (
            (w as f64 * scale) as u32 + 260,
            (h as f64 * scale) as u32 + 120,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult<()> {
        let body = root
            .margin(14, 8, 8, 8)
            .titled(&self.title, (FONT, 24).into_font().style(FontStyle::Bold))?;
        let (w, _) = body.dim_in_pixel();
        let (map, bar) = body.split_horizontally(w.saturating_sub(150));
        let (iw, ih) = (self.image.0 as f64, self.image.1 as f64);
        let mut chart = ChartBuilder::on(&map)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..iw, ih..0.0)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (px)")
            .y_desc("y (px)")
            .label_style((FONT, 16))
            .draw()?;
        let finite: Vec<f64> = self
            .values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        let (lo, hi) = finite
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        let (lo, hi) = if finite.is_empty() || hi <= lo {
            (0.0, 1.0)
        } else {
            (lo, hi)
        };
        let (nx, ny) = (self.xs.len(), self.ys.len());
        let hx = if nx > 1 {
            0.5 * (self.xs[1] - self.xs[0])
        } else {
            0.5
        };
        let hy = if ny > 1 {
            0.5 * (self.ys[1] - self.ys[0])
        } else {
            0.5
        };
        chart.draw_series((0..ny).flat_map(|j| {
            (0..nx).filter_map(move |i| {
                let v = self.values[j * nx + i];
                v.is_finite().then(|| {
                    let (x, y) = (self.xs[i], self.ys[j]);
                    Rectangle::new(
                        [(x - hx, y - hy), (x + hx, y + hy)],
                        colour((v - lo) / (hi - lo)).filled(),
                    )
                })
            })
        }))?;
        for &(x, y, dx, dy) in &self.arrows {
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(x, y), (x + dx, y + dy)],
                WHITE.stroke_width(1),
            )))?;
            // Head: two short strokes.
            let len = dx.hypot(dy);
            if len > 1e-9 {
                let (ux, uy) = (dx / len, dy / len);
                let head = (0.35 * len).min(6.0);
                for s in [-1.0, 1.0] {
                    let (px, py) = (
                        x + dx - head * (ux - s * 0.5 * uy),
                        y + dy - head * (uy + s * 0.5 * ux),
                    );
                    chart.draw_series(std::iter::once(PathElement::new(
                        vec![(x + dx, y + dy), (px, py)],
                        WHITE.stroke_width(1),
                    )))?;
                }
            }
        }
        for outline in &self.outlines {
            let mut pts = outline.clone();
            if let Some(&first) = outline.first() {
                pts.push(first);
            }
            chart.draw_series(std::iter::once(PathElement::new(pts, RED.stroke_width(3))))?;
        }
        // Colour bar.
        let mut cb = ChartBuilder::on(&bar.margin(30, 40, 10, 10))
            .y_label_area_size(70)
            .caption(&self.label, (FONT, 16))
            .build_cartesian_2d(0.0..1.0, lo..hi)?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .label_style((FONT, 14))
            .draw()?;
        let steps = 64;
        cb.draw_series((0..steps).map(|k| {
            let a = lo + (hi - lo) * k as f64 / steps as f64;
            let b = lo + (hi - lo) * (k + 1) as f64 / steps as f64;
            Rectangle::new(
                [(0.0, a), (1.0, b)],
                colour((k as f64 + 0.5) / steps as f64).filled(),
            )
        }))?;
        Ok(())
    }
}

/// One animation frame: the grey frame A of a pair with its vectors drawn as yellow arrows
/// (every `stride`-th vector, scaled by `scale`), as RGBA, reduced to at most 640 px wide.
pub fn animation_frame(
    img: &super::piv::Image,
    field: &super::piv::VectorField,
    stride: usize,
    scale: f64,
) -> image::RgbaImage {
    let step = img.width.div_ceil(640).max(1);
    let (w, h) = ((img.width / step) as u32, (img.height / step) as u32);
    let sf = step as f64;
    let (lo, hi) = img
        .data
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    let span = (hi - lo).max(1.0);
    let mut out = image::RgbaImage::from_fn(w, h, |x, y| {
        let k = y as usize * step * img.width + x as usize * step;
        let v = ((img.data[k] - lo) / span * 255.0) as u8;
        image::Rgba([v, v, v, 255])
    });
    let mut put = |x: f64, y: f64| {
        let (x, y) = (x / sf, y / sf);
        if x >= 0.0 && y >= 0.0 && (x as u32) < w && (y as u32) < h {
            out.put_pixel(x as u32, y as u32, image::Rgba([255, 220, 0, 255]));
        }
    };
    for j in (0..field.ny).step_by(stride.max(1)) {
        for i in (0..field.nx).step_by(stride.max(1)) {
            let k = j * field.nx + i;
            let (u, v) = (field.u[k], field.v[k]);
            if !(u.is_finite() && v.is_finite()) {
                continue;
            }
            let (x0, y0) = (field.xs[i], field.ys[j]);
            let (dx, dy) = (u * scale, v * scale);
            let steps = dx.hypot(dy).ceil().max(1.0) as usize;
            for s in 0..=steps {
                let t = s as f64 / steps as f64;
                put(x0 + dx * t, y0 + dy * t);
            }
            put(x0, y0);
            put(x0 + 1.0, y0);
            put(x0, y0 + 1.0);
        }
    }
    out
}

/// Write `frames` as a looping GIF, `delay_ms` per frame.
pub fn write_gif(
    path: &std::path::Path,
    frames: Vec<image::RgbaImage>,
    delay_ms: u32,
) -> Result<(), String> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let file = std::fs::File::create(path)
        .map_err(|e| format!("cannot create {}: {e}", path.display()))?;
    let mut enc = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 30);
    enc.set_repeat(Repeat::Infinite)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let delay = image::Delay::from_numer_denom_ms(delay_ms, 1);
    enc.encode_frames(
        frames
            .into_iter()
            .map(|f| image::Frame::from_parts(f, 0, 0, delay)),
    )
    .map_err(|e| format!("cannot write {}: {e}", path.display()))
}
