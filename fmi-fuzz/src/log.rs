//! What the FMU logs: one [`LogSink`] per instance (its address is the componentEnvironment),
//! filled by the C shim in csrc/logger.c.

use fmi_abi::types::{fmi2CallbackFunctions, fmi2CallbackLogger};
use std::ffi::{CStr, c_char, c_int, c_long, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Mutex;

unsafe extern "C" {
    fn fmi_fuzz_logger(
        env: *mut c_void,
        instance: *const c_char,
        status: c_int,
        category: *const c_char,
        fmt: *const c_char,
        ...
    );
    fn fmi_fuzz_orphan_messages() -> c_long;
}

/// One call of the logger, as received.
#[derive(Debug, Clone)]
pub struct Record {
    /// `None` when the FMU passed a NULL instance name.
    pub instance: Option<String>,
    /// The status argument as passed (an out-of-range value is kept, not mapped).
    pub status: i32,
    /// `None` when the FMU passed a NULL category.
    pub category: Option<String>,
    /// `None` when the FMU passed a NULL format.
    pub message: Option<String>,
}

type DeliverFn = unsafe extern "C" fn(
    env: *mut c_void,
    instance: *const c_char,
    status: c_int,
    category: *const c_char,
    message: *const c_char,
    len: usize,
);

/// The componentEnvironment of one instance. `#[repr(C)]`: the shim reads `deliver`.
#[repr(C)]
pub struct LogSink {
    deliver: DeliverFn,
    records: Mutex<Vec<Record>>,
}

impl Default for LogSink {
    fn default() -> Self {
        LogSink {
            deliver,
            records: Mutex::new(Vec::new()),
        }
    }
}

impl LogSink {
    /// Takes everything logged since the last call.
    pub fn take(&self) -> Vec<Record> {
        std::mem::take(&mut *self.records.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// The callback structure pointing at this sink (`logger = None` when `with_logger` is
    /// false; `env = NULL` when `with_env` is false).
    pub fn callbacks(&self, with_logger: bool, with_env: bool) -> fmi2CallbackFunctions {
        fmi2CallbackFunctions {
            logger: if with_logger { logger() } else { None },
            allocate_memory: Some(libc_calloc),
            free_memory: Some(libc_free),
            step_finished: None,
            component_environment: if with_env {
                self as *const LogSink as *mut c_void
            } else {
                std::ptr::null_mut()
            },
        }
    }
}

/// The shim as an `fmi2CallbackLogger`.
pub fn logger() -> fmi2CallbackLogger {
    Some(fmi_fuzz_logger)
}

/// Messages logged with a NULL componentEnvironment, process-wide.
pub fn orphan_messages() -> i64 {
    // SAFETY: reads an atomic counter.
    unsafe { fmi_fuzz_orphan_messages() as i64 }
}

unsafe extern "C" {
    fn calloc(n: usize, size: usize) -> *mut c_void;
    fn free(p: *mut c_void);
}

unsafe extern "C" fn libc_calloc(n: usize, size: usize) -> *mut c_void {
    // SAFETY: calloc accepts any count and size; it returns NULL when it cannot allocate (or the
    // product overflows), which is what fmi2CallbackAllocateMemory may return.
    unsafe { calloc(n, size) }
}

unsafe extern "C" fn libc_free(p: *mut c_void) {
    // SAFETY: the FMI contract has the FMU free only NULL or memory it got from
    // `libc_calloc`, i.e. from calloc. An FMU that breaks it is a finding of the fuzzer (valgrind
    // reports it), not something this shim can check.
    unsafe { free(p) }
}

fn opt_str(p: *const c_char) -> Option<String> {
    // SAFETY: the FMU passes NUL-terminated strings or NULL (the contract under test; a
    // garbage pointer would show up as a crash, which is what the fuzzer looks for).
    (!p.is_null()).then(|| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}

unsafe extern "C" fn deliver(
    env: *mut c_void,
    instance: *const c_char,
    status: c_int,
    category: *const c_char,
    message: *const c_char,
    len: usize,
) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: `env` is the LogSink the callbacks were made from; it outlives the instance.
        let sink = unsafe { &*(env as *const LogSink) };
        let message = (!message.is_null()).then(|| {
            // SAFETY: the shim passes its formatted buffer and its length.
            let bytes = unsafe { std::slice::from_raw_parts(message as *const u8, len) };
            String::from_utf8_lossy(bytes).into_owned()
        });
        let record = Record {
            instance: opt_str(instance),
            status,
            category: opt_str(category),
            message,
        };
        sink.records
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(record);
    }));
}
