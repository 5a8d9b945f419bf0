//! A fast, strict FMI 2.0 co-simulation master.
//!
//! - [`system`]: components, connections, parameters, experiment (independent of any file format);
//! - [`ssp`]: SSP 1.0 system descriptions (.ssd / .ssp) read and written;
//! - [`resolve`]: checks a system against its FMUs (connections, types, parameters, algebraic loops);
//! - [`master`]: instantiation, initialization with propagated values, Gauss-Seidel/Jacobi
//!   stepping; its seams: external inputs by `component.variable`, [`master::Observer`]s (the
//!   recording is one; an observer can end a run), a per-run [`master::StopToken`];
//! - [`outdir`], [`outfile`]: what a command may write and replace (one policy for all);
//! - [`record`]: the results writer;
//! - [`parquet`]: Parquet tables of numbers (recordings and results), with units and provenance;
//! - [`simulate`]: one FMU with input signals from a CSV file;
//! - [`info`]: the description of an FMU;
//! - [`cli`]: the command line's commands as functions returning values.
//!
//! FMUs are loaded by the `fmi-import` crate.

// FmiError and ImportError carry the FMU path, the call and the FMU's messages; they are
// returned only when a run stops, so their size costs nothing on the stepping path (measured
// in benches/master.rs).
#![allow(clippy::result_large_err)]
// `!(x > 0.0)` is how we reject NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cli;
pub mod csv;
pub mod info;
pub mod input;
pub mod master;
pub mod outdir;
pub mod outfile;
pub mod parquet;
pub mod record;
pub mod resolve;
pub mod simulate;
pub mod ssp;
pub mod system;
