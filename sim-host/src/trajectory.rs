//! trajectory (in progress)
