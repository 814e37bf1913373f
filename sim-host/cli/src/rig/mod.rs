//! The subcommands `sandjumper hil` and `sandjumper rig`: faces over `sandjumper_rig`'s typed
//! calls ([`sandjumper_rig::hil_command`], [`sandjumper_rig::tool`]).

pub mod face;
/// `sandjumper hil`.
pub mod hil {
    pub mod command;
}
pub mod tool;
