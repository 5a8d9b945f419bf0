//! The fmi2Get*Status queries about asynchronous steps; we never step asynchronously, so only
//! the last successful time and the terminated flag have answers.

use super::{slice_mut, with};
use crate::model::Model;
use crate::types::*;
use std::ffi::c_int;

/// # Safety
/// FMI contract.
pub unsafe fn get_status<M: Model>(c: fmi2Component, kind: c_int, value: *mut c_int) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetStatus", |inst| {
            inst.check_status_query("fmi2GetStatus")?;
            let _ = slice_mut(inst, value, 1, "value", "fmi2GetStatus")?;
            inst.log
                .call(|| format!("fmi2GetStatus({kind}): no asynchronous step, nothing to report"));
            Ok(fmi2Status::Discard)
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn get_real_status<M: Model>(
    c: fmi2Component,
    kind: c_int,
    value: *mut f64,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetRealStatus", |inst| {
            inst.check_status_query("fmi2GetRealStatus")?;
            let out = slice_mut(inst, value, 1, "value", "fmi2GetRealStatus")?;
            if kind == FMI2_LAST_SUCCESSFUL_TIME {
                out[0] = inst.last_successful_time();
                Ok(fmi2Status::OK)
            } else {
                Ok(fmi2Status::Discard)
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn get_integer_status<M: Model>(
    c: fmi2Component,
    _kind: c_int,
    value: *mut c_int,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetIntegerStatus", |inst| {
            inst.check_status_query("fmi2GetIntegerStatus")?;
            let _ = slice_mut(inst, value, 1, "value", "fmi2GetIntegerStatus")?;
            Ok(fmi2Status::Discard)
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn get_boolean_status<M: Model>(
    c: fmi2Component,
    kind: c_int,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetBooleanStatus", |inst| {
            inst.check_status_query("fmi2GetBooleanStatus")?;
            let out = slice_mut(inst, value, 1, "value", "fmi2GetBooleanStatus")?;
            if kind == FMI2_TERMINATED {
                out[0] = if inst.terminated() {
                    FMI2_TRUE
                } else {
                    FMI2_FALSE
                };
                Ok(fmi2Status::OK)
            } else {
                Ok(fmi2Status::Discard)
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn get_string_status<M: Model>(
    c: fmi2Component,
    _kind: c_int,
    value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetStringStatus", |inst| {
            inst.check_status_query("fmi2GetStringStatus")?;
            let _ = slice_mut(inst, value, 1, "value", "fmi2GetStringStatus")?;
            Ok(fmi2Status::Discard)
        })
    }
}
