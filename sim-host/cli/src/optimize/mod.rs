//! `sandjumper optimize`: the best stroke the robot can make ([`sandjumper_optimize`]).

pub mod command;
