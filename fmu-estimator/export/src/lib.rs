//! The 34 FMI 2.0 co-simulation functions of [`fmu_estimator::Estimator`], built as the shared library
//! that `cargo xtask fmu` packages into `AlignmentEstimator.fmu`.
//!
//! A crate of its own so that the model crate carries no `#[no_mangle]` `fmi2*` symbols: the
//! orchestrator and xtask link several model crates at once, and identical exported symbols
//! from each would clash at link time (they did in a non-incremental debug build of xtask).

fmi_abi::export_fmu!(fmu_estimator::Estimator);
