//! Hostile-caller checks for FMI 2.0 co-simulation FMUs (issue 7, part A).
//!
//! - [`fuzz`]: a seeded state-machine fuzzer over all 34 fmi2 functions with edge-case and
//!   NULL arguments, checked against [`oracle`] (the standard's state table) after every call;
//! - [`runner`]: runs batches of sequences in child processes (this binary re-invoked), so
//!   that a segfault, an abort or a hang is caught and reported with the seed that causes it,
//!   and replays a seed with its call trace;
//! - [`cycles`]: instantiate / initialize / step / FMU-state / free cycles, to run under
//!   valgrind;
//! - [`api`]: an FMU opened for raw calls; [`log`]: the logger callback (a C shim);
//! - [`cli`]: the command line, one module per command (`main.rs` only dispatches).
//!
//! Reproduce any failure with `fmi-fuzz --fmu <FMU> --seed <seed> --sequences 1 --trace`.

// `!(x > 0.0)` is how NaN is caught together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod api;
pub mod cli;
pub mod cycles;
pub mod fuzz;
pub mod log;
pub mod oracle;
pub mod rng;
pub mod runner;
