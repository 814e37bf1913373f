//! `sandjumper-sim`: the plant simulator (MODEL.md) and the `sandjumper` CLI.
