//! The alignment-estimation studies of the paper, on top of the `orchestrator` master: accuracy
//! metrics in the EN 13848 bands, identification and calibration of the simplified model, the
//! paper's evaluation cases, the estimator's variants and the learned filters ([`study`]), and
//! the estimator run offline over recorded signals ([`smooth`]); what each command produces,
//! as a value ([`report`]); the command line's commands ([`cli`]).
//!
//! A crate of its own so that the master depends on no model, plotting or signal-processing
//! crate: a user of the master does not get the railway science, and the studies read as a
//! client of the master's library.

// RunError carries the FMU's messages; it is returned only when a run stops.
#![allow(clippy::result_large_err)]
// `!(x > 0.0)` is how we reject NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cli;
pub mod error;
pub mod report;
pub mod smooth;
pub mod study;

pub use error::Error;
