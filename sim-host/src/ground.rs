//! ground (in progress)
