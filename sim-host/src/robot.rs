//! robot (in progress)
