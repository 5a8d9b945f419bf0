//! The FMI 2.0 C ABI, written once for every FMU of the project and shared with the importer.
//!
//! - [`types`]: the C types of the FMI 2.0 headers (also used by the orchestrator to import).
//! - [`variables`]: the variable table an FMU declares, and the value store built from it.
//! - [`model`]: the [`Model`] trait, the only thing an FMU crate implements.
//! - [`instance`]: one instance and the co-simulation state machine, in safe Rust.
//! - [`export`]: the 34 C entry points, generic over the model; [`export_fmu!`] instantiates them.
//! - [`description`]: modelDescription.xml and documentation generated from the variable table.
//!
//! Guarantees every FMU built on this layer gives its importer:
//! - all 34 functions are exported; unsupported ones return fmi2Error with a logged reason;
//! - a call in the wrong state, an unknown value reference, a NULL array or a non-finite step
//!   returns fmi2Error with a logged message naming the problem, and changes nothing;
//! - every entry point catches panics: the call returns fmi2Fatal and the instance is marked
//!   fatal, the host process is never taken down;
//! - the logger receives the caller's componentEnvironment, our copy of the instance name, a
//!   non-NULL category, and "%s" as the format;
//! - no global mutable state: instances are independent and may run in parallel threads;
//! - fmi2Reset restores a fresh instance; FMU states can be saved, restored, freed and
//!   (de)serialized, and a restored state replays bit for bit;
//! - tolerated deviations: parameters and inputs set before fmi2SetupExperiment, no stop time,
//!   NULL callbacks or logger, NULL componentEnvironment, a second fmi2Terminate, a
//!   fmuResourceLocation in any of the forms importers send.

// `!(x > 0.0)` is how we reject NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod description;
pub mod export;
pub mod instance;
pub mod logger;
pub mod model;
pub mod resource;
pub mod step;
pub mod types;
pub mod units;
pub mod variables;

pub use logger::Logger;
pub use model::{InstantiateContext, Model, ModelInfo, StepOutcome};
pub use variables::{Values, VarSpec};
