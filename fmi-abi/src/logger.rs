//! Messages to the importer's logger, the way every importer can take them.
//!
//! Lessons from importers (docs/references.md section 7.7): pass the caller's componentEnvironment back
//! unchanged, pass our own copy of the instance name, never pass a NULL category (OMSimulator
//! crashes on one), and pass the text through "%s" so '%' in a message is never a conversion.
//! A NULL callback structure or NULL logger simply means nobody listens.

use crate::types::{fmi2CallbackFunctions, fmi2Status};
use std::ffi::{CStr, CString, c_void};

/// The log categories every FMU of ours declares, in the order written to the XML.
pub const CATEGORIES: &[(&CStr, &str)] = &[
    (
        c"logStatusWarning",
        "Warnings: a call succeeded with a caveat (for example a skipped NaN sample).",
    ),
    (
        c"logStatusError",
        "Errors: a call failed; the message says which argument or state was wrong.",
    ),
    (
        c"logStatusFatal",
        "Fatal errors: an internal fault was caught; only fmi2FreeInstance is allowed.",
    ),
    (
        c"logCalls",
        "Every FMI function call with its arguments (verbose).",
    ),
    (
        c"logModel",
        "Information from the model (for example when it rebuilds its matrices).",
    ),
];

/// Index into [`CATEGORIES`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Category {
    /// `logStatusWarning`: on from the start.
    Warning = 0,
    /// `logStatusError`: on from the start.
    Error = 1,
    /// `logStatusFatal`: on from the start.
    Fatal = 2,
    /// `logCalls`: every FMI call with its arguments; on only with loggingOn or
    /// fmi2SetDebugLogging.
    Calls = 3,
    /// `logModel`: the model's informational messages; on only with loggingOn or
    /// fmi2SetDebugLogging.
    Model = 4,
}

/// The logger of one instance: the caller's callbacks, a copy of the instance name, and which
/// categories are switched on.
pub struct Logger {
    callbacks: Option<fmi2CallbackFunctions>,
    instance_name: CString,
    enabled: [bool; CATEGORIES.len()],
}

// SAFETY: the callbacks are plain C function pointers plus the caller's opaque environment pointer,
// which the FMI standard lets us hand back from whichever thread runs the instance.
unsafe impl Send for Logger {}

impl Logger {
    /// Status categories (warning, error, fatal) are on from the start; the debug categories
    /// follow `logging_on`, as fmi2Instantiate's loggingOn asks.
    pub fn new(
        callbacks: Option<fmi2CallbackFunctions>,
        instance_name: &str,
        logging_on: bool,
    ) -> Logger {
        let name = CString::new(instance_name.replace('\0', "")).unwrap_or_default();
        Logger {
            callbacks,
            instance_name: name,
            enabled: [true, true, true, logging_on, logging_on],
        }
    }

    /// A logger that drops everything, for tests and for running models outside an importer.
    pub fn silent() -> Logger {
        Logger {
            callbacks: None,
            instance_name: CString::default(),
            enabled: [false; CATEGORIES.len()],
        }
    }

    /// The instance name as passed to fmi2Instantiate (NUL characters removed), for messages.
    pub fn instance_name(&self) -> &str {
        self.instance_name.to_str().unwrap_or("")
    }

    /// fmi2SetDebugLogging: no names means every category; returns the names not known.
    pub fn set_categories(&mut self, on: bool, names: &[String]) -> Vec<String> {
        if names.is_empty() {
            self.enabled = [on; CATEGORIES.len()];
            return vec![];
        }
        let mut unknown = vec![];
        for name in names {
            match CATEGORIES
                .iter()
                .position(|(c, _)| c.to_bytes() == name.as_bytes())
            {
                Some(i) => self.enabled[i] = on,
                None => unknown.push(name.clone()),
            }
        }
        unknown
    }

    /// Whether a message of `category` would reach anybody, so callers can skip building it.
    pub fn enabled(&self, category: Category) -> bool {
        self.enabled[category as usize] && self.callbacks.and_then(|c| c.logger).is_some()
    }

    /// Sends `message` to the importer's logger with `status` and the category's name, through
    /// "%s" (NUL characters become spaces); dropped when the category is off or nobody listens.
    pub fn log(&self, status: fmi2Status, category: Category, message: &str) {
        if !self.enabled(category) {
            return;
        }
        let Some(cb) = self.callbacks else { return };
        let Some(logger) = cb.logger else { return };
        let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
        let cat = CATEGORIES[category as usize].0;
        // SAFETY: the importer gave us this function for exactly this call; every pointer we
        // pass is a valid NUL-terminated string that outlives the call.
        unsafe {
            logger(
                cb.component_environment,
                self.instance_name.as_ptr(),
                status as i32,
                cat.as_ptr(),
                c"%s".as_ptr(),
                text.as_ptr(),
            );
        }
    }

    /// A message with fmi2Warning in `logStatusWarning`.
    pub fn warning(&self, message: &str) {
        self.log(fmi2Status::Warning, Category::Warning, message);
    }

    /// A message with fmi2Error in `logStatusError`: say which argument or state was wrong.
    pub fn error(&self, message: &str) {
        self.log(fmi2Status::Error, Category::Error, message);
    }

    /// A message with fmi2Fatal in `logStatusFatal`.
    pub fn fatal(&self, message: &str) {
        self.log(fmi2Status::Fatal, Category::Fatal, message);
    }

    /// A message with fmi2OK in `logModel`, seen only when debug logging is on.
    pub fn info(&self, message: &str) {
        self.log(fmi2Status::OK, Category::Model, message);
    }

    /// The logCalls trace; the message is only built when somebody listens.
    pub fn call(&self, message: impl FnOnce() -> String) {
        if self.enabled(Category::Calls) {
            self.log(fmi2Status::OK, Category::Calls, &message());
        }
    }

    /// The environment pointer, for fmi2StepFinished (not used: we never return fmi2Pending).
    pub fn component_environment(&self) -> *mut c_void {
        self.callbacks
            .map_or(std::ptr::null_mut(), |c| c.component_environment)
    }
}

/// Warnings that can recur on every step (a sensor that keeps sending NaN, a speed that stays
/// negative): the first occurrence is logged in full, then only the 10th, 100th, 1000th, ...
/// as a count, and [`Repeats::report`] gives the totals (at fmi2Terminate). A 2 s run at 1 kHz
/// with a broken sensor logs four lines, not 2000. Part of the model, so FMU state keeps it.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Repeats {
    counts: std::collections::BTreeMap<String, u64>,
}

impl Repeats {
    /// Counts one occurrence of the warning `key` and logs it when due; `message` is built only
    /// for the first one.
    pub fn warn(&mut self, log: &Logger, key: &str, message: impl FnOnce() -> String) {
        let n = self.counts.entry(key.to_string()).or_insert(0);
        *n += 1;
        if *n == 1 {
            log.warning(&format!(
                "{} (further '{key}' warnings are counted: logged at the 10th, 100th, ... and in all at fmi2Terminate)",
                message()
            ));
        } else if is_power_of_ten(*n) {
            log.warning(&format!("'{key}': {n} times so far"));
        }
    }

    /// How many times `key` occurred.
    pub fn count(&self, key: &str) -> u64 {
        self.counts.get(key).copied().unwrap_or(0)
    }

    /// Logs the total of every warning that occurred more than once.
    pub fn report(&self, log: &Logger) {
        for (key, n) in &self.counts {
            if *n > 1 {
                log.warning(&format!("'{key}': {n} times in all"));
            }
        }
    }

    /// Forgets every count, so the next occurrence is logged in full again (for a model starting
    /// a new run).
    pub fn clear(&mut self) {
        self.counts.clear();
    }
}

fn is_power_of_ten(mut n: u64) -> bool {
    while n >= 10 && n.is_multiple_of(10) {
        n /= 10;
    }
    n == 1
}

#[cfg(test)]
mod repeats_tests {
    use super::*;

    #[test]
    fn counts_every_occurrence_and_names_the_powers_of_ten() {
        assert!([1, 10, 100, 1000].iter().all(|n| is_power_of_ten(*n)));
        assert!([2, 11, 20, 101, 0].iter().all(|n| !is_power_of_ten(*n)));
        let mut r = Repeats::default();
        let mut built = 0;
        for _ in 0..2000 {
            r.warn(&Logger::silent(), "nan", || {
                built += 1;
                "sensor NaN".into()
            });
        }
        assert_eq!(r.count("nan"), 2000);
        assert_eq!(built, 1, "the message is built once");
    }
}
