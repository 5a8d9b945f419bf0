//! A fast, strict FMI 2.0 co-simulation master.
//!
//! - [`system`]: components, connections, parameters, experiment (independent of any file format);
//! - [`ssp`]: SSP 1.0 system descriptions (.ssd / .ssp) read and written;
//! - [`resolve`]: checks a system against its FMUs (connections, types, parameters, algebraic loops);
//! - [`master`]: instantiation, initialization with propagated values, Gauss-Seidel/Jacobi stepping;
//! - [`record`]: the results writer;
//! - [`simulate`]: one FMU with input signals from a CSV file;
//! - [`info`]: the description of an FMU.
//!
//! FMUs are loaded by the `fmi-import` crate.

pub mod info;
pub mod master;
pub mod record;
pub mod resolve;
pub mod simulate;
pub mod ssp;
pub mod study;
pub mod system;
