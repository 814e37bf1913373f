//! `sandjumper piv FRAMES`: PIV of side-wall grain videos, the derived fields, grain momentum
//! and added mass; `sandjumper piv-synthetic`: grain images with a known motion. The runs are
//! `sandjumper_flow::run` and `sandjumper_flow::piv_synthetic`; this is their face.

use std::path::PathBuf;

use clap::Args;

use super::analysis::Pairing;
use super::piv::{PivConfig, SubPixel};
use super::piv_synthetic::SyntheticRequest;
pub use super::piv_synthetic::cone_displacement;
use super::preprocess::Preprocess;
use super::run::{PivRequest, parse_point, parse_ratio, parse_sigma, parse_windows};
use crate::command::CliError;
use crate::command::args::{parse_number, parse_positive};
use crate::command::progress::Bars;
use sandjumper_flow::FlowError;

/// `sandjumper piv`.
#[derive(Debug, Clone, Args)]
#[allow(clippy::struct_excessive_bools)]
pub struct PivArgs {
    /// The frames (a directory, a glob or a multi-page TIFF; see `track`).
    #[arg(value_name = "FRAMES")]
    pub frames: String,
    /// Pairing of the frames.
    #[arg(long, value_enum, default_value = "consecutive")]
    pub pairs: Pairing,
    /// Analyse every Nth pair.
    #[arg(long, value_name = "N", default_value = "1", value_parser = clap::value_parser!(u32).range(1..))]
    pub every: u32,
    /// Window sizes of the passes, px.
    #[arg(long, value_name = "N,N,..", default_value = "64,32,16")]
    pub windows: String,
    /// Window overlap, 0..=0.9.
    #[arg(long, value_name = "F", default_value = "0.5", value_parser = parse_number)]
    pub overlap: f64,
    /// Do not deform the windows (offset them by the rounded prediction instead).
    #[arg(long)]
    pub no_deform: bool,
    /// Sub-pixel peak estimator.
    #[arg(long, value_enum, default_value = "gaussian")]
    pub subpixel: SubPixel,
    /// Normalised median test threshold.
    #[arg(long, value_name = "X", default_value = "2", value_parser = parse_positive)]
    pub median_threshold: f64,
    /// Smallest accepted ratio of the first to the second correlation peak.
    #[arg(long, value_name = "X", default_value = "1.2", value_parser = parse_number)]
    pub min_peak_ratio: f64,
    /// Local contrast normalisation: each pixel against its neighbourhood's mean and spread
    /// (a Gaussian of this width, px, about a grain; 0: off). Gives dim, untextured grains
    /// contrast with no displacement bias.
    #[arg(long, value_name = "PX", default_value = "4", value_parser = parse_sigma)]
    pub local_contrast: f64,
    /// CLAHE tile size, px (0: no CLAHE, the default). PIVlab's 64 px tiles are fixed in the
    /// frame while the grains move through them: about 0.07 px of bias on real grain images.
    #[arg(long, value_name = "PX", default_value = "0")]
    pub clahe_tile: usize,
    /// CLAHE clip limit (share of a tile's pixels one grey level may hold).
    #[arg(long, value_name = "F", default_value = "0.01", value_parser = parse_positive)]
    pub clahe_clip: f64,
    /// Subtract the sequence's per-pixel minimum (the static background).
    #[arg(long)]
    pub subtract_background: bool,
    /// Cap intensities at median + S standard deviations (0: off).
    #[arg(long, value_name = "S", default_value = "0", value_parser = parse_number)]
    pub cap_sigma: f64,
    /// Static mask image (same size as the frames; non-zero pixels are not grain flow).
    #[arg(long, value_name = "MASK.png")]
    pub mask: Option<PathBuf>,
    /// The foot's outline per frame: CSV `frame,x_px,y_px`, the polygon's vertices in order;
    /// inside is masked, and its lowest point gives the foot's depth and velocity.
    #[arg(long, value_name = "FOOT.csv")]
    pub foot: Option<PathBuf>,
    /// Scale, metres per pixel (enables the SI fields, momentum and added mass).
    #[arg(long, value_name = "M", value_parser = parse_positive)]
    pub m_per_px: Option<f64>,
    /// Frame rate, frames/s.
    #[arg(long, value_name = "FPS", value_parser = parse_positive, conflicts_with = "log")]
    pub fps: Option<f64>,
    /// Acquisition log timing the frames by its camera ticks.
    #[arg(long, value_name = "ACQ.csv")]
    pub log: Option<PathBuf>,
    /// The foot's axis at the undisturbed surface, px: origin of x and height.
    #[arg(long, value_name = "X,Y", value_parser = parse_point)]
    pub origin: Option<(f64, f64)>,
    /// Packing fraction of the bed (momentum: rho phi).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = crate::command::args::parse_phi)]
    pub phi: f64,
    /// Grain density, kg/m^3.
    #[arg(long, value_name = "KG_M3", default_value = "1000", value_parser = parse_positive)]
    pub grain_density: f64,
    /// The added mass `P / v_foot` (P: the column under the foot) is kept only while the foot
    /// intrudes at least this fraction of its fastest intrusion (the paper's 0.3; near v = 0
    /// the ratio is singular), 0 to 1.
    #[arg(long, value_name = "RATIO", default_value = "0.3", value_parser = parse_ratio)]
    pub min_speed_ratio: f64,
    /// Write fields/, the .npy arrays, flow.csv, added_mass.csv, figures and piv.toml into DIR.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// `sandjumper piv-synthetic`.
#[derive(Debug, Clone, Args)]
pub struct SyntheticArgs {
    /// The sequence.
    #[command(flatten)]
    pub request: SyntheticRequest,
    /// Output directory (frame_NNNNNN.png, foot.csv for the cone, synthetic.toml).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

impl PivArgs {
    /// The request these arguments make (`--windows` parsed here).
    pub fn request(&self) -> Result<PivRequest, FlowError> {
        Ok(PivRequest {
            frames: self.frames.clone(),
            pairs: self.pairs,
            every: self.every as usize,
            piv: PivConfig {
                windows: parse_windows(&self.windows)?,
                overlap: self.overlap,
                deform: !self.no_deform,
                subpixel: self.subpixel,
                median_threshold: self.median_threshold,
                min_peak_ratio: self.min_peak_ratio,
            },
            preprocess: Preprocess {
                local_contrast_sigma_px: self.local_contrast,
                clahe_tile_px: self.clahe_tile,
                clahe_clip: self.clahe_clip,
                subtract_background: self.subtract_background,
                cap_sigma: self.cap_sigma,
            },
            mask: self.mask.clone(),
            foot: self.foot.clone(),
            m_per_px: self.m_per_px,
            fps: self.fps,
            log: self.log.clone(),
            origin_px: self.origin,
            phi: self.phi,
            grain_density_kg_m3: self.grain_density,
            min_speed_ratio: self.min_speed_ratio,
        })
    }
}

/// Run `sandjumper piv`: `--out` written (then `wrote DIR`), the notes, the summary.
pub fn run(a: &PivArgs) -> Result<(), CliError> {
    let progress = Bars::holding();
    let request = a.request()?;
    let (outcome, written) = match a.out.as_deref() {
        Some(out) => super::run::run_into(&request, out, &progress).map(|(o, d)| (o, Some(d)))?,
        None => (super::run::run(&request, &progress)?, None),
    };
    progress.release(written.as_deref());
    crate::command::print_outcome(a.json, &outcome, || outcome.summary_json())
}

/// Run `sandjumper piv-synthetic`.
pub fn run_synthetic(a: &SyntheticArgs) -> Result<(), CliError> {
    let outcome = super::piv_synthetic::run(&a.request, &Bars::new())?;
    let dir = outcome.write(&a.out)?;
    eprintln!("wrote {}", dir.display());
    Ok(())
}
