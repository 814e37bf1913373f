//! integrate (in progress)
