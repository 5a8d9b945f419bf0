//! The co-simulation master (in progress).
