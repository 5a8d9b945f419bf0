//! The C side of the export layer: pointer checks, argument conversion and panic containment
//! for each of the 34 FMI 2.0 co-simulation functions, generic over the model. The
//! [`export_fmu!`](crate::export_fmu) macro instantiates them as unmangled symbols in an FMU
//! crate. Nothing here keeps global state, so instances can run in parallel threads.
//!
//! One file per group of entry points; this one keeps what they all share: the tag that tells
//! our instances from foreign pointers, and `with`, which checks it and contains panics.

use crate::instance::{Instance, MAGIC};
use crate::model::Model;
use crate::types::*;
use std::any::Any;
use std::ffi::CStr;
use std::panic::{AssertUnwindSafe, catch_unwind};

mod fmu_macro;
mod lifecycle;
mod state;
mod status;
mod step;
mod values;

pub use fmu_macro::FUNCTION_NAMES;
pub use lifecycle::{
    enter_initialization_mode, exit_initialization_mode, free_instance, get_types_platform,
    get_version, instantiate, reset, set_debug_logging, setup_experiment, terminate,
};
pub use state::{
    deserialize_fmu_state, free_fmu_state, get_fmu_state, serialize_fmu_state,
    serialized_fmu_state_size, set_fmu_state,
};
pub use status::{
    get_boolean_status, get_integer_status, get_real_status, get_status, get_string_status,
};
pub use step::{cancel_step, do_step, unsupported};
pub use values::{
    get_boolean, get_integer, get_real, get_string, set_boolean, set_integer, set_real, set_string,
};

/// Distinguishes one model's instances from another's, so a pointer of the wrong FMU is refused.
const fn model_magic(guid: &str) -> u64 {
    let bytes = guid.as_bytes();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut i = 0;
    while i < bytes.len() {
        h ^= bytes[i] as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
        i += 1;
    }
    MAGIC ^ h
}

#[repr(C)]
struct Handle<M: Model> {
    magic: u64,
    inst: Instance<M>,
}

fn panic_text(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".into()
    }
}

/// The instance behind `c`, if `c` is one of this model's live instances.
///
/// # Safety
/// `c` must be NULL or a pointer the caller got from our fmi2Instantiate (the FMI contract); we
/// still check the tag so that a pointer from another FMU fails cleanly.
unsafe fn handle<'a, M: Model>(c: fmi2Component) -> Option<&'a mut Handle<M>> {
    if c.is_null() {
        return None;
    }
    let h = c as *mut Handle<M>;
    // SAFETY: per the contract above `c` points to readable memory at least one u64 long.
    if unsafe { (*h).magic } != const { model_magic(M::INFO.guid) } {
        return None;
    }
    // SAFETY: the tag matched: `h` is one of our live handles.
    Some(unsafe { &mut *h })
}

/// Runs `f` on the instance with panics contained: a panic marks the instance fatal.
unsafe fn with<M: Model>(
    c: fmi2Component,
    function: &str,
    f: impl FnOnce(&mut Instance<M>) -> Result<fmi2Status, fmi2Status>,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `handle` checks the tag.
    let Some(h) = (unsafe { handle::<M>(c) }) else {
        return fmi2Status::Error;
    };
    let inst: *mut Instance<M> = &mut h.inst;
    // After fmi2Fatal nothing but fmi2FreeInstance (which does not come through here).
    // SAFETY: `inst` points into the live handle `h`, borrowed for this call only.
    if let Err(s) = unsafe { &*inst }.refuse_if_fatal(function) {
        return s;
    }
    // SAFETY: `inst` points into the live handle `h`, borrowed for this call only.
    match catch_unwind(AssertUnwindSafe(|| f(unsafe { &mut *inst }))) {
        Ok(Ok(s)) | Ok(Err(s)) => s,
        Err(payload) => {
            let text = panic_text(payload.as_ref());
            // SAFETY: `inst` points into the live handle `h`, borrowed for this call only.
            let inst = unsafe { &mut *inst };
            let _ = catch_unwind(AssertUnwindSafe(|| {
                inst.poison(&format!(
                    "{function}: internal error ({text}); the instance can only be freed"
                ))
            }));
            fmi2Status::Fatal
        }
    }
}

/// A slice from a C array, or an error naming the argument when it is NULL.
unsafe fn slice<'a, T>(
    inst: &Instance<impl Model>,
    p: *const T,
    n: usize,
    what: &str,
    function: &str,
) -> Result<&'a [T], fmi2Status> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        inst.log
            .error(&format!("{function}: {what} is NULL but nvr = {n}"));
        return Err(fmi2Status::Error);
    }
    // SAFETY: `p` is non-NULL (checked above) and, by the FMI contract, points to `n` values.
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

unsafe fn slice_mut<'a, T>(
    inst: &Instance<impl Model>,
    p: *mut T,
    n: usize,
    what: &str,
    function: &str,
) -> Result<&'a mut [T], fmi2Status> {
    if n == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        inst.log
            .error(&format!("{function}: {what} is NULL but nvr = {n}"));
        return Err(fmi2Status::Error);
    }
    // SAFETY: `p` is non-NULL (checked above) and, by the FMI contract, points to `n` values.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

unsafe fn string_arg(p: fmi2String) -> Option<String> {
    if p.is_null() {
        return None;
    }
    // SAFETY: the pointer is NULL (handled) or a NUL-terminated string, as FMI requires of string arguments.
    Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}

fn ok(r: Result<(), fmi2Status>) -> Result<fmi2Status, fmi2Status> {
    r.map(|()| fmi2Status::OK)
}
