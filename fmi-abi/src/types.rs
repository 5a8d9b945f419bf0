//! The C types of the FMI 2.0 headers (`fmi2TypesPlatform.h`, `fmi2FunctionTypes.h`), shared by
//! the export layer and by the orchestrator's importer so both sides agree on one definition.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_int, c_uint, c_void};

/// An instance, opaque to the importer: what fmi2Instantiate returns and every call takes.
pub type fmi2Component = *mut c_void;
/// The importer's own pointer, handed back unchanged to its callbacks (the logger's first
/// argument); the FMU never dereferences it.
pub type fmi2ComponentEnvironment = *mut c_void;
/// A saved FMU state, opaque to the importer; owned by the instance that made it.
pub type fmi2FMUstate = *mut c_void;
/// A value reference: the handle of a variable within its base type, from modelDescription.xml
/// (our FMUs number them densely from 0; others need not).
pub type fmi2ValueReference = c_uint;
/// A Real value: a C double.
pub type fmi2Real = f64;
/// An Integer value: a C int.
pub type fmi2Integer = c_int;
/// A Boolean as a C int: compare with [`FMI2_TRUE`] / [`FMI2_FALSE`]; other values are
/// undefined by the standard.
pub type fmi2Boolean = c_int;
/// A character of an [`fmi2String`].
pub type fmi2Char = c_char;
/// A NUL-terminated string; strings the FMU returns stay valid only until its next call.
pub type fmi2String = *const c_char;
/// A byte of a serialized FMU state.
pub type fmi2Byte = c_char;

/// `fmi2True`.
pub const FMI2_TRUE: fmi2Boolean = 1;
/// `fmi2False`.
pub const FMI2_FALSE: fmi2Boolean = 0;

/// `fmi2Status`. Ordered by severity, so the worse of two statuses is their maximum.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum fmi2Status {
    /// The call succeeded.
    OK = 0,
    /// The call succeeded, but something was logged that the user should see.
    Warning = 1,
    /// The step was not completed as asked (in co-simulation: check fmi2Terminated and
    /// fmi2LastSuccessfulTime); the instance can still be used.
    Discard = 2,
    /// The call failed; the instance may be reset (fmi2Reset) or freed.
    Error = 3,
    /// The instance is unusable; only fmi2FreeInstance may follow.
    Fatal = 4,
    /// An asynchronous step is still running (never returned by our FMUs).
    Pending = 5,
}

impl fmi2Status {
    /// Maps the integer a foreign FMU returned; anything outside the enum counts as fatal.
    pub fn from_raw(v: c_int) -> fmi2Status {
        match v {
            0 => fmi2Status::OK,
            1 => fmi2Status::Warning,
            2 => fmi2Status::Discard,
            3 => fmi2Status::Error,
            5 => fmi2Status::Pending,
            _ => fmi2Status::Fatal,
        }
    }

    /// The standard's spelling, e.g. "fmi2Error", for messages a user can search the spec for.
    pub fn name(self) -> &'static str {
        match self {
            fmi2Status::OK => "fmi2OK",
            fmi2Status::Warning => "fmi2Warning",
            fmi2Status::Discard => "fmi2Discard",
            fmi2Status::Error => "fmi2Error",
            fmi2Status::Fatal => "fmi2Fatal",
            fmi2Status::Pending => "fmi2Pending",
        }
    }
}

/// `fmi2Type`: 0 = model exchange, 1 = co-simulation.
pub const FMI2_MODEL_EXCHANGE: c_int = 0;
/// `fmi2CoSimulation`: the only type our FMUs and importer support.
pub const FMI2_CO_SIMULATION: c_int = 1;

/// `fmi2StatusKind`.
pub const FMI2_DO_STEP_STATUS: c_int = 0;
/// `fmi2PendingStatus`: fmi2GetStringStatus's text while a step is pending.
pub const FMI2_PENDING_STATUS: c_int = 1;
/// `fmi2LastSuccessfulTime`: fmi2GetRealStatus's time reached by the last step, e.g. after
/// fmi2Discard.
pub const FMI2_LAST_SUCCESSFUL_TIME: c_int = 2;
/// `fmi2Terminated`: fmi2GetBooleanStatus is true when the FMU itself ended the simulation.
pub const FMI2_TERMINATED: c_int = 3;

/// The variadic, printf-style logger. Rust cannot define one but can call one; we always pass
/// the message through "%s" so that '%' in a message is never read as a conversion.
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, c_int, fmi2String, fmi2String, ...),
>;
/// calloc's contract: (count, size) -> zeroed memory or NULL. Our FMUs do not call it (they
/// declare canNotUseMemoryManagementFunctions).
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
/// free's contract, for memory from the matching allocateMemory.
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
/// Called by an FMU when an asynchronous fmi2DoStep ends (NULL: the importer steps
/// synchronously).
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, c_int)>;

/// `fmi2CallbackFunctions` (40 bytes on x86_64).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct fmi2CallbackFunctions {
    /// Where the FMU's messages go; may be NULL (then nothing is logged).
    pub logger: fmi2CallbackLogger,
    /// The importer's allocator.
    pub allocate_memory: fmi2CallbackAllocateMemory,
    /// Frees what `allocate_memory` returned.
    pub free_memory: fmi2CallbackFreeMemory,
    /// For asynchronous steps; may be NULL.
    pub step_finished: fmi2StepFinished,
    /// Passed back as the first argument of `logger` and `step_finished`.
    pub component_environment: fmi2ComponentEnvironment,
}

#[cfg(test)]
mod tests {
    #[test]
    fn callback_struct_has_the_c_layout() {
        assert_eq!(
            std::mem::size_of::<super::fmi2CallbackFunctions>(),
            5 * std::mem::size_of::<usize>()
        );
    }

    #[test]
    fn status_order_is_severity() {
        use super::fmi2Status::*;
        assert!(OK < Warning && Warning < Discard && Discard < Error && Error < Fatal);
        assert_eq!(super::fmi2Status::from_raw(42), Fatal);
    }
}
