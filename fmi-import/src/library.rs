//! The FMU's shared library: platform folder, loading, and the 34 resolved function pointers.

use fmi_abi::types::{
    fmi2Boolean, fmi2Byte, fmi2CallbackFunctions, fmi2Component, fmi2FMUstate, fmi2Real,
    fmi2String, fmi2ValueReference,
};
use libloading::Library;
use std::ffi::{c_char, c_int, c_void};
use std::path::Path;

/// FMI 2.0's name for this platform's binaries folder and the shared-library extension.
const PLATFORM: Option<(&str, &str)> = platform();

const fn platform() -> Option<(&'static str, &'static str)> {
    if cfg!(target_os = "linux") {
        if cfg!(target_pointer_width = "64") {
            Some(("linux64", "so"))
        } else {
            Some(("linux32", "so"))
        }
    } else if cfg!(target_os = "macos") {
        Some(("darwin64", "dylib"))
    } else if cfg!(target_os = "windows") {
        if cfg!(target_pointer_width = "64") {
            Some(("win64", "dll"))
        } else {
            Some(("win32", "dll"))
        }
    } else {
        None
    }
}

/// The binary an FMU with this model identifier must ship for this platform, relative to the
/// archive root (`binaries/linux64/<id>.so` here); `None` on a platform FMI 2.0 does not name.
pub fn platform_binary(model_identifier: &str) -> Option<String> {
    PLATFORM.map(|(folder, ext)| format!("binaries/{folder}/{model_identifier}.{ext}"))
}

/// Loads the library resolving every symbol now (RTLD_NOW): an undefined symbol is reported
/// here, with the loader's message, instead of aborting the process at the first call that
/// needs it. RTLD_LOCAL keeps two FMUs' symbols (all named fmi2...) apart.
pub fn load(path: &Path) -> Result<Library, String> {
    #[cfg(unix)]
    {
        use libloading::os::unix::{Library as UnixLibrary, RTLD_LOCAL, RTLD_NOW};
        // SAFETY: running the library's initializers is inherent in importing an FMU.
        unsafe { UnixLibrary::open(Some(path), RTLD_NOW | RTLD_LOCAL) }
            .map(Library::from)
            .map_err(|e| with_sources(&e))
    }
    #[cfg(not(unix))]
    {
        // SAFETY: as above.
        unsafe { Library::new(path) }.map_err(|e| with_sources(&e))
    }
}

/// "dlopen failed: <the loader's own message>": libloading keeps the loader's text in the
/// error's source.
fn with_sources(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

macro_rules! functions {
    ($($field:ident : $name:literal = fn($($arg:ty),* $(,)?) $(-> $ret:ty)?;)*) => {
        /// The 34 FMI 2.0 co-simulation functions as plain function pointers, resolved once.
        /// Every status is declared as `c_int`, not as the `fmi2Status` enum: a foreign
        /// library returning a value outside the enum must not be undefined behaviour.
        /// Some are resolved only to check the FMU is complete (this API does not call them).
        #[derive(Clone, Copy)]
        pub struct Functions {
            $(
                #[doc = concat!("`", $name, "`, resolved from the FMU's library.")]
                pub $field: unsafe extern "C" fn($($arg),*) $(-> $ret)?,
            )*
        }

        /// The names, in declaration order.
        pub const NAMES: &[&str] = &[$($name),*];

        impl Functions {
            /// Resolves all functions, or returns every missing name.
            pub fn resolve(lib: &Library) -> Result<Functions, Vec<&'static str>> {
                let mut missing = Vec::new();
                $(
                    let $field = match lookup(lib, $name) {
                        // SAFETY: an exported fmi2 function of this name has this signature
                        // (FMI 2.0 fmi2FunctionTypes.h); a library lying about it is outside
                        // anything an importer can check.
                        Some(p) => Some(unsafe {
                            std::mem::transmute::<*mut c_void, unsafe extern "C" fn($($arg),*) $(-> $ret)?>(p)
                        }),
                        None => {
                            missing.push($name);
                            None
                        }
                    };
                )*
                let all = || Some(Functions { $($field: $field?,)* });
                all().ok_or(missing)
            }
        }
    };
}

/// A non-NULL symbol address.
fn lookup(lib: &Library, name: &str) -> Option<*mut c_void> {
    // SAFETY: we read the symbol's address only; it is typed by the caller.
    let sym = unsafe { lib.get::<*mut c_void>(name) }.ok()?;
    let p = *sym;
    (!p.is_null()).then_some(p)
}

type C = fmi2Component;
type Vr = *const fmi2ValueReference;

functions! {
    get_types_platform: "fmi2GetTypesPlatform" = fn() -> *const c_char;
    get_version: "fmi2GetVersion" = fn() -> *const c_char;
    set_debug_logging: "fmi2SetDebugLogging" = fn(C, fmi2Boolean, usize, *const fmi2String) -> c_int;
    instantiate: "fmi2Instantiate" = fn(
        fmi2String, c_int, fmi2String, fmi2String, *const fmi2CallbackFunctions, fmi2Boolean,
        fmi2Boolean,
    ) -> C;
    free_instance: "fmi2FreeInstance" = fn(C);
    setup_experiment: "fmi2SetupExperiment" = fn(C, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real) -> c_int;
    enter_initialization_mode: "fmi2EnterInitializationMode" = fn(C) -> c_int;
    exit_initialization_mode: "fmi2ExitInitializationMode" = fn(C) -> c_int;
    terminate: "fmi2Terminate" = fn(C) -> c_int;
    reset: "fmi2Reset" = fn(C) -> c_int;
    get_real: "fmi2GetReal" = fn(C, Vr, usize, *mut fmi2Real) -> c_int;
    get_integer: "fmi2GetInteger" = fn(C, Vr, usize, *mut c_int) -> c_int;
    get_boolean: "fmi2GetBoolean" = fn(C, Vr, usize, *mut fmi2Boolean) -> c_int;
    get_string: "fmi2GetString" = fn(C, Vr, usize, *mut fmi2String) -> c_int;
    set_real: "fmi2SetReal" = fn(C, Vr, usize, *const fmi2Real) -> c_int;
    set_integer: "fmi2SetInteger" = fn(C, Vr, usize, *const c_int) -> c_int;
    set_boolean: "fmi2SetBoolean" = fn(C, Vr, usize, *const fmi2Boolean) -> c_int;
    set_string: "fmi2SetString" = fn(C, Vr, usize, *const fmi2String) -> c_int;
    get_fmu_state: "fmi2GetFMUstate" = fn(C, *mut fmi2FMUstate) -> c_int;
    set_fmu_state: "fmi2SetFMUstate" = fn(C, fmi2FMUstate) -> c_int;
    free_fmu_state: "fmi2FreeFMUstate" = fn(C, *mut fmi2FMUstate) -> c_int;
    serialized_fmu_state_size: "fmi2SerializedFMUstateSize" = fn(C, fmi2FMUstate, *mut usize) -> c_int;
    serialize_fmu_state: "fmi2SerializeFMUstate" = fn(C, fmi2FMUstate, *mut fmi2Byte, usize) -> c_int;
    deserialize_fmu_state: "fmi2DeSerializeFMUstate" = fn(C, *const fmi2Byte, usize, *mut fmi2FMUstate) -> c_int;
    get_directional_derivative: "fmi2GetDirectionalDerivative" = fn(
        C, Vr, usize, Vr, usize, *const fmi2Real, *mut fmi2Real,
    ) -> c_int;
    set_real_input_derivatives: "fmi2SetRealInputDerivatives" = fn(C, Vr, usize, *const c_int, *const fmi2Real) -> c_int;
    get_real_output_derivatives: "fmi2GetRealOutputDerivatives" = fn(C, Vr, usize, *const c_int, *mut fmi2Real) -> c_int;
    do_step: "fmi2DoStep" = fn(C, fmi2Real, fmi2Real, fmi2Boolean) -> c_int;
    cancel_step: "fmi2CancelStep" = fn(C) -> c_int;
    get_status: "fmi2GetStatus" = fn(C, c_int, *mut c_int) -> c_int;
    get_real_status: "fmi2GetRealStatus" = fn(C, c_int, *mut fmi2Real) -> c_int;
    get_integer_status: "fmi2GetIntegerStatus" = fn(C, c_int, *mut c_int) -> c_int;
    get_boolean_status: "fmi2GetBooleanStatus" = fn(C, c_int, *mut fmi2Boolean) -> c_int;
    get_string_status: "fmi2GetStringStatus" = fn(C, c_int, *mut fmi2String) -> c_int;
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_34_functions_are_fmi_abis_list() {
        let mut ours: Vec<&str> = super::NAMES.to_vec();
        let mut theirs: Vec<&str> = fmi_abi::export::FUNCTION_NAMES.to_vec();
        ours.sort_unstable();
        theirs.sort_unstable();
        assert_eq!(ours, theirs);
    }
}
