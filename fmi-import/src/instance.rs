//! [`Instance`]: one co-simulation slave, and [`FmuState`]: a saved state of one.

use crate::error::{FmiError, ImportError};
use crate::fmu::FmuInner;
use crate::library::Functions;
use crate::logging::{LogConfig, LogState, callbacks};
use fmi_abi::types::{
    FMI2_CO_SIMULATION, FMI2_FALSE, FMI2_LAST_SUCCESSFUL_TIME, FMI2_TERMINATED, FMI2_TRUE,
    fmi2Boolean, fmi2CallbackFunctions, fmi2Component, fmi2FMUstate, fmi2Status, fmi2String,
};
use model_description::ModelDescription;
use std::ffi::{CStr, CString, c_int};
use std::path::Path;
use std::ptr::{NonNull, null, null_mut};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex, MutexGuard};

/// Where the instance is in the FMI 2.0 co-simulation state machine, as far as the importer
/// knows from the calls it made and their results (the states the export layer enforces). Only
/// used to decide what `Drop` may call.
use fmi_abi::instance::State as Lifecycle;

/// The FMU states an instance handed out, shared with them so that dropping a state never
/// calls the FMU (see [`FmuState`]).
#[derive(Default)]
struct StateShelf {
    /// False once the instance is gone: later drops have nothing to give back.
    alive: bool,
    /// States whose [`FmuState`] was dropped, waiting for fmi2FreeFMUstate.
    dropped: Vec<usize>,
}

type Shelf = Arc<Mutex<StateShelf>>;

fn lock(shelf: &Shelf) -> MutexGuard<'_, StateShelf> {
    shelf.lock().unwrap_or_else(|e| e.into_inner())
}

/// One instance of a co-simulation FMU.
///
/// Methods are thin: each is one call through a function pointer resolved at
/// [`Fmu::open`](crate::Fmu::open), a check of the returned status, and no allocation on the
/// success path (except for strings, serialized states and FMU states, which allocate by
/// nature).
///
/// Status policy: fmi2OK and fmi2Warning are `Ok` (warnings went to the log sink);
/// fmi2Discard, fmi2Error, fmi2Fatal and fmi2Pending are `Err(FmiError)` with the function,
/// status, time and the warning/error messages the FMU logged during the call.
///
/// Drop: if the instance was initialized and not terminated, fmi2Terminate; then
/// fmi2FreeInstance. After fmi2Error (or fmi2Pending, which we never ask for) fmi2Terminate
/// is illegal, so only fmi2FreeInstance is called. After fmi2Fatal the spec says the FMU is
/// irreparably corrupted and allows no further call: nothing is called, and the instance's
/// memory, its logging state (the FMU may still hold a pointer to it) and the library are
/// deliberately leaked, never unloaded, so a stray thread of the broken FMU cannot run into
/// unmapped code. A successful fmi2Reset leaves the error state.
pub struct Instance {
    fns: Functions,
    component: fmi2Component,
    lifecycle: Lifecycle,
    /// The current communication point as far as we know it (for error messages).
    time: Option<f64>,
    /// Scratch for booleans (fmi2Boolean is an int); grows once, then reused.
    bools: Vec<fmi2Boolean>,
    /// FMU states handed out and not yet freed.
    live_states: Vec<fmi2FMUstate>,
    shelf: Shelf,
    name: String,
    /// Heap allocations the FMU holds pointers to: freed after fmi2FreeInstance only.
    log: NonNull<LogState>,
    callbacks: NonNull<fmi2CallbackFunctions>,
    c_name: CString,
    fmu: Arc<FmuInner>,
}

// SAFETY: FMI 2.0 allows different instances to run on different threads (functions of one
// instance need not be thread-safe, those of different instances must not share mutable
// global state). An Instance is only ever used through `&mut self` for FMU calls, so one
// thread at a time calls into its component; moving it between calls is fine. The raw
// pointers it holds (component, logging state, callbacks, FMU states) are owned by it alone,
// and the logging state is Sync (a mutex and an atomic). Not Sync: nothing needs it.
unsafe impl Send for Instance {}

impl Instance {
    pub(crate) fn new(
        fmu: Arc<FmuInner>,
        c_name: CString,
        name: &str,
        config: LogConfig,
    ) -> Result<Instance, ImportError> {
        let log = NonNull::from(Box::leak(Box::new(LogState::new(name, &config))));
        let callbacks = NonNull::from(Box::leak(Box::new(callbacks(log.as_ptr()))));
        let fns = fmu.functions;
        // SAFETY: all strings are NUL-terminated and outlive the instance (they are stored in
        // it or in the Fmu it keeps alive); `callbacks` and `log` live until after
        // fmi2FreeInstance.
        let component = unsafe {
            (fns.instantiate)(
                c_name.as_ptr(),
                FMI2_CO_SIMULATION,
                fmu.guid.as_ptr(),
                fmu.resource_uri.as_ptr(),
                callbacks.as_ptr(),
                FMI2_FALSE,
                if config.debug_logging {
                    FMI2_TRUE
                } else {
                    FMI2_FALSE
                },
            )
        };
        if component.is_null() {
            // SAFETY: the FMU returned no instance, so nothing refers to these any more.
            let log = unsafe { Box::from_raw(log.as_ptr()) };
            // SAFETY: `callbacks` came from `Box::into_raw` above and, with no instance made,
            // nothing else holds it.
            drop(unsafe { Box::from_raw(callbacks.as_ptr()) });
            fmu.live.fetch_sub(1, Ordering::AcqRel);
            return Err(ImportError::Instantiate {
                path: fmu.path.clone(),
                instance: name.to_string(),
                messages: log.take_messages(),
            });
        }
        let mut inst = Instance {
            fns,
            component,
            lifecycle: Lifecycle::Instantiated,
            time: None,
            bools: Vec::new(),
            live_states: Vec::new(),
            shelf: Arc::new(Mutex::new(StateShelf {
                alive: true,
                dropped: Vec::new(),
            })),
            name: name.to_string(),
            log,
            callbacks,
            c_name,
            fmu,
        };
        if let Some(categories) = &config.categories {
            let refs: Vec<&str> = categories.iter().map(String::as_str).collect();
            inst.set_debug_logging(config.debug_logging, &refs)?;
        }
        Ok(inst)
    }

    /// The name given to [`Fmu::instantiate`](crate::Fmu::instantiate).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The `.fmu` file of this instance.
    pub fn fmu_path(&self) -> &Path {
        &self.fmu.path
    }

    /// The model description of the FMU this instance came from (shared with the [`Fmu`](crate::Fmu)), for
    /// looking up value references without keeping the `Fmu` around.
    pub fn model_description(&self) -> &ModelDescription {
        &self.fmu.md
    }

    /// The communication point the importer believes the instance is at: the start time after
    /// setup, `t + h` after each successful step; None when unknown.
    pub fn time(&self) -> Option<f64> {
        self.time
    }

    // ---- the per-call machinery -------------------------------------------------------------

    #[inline(always)]
    fn log(&self) -> &LogState {
        // SAFETY: allocated in `new`, freed only in `drop`.
        unsafe { self.log.as_ref() }
    }

    /// Resets the per-call message buffer (one atomic load when it is already empty).
    #[inline(always)]
    fn begin(&self) {
        self.log().begin_call();
    }

    /// Maps a returned status: fmi2OK and fmi2Warning are success.
    #[inline(always)]
    fn check(&mut self, function: &'static str, raw: c_int) -> Result<(), FmiError> {
        if (raw as u32) <= fmi2Status::Warning as u32 {
            Ok(())
        } else {
            Err(self.failed(function, raw, self.time))
        }
    }

    /// Builds the error for a failed call and updates the lifecycle.
    #[cold]
    #[inline(never)]
    fn failed(&mut self, function: &'static str, raw: c_int, time: Option<f64>) -> FmiError {
        let status = fmi2Status::from_raw(raw);
        match status {
            fmi2Status::Fatal => self.lifecycle = Lifecycle::Fatal,
            fmi2Status::Error | fmi2Status::Pending if self.lifecycle != Lifecycle::Fatal => {
                self.lifecycle = Lifecycle::Error;
            }
            _ => {}
        }
        FmiError {
            instance: self.name.clone(),
            fmu: self.fmu.path.clone(),
            function,
            status,
            time,
            last_successful_time: None,
            terminated: false,
            messages: self.log().take_messages(),
        }
    }

    /// An error the importer raises itself, without calling the FMU.
    #[cold]
    #[inline(never)]
    fn refused(&self, function: &'static str, message: String) -> FmiError {
        FmiError {
            instance: self.name.clone(),
            fmu: self.fmu.path.clone(),
            function,
            status: fmi2Status::Error,
            time: self.time,
            last_successful_time: None,
            terminated: false,
            messages: vec![message],
        }
    }

    #[inline(always)]
    fn same_length(
        &self,
        function: &'static str,
        vr: usize,
        values: usize,
    ) -> Result<(), FmiError> {
        if vr == values {
            Ok(())
        } else {
            Err(self.refused(
                function,
                format!(
                    "{vr} value references but {values} values: the slices must have the same length (the FMU was not called)"
                ),
            ))
        }
    }

    // ---- lifecycle ----------------------------------------------------------------------------

    /// fmi2SetDebugLogging: switches `categories` (all when empty) on or off.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<(), FmiError> {
        let mut owned = Vec::with_capacity(categories.len());
        for c in categories {
            match CString::new(*c) {
                Ok(s) => owned.push(s),
                Err(_) => {
                    return Err(self.refused(
                        "fmi2SetDebugLogging",
                        format!("log category {c:?} contains a NUL character"),
                    ));
                }
            }
        }
        let ptrs: Vec<fmi2String> = owned.iter().map(|c| c.as_ptr()).collect();
        self.begin();
        // SAFETY: `ptrs` holds `len` valid strings for the duration of the call.
        let raw = unsafe {
            (self.fns.set_debug_logging)(
                self.component,
                if on { FMI2_TRUE } else { FMI2_FALSE },
                ptrs.len(),
                if ptrs.is_empty() {
                    null()
                } else {
                    ptrs.as_ptr()
                },
            )
        };
        self.check("fmi2SetDebugLogging", raw)
    }

    /// fmi2SetupExperiment.
    pub fn setup_experiment(
        &mut self,
        start: f64,
        stop: Option<f64>,
        tolerance: Option<f64>,
    ) -> Result<(), FmiError> {
        self.begin();
        let flag = |o: Option<f64>| if o.is_some() { FMI2_TRUE } else { FMI2_FALSE };
        // SAFETY: FMI call on our live component.
        let raw = unsafe {
            (self.fns.setup_experiment)(
                self.component,
                flag(tolerance),
                tolerance.unwrap_or(0.0),
                start,
                flag(stop),
                stop.unwrap_or(0.0),
            )
        };
        self.check("fmi2SetupExperiment", raw)?;
        self.time = Some(start);
        Ok(())
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization_mode(&mut self) -> Result<(), FmiError> {
        self.begin();
        // SAFETY: FMI call on our live component.
        let raw = unsafe { (self.fns.enter_initialization_mode)(self.component) };
        self.check("fmi2EnterInitializationMode", raw)?;
        self.lifecycle = Lifecycle::InitializationMode;
        Ok(())
    }

    /// fmi2ExitInitializationMode.
    pub fn exit_initialization_mode(&mut self) -> Result<(), FmiError> {
        self.begin();
        // SAFETY: FMI call on our live component.
        let raw = unsafe { (self.fns.exit_initialization_mode)(self.component) };
        self.check("fmi2ExitInitializationMode", raw)?;
        self.lifecycle = Lifecycle::StepComplete;
        Ok(())
    }

    /// fmi2DoStep from `t` to `t + h`, with noSetFMUStatePriorToCurrentPoint = false (the
    /// importer may restore earlier states). On fmi2Discard the error carries the FMU's
    /// fmi2LastSuccessfulTime.
    #[inline]
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), FmiError> {
        self.begin();
        // SAFETY: FMI call on our live component.
        let raw = unsafe { (self.fns.do_step)(self.component, t, h, FMI2_FALSE) };
        if (raw as u32) <= fmi2Status::Warning as u32 {
            self.time = Some(t + h);
            Ok(())
        } else {
            Err(self.step_failed(t, raw))
        }
    }

    #[cold]
    #[inline(never)]
    fn step_failed(&mut self, t: f64, raw: c_int) -> FmiError {
        let mut e = self.failed("fmi2DoStep", raw, Some(t));
        if e.status == fmi2Status::Discard {
            self.lifecycle = Lifecycle::StepFailed;
            e.last_successful_time = self.last_successful_time();
            e.terminated = self.terminated() == Some(true);
            self.begin();
        }
        e
    }

    /// fmi2GetRealStatus(fmi2LastSuccessfulTime); None if the FMU does not answer with OK or
    /// Warning.
    pub fn last_successful_time(&mut self) -> Option<f64> {
        let mut t = f64::NAN;
        // SAFETY: FMI call on our live component; `t` is a valid out-pointer.
        let raw = unsafe {
            (self.fns.get_real_status)(self.component, FMI2_LAST_SUCCESSFUL_TIME, &mut t)
        };
        ((raw as u32) <= fmi2Status::Warning as u32).then_some(t)
    }

    /// fmi2GetBooleanStatus(fmi2Terminated): whether the FMU asks to end the simulation; None
    /// if it does not answer with OK or Warning.
    pub fn terminated(&mut self) -> Option<bool> {
        let mut b: fmi2Boolean = FMI2_FALSE;
        // SAFETY: FMI call on our live component; `b` is a valid out-pointer.
        let raw = unsafe { (self.fns.get_boolean_status)(self.component, FMI2_TERMINATED, &mut b) };
        ((raw as u32) <= fmi2Status::Warning as u32).then_some(b != FMI2_FALSE)
    }

    /// fmi2Terminate.
    pub fn terminate(&mut self) -> Result<(), FmiError> {
        self.begin();
        // SAFETY: FMI call on our live component.
        let raw = unsafe { (self.fns.terminate)(self.component) };
        self.check("fmi2Terminate", raw)?;
        self.lifecycle = Lifecycle::Terminated;
        Ok(())
    }

    /// fmi2Reset: back to "just instantiated" (also the way out of the error state).
    pub fn reset(&mut self) -> Result<(), FmiError> {
        self.begin();
        // SAFETY: FMI call on our live component.
        let raw = unsafe { (self.fns.reset)(self.component) };
        self.check("fmi2Reset", raw)?;
        self.lifecycle = Lifecycle::Instantiated;
        self.time = None;
        Ok(())
    }

    // ---- values -------------------------------------------------------------------------------

    /// fmi2GetReal. `vr` and `out` must have the same length.
    #[inline]
    pub fn get_real(&mut self, vr: &[u32], out: &mut [f64]) -> Result<(), FmiError> {
        self.same_length("fmi2GetReal", vr.len(), out.len())?;
        self.begin();
        // SAFETY: both arrays hold `vr.len()` elements.
        let raw =
            unsafe { (self.fns.get_real)(self.component, vr.as_ptr(), vr.len(), out.as_mut_ptr()) };
        self.check("fmi2GetReal", raw)
    }

    /// fmi2SetReal.
    #[inline]
    pub fn set_real(&mut self, vr: &[u32], values: &[f64]) -> Result<(), FmiError> {
        self.same_length("fmi2SetReal", vr.len(), values.len())?;
        self.begin();
        // SAFETY: both arrays hold `vr.len()` elements.
        let raw =
            unsafe { (self.fns.set_real)(self.component, vr.as_ptr(), vr.len(), values.as_ptr()) };
        self.check("fmi2SetReal", raw)
    }

    /// fmi2GetInteger.
    #[inline]
    pub fn get_integer(&mut self, vr: &[u32], out: &mut [i32]) -> Result<(), FmiError> {
        self.same_length("fmi2GetInteger", vr.len(), out.len())?;
        self.begin();
        // SAFETY: both arrays hold `vr.len()` elements; fmi2Integer is i32.
        let raw = unsafe {
            (self.fns.get_integer)(self.component, vr.as_ptr(), vr.len(), out.as_mut_ptr())
        };
        self.check("fmi2GetInteger", raw)
    }

    /// fmi2SetInteger.
    #[inline]
    pub fn set_integer(&mut self, vr: &[u32], values: &[i32]) -> Result<(), FmiError> {
        self.same_length("fmi2SetInteger", vr.len(), values.len())?;
        self.begin();
        // SAFETY: both arrays hold `vr.len()` elements.
        let raw = unsafe {
            (self.fns.set_integer)(self.component, vr.as_ptr(), vr.len(), values.as_ptr())
        };
        self.check("fmi2SetInteger", raw)
    }

    /// fmi2GetBoolean (fmi2Boolean is an int: converted through a reused scratch buffer).
    #[inline]
    pub fn get_boolean(&mut self, vr: &[u32], out: &mut [bool]) -> Result<(), FmiError> {
        self.same_length("fmi2GetBoolean", vr.len(), out.len())?;
        let mut bools = std::mem::take(&mut self.bools);
        bools.clear();
        bools.resize(vr.len(), FMI2_FALSE);
        self.begin();
        // SAFETY: both arrays hold `vr.len()` elements.
        let raw = unsafe {
            (self.fns.get_boolean)(self.component, vr.as_ptr(), vr.len(), bools.as_mut_ptr())
        };
        for (o, b) in out.iter_mut().zip(&bools) {
            *o = *b != FMI2_FALSE;
        }
        self.bools = bools;
        self.check("fmi2GetBoolean", raw)
    }

    /// fmi2SetBoolean.
    #[inline]
    pub fn set_boolean(&mut self, vr: &[u32], values: &[bool]) -> Result<(), FmiError> {
        self.same_length("fmi2SetBoolean", vr.len(), values.len())?;
        let mut bools = std::mem::take(&mut self.bools);
        bools.clear();
        bools.extend(
            values
                .iter()
                .map(|&b| if b { FMI2_TRUE } else { FMI2_FALSE }),
        );
        self.begin();
        // SAFETY: both arrays hold `vr.len()` elements.
        let raw = unsafe {
            (self.fns.set_boolean)(self.component, vr.as_ptr(), vr.len(), bools.as_ptr())
        };
        self.bools = bools;
        self.check("fmi2SetBoolean", raw)
    }

    /// fmi2GetString; the strings are copied at once (the FMU's pointers are only valid until
    /// its next call).
    pub fn get_string(&mut self, vr: &[u32]) -> Result<Vec<String>, FmiError> {
        let mut ptrs: Vec<fmi2String> = vec![null(); vr.len()];
        self.begin();
        // SAFETY: both arrays hold `vr.len()` elements.
        let raw = unsafe {
            (self.fns.get_string)(self.component, vr.as_ptr(), vr.len(), ptrs.as_mut_ptr())
        };
        self.check("fmi2GetString", raw)?;
        let mut out = Vec::with_capacity(vr.len());
        for (p, r) in ptrs.iter().zip(vr) {
            if p.is_null() {
                return Err(self.refused(
                    "fmi2GetString",
                    format!("the FMU returned a NULL string for value reference {r}"),
                ));
            }
            // SAFETY: a non-NULL fmi2String is NUL-terminated and valid until the next call.
            out.push(unsafe { CStr::from_ptr(*p) }.to_string_lossy().into_owned());
        }
        Ok(out)
    }

    /// fmi2SetString.
    pub fn set_string(&mut self, vr: &[u32], values: &[&str]) -> Result<(), FmiError> {
        self.same_length("fmi2SetString", vr.len(), values.len())?;
        let mut owned = Vec::with_capacity(values.len());
        for (v, r) in values.iter().zip(vr) {
            match CString::new(*v) {
                Ok(c) => owned.push(c),
                Err(_) => {
                    return Err(self.refused(
                        "fmi2SetString",
                        format!("the value for value reference {r} contains a NUL character"),
                    ));
                }
            }
        }
        let ptrs: Vec<fmi2String> = owned.iter().map(|c| c.as_ptr()).collect();
        self.begin();
        // SAFETY: both arrays hold `vr.len()` elements; the strings outlive the call.
        let raw =
            unsafe { (self.fns.set_string)(self.component, vr.as_ptr(), vr.len(), ptrs.as_ptr()) };
        self.check("fmi2SetString", raw)
    }

    // ---- FMU states ---------------------------------------------------------------------------

    /// Frees (fmi2FreeFMUstate) the states whose [`FmuState`] has been dropped since.
    fn free_dropped_states(&mut self) {
        let dropped = std::mem::take(&mut lock(&self.shelf).dropped);
        for p in dropped {
            let mut s = p as fmi2FMUstate;
            if let Some(i) = self.live_states.iter().position(|&l| l == s) {
                self.live_states.swap_remove(i);
            }
            self.begin();
            // SAFETY: `s` is a state of this component that nobody refers to any more.
            let raw = unsafe { (self.fns.free_fmu_state)(self.component, &mut s) };
            let _ = self.check("fmi2FreeFMUstate", raw);
        }
    }

    fn hand_out(&mut self, s: fmi2FMUstate, from_instance: bool) -> FmuState {
        self.live_states.push(s);
        FmuState {
            ptr: s,
            shelf: Arc::clone(&self.shelf),
            lifecycle: from_instance.then_some(self.lifecycle),
            time: if from_instance { self.time } else { None },
        }
    }

    fn check_owner(&self, function: &'static str, s: &FmuState) -> Result<(), FmiError> {
        if Arc::ptr_eq(&s.shelf, &self.shelf) {
            Ok(())
        } else {
            Err(self.refused(
                function,
                "the FMU state belongs to another instance (an FMU state can only be used with \
                 the instance that made it; serialize it to move it to another instance)"
                    .into(),
            ))
        }
    }

    /// fmi2GetFMUstate: a snapshot of the whole instance.
    pub fn get_fmu_state(&mut self) -> Result<FmuState, FmiError> {
        self.free_dropped_states();
        let mut s: fmi2FMUstate = null_mut();
        self.begin();
        // SAFETY: `s` is NULL, so the FMU allocates a new state.
        let raw = unsafe { (self.fns.get_fmu_state)(self.component, &mut s) };
        self.check("fmi2GetFMUstate", raw)?;
        if s.is_null() {
            return Err(self.refused(
                "fmi2GetFMUstate",
                "the FMU returned success but no state (NULL)".into(),
            ));
        }
        Ok(self.hand_out(s, true))
    }

    /// fmi2GetFMUstate into an existing state of this instance (the FMU reuses its memory):
    /// the allocation-free way to take a snapshot every step.
    pub fn update_fmu_state(&mut self, s: &mut FmuState) -> Result<(), FmiError> {
        self.check_owner("fmi2GetFMUstate", s)?;
        let before = s.ptr;
        self.begin();
        // SAFETY: `s.ptr` is a live state of this component.
        let raw = unsafe { (self.fns.get_fmu_state)(self.component, &mut s.ptr) };
        if s.ptr != before {
            // Not the reuse the spec describes, but keep track of whatever we now hold.
            if let Some(i) = self.live_states.iter().position(|&l| l == before) {
                self.live_states[i] = s.ptr;
            }
        }
        self.check("fmi2GetFMUstate", raw)?;
        s.lifecycle = Some(self.lifecycle);
        s.time = self.time;
        Ok(())
    }

    /// fmi2SetFMUstate: restores a state made by this instance.
    pub fn set_fmu_state(&mut self, s: &FmuState) -> Result<(), FmiError> {
        self.check_owner("fmi2SetFMUstate", s)?;
        self.begin();
        // SAFETY: `s.ptr` is a live state of this component.
        let raw = unsafe { (self.fns.set_fmu_state)(self.component, s.ptr) };
        self.check("fmi2SetFMUstate", raw)?;
        match s.lifecycle {
            Some(l) => {
                self.lifecycle = l;
                self.time = s.time;
            }
            None => {
                // Deserialized: where it stands is only known to the FMU. A restored state is
                // normally a running one.
                if matches!(self.lifecycle, Lifecycle::StepFailed | Lifecycle::Error) {
                    self.lifecycle = Lifecycle::StepComplete;
                }
                self.time = None;
            }
        }
        Ok(())
    }

    /// fmi2SerializedFMUstateSize + fmi2SerializeFMUstate.
    pub fn serialize_fmu_state(&mut self, s: &FmuState) -> Result<Vec<u8>, FmiError> {
        self.check_owner("fmi2SerializeFMUstate", s)?;
        let mut size = 0usize;
        self.begin();
        // SAFETY: `s.ptr` is a live state of this component.
        let raw = unsafe { (self.fns.serialized_fmu_state_size)(self.component, s.ptr, &mut size) };
        self.check("fmi2SerializedFMUstateSize", raw)?;
        let mut bytes = vec![0u8; size];
        self.begin();
        // SAFETY: `bytes` holds `size` bytes.
        let raw = unsafe {
            (self.fns.serialize_fmu_state)(self.component, s.ptr, bytes.as_mut_ptr().cast(), size)
        };
        self.check("fmi2SerializeFMUstate", raw)?;
        Ok(bytes)
    }

    /// fmi2DeSerializeFMUstate: a state of this instance from bytes serialized by any instance
    /// of the same FMU.
    pub fn deserialize_fmu_state(&mut self, bytes: &[u8]) -> Result<FmuState, FmiError> {
        self.free_dropped_states();
        let mut s: fmi2FMUstate = null_mut();
        self.begin();
        // SAFETY: `bytes` holds `len` bytes; `s` is NULL so the FMU allocates.
        let raw = unsafe {
            (self.fns.deserialize_fmu_state)(
                self.component,
                bytes.as_ptr().cast(),
                bytes.len(),
                &mut s,
            )
        };
        self.check("fmi2DeSerializeFMUstate", raw)?;
        if s.is_null() {
            return Err(self.refused(
                "fmi2DeSerializeFMUstate",
                "the FMU returned success but no state (NULL)".into(),
            ));
        }
        Ok(self.hand_out(s, false))
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        {
            let mut shelf = lock(&self.shelf);
            shelf.alive = false;
            shelf.dropped.clear();
        }
        if self.lifecycle == Lifecycle::Fatal {
            // See the type's docs: call nothing, free nothing the FMU may still point to, keep
            // its code mapped.
            std::mem::forget(Arc::clone(&self.fmu.library));
            std::mem::forget(std::mem::take(&mut self.c_name));
        } else {
            // States still held by FmuState values are freed too: their owner is going away,
            // and with `alive` false those values never touch them again.
            for mut s in std::mem::take(&mut self.live_states) {
                // SAFETY: a state of this component, not yet freed.
                unsafe { (self.fns.free_fmu_state)(self.component, &mut s) };
            }
            if matches!(
                self.lifecycle,
                Lifecycle::StepComplete | Lifecycle::StepFailed
            ) {
                // SAFETY: FMI call on our live component, legal in these states.
                unsafe { (self.fns.terminate)(self.component) };
            }
            // SAFETY: the component is not used after this.
            unsafe { (self.fns.free_instance)(self.component) };
            // SAFETY: allocated in `new` with Box; the FMU is gone, nothing points here now.
            unsafe {
                drop(Box::from_raw(self.callbacks.as_ptr()));
                drop(Box::from_raw(self.log.as_ptr()));
            }
        }
        self.fmu.live.fetch_sub(1, Ordering::AcqRel);
    }
}

impl std::fmt::Debug for Instance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Instance")
            .field("name", &self.name)
            .field("fmu", &self.fmu.path)
            .field("lifecycle", &self.lifecycle)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

/// A saved state of one [`Instance`] (fmi2GetFMUstate / fmi2DeSerializeFMUstate).
///
/// Lifetime rule: a state belongs to the instance that made it and is only valid with it; it
/// must not outlive it. This is checked at run time rather than with a borrow (a borrow would
/// forbid the `&mut self` calls the state exists for): using a state with another instance is
/// an [`FmiError`], and when the instance is dropped it frees all its states, after which the
/// remaining `FmuState` values are inert (dropping them does nothing).
///
/// Dropping a state never calls the FMU: it hands the pointer back to its instance, which
/// calls fmi2FreeFMUstate at its next [`get_fmu_state`](Instance::get_fmu_state) /
/// [`deserialize_fmu_state`](Instance::deserialize_fmu_state) or when it is dropped. So a
/// state can be dropped on any thread without racing the thread that runs the instance.
pub struct FmuState {
    ptr: fmi2FMUstate,
    shelf: Shelf,
    /// Where the instance stood when the state was taken (None: deserialized, unknown).
    lifecycle: Option<Lifecycle>,
    time: Option<f64>,
}

// SAFETY: the pointer is only dereferenced by the FMU, in calls made by the owning Instance
// (which checks ownership, and is itself used by one thread at a time); the shelf is a mutex.
unsafe impl Send for FmuState {}
// SAFETY: through a shared `&FmuState` our code only reads plain fields (`time`, `Debug` prints
// the address without dereferencing it). The FMU touches the pointee only in calls the owning
// Instance makes, one at a time (`&mut self`, ownership checked): it only reads a state passed
// as `&FmuState` (set, serialize) and overwrites one only through `&mut FmuState` (update).
unsafe impl Sync for FmuState {}

impl FmuState {
    /// The communication point the state was taken at, if known (None for deserialized states).
    pub fn time(&self) -> Option<f64> {
        self.time
    }
}

impl Drop for FmuState {
    fn drop(&mut self) {
        let mut shelf = lock(&self.shelf);
        if shelf.alive {
            shelf.dropped.push(self.ptr as usize);
        }
    }
}

impl std::fmt::Debug for FmuState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FmuState")
            .field("ptr", &self.ptr)
            .field("time", &self.time)
            .finish()
    }
}

const _: () = {
    const fn send<T: Send>() {}
    send::<Instance>();
    send::<FmuState>();
};
