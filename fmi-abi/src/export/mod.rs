//! The C side of the export layer: pointer checks, argument conversion and panic containment
//! for each of the 34 FMI 2.0 co-simulation functions, generic over the model. The
//! [`export_fmu!`](crate::export_fmu) macro instantiates them as unmangled symbols in an FMU
//! crate. Nothing here keeps global state, so instances can run in parallel threads.

use crate::instance::{Instance, MAGIC, Snapshot, deserialize, serialize};
use crate::logger::Logger;
use crate::model::{InstantiateContext, Model};
use crate::resource::resource_dir;
use crate::types::*;
use std::any::Any;
use std::ffi::{CStr, c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

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

/// A boxed FMU state, tagged like an instance.
#[repr(C)]
struct StateBox<M: Model> {
    magic: u64,
    snap: Snapshot<M>,
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

pub fn get_types_platform() -> *const c_char {
    c"default".as_ptr()
}

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

/// The state box behind `s`, if it is one of this model's.
///
/// # Safety
/// `s` must be NULL or a pointer the caller got from our fmi2GetFMUstate or
/// fmi2DeSerializeFMUstate (the FMI contract); the tag is still checked.
unsafe fn state_box<'a, M: Model>(s: fmi2FMUstate) -> Option<&'a mut StateBox<M>> {
    if s.is_null() {
        return None;
    }
    let b = s as *mut StateBox<M>;
    // SAFETY: per the contract above `b` points to readable memory at least one u64 long.
    if unsafe { (*b).magic } != const { model_magic(M::INFO.guid) } {
        return None;
    }
    // SAFETY: the tag matched: `b` is one of our live state boxes.
    Some(unsafe { &mut *b })
}

fn new_state<M: Model>(snap: Snapshot<M>) -> fmi2FMUstate {
    Box::into_raw(Box::new(StateBox {
        magic: const { model_magic(M::INFO.guid) },
        snap,
    })) as fmi2FMUstate
}

/// # Safety
/// FMI contract.
pub unsafe fn get_fmu_state<M: Model>(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetFMUstate", |inst| {
            let slot = slice_mut(inst, state, 1, "FMUstate", "fmi2GetFMUstate")?;
            if slot[0].is_null() {
                slot[0] = new_state(inst.snapshot());
                return Ok(fmi2Status::OK);
            }
            match state_box::<M>(slot[0]) {
                Some(b) => {
                    b.snap.clone_from(&inst.sim);
                    Ok(fmi2Status::OK)
                }
                None => {
                    inst.log.error(
                        "fmi2GetFMUstate: *FMUstate is neither NULL nor a state of this FMU",
                    );
                    Err(fmi2Status::Error)
                }
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn set_fmu_state<M: Model>(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SetFMUstate", |inst| match state_box::<M>(state) {
            Some(b) => ok(inst.restore(&b.snap)),
            None => {
                inst.log
                    .error("fmi2SetFMUstate: FMUstate is NULL or not a state of this FMU");
                Err(fmi2Status::Error)
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn free_fmu_state<M: Model>(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2FreeFMUstate", |inst| {
            if state.is_null() || (*state).is_null() {
                return Ok(fmi2Status::OK);
            }
            match state_box::<M>(*state) {
                Some(b) => {
                    b.magic = 0;
                    drop(Box::from_raw(b as *mut StateBox<M>));
                    *state = std::ptr::null_mut();
                    Ok(fmi2Status::OK)
                }
                None => {
                    inst.log
                        .error("fmi2FreeFMUstate: FMUstate is not a state of this FMU");
                    Err(fmi2Status::Error)
                }
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn serialized_fmu_state_size<M: Model>(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SerializedFMUstateSize", |inst| {
            let out = slice_mut(inst, size, 1, "size", "fmi2SerializedFMUstateSize")?;
            let Some(b) = state_box::<M>(state) else {
                inst.log.error(
                    "fmi2SerializedFMUstateSize: FMUstate is NULL or not a state of this FMU",
                );
                return Err(fmi2Status::Error);
            };
            match serialize(&b.snap) {
                Ok(bytes) => {
                    out[0] = bytes.len();
                    Ok(fmi2Status::OK)
                }
                Err(e) => {
                    inst.log.error(&e);
                    Err(fmi2Status::Error)
                }
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn serialize_fmu_state<M: Model>(
    c: fmi2Component,
    state: fmi2FMUstate,
    bytes: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SerializeFMUstate", |inst| {
            let Some(b) = state_box::<M>(state) else {
                inst.log
                    .error("fmi2SerializeFMUstate: FMUstate is NULL or not a state of this FMU");
                return Err(fmi2Status::Error);
            };
            let data = serialize(&b.snap).map_err(|e| {
                inst.log.error(&e);
                fmi2Status::Error
            })?;
            if size < data.len() {
                inst.log.error(&format!(
                    "fmi2SerializeFMUstate: buffer of {size} bytes is smaller than the {} bytes fmi2SerializedFMUstateSize reports",
                    data.len()
                ));
                return Err(fmi2Status::Error);
            }
            let out = slice_mut(
                inst,
                bytes as *mut u8,
                data.len(),
                "serializedState",
                "fmi2SerializeFMUstate",
            )?;
            out.copy_from_slice(&data);
            Ok(fmi2Status::OK)
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn deserialize_fmu_state<M: Model>(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2DeSerializeFMUstate", |inst| {
            let data = slice(
                inst,
                bytes as *const u8,
                size,
                "serializedState",
                "fmi2DeSerializeFMUstate",
            )?;
            let slot = slice_mut(inst, state, 1, "FMUstate", "fmi2DeSerializeFMUstate")?;
            match deserialize::<M>(data) {
                Ok(snap) => {
                    if let Some(b) = state_box::<M>(slot[0]) {
                        b.snap = snap;
                    } else {
                        slot[0] = new_state(snap);
                    }
                    Ok(fmi2Status::OK)
                }
                Err(e) => {
                    inst.log.error(&format!("fmi2DeSerializeFMUstate: {e}"));
                    Err(fmi2Status::Error)
                }
            }
        })
    }
}

/// Exports the 34 FMI 2.0 co-simulation functions for `$model`. Use once, in a crate of its own
/// built as a `cdylib` (the FMU's `export/` crate), not in the model crate: two crates that both
/// export them cannot be linked into one program.
#[macro_export]
macro_rules! export_fmu {
    ($model:ty) => {
        mod __fmi2_exports {
            use super::*;
            use ::std::ffi::{c_char, c_int};
            use $crate::export as x;
            use $crate::types::*;
            type M = $model;

            #[unsafe(no_mangle)]
            pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
                x::get_types_platform()
            }
            #[unsafe(no_mangle)]
            pub extern "C" fn fmi2GetVersion() -> *const c_char {
                x::get_version()
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetDebugLogging(
                c: fmi2Component,
                on: fmi2Boolean,
                n: usize,
                cats: *const fmi2String,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::set_debug_logging::<M>(c, on, n, cats) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2Instantiate(
                name: fmi2String,
                ty: c_int,
                guid: fmi2String,
                res: fmi2String,
                functions: *const fmi2CallbackFunctions,
                visible: fmi2Boolean,
                logging_on: fmi2Boolean,
            ) -> fmi2Component {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::instantiate::<M>(name, ty, guid, res, functions, visible, logging_on) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::free_instance::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetupExperiment(
                c: fmi2Component,
                tol_defined: fmi2Boolean,
                tol: f64,
                start: f64,
                stop_defined: fmi2Boolean,
                stop: f64,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::setup_experiment::<M>(c, tol_defined, tol, start, stop_defined, stop) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::enter_initialization_mode::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::exit_initialization_mode::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::terminate::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::reset::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetReal(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *mut f64,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_real::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetInteger(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *mut c_int,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_integer::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetBoolean(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *mut fmi2Boolean,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_boolean::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetString(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *mut fmi2String,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_string::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetReal(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *const f64,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::set_real::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetInteger(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *const c_int,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::set_integer::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetBoolean(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *const fmi2Boolean,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::set_boolean::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetString(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *const fmi2String,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::set_string::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetFMUstate(
                c: fmi2Component,
                s: *mut fmi2FMUstate,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_fmu_state::<M>(c, s) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetFMUstate(
                c: fmi2Component,
                s: fmi2FMUstate,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::set_fmu_state::<M>(c, s) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2FreeFMUstate(
                c: fmi2Component,
                s: *mut fmi2FMUstate,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::free_fmu_state::<M>(c, s) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
                c: fmi2Component,
                s: fmi2FMUstate,
                size: *mut usize,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::serialized_fmu_state_size::<M>(c, s, size) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SerializeFMUstate(
                c: fmi2Component,
                s: fmi2FMUstate,
                bytes: *mut fmi2Byte,
                size: usize,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::serialize_fmu_state::<M>(c, s, bytes, size) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
                c: fmi2Component,
                bytes: *const fmi2Byte,
                size: usize,
                s: *mut fmi2FMUstate,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::deserialize_fmu_state::<M>(c, bytes, size, s) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
                c: fmi2Component,
                _unknown: *const fmi2ValueReference,
                _nu: usize,
                _known: *const fmi2ValueReference,
                _nk: usize,
                _dv_known: *const f64,
                _dv_unknown: *mut f64,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe {
                    x::unsupported::<M>(
                        c,
                        "fmi2GetDirectionalDerivative",
                        "providesDirectionalDerivative is false",
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
                c: fmi2Component,
                _vr: *const fmi2ValueReference,
                _n: usize,
                _order: *const c_int,
                _v: *const f64,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe {
                    x::unsupported::<M>(
                        c,
                        "fmi2SetRealInputDerivatives",
                        "canInterpolateInputs is false",
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
                c: fmi2Component,
                _vr: *const fmi2ValueReference,
                _n: usize,
                _order: *const c_int,
                _v: *mut f64,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe {
                    x::unsupported::<M>(
                        c,
                        "fmi2GetRealOutputDerivatives",
                        "maxOutputDerivativeOrder is 0",
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2DoStep(
                c: fmi2Component,
                t: f64,
                h: f64,
                no_prior: fmi2Boolean,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::do_step::<M>(c, t, h, no_prior) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::cancel_step::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetStatus(
                c: fmi2Component,
                kind: c_int,
                v: *mut c_int,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_status::<M>(c, kind, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetRealStatus(
                c: fmi2Component,
                kind: c_int,
                v: *mut f64,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_real_status::<M>(c, kind, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetIntegerStatus(
                c: fmi2Component,
                kind: c_int,
                v: *mut c_int,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_integer_status::<M>(c, kind, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetBooleanStatus(
                c: fmi2Component,
                kind: c_int,
                v: *mut fmi2Boolean,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_boolean_status::<M>(c, kind, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetStringStatus(
                c: fmi2Component,
                kind: c_int,
                v: *mut fmi2String,
            ) -> fmi2Status {
                // SAFETY: the importer passes arguments as the FMI 2.0 function requires; the callee checks NULLs and the instance tag.
                unsafe { x::get_string_status::<M>(c, kind, v) }
            }
        }
    };
}

/// The names of the 34 functions, for tests and for the importer's symbol check.
pub const FUNCTION_NAMES: [&str; 34] = [
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];
