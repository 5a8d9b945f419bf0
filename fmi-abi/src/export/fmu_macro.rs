//! The [`export_fmu!`](crate::export_fmu) macro, which turns the generic functions of
//! `crate::export` into the 34 unmangled symbols of an FMU, and the list of their names kept
//! next to it.

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
