//! Import of FMI 2.0 co-simulation FMUs: open any `.fmu`, instantiate it, drive it.
//!
//! ```no_run
//! use fmi_import::{Fmu, LogConfig};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let fmu = Fmu::open("target/fmu/RailVehicle.fmu".as_ref())?;
//! let (_, acc) = fmu.value_reference("ws_acc_y")?;
//! let mut vehicle = fmu.instantiate("vehicle", LogConfig::default())?;
//! vehicle.setup_experiment(0.0, Some(1.0), None)?;
//! vehicle.enter_initialization_mode()?;
//! vehicle.exit_initialization_mode()?;
//! let mut y = [0.0];
//! for k in 0..1000 {
//!     vehicle.do_step(k as f64 * 1e-3, 1e-3)?;
//!     vehicle.get_real(&[acc], &mut y)?;
//! }
//! vehicle.terminate()?;
//! # Ok(()) }
//! ```
//!
//! # Opening ([`Fmu::open`])
//! The archive is unpacked into a fresh temporary directory that lives as long as the
//! [`Fmu`] and its instances (an FMU may read its resources at any time), and is removed after
//! the library is unloaded. Before a single byte is written, every entry is checked, and the
//! archive refused with the offending entry named, if it is an absolute path, has a `..`
//! component, contains a backslash or NUL, is a symbolic link or other special file (by the
//! unix mode stored in the entry), or appears twice: an FMU is foreign input, and a crafted
//! archive must not write outside its directory (zip-slip) or plant links. Files are then
//! created with `create_new` only. Zip bombs are refused by [`UnpackLimits`] (default 4 GiB
//! uncompressed, 100 000 entries; [`Fmu::open_with_limits`] sets others): on the sizes the
//! entries declare before anything is written, and on the bytes actually decompressed, since
//! declared sizes can lie.
//!
//! The model description must parse (errors give line and column), declare FMI 2.x and a
//! `<CoSimulation>` element. The binary is `binaries/<platform>/<modelIdentifier>.<ext>`
//! (linux64/linux32/darwin64/win64/win32, from the build target); when it is missing the error
//! lists the platform folders the FMU does have. It is loaded with `RTLD_NOW | RTLD_LOCAL`:
//! an undefined symbol is reported now with the loader's message, instead of killing the
//! process at the first call that needs it, and several FMUs exporting the same `fmi2...`
//! names cannot interpose each other. All 34 functions are resolved once into a struct of
//! plain function pointers (a missing function is one error listing every missing name), and
//! `fmi2GetVersion`/`fmi2GetTypesPlatform` must say "2.0"/"default".
//!
//! # Logging: the C shim
//! `fmi2CallbackLogger` is a C-variadic, printf-style function; Rust cannot define one. A
//! small C file (csrc/logger.c, built by build.rs with `cc`) is the logger every instance
//! gets: it drops messages below the instance's threshold before formatting, formats with
//! `vsnprintf` (a second, heap-sized pass for long messages, so nothing is truncated
//! silently; NULL instance/category/format tolerated), and hands the text to a Rust function
//! that catches panics. The componentEnvironment is a per-instance [`LogConfig`]-derived state
//! that lives until after fmi2FreeInstance: the sink, `min_status`, and a buffer of the
//! warnings and errors logged during the current call, which [`FmiError::messages`] quotes.
//! The memory callbacks are the C library's `calloc`/`free`.
//!
//! # Error policy
//! [`ImportError`]: the FMU cannot be opened or instantiated; always names the `.fmu` file,
//! and the entry, library, symbols or variable where that applies. A NULL from
//! fmi2Instantiate quotes what the FMU logged (e.g. its GUID-mismatch message).
//!
//! [`FmiError`]: a call returned fmi2Discard, fmi2Error, fmi2Fatal or fmi2Pending (fmi2OK and
//! fmi2Warning are success). It names the function, instance, file, status, the time, and
//! the messages; for fmi2DoStep's fmi2Discard also fmi2LastSuccessfulTime. Statuses are read
//! as plain ints, so a library returning garbage is fmi2Fatal, not undefined behaviour.
//! Dropping an [`Instance`] terminates it if it is initialized and not terminated, then frees
//! it; after fmi2Error it only frees it (terminating is illegal there); after fmi2Fatal it
//! calls nothing and leaks the instance and the library mapping on purpose (the standard
//! allows no further call, and a broken FMU might still run code).
//!
//! Every `extern "C"` function of this crate (the log delivery) catches panics: a panicking
//! log sink never unwinds into the FMU.
//!
//! # Speed
//! `do_step`, `get_*`/`set_*` for numbers are one indirect call plus one atomic load (to
//! reset the per-call message buffer only when something was logged) and a status compare;
//! no allocation on the success path (booleans go through a reused scratch buffer). See
//! `benches/overhead.rs`.
//!
//! # Threads
//! [`Fmu`] is `Send + Sync` and cheap to clone. [`Instance`] is `Send`: FMI 2.0 lets
//! different instances run in different threads, and every FMU call goes through `&mut
//! self`, so one instance is only ever entered by one thread at a time. [`FmuState`] is
//! `Send + Sync`: dropping one never calls the FMU (its instance frees it later), so it cannot
//! race the thread stepping the instance.

// The error types are large on purpose: they carry the file, instance, time and the FMU's own
// messages, and FmiError's fields are public API. They are only built on the cold path; on
// success a `Result<(), FmiError>` is a discriminant, so boxing would buy nothing.
#![allow(clippy::result_large_err)]

mod error;
mod fmu;
mod instance;
mod library;
mod logging;
mod unpack;

pub use error::{FmiError, ImportError};
pub use fmi_abi::types::fmi2Status;
pub use fmu::Fmu;
pub use instance::{FmuState, Instance};
pub use library::platform_binary;
pub use logging::{LogConfig, LogRecord, stderr_sink};
pub use model_description::ModelDescription;
pub use unpack::UnpackLimits;

/// The FMU's shared library at the level of the C API: the 34 functions as raw pointers (every
/// status a `c_int`), for tools that must call them with any argument in any state, such as the
/// `fmi-fuzz` state-machine fuzzer. [`Instance`] is the safe way to drive an FMU.
pub mod raw {
    pub use crate::library::{Functions, NAMES, load};
}
