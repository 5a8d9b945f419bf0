//! The C types of the FMI 2.0 headers (`fmi2TypesPlatform.h`, `fmi2FunctionTypes.h`), shared by
//! the export layer and by the orchestrator's importer so both sides agree on one definition.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_int, c_uint, c_void};

pub type fmi2Component = *mut c_void;
pub type fmi2ComponentEnvironment = *mut c_void;
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = c_uint;
pub type fmi2Real = f64;
pub type fmi2Integer = c_int;
pub type fmi2Boolean = c_int;
pub type fmi2Char = c_char;
pub type fmi2String = *const c_char;
pub type fmi2Byte = c_char;

pub const FMI2_TRUE: fmi2Boolean = 1;
pub const FMI2_FALSE: fmi2Boolean = 0;

/// `fmi2Status`. Ordered by severity, so the worse of two statuses is their maximum.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum fmi2Status {
    OK = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
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
pub const FMI2_CO_SIMULATION: c_int = 1;

/// `fmi2StatusKind`.
pub const FMI2_DO_STEP_STATUS: c_int = 0;
pub const FMI2_PENDING_STATUS: c_int = 1;
pub const FMI2_LAST_SUCCESSFUL_TIME: c_int = 2;
pub const FMI2_TERMINATED: c_int = 3;

/// The variadic, printf-style logger. Rust cannot define one but can call one; we always pass
/// the message through "%s" so that '%' in a message is never read as a conversion.
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, c_int, fmi2String, fmi2String, ...),
>;
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, c_int)>;

/// `fmi2CallbackFunctions` (40 bytes on x86_64).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct fmi2CallbackFunctions {
    pub logger: fmi2CallbackLogger,
    pub allocate_memory: fmi2CallbackAllocateMemory,
    pub free_memory: fmi2CallbackFreeMemory,
    pub step_finished: fmi2StepFinished,
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
