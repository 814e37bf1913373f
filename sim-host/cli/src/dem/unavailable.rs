//! `sandjumper dem` and `figures dem` in a build without the `dem` feature: any arguments,
//! refused with exit status 2.

/// `dem` in a build without it.
pub mod command {
    crate::command::unavailable::stand_in! {
        DemArgs, run: "dem" needs "DEM" from "dem";
    }
}

/// `figures dem` in a build without it.
pub mod paper_figures {
    crate::command::unavailable::stand_in! {
        DemFiguresArgs, run: "figures dem" needs "DEM" from "dem";
    }
}
