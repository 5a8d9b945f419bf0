//! The orchestrator's test helper, shared rather than copied: where the tests find the
//! packaged FMUs.

#[path = "../../../orchestrator/tests/common/mod.rs"]
mod shared;

#[allow(unused_imports)] // each test crate uses its own part
pub use shared::{fmu, hidden_files, mkfifo};

/// The packaged vehicle and estimator FMUs, as the studies run them.
#[allow(dead_code)] // not every test crate runs the studies
pub fn fmus() -> alignment_studies::study::runs::Fmus {
    alignment_studies::study::runs::Fmus::new(fmu("RailVehicle"), fmu("AlignmentEstimator"))
}
