//! Import of FMI 2.0 co-simulation FMUs (in progress).
