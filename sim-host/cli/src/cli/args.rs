//! The `sandjumper` command line as clap sees it: the subcommands, each defined beside the
//! code that runs it, and `params`' own arguments.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use crate::acqlog::command::LogArgs;
use crate::command::args::parse_phi;
use crate::flow::command::{PivArgs, SyntheticArgs};
use crate::imaging::command::{CameraScaleArgs, TrackArgs};
use crate::rig::hil::command::HilArgs;
use crate::rig::tool::RigArgs;
use crate::study::figures::FiguresArgs;
use crate::study::fit::FitArgs;
use crate::study::jump_command::JumpArgs;
use crate::study::replay::ReplayArgs;
use crate::study::sweep::{MergeArgs, SweepArgs};

/// Simulate the spring-mass jumping robot on granular media (Aguilar & Goldman, Nature
/// Physics 2016). Exit status: 0 success, 2 bad input, 1 internal failure.
#[derive(Debug, Parser)]
#[command(name = "sandjumper", version, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
// A build without some features has small stand-ins for their commands' arguments.
#[cfg_attr(
    not(all(
        feature = "rig",
        feature = "imaging",
        feature = "dem",
        feature = "campaign"
    )),
    allow(clippy::large_enum_variant)
)]
pub enum Command {
    /// Simulate one jump: a summary (or --json), and with --out the time series, parameters,
    /// summary and a figure.
    Jump(JumpArgs),
    /// Simulate every combination of kinds, models, packing fractions, delays and frequencies,
    /// in parallel; writes sweep.csv, failures.csv, sweep.toml, parameters and figures.
    Sweep(SweepArgs),
    /// Join the shard directories of one sweep (`sweep --shard I/N`) into one sweep directory.
    Merge(MergeArgs),
    /// Print the resolved parameters as TOML (re-readable with --params).
    Params(ParamsArgs),
    /// Fit the granular model to measurements (intrusion curves, added mass, jump heights);
    /// writes a params file for --params.
    Fit(FitArgs),
    /// Regenerate the simulations behind the paper's figures: PNG, SVG and CSV.
    Figures(FiguresArgs),
    /// Search for the stroke that jumps highest (or best by another objective) within the
    /// rig's limits; compare it with the best single, stutter and delayed stutter; re-run
    /// both through the controller; write stroke.csv for jump, hil and rig replay --stroke.
    Optimize(Box<crate::optimize::command::OptimizeArgs>),
    /// Run one jump through the control loop against the simulated rig: the core in-process
    /// (sil), the firmware in QEMU (pil), the F407 release binary on the virtual board (f407)
    /// or a board on a serial port (serial:PATH).
    Hil(HilArgs),
    /// Replay an acquisition log's encoder record in the simulator (the paper's method):
    /// reports what `jump` reports, and predicted vs measured if the log has measurements.
    Replay(ReplayArgs),
    /// Check (validate and summarise) or convert acquisition logs.
    Log(LogArgs),
    /// Track the rod's ball through camera frames (sub-pixel) and measure the jump height
    /// the paper's way: the apex of a free-flight parabola minus the rest height.
    Track(TrackArgs),
    /// The camera's metres per pixel from frames of a slow motor move and its encoder log.
    CameraScale(CameraScaleArgs),
    /// PIV of side-wall grain videos: multipass FFT correlation with window deformation,
    /// validation, shear rate, grain momentum and added mass.
    Piv(Box<PivArgs>),
    /// Grain images with a known motion (shift, shear, rotation, a descending foot's cone),
    /// to test PIV settings against.
    PivSynthetic(SyntheticArgs),
    /// The 2-D DEM of Supplementary I: prepare a bed, intrude, check a collision
    Dem(crate::dem::command::DemArgs),
    /// Automated campaigns: prepare the bed to a target phi, jump, record and analyse over a
    /// parameter space; resumable after a crash
    Campaign(crate::campaign::command::CampaignArgs),
    /// The rig's board over its USB serial port (--port PATH), or a simulated controller and
    /// rig (--link sil|pil|f407): flash, status, jump, intrude, replay.
    Rig(RigArgs),
}

/// `sandjumper params`.
#[derive(Debug, Clone, Args)]
pub struct ParamsArgs {
    /// Packing fraction phi of the sand (presets 0.57..=0.62).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = parse_phi, allow_negative_numbers = true)]
    pub phi: f64,
    /// TOML file overriding any parameter.
    #[arg(long, value_name = "FILE.toml")]
    pub params: Option<PathBuf>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::args::{KindArg, ModelArg};
    use clap::{CommandFactory, ValueEnum};
    use sandjumper_core::trajectory::JumpKind;
    use sandjumper_model::params::ModelName;

    #[test]
    fn clap_definitions_are_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn kinds_and_models_map_to_the_library_names() {
        assert_eq!(JumpKind::from(KindArg::Delayed), JumpKind::DelayedStutter);
        for m in ModelArg::value_variants() {
            let name = m.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(ModelName::from(*m).as_str(), name);
        }
    }

    #[test]
    fn sweep_takes_lists_and_ranges() {
        let cli = Cli::try_parse_from([
            "sandjumper",
            "sweep",
            "--kind",
            "single,stutter",
            "--freq",
            "5:7:1",
            "--model",
            "eq1,eq4",
            "--out",
            "x",
        ])
        .unwrap();
        let Command::Sweep(a) = cli.command else {
            panic!("not a sweep")
        };
        assert_eq!(a.kind, vec![KindArg::Single, KindArg::Stutter]);
        assert_eq!(a.freq.values, vec![5.0, 6.0, 7.0]);
        assert_eq!(a.model, vec![ModelArg::Eq1, ModelArg::Eq4]);
        assert_eq!(a.tau.values, vec![0.0]);
    }
}
