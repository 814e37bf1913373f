//! The motor's stroke (docs/model.md section 1): every trajectory and replay table stays within it.

/// Motor stroke limit: `|p| <= STROKE_M` (docs/model.md section 1), metres.
pub const STROKE_M: f64 = 0.025;
