//! The orchestrator's test helper, shared rather than copied: where the tests find the
//! packaged FMUs.

#[path = "../../../orchestrator/tests/common/mod.rs"]
mod shared;

pub use shared::fmu;
