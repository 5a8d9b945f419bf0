//! Stepping: fmi2DoStep and fmi2CancelStep, and the common body of the optional functions this
//! layer does not provide (they fail with a logged reason).

use super::with;
use crate::model::Model;
use crate::types::*;

/// # Safety
/// FMI contract.
pub unsafe fn do_step<M: Model>(
    c: fmi2Component,
    t: f64,
    h: f64,
    _no_set_prior: fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe { with::<M>(c, "fmi2DoStep", |inst| inst.do_step(t, h)) }
}

/// # Safety
/// FMI contract.
pub unsafe fn cancel_step<M: Model>(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2CancelStep", |inst| {
            inst.log.error(
                "fmi2CancelStep: this FMU never returns fmi2Pending, so there is no step to cancel",
            );
            Err(fmi2Status::Error)
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn unsupported<M: Model>(c: fmi2Component, function: &str, why: &str) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, function, |inst| {
            inst.log
                .error(&format!("{function} is not supported: {why}"));
            Err(fmi2Status::Error)
        })
    }
}
