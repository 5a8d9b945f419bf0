//! The orchestrator's test helper, shared rather than copied: where the tests find the
//! packaged FMUs.

#[path = "../../../orchestrator/tests/common/mod.rs"]
mod shared;

#[allow(unused_imports)] // each test crate uses its own part
pub use shared::{fmu, hidden_files, mkfifo};
