//! Routing the FMU's log messages: the C shim (csrc/logger.c) formats, [`deliver`] routes.
//!
//! Each instance owns one heap-allocated [`LogState`]; its address is the componentEnvironment
//! the FMU passes back to the logger. The state holds the sink, the filter, and the buffer of
//! warning and error messages logged during the current call, which [`FmiError`] quotes.
//!
//! [`FmiError`]: crate::FmiError

use fmi_abi::types::{fmi2CallbackFunctions, fmi2Status};
use std::ffi::{CStr, c_char, c_int, c_void};
use std::fmt;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

/// How an instance's log messages are filtered and where they go.
#[derive(Clone)]
pub struct LogConfig {
    /// Messages with a lower status are dropped (before they are even formatted). Default:
    /// [`fmi2Status::Warning`]. Warnings and errors are still collected for [`FmiError`]
    /// messages whatever this is set to.
    ///
    /// [`FmiError`]: crate::FmiError
    pub min_status: fmi2Status,
    /// When `Some`, passed to fmi2SetDebugLogging right after instantiation (with
    /// `debug_logging` as the on/off flag). An empty list means "all categories".
    pub categories: Option<Vec<String>>,
    /// fmi2Instantiate's `loggingOn`: whether the FMU emits its debug categories at all.
    /// Needed to see fmi2OK-level messages (set `min_status` to OK too).
    pub debug_logging: bool,
    /// Receives every message at or above `min_status`, possibly from the thread that runs the
    /// instance (so it must be `Send + Sync`). Default: `eprintln!("[instance] category status:
    /// message")`.
    pub sink: Arc<dyn Fn(&LogRecord) + Send + Sync>,
}

impl Default for LogConfig {
    fn default() -> Self {
        LogConfig {
            min_status: fmi2Status::Warning,
            categories: None,
            debug_logging: false,
            sink: Arc::new(stderr_sink),
        }
    }
}

impl fmt::Debug for LogConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LogConfig")
            .field("min_status", &self.min_status)
            .field("categories", &self.categories)
            .field("debug_logging", &self.debug_logging)
            .finish_non_exhaustive()
    }
}

/// The default sink.
pub fn stderr_sink(r: &LogRecord) {
    eprintln!("{r}");
}

/// One message from an FMU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogRecord {
    /// The name the instance was created with (the importer's, not whatever the FMU passed).
    pub instance: String,
    /// The status the FMU logged with (a value outside the enum counts as fmi2Fatal).
    pub status: fmi2Status,
    /// The FMU's log category; empty when it passed NULL.
    pub category: String,
    /// The formatted message, complete (lossily converted to UTF-8).
    pub message: String,
}

impl fmt::Display for LogRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "[{}] {} {}: {}",
            self.instance,
            self.category,
            self.status.name(),
            self.message
        )
    }
}

type DeliverFn = unsafe extern "C" fn(
    env: *mut c_void,
    instance: *const c_char,
    status: c_int,
    category: *const c_char,
    message: *const c_char,
    len: usize,
);

/// The componentEnvironment of one instance. `#[repr(C)]` because the C shim reads the first
/// two fields (`struct fmi_import_log_header`).
#[repr(C)]
pub(crate) struct LogState {
    deliver: DeliverFn,
    /// The lowest status the shim formats: min(min_status, Warning), so that warnings and
    /// errors always reach the per-call buffer.
    threshold: c_int,
    min_status: fmi2Status,
    instance: String,
    sink: Arc<dyn Fn(&LogRecord) + Send + Sync>,
    /// Set when `messages` is non-empty, so the per-call reset costs one load on the fast path.
    has_messages: AtomicBool,
    /// Warning and error messages since the last reset. A mutex, not a cell: an FMU may log
    /// from a thread of its own.
    messages: Mutex<Vec<String>>,
}

impl LogState {
    pub(crate) fn new(instance: &str, config: &LogConfig) -> LogState {
        LogState {
            deliver,
            threshold: config.min_status.min(fmi2Status::Warning) as c_int,
            min_status: config.min_status,
            instance: instance.to_string(),
            sink: Arc::clone(&config.sink),
            has_messages: AtomicBool::new(false),
            messages: Mutex::new(Vec::new()),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Vec<String>> {
        self.messages.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Forgets the messages of the previous call; one atomic load when there were none.
    #[inline(always)]
    pub(crate) fn begin_call(&self) {
        if self.has_messages.load(Ordering::Relaxed) {
            self.clear();
        }
    }

    #[cold]
    fn clear(&self) {
        let mut m = self.lock();
        m.clear();
        self.has_messages.store(false, Ordering::Relaxed);
    }

    /// The messages logged since the last [`begin_call`](Self::begin_call).
    pub(crate) fn take_messages(&self) -> Vec<String> {
        if !self.has_messages.load(Ordering::Acquire) {
            return Vec::new();
        }
        let mut m = self.lock();
        self.has_messages.store(false, Ordering::Relaxed);
        std::mem::take(&mut *m)
    }

    fn record(&self, status: c_int, category: *const c_char, message: *const c_char, len: usize) {
        let status = fmi2Status::from_raw(status);
        let text = if message.is_null() || len == 0 {
            String::new()
        } else {
            // SAFETY: the shim passes a buffer of `len` initialized bytes, valid for this call.
            let bytes = unsafe { std::slice::from_raw_parts(message.cast::<u8>(), len) };
            String::from_utf8_lossy(bytes).into_owned()
        };
        let to_sink = status >= self.min_status;
        if status >= fmi2Status::Warning {
            let mut m = self.lock();
            m.push(text.clone());
            self.has_messages.store(true, Ordering::Release);
        }
        if to_sink {
            let category = if category.is_null() {
                String::new()
            } else {
                // SAFETY: the FMU passes a NUL-terminated string valid during the call.
                unsafe { CStr::from_ptr(category) }
                    .to_string_lossy()
                    .into_owned()
            };
            (self.sink)(&LogRecord {
                instance: self.instance.clone(),
                status,
                category,
                message: text,
            });
        }
    }
}

/// Called by the C shim with the formatted message. Never unwinds into C.
unsafe extern "C" fn deliver(
    env: *mut c_void,
    _instance: *const c_char,
    status: c_int,
    category: *const c_char,
    message: *const c_char,
    len: usize,
) {
    if env.is_null() {
        return; // the shim only calls us through a non-NULL env
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: env is the LogState this instance registered; it lives until the instance
        // is freed, and is only accessed through shared references.
        let state = unsafe { &*(env as *const LogState) };
        state.record(status, category, message, len);
    }));
}

unsafe extern "C" {
    /// csrc/logger.c
    fn fmi_import_logger(
        env: *mut c_void,
        instance: *const c_char,
        status: c_int,
        category: *const c_char,
        fmt: *const c_char,
        ...
    );
    fn calloc(n: usize, size: usize) -> *mut c_void;
    fn free(p: *mut c_void);
}

/// The callback structure for one instance: our logger, the C allocator, no stepFinished
/// (we never run steps asynchronously), and `env` as componentEnvironment.
pub(crate) fn callbacks(env: *mut LogState) -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: Some(fmi_import_logger),
        allocate_memory: Some(calloc),
        free_memory: Some(free),
        step_finished: None,
        component_environment: env.cast(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    fn capture(min_status: fmi2Status) -> (Arc<Mutex<Vec<LogRecord>>>, Box<LogState>) {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let s2 = Arc::clone(&seen);
        let config = LogConfig {
            min_status,
            sink: Arc::new(move |r: &LogRecord| s2.lock().unwrap().push(r.clone())),
            ..LogConfig::default()
        };
        (seen, Box::new(LogState::new("inst", &config)))
    }

    #[test]
    fn the_shim_formats_and_routes() {
        let (seen, state) = capture(fmi2Status::OK);
        let env = &*state as *const LogState as *mut c_void;
        let cb = callbacks(env.cast());
        let logger = cb.logger.unwrap();
        // SAFETY: `env` is a live boxed LogState (its header first, as the shim reads it); the
        // strings are NUL-terminated literals or NULL, which the shim tolerates; the variadic
        // arguments match the format: an int for %d, a NUL-terminated string for %s.
        unsafe {
            logger(
                env,
                c"x".as_ptr(),
                1,
                c"cat".as_ptr(),
                c"%d%% of %s".as_ptr(),
                42 as c_int,
                c"all".as_ptr(),
            );
            logger(env, std::ptr::null(), 0, std::ptr::null(), std::ptr::null());
        }
        let seen = seen.lock().unwrap();
        assert_eq!(seen.len(), 2);
        assert_eq!(seen[0].message, "42% of all");
        assert_eq!(seen[0].category, "cat");
        assert_eq!(seen[0].instance, "inst");
        assert_eq!(seen[0].status, fmi2Status::Warning);
        assert_eq!(seen[1].message, "");
        assert_eq!(seen[1].category, "");
        assert_eq!(state.take_messages(), vec!["42% of all".to_string()]);
        assert!(state.take_messages().is_empty());
    }

    #[test]
    fn long_messages_are_not_truncated() {
        let (seen, state) = capture(fmi2Status::OK);
        let env = &*state as *const LogState as *mut c_void;
        let long = "é".repeat(5000) + "%end";
        let c = std::ffi::CString::new(long.clone()).unwrap();
        // SAFETY: `env` is a live boxed LogState; the strings are NUL-terminated and `c`
        // outlives the call; one string argument for the one %s.
        unsafe {
            fmi_import_logger(
                env,
                c"x".as_ptr(),
                3,
                c"e".as_ptr(),
                c"%s".as_ptr(),
                c.as_ptr(),
            );
        }
        assert_eq!(seen.lock().unwrap()[0].message, long);
        assert_eq!(state.take_messages(), vec![long]);
    }

    #[test]
    fn below_min_status_is_dropped_but_errors_are_kept() {
        let (seen, state) = capture(fmi2Status::Fatal);
        let env = &*state as *const LogState as *mut c_void;
        // SAFETY: `env` is a live boxed LogState; NUL-terminated literals; the formats have no
        // conversions, so no variadic arguments are read.
        unsafe {
            fmi_import_logger(env, c"x".as_ptr(), 0, c"c".as_ptr(), c"ok".as_ptr());
            fmi_import_logger(env, c"x".as_ptr(), 3, c"c".as_ptr(), c"bad".as_ptr());
        }
        assert!(seen.lock().unwrap().is_empty());
        assert_eq!(state.take_messages(), vec!["bad".to_string()]);
    }

    #[test]
    fn a_panicking_sink_does_not_unwind_into_c() {
        let config = LogConfig {
            sink: Arc::new(|_: &LogRecord| panic!("sink panicked on purpose")),
            ..LogConfig::default()
        };
        let state = Box::new(LogState::new("p", &config));
        let env = &*state as *const LogState as *mut c_void;
        // SAFETY: `env` is a live boxed LogState; NUL-terminated literals; the format has no
        // conversions, so no variadic argument is read.
        unsafe {
            fmi_import_logger(env, c"x".as_ptr(), 3, c"c".as_ptr(), c"boom".as_ptr());
        }
        assert_eq!(state.take_messages(), vec!["boom".to_string()]);
    }
}
