//! Image sequences: a directory of frames, a glob, or one multi-page TIFF; PNG, TIFF and BMP;
//! 8- and 16-bit grey, RGB(A) converted to grey by BT.601 luma ([`luma_bt601`]).
//!
//! Frames of a directory or glob are ordered by the **number in the file name** (the last run
//! of digits: `frame_9.png` before `frame_10.png`), not lexically; that number is the frame's
//! number. A sequence is refused, naming the file and the reason, when it is empty, a file
//! cannot be read or decoded (truncated, not an image), a file name has no number or two
//! files share one, the frame size changes, or the bit depth changes.

use std::fmt;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use image::{DynamicImage, ImageReader};
use tiff::decoder::{Decoder as TiffDecoder, DecodingResult};

use super::frame::{BitDepth, GrayFrame, luma_bt601};

/// File extensions read from a directory (case-insensitive).
pub const EXTENSIONS: [&str; 4] = ["png", "tif", "tiff", "bmp"];

/// Why a sequence (or one of its frames) cannot be used.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceError {
    /// The directory, pattern, file or `file#page` concerned.
    pub source: String,
    /// What is wrong, and what is allowed.
    pub reason: String,
}

impl fmt::Display for SequenceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.source, self.reason)
    }
}

impl std::error::Error for SequenceError {}

fn err(source: impl fmt::Display, reason: impl Into<String>) -> SequenceError {
    SequenceError {
        source: source.to_string(),
        reason: reason.into(),
    }
}

/// One decoded frame of a sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceFrame {
    /// Position in the sequence (0, 1, ...).
    pub index: usize,
    /// The frame's number: from the file name, or the page of a multi-page TIFF.
    pub number: u64,
    /// Where it came from (`file`, or `file#page`).
    pub source: String,
    /// The pixels.
    pub frame: GrayFrame,
}

/// Where the frames are.
#[derive(Clone, Debug, PartialEq)]
enum Layout {
    /// One image per file, with the numbers from the names.
    Files(Vec<(u64, PathBuf)>),
    /// The pages of one TIFF.
    Pages { path: PathBuf, pages: usize },
}

/// An opened image sequence (files listed, nothing decoded yet).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageSequence {
    layout: Layout,
}

/// The last run of ASCII digits in a file's stem.
pub fn number_in_name(path: &Path) -> Option<u64> {
    let stem = path.file_stem()?.to_str()?;
    let end = stem.rfind(|c: char| c.is_ascii_digit())? + 1;
    let start = stem[..end]
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    stem[start..end].parse().ok()
}

fn has_image_extension(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| EXTENSIONS.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

fn is_tiff(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff"))
}

impl ImageSequence {
    /// Open `spec`: a directory (its PNG/TIFF/BMP files), a glob pattern (`*`, `?`, `[`), or
    /// one file (a multi-page TIFF gives one frame per page; another image, one frame).
    pub fn open(spec: &str) -> Result<Self, SequenceError> {
        let path = Path::new(spec);
        if path.is_dir() {
            let entries = std::fs::read_dir(path)
                .map_err(|e| err(spec, format!("cannot list the directory: {e}")))?;
            let mut files = Vec::new();
            for entry in entries {
                let p = entry
                    .map_err(|e| err(spec, format!("cannot list the directory: {e}")))?
                    .path();
                if p.is_file() && has_image_extension(&p) {
                    files.push(p);
                }
            }
            if files.is_empty() {
                return Err(err(
                    spec,
                    format!(
                        "no frames: the directory holds no {} file",
                        EXTENSIONS.join("/")
                    ),
                ));
            }
            return Self::numbered(files);
        }
        if spec.contains(['*', '?', '[']) {
            let paths = glob::glob(spec).map_err(|e| err(spec, format!("bad pattern: {e}")))?;
            let mut files = Vec::new();
            for p in paths {
                let p = p.map_err(|e| err(spec, format!("cannot read a match: {e}")))?;
                if p.is_file() {
                    files.push(p);
                }
            }
            if files.is_empty() {
                return Err(err(spec, "no frames: the pattern matches no file"));
            }
            return Self::numbered(files);
        }
        if !path.exists() {
            return Err(err(
                spec,
                "no such file or directory (allowed: a directory of frames, a glob, or a multi-page TIFF)",
            ));
        }
        if is_tiff(path) {
            let pages = count_tiff_pages(path)?;
            return Ok(Self {
                layout: Layout::Pages {
                    path: path.to_path_buf(),
                    pages,
                },
            });
        }
        Ok(Self {
            layout: Layout::Files(vec![(
                number_in_name(path).unwrap_or(0),
                path.to_path_buf(),
            )]),
        })
    }

    /// A sequence of the given files, ordered by the numbers in their names.
    pub fn numbered(files: Vec<PathBuf>) -> Result<Self, SequenceError> {
        let mut numbered = Vec::with_capacity(files.len());
        for f in files {
            let n = number_in_name(&f).ok_or_else(|| {
                err(
                    f.display(),
                    "no frame number in the file name (frames are ordered by the number in their names, e.g. frame_000012.png)",
                )
            })?;
            numbered.push((n, f));
        }
        numbered.sort();
        if let Some(w) = numbered.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(err(
                w[1].1.display(),
                format!(
                    "frame number {} is also the number of {}",
                    w[0].0,
                    w[0].1.display()
                ),
            ));
        }
        Ok(Self {
            layout: Layout::Files(numbered),
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        match &self.layout {
            Layout::Files(f) => f.len(),
            Layout::Pages { pages, .. } => *pages,
        }
    }

    /// Whether the sequence has no frame (never true for an opened one).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The frame numbers, in order.
    pub fn numbers(&self) -> Vec<u64> {
        match &self.layout {
            Layout::Files(f) => f.iter().map(|(n, _)| *n).collect(),
            Layout::Pages { pages, .. } => (0..*pages as u64).collect(),
        }
    }

    /// Frame `index` alone, decoded (`None` past the end).
    pub fn nth(&self, index: usize) -> Option<Result<SequenceFrame, SequenceError>> {
        match &self.layout {
            Layout::Files(files) => files.get(index).map(|(n, p)| {
                decode_file(p).map(|frame| SequenceFrame {
                    index,
                    number: *n,
                    source: p.display().to_string(),
                    frame,
                })
            }),
            Layout::Pages { .. } => self.frames().nth(index),
        }
    }

    /// The frames, decoded one by one in order; each checked against the first frame's size
    /// and bit depth.
    pub fn frames(&self) -> Box<dyn Iterator<Item = Result<SequenceFrame, SequenceError>> + '_> {
        let mut first: Option<(u32, u32, BitDepth, String)> = None;
        let check = move |f: SequenceFrame| -> Result<SequenceFrame, SequenceError> {
            let fr = &f.frame;
            match &first {
                None => {
                    first = Some((fr.width(), fr.height(), fr.depth(), f.source.clone()));
                    Ok(f)
                }
                Some((w, h, d, src)) => {
                    if (fr.width(), fr.height()) != (*w, *h) {
                        Err(err(
                            &f.source,
                            format!(
                                "frame size {}x{} differs from {w}x{h} of {src} (all frames must have one size)",
                                fr.width(),
                                fr.height()
                            ),
                        ))
                    } else if fr.depth() != *d {
                        Err(err(
                            &f.source,
                            format!(
                                "bit depth {} differs from {} of {src} (the depth may not change mid-sequence)",
                                fr.depth().bits(),
                                d.bits()
                            ),
                        ))
                    } else {
                        Ok(f)
                    }
                }
            }
        };
        let mut check = check;
        match &self.layout {
            Layout::Files(files) => Box::new(files.iter().enumerate().map(move |(i, (n, p))| {
                let frame = decode_file(p)?;
                check(SequenceFrame {
                    index: i,
                    number: *n,
                    source: p.display().to_string(),
                    frame,
                })
            })),
            Layout::Pages { path, pages } => {
                let mut pages_iter = TiffPages::new(path, *pages);
                Box::new(
                    std::iter::from_fn(move || pages_iter.next())
                        .map(move |r| r.and_then(&mut check)),
                )
            }
        }
    }
}

/// Decode one image file to grey.
pub fn decode_file(path: &Path) -> Result<GrayFrame, SequenceError> {
    let reader = ImageReader::open(path)
        .map_err(|e| err(path.display(), format!("cannot open: {e}")))?
        .with_guessed_format()
        .map_err(|e| err(path.display(), format!("cannot read: {e}")))?;
    let mut reader = reader;
    reader.no_limits();
    let image = reader.decode().map_err(|e| {
        err(
            path.display(),
            format!("cannot decode (truncated or not a PNG/TIFF/BMP image?): {e}"),
        )
    })?;
    to_gray(image).map_err(|reason| err(path.display(), reason))
}

/// A decoded image as a grey frame.
pub fn to_gray(image: DynamicImage) -> Result<GrayFrame, String> {
    let (w, h) = (image.width(), image.height());
    let bad = || "pixel buffer size does not match the image size".to_string();
    let luma = |p: [f32; 3]| luma_bt601(p[0], p[1], p[2]);
    match image {
        DynamicImage::ImageLuma8(i) => GrayFrame::from_u8(w, h, i.into_raw()).ok_or_else(bad),
        DynamicImage::ImageLuma16(i) => GrayFrame::from_u16(w, h, i.into_raw()).ok_or_else(bad),
        DynamicImage::ImageLumaA8(i) => {
            GrayFrame::from_u8(w, h, i.pixels().map(|p| p.0[0]).collect()).ok_or_else(bad)
        }
        DynamicImage::ImageLumaA16(i) => {
            GrayFrame::from_u16(w, h, i.pixels().map(|p| p.0[0]).collect()).ok_or_else(bad)
        }
        DynamicImage::ImageRgb8(_) | DynamicImage::ImageRgba8(_) => {
            let rgb = image.to_rgb8();
            let px = rgb.pixels().map(|p| luma(p.0.map(f32::from)) as u8);
            GrayFrame::from_u8(w, h, px.collect()).ok_or_else(bad)
        }
        DynamicImage::ImageRgb16(_) | DynamicImage::ImageRgba16(_) => {
            let rgb = image.to_rgb16();
            let px = rgb.pixels().map(|p| luma(p.0.map(f32::from)) as u16);
            GrayFrame::from_u16(w, h, px.collect()).ok_or_else(bad)
        }
        other => Err(format!(
            "pixel type {:?} not supported (allowed: 8- or 16-bit grey, RGB, RGBA)",
            other.color()
        )),
    }
}

fn open_tiff(path: &Path) -> Result<TiffDecoder<BufReader<File>>, SequenceError> {
    let file = File::open(path).map_err(|e| err(path.display(), format!("cannot open: {e}")))?;
    TiffDecoder::new(BufReader::new(file))
        .map(|d| d.with_limits(tiff::decoder::Limits::unlimited()))
        .map_err(|e| err(path.display(), format!("not a readable TIFF: {e}")))
}

fn count_tiff_pages(path: &Path) -> Result<usize, SequenceError> {
    let mut d = open_tiff(path)?;
    let mut pages = 1;
    while d.more_images() {
        d.next_image().map_err(|e| {
            err(
                format!("{}#{pages}", path.display()),
                format!("cannot read the page: {e}"),
            )
        })?;
        pages += 1;
    }
    Ok(pages)
}

/// The pages of a multi-page TIFF, decoded in order.
struct TiffPages {
    path: PathBuf,
    pages: usize,
    next: usize,
    decoder: Option<TiffDecoder<BufReader<File>>>,
}

impl TiffPages {
    fn new(path: &Path, pages: usize) -> Self {
        Self {
            path: path.to_path_buf(),
            pages,
            next: 0,
            decoder: None,
        }
    }

    fn next(&mut self) -> Option<Result<SequenceFrame, SequenceError>> {
        if self.next >= self.pages {
            return None;
        }
        let page = self.next;
        self.next += 1;
        let source = format!("{}#{page}", self.path.display());
        let result = (|| {
            if let Some(d) = self.decoder.as_mut() {
                d.next_image()
                    .map_err(|e| err(&source, format!("cannot read the page: {e}")))?;
            } else {
                self.decoder = Some(open_tiff(&self.path)?);
            }
            let Some(d) = self.decoder.as_mut() else {
                return Err(err(&source, "the TIFF decoder is gone"));
            };
            let (w, h) = d
                .dimensions()
                .map_err(|e| err(&source, format!("cannot read the page size: {e}")))?;
            let colour = d
                .colortype()
                .map_err(|e| err(&source, format!("cannot read the pixel type: {e}")))?;
            let data = d
                .read_image()
                .map_err(|e| err(&source, format!("cannot decode (truncated?): {e}")))?;
            tiff_page_to_gray(w, h, colour, data).map_err(|reason| err(&source, reason))
        })();
        Some(result.map(|frame| SequenceFrame {
            index: page,
            number: page as u64,
            source,
            frame,
        }))
    }
}

fn tiff_page_to_gray(
    w: u32,
    h: u32,
    colour: tiff::ColorType,
    data: DecodingResult,
) -> Result<GrayFrame, String> {
    use tiff::ColorType as C;
    let bad = || format!("pixel data of a {w}x{h} page has the wrong length");
    let luma = |p: &[f32]| luma_bt601(p[0], p[1], p[2]);
    match (colour, data) {
        (C::Gray(8), DecodingResult::U8(v)) => GrayFrame::from_u8(w, h, v).ok_or_else(bad),
        (C::Gray(16), DecodingResult::U16(v)) => GrayFrame::from_u16(w, h, v).ok_or_else(bad),
        (C::RGB(8) | C::RGBA(8), DecodingResult::U8(v)) => {
            let n = if matches!(colour, C::RGB(_)) { 3 } else { 4 };
            let px: Vec<u8> = v
                .chunks_exact(n)
                .map(|c| luma(&[c[0].into(), c[1].into(), c[2].into()]) as u8)
                .collect();
            GrayFrame::from_u8(w, h, px).ok_or_else(bad)
        }
        (C::RGB(16) | C::RGBA(16), DecodingResult::U16(v)) => {
            let n = if matches!(colour, C::RGB(_)) { 3 } else { 4 };
            let px: Vec<u16> = v
                .chunks_exact(n)
                .map(|c| luma(&[c[0].into(), c[1].into(), c[2].into()]) as u16)
                .collect();
            GrayFrame::from_u16(w, h, px).ok_or_else(bad)
        }
        (c, _) => Err(format!(
            "pixel type {c:?} not supported (allowed: 8- or 16-bit grey, RGB, RGBA)"
        )),
    }
}
