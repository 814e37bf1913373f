//! `sandjumper optimize` in a build without the `optimize` feature (the README's first
//! command builds without it): any arguments, refused with exit status 2.

/// The command in a build without it.
pub mod command {
    crate::command::unavailable::stand_in! {
        OptimizeArgs, run: "optimize" needs "optimiser" from "optimize";
    }
}
