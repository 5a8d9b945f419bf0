//! fmi2Get/Set for Real, Integer, Boolean and String: C arrays checked and converted to slices,
//! fmi2Boolean to bool and C strings to owned ones, before the instance sees them.

use super::{ok, slice, slice_mut, string_arg, with};
use crate::model::Model;
use crate::types::*;
use std::ffi::c_int;

/// # Safety
/// FMI contract.
pub unsafe fn get_real<M: Model>(
    c: fmi2Component,
    vr: *const u32,
    n: usize,
    value: *mut f64,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetReal", |inst| {
            let vr = slice(inst, vr, n, "vr", "fmi2GetReal")?;
            let out = slice_mut(inst, value, n, "value", "fmi2GetReal")?;
            ok(inst.get_real(vr, out))
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn get_integer<M: Model>(
    c: fmi2Component,
    vr: *const u32,
    n: usize,
    value: *mut c_int,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetInteger", |inst| {
            let vr = slice(inst, vr, n, "vr", "fmi2GetInteger")?;
            let out = slice_mut(inst, value, n, "value", "fmi2GetInteger")?;
            ok(inst.get_integer(vr, out))
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn get_boolean<M: Model>(
    c: fmi2Component,
    vr: *const u32,
    n: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetBoolean", |inst| {
            let vr = slice(inst, vr, n, "vr", "fmi2GetBoolean")?;
            let out = slice_mut(inst, value, n, "value", "fmi2GetBoolean")?;
            let mut tmp = vec![false; n];
            inst.get_boolean(vr, &mut tmp)?;
            for (o, b) in out.iter_mut().zip(tmp) {
                *o = b as fmi2Boolean;
            }
            Ok(fmi2Status::OK)
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn get_string<M: Model>(
    c: fmi2Component,
    vr: *const u32,
    n: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetString", |inst| {
            let vr = slice(inst, vr, n, "vr", "fmi2GetString")?;
            let out = slice_mut(inst, value, n, "value", "fmi2GetString")?;
            let ptrs = inst.get_string(vr)?;
            out.copy_from_slice(&ptrs);
            Ok(fmi2Status::OK)
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn set_real<M: Model>(
    c: fmi2Component,
    vr: *const u32,
    n: usize,
    value: *const f64,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SetReal", |inst| {
            let vr = slice(inst, vr, n, "vr", "fmi2SetReal")?;
            let vals = slice(inst, value, n, "value", "fmi2SetReal")?;
            ok(inst.set_real(vr, vals))
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn set_integer<M: Model>(
    c: fmi2Component,
    vr: *const u32,
    n: usize,
    value: *const c_int,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SetInteger", |inst| {
            let vr = slice(inst, vr, n, "vr", "fmi2SetInteger")?;
            let vals = slice(inst, value, n, "value", "fmi2SetInteger")?;
            ok(inst.set_integer(vr, vals))
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn set_boolean<M: Model>(
    c: fmi2Component,
    vr: *const u32,
    n: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SetBoolean", |inst| {
            let vr = slice(inst, vr, n, "vr", "fmi2SetBoolean")?;
            let vals: Vec<bool> = slice(inst, value, n, "value", "fmi2SetBoolean")?
                .iter()
                .map(|&b| b != 0)
                .collect();
            ok(inst.set_boolean(vr, &vals))
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn set_string<M: Model>(
    c: fmi2Component,
    vr: *const u32,
    n: usize,
    value: *const fmi2String,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SetString", |inst| {
            let vr = slice(inst, vr, n, "vr", "fmi2SetString")?;
            let ptrs = slice(inst, value, n, "value", "fmi2SetString")?;
            let mut vals = Vec::with_capacity(n);
            for (i, &p) in ptrs.iter().enumerate() {
                match string_arg(p) {
                    Some(s) => vals.push(s),
                    None => {
                        inst.log
                            .error(&format!("fmi2SetString: value[{i}] is NULL"));
                        return Err(fmi2Status::Error);
                    }
                }
            }
            ok(inst.set_string(vr, &vals))
        })
    }
}
