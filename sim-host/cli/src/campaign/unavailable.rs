//! `sandjumper campaign` in a build without the `campaign` feature: any arguments, refused
//! with exit status 2.

/// The command in a build without it.
pub mod command {
    crate::command::unavailable::stand_in! {
        CampaignArgs, run: "campaign" needs "campaigns" from "campaign";
    }
}
