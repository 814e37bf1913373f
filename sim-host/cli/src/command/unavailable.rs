//! A command in a build without its feature (the README's first command builds with
//! `--no-default-features`): it still parses, whatever its arguments, and is refused with exit
//! status 2, saying how to build it.

use crate::command::CliError;

/// Whatever was given to a command this build has not got.
#[derive(Debug, Clone, clap::Args)]
pub struct Unbuilt {
    /// The arguments, unread.
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, hide = true)]
    pub rest: Vec<String>,
}

/// Refuse `command`: this build has no `what`, which the cargo feature `feature` builds.
pub fn refuse(command: &str, what: &str, feature: &str) -> Result<(), CliError> {
    Err(CliError::input(format!(
        "{command}: this build has no {what} (built with --no-default-features; build \
         sandjumper-cli with its default features, or with --features {feature})"
    )))
}

/// The stand-ins of a module's commands: for each, `ARGS, RUN: "command" needs "what" from
/// "feature";` declares `ARGS` ([`Unbuilt`]) and `RUN`, which [`refuse`]s it. (A build with
/// every feature has no stand-in.)
#[allow(unused_macros)]
macro_rules! stand_in {
    ($($args:ident, $run:ident: $command:literal needs $what:literal from $feature:literal;)+) => {
        $(
            #[doc = concat!("Whatever was given to `", $command, "`.")]
            pub type $args = $crate::command::unavailable::Unbuilt;

            #[doc = concat!("Refuse `", $command, "`: this build has no ", $what, ".")]
            pub fn $run(_: &$args) -> Result<(), $crate::command::CliError> {
                $crate::command::unavailable::refuse($command, $what, $feature)
            }
        )+
    };
}
#[allow(unused_imports)]
pub(crate) use stand_in;
