//! The instance's life: version queries, fmi2Instantiate and fmi2FreeInstance, and the calls that
//! move it through the co-simulation state machine (setup, initialization, terminate, reset).

use super::{Handle, handle, model_magic, ok, slice, string_arg, with};
use crate::instance::Instance;
use crate::logger::Logger;
use crate::model::{InstantiateContext, Model};
use crate::resource::resource_dir;
use crate::types::*;
use std::ffi::{c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// fmi2GetTypesPlatform: "default", the platform types of the FMI 2.0 headers (a static string).
pub fn get_types_platform() -> *const c_char {
    c"default".as_ptr()
}

/// fmi2GetVersion: "2.0" (a static string).
pub fn get_version() -> *const c_char {
    c"2.0".as_ptr()
}

/// # Safety
/// Pointer arguments follow the FMI contract; NULLs are tolerated where noted in the crate docs.
pub unsafe fn instantiate<M: Model>(
    instance_name: fmi2String,
    fmu_type: c_int,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    let result = catch_unwind(AssertUnwindSafe(|| {
        let callbacks = if functions.is_null() {
            None
        } else {
            // SAFETY: `functions` is non-NULL (checked) and points to the importer's callback struct (FMI contract).
            Some(unsafe { *functions })
        };
        // SAFETY: the pointer is NULL (handled) or a NUL-terminated string, as FMI requires of string arguments.
        let name = unsafe { string_arg(instance_name) }.unwrap_or_default();
        let log = Logger::new(callbacks, &name, logging_on != 0);
        if instance_name.is_null() {
            log.warning("fmi2Instantiate: instanceName is NULL; using an empty name");
        }
        if fmu_type != FMI2_CO_SIMULATION {
            log.error(&format!(
                "fmi2Instantiate: fmuType {fmu_type} requested, but {} supports only co-simulation (fmi2CoSimulation = 1)",
                M::INFO.model_name
            ));
            return std::ptr::null_mut();
        }
        // SAFETY: the pointer is NULL (handled) or a NUL-terminated string, as FMI requires of string arguments.
        match unsafe { string_arg(guid) } {
            Some(g) if g.trim() == M::INFO.guid => {}
            Some(g) => {
                log.error(&format!(
                    "fmi2Instantiate: GUID '{g}' does not match this FMU's GUID '{}': the modelDescription.xml and the binary come from different FMUs or versions",
                    M::INFO.guid
                ));
                return std::ptr::null_mut();
            }
            None => {
                log.error("fmi2Instantiate: fmuGUID is NULL");
                return std::ptr::null_mut();
            }
        }
        // SAFETY: the pointer is NULL (handled) or a NUL-terminated string, as FMI requires of string arguments.
        let location = unsafe { string_arg(resource_location) };
        let resources = location.as_deref().and_then(resource_dir);
        if resources.is_none() {
            log.warning(&format!(
                "fmi2Instantiate: cannot use fmuResourceLocation {:?}; continuing without resources",
                location.as_deref().unwrap_or("NULL")
            ));
        }
        let ctx = InstantiateContext {
            instance_name: name,
            resources,
        };
        match Instance::<M>::new(&ctx, log) {
            Ok(inst) => {
                let h = Box::new(Handle {
                    magic: const { model_magic(M::INFO.guid) },
                    inst,
                });
                Box::into_raw(h) as fmi2Component
            }
            Err((log, e)) => {
                log.error(&format!("fmi2Instantiate: {e}"));
                std::ptr::null_mut()
            }
        }
    }));
    result.unwrap_or(std::ptr::null_mut())
}

/// # Safety
/// `c` is NULL or an instance of ours not yet freed.
pub unsafe fn free_instance<M: Model>(c: fmi2Component) {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `handle` checks the tag.
    if let Some(h) = unsafe { handle::<M>(c) } {
        h.magic = 0;
        // SAFETY: `h` came from `Box::into_raw` in fmi2Instantiate and its tag was live; it is cleared first, so a second free finds no instance.
        let boxed = unsafe { Box::from_raw(h as *mut Handle<M>) };
        let _ = catch_unwind(AssertUnwindSafe(move || drop(boxed)));
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn set_debug_logging<M: Model>(
    c: fmi2Component,
    on: fmi2Boolean,
    n: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SetDebugLogging", |inst| {
            let cats = slice(inst, categories, n, "categories", "fmi2SetDebugLogging")?;
            let names: Vec<String> = cats
                .iter()
                .map(|&p| string_arg(p).unwrap_or_default())
                .collect();
            let unknown = inst.log.set_categories(on != 0, &names);
            if unknown.is_empty() {
                Ok(fmi2Status::OK)
            } else {
                inst.log.warning(&format!(
                    "fmi2SetDebugLogging: unknown log categories {unknown:?} ignored"
                ));
                Ok(fmi2Status::Warning)
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn setup_experiment<M: Model>(
    c: fmi2Component,
    _tolerance_defined: fmi2Boolean,
    _tolerance: f64,
    start: f64,
    stop_defined: fmi2Boolean,
    stop: f64,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SetupExperiment", |inst| {
            ok(inst.setup_experiment(start, (stop_defined != 0).then_some(stop)))
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn enter_initialization_mode<M: Model>(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2EnterInitializationMode", |inst| {
            ok(inst.enter_initialization_mode())
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn exit_initialization_mode<M: Model>(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2ExitInitializationMode", |inst| {
            ok(inst.exit_initialization_mode())
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn terminate<M: Model>(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe { with::<M>(c, "fmi2Terminate", |inst| ok(inst.terminate())) }
}

/// # Safety
/// FMI contract.
pub unsafe fn reset<M: Model>(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe { with::<M>(c, "fmi2Reset", |inst| ok(inst.reset())) }
}
