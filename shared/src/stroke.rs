//! The motor's stroke (MODEL.md section 1): every trajectory and replay table stays within it.

/// Motor stroke limit: `|p| <= STROKE_M` (MODEL.md section 1), metres.
pub const STROKE_M: f64 = 0.025;
