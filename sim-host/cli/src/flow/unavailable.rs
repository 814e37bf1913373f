//! `sandjumper piv` and `piv-synthetic` in a build without the `imaging` feature: any
//! arguments, refused with exit status 2.

/// The commands in a build without them.
pub mod command {
    crate::command::unavailable::stand_in! {
        PivArgs, run: "piv" needs "PIV" from "imaging";
        SyntheticArgs, run_synthetic: "piv-synthetic" needs "PIV" from "imaging";
    }
}
