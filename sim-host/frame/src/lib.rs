//! `sandjumper-frame`: one grey-level camera frame (8- or 16-bit pixels, row by row, `y` growing
//! downward) and a region of interest: the pixel type the rod camera (`sandjumper-imaging`) and
//! PIV (`sandjumper-flow`) both read, so neither depends on the other.

/// Bits per pixel of a grey frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum BitDepth {
    /// 0..=255.
    Eight,
    /// 0..=65535.
    Sixteen,
}

impl BitDepth {
    /// Bits per pixel.
    pub fn bits(self) -> u32 {
        match self {
            Self::Eight => 8,
            Self::Sixteen => 16,
        }
    }

    /// Largest pixel value.
    pub fn max_value(self) -> f32 {
        match self {
            Self::Eight => 255.0,
            Self::Sixteen => 65535.0,
        }
    }
}

/// Pixel storage of a frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Pixels {
    /// 8-bit grey.
    Eight(Vec<u8>),
    /// 16-bit grey.
    Sixteen(Vec<u16>),
}

/// A grey frame, `width x height` pixels, row-major, `y` growing downward.
#[derive(Clone, Debug, PartialEq)]
pub struct GrayFrame {
    width: u32,
    height: u32,
    pixels: Pixels,
}

impl GrayFrame {
    /// A frame from 8-bit pixels; `None` if the length is not `width * height`.
    pub fn from_u8(width: u32, height: u32, pixels: Vec<u8>) -> Option<Self> {
        (pixels.len() == width as usize * height as usize).then_some(Self {
            width,
            height,
            pixels: Pixels::Eight(pixels),
        })
    }

    /// A frame from 16-bit pixels; `None` if the length is not `width * height`.
    pub fn from_u16(width: u32, height: u32, pixels: Vec<u16>) -> Option<Self> {
        (pixels.len() == width as usize * height as usize).then_some(Self {
            width,
            height,
            pixels: Pixels::Sixteen(pixels),
        })
    }

    /// Width, px.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height, px.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Bit depth.
    pub fn depth(&self) -> BitDepth {
        match self.pixels {
            Pixels::Eight(_) => BitDepth::Eight,
            Pixels::Sixteen(_) => BitDepth::Sixteen,
        }
    }

    /// The pixels.
    pub fn pixels(&self) -> &Pixels {
        &self.pixels
    }

    /// Pixel `(x, y)` as a float (no bounds check beyond the slice's).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> f32 {
        let i = y as usize * self.width as usize + x as usize;
        match &self.pixels {
            Pixels::Eight(p) => f32::from(p[i]),
            Pixels::Sixteen(p) => f32::from(p[i]),
        }
    }

    /// Row `y`, columns `x0..x1`, as floats into `out` (cleared first).
    #[inline]
    pub fn row_into(&self, y: u32, x0: u32, x1: u32, out: &mut Vec<f32>) {
        out.clear();
        let start = y as usize * self.width as usize;
        let (a, b) = (start + x0 as usize, start + x1 as usize);
        match &self.pixels {
            Pixels::Eight(p) => out.extend(p[a..b].iter().map(|&v| f32::from(v))),
            Pixels::Sixteen(p) => out.extend(p[a..b].iter().map(|&v| f32::from(v))),
        }
    }

    /// The frame cut to `roi` (which must lie inside it).
    pub fn crop(&self, roi: Roi) -> GrayFrame {
        let w = self.width as usize;
        let rows = (roi.y..roi.y + roi.height).map(|y| y as usize * w);
        let (x0, x1) = (roi.x as usize, (roi.x + roi.width) as usize);
        let pixels = match &self.pixels {
            Pixels::Eight(p) => {
                Pixels::Eight(rows.flat_map(|s| &p[s + x0..s + x1]).copied().collect())
            }
            Pixels::Sixteen(p) => {
                Pixels::Sixteen(rows.flat_map(|s| &p[s + x0..s + x1]).copied().collect())
            }
        };
        GrayFrame {
            width: roi.width,
            height: roi.height,
            pixels,
        }
    }
}

/// A region of interest, px: columns `x..x+width`, rows `y..y+height`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Roi {
    /// First column.
    pub x: u32,
    /// First row.
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl Roi {
    /// Whether the region lies inside a `width x height` frame and is not empty.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.width > 0
            && self.height > 0
            && u64::from(self.x) + u64::from(self.width) <= u64::from(width)
            && u64::from(self.y) + u64::from(self.height) <= u64::from(height)
    }
}

/// Grey level of an RGB pixel: ITU-R BT.601 luma on the stored (gamma-encoded) values,
/// `Y = 0.299 R + 0.587 G + 0.114 B` (MATLAB's `rgb2gray`, which PIVlab uses), rounded.
pub fn luma_bt601(r: f32, g: f32, b: f32) -> f32 {
    (0.299 * r + 0.587 * g + 0.114 * b).round()
}
