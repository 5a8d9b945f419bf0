//! One FMU instance and the FMI 2.0 co-simulation state machine (spec section 4.2.4), in safe
//! Rust. The C entry points in `export` only check pointers and convert arguments.
//!
//! Policy on misuse: a call in the wrong state, an unknown value reference or a bad argument
//! returns fmi2Error with a logged reason and leaves the instance as it was, so a lenient master
//! loses nothing. A failure of the model itself moves the instance to the error state, from which
//! fmi2Reset recovers. A caught panic moves it to the fatal state.

use crate::logger::Logger;
use crate::model::{InstantiateContext, Model, StepOutcome};
use crate::types::fmi2Status;
use crate::variables::{Base, Start, Values, VarIndex, VarSpec};
use model_description::{Causality, Initial, Variability};
use serde::{Deserialize, Serialize};
use std::ffi::CString;

/// The states of the co-simulation state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum State {
    /// After fmi2Instantiate or fmi2Reset: parameters and start values may be set.
    Instantiated,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode: outputs read here are
    /// computed from the current parameters (`Model::calculate_initial`).
    InitializationMode,
    /// Ready for fmi2DoStep, inputs and tunable parameters.
    StepComplete,
    /// The model ended the simulation within the last step (fmi2Discard with fmi2Terminated):
    /// values may be read, no further step taken.
    StepFailed,
    /// After fmi2Terminate: final values may be read.
    Terminated,
    /// The model returned an error; values may be read, fmi2Reset recovers.
    Error,
    /// A panic was caught; only fmi2FreeInstance is accepted.
    Fatal,
}

impl State {
    fn name(self) -> &'static str {
        match self {
            State::Instantiated => "instantiated",
            State::InitializationMode => "initialization mode",
            State::StepComplete => "step complete",
            State::StepFailed => "step failed",
            State::Terminated => "terminated",
            State::Error => "error",
            State::Fatal => "fatal",
        }
    }
}

/// Everything that a saved FMU state must restore. The logger and the caller's callbacks are
/// not part of it: they belong to the instance, not to the simulation.
#[derive(Clone, Serialize, Deserialize)]
#[serde(bound = "M: Model")]
pub struct Snapshot<M: Model> {
    /// Where the state machine stood; restoring a state restores it too.
    pub state: State,
    /// Every FMI variable's current value.
    pub values: Values,
    /// The model's own state (filter, integrator...), beyond its FMI variables.
    pub model: M,
    /// The current communication point in seconds: the next fmi2DoStep must start here.
    pub time: f64,
    /// fmi2SetupExperiment's startTime (0 until it is called).
    pub start_time: f64,
    /// fmi2SetupExperiment's stopTime, if it defined one.
    pub stop_time: Option<f64>,
    /// A tunable parameter was set between steps: `Model::parameters_changed` runs before the
    /// next step.
    pub parameters_dirty: bool,
    /// Parameters or start values changed since `Model::calculate_initial` last ran: a read
    /// in initialization mode recomputes first.
    pub initial_dirty: bool,
    /// Inputs were set since the outputs were last computed (direct feedthrough).
    pub inputs_dirty: bool,
    /// The model ended the simulation ([`StepOutcome::Terminated`]).
    #[serde(default)]
    pub terminated: bool,
}

/// An instance as fmi2Instantiate returns it (wrapped in a tagged handle by `export`).
pub struct Instance<M: Model> {
    /// Where the model's and the layer's messages go: the caller's logger callback.
    pub log: Logger,
    index: VarIndex,
    pub(crate) sim: Snapshot<M>,
    fresh: Snapshot<M>,
    /// Strings returned by fmi2GetString stay valid until the next call (spec 2.1.7).
    strings_out: Vec<CString>,
}

pub(crate) const MAGIC: u64 = 0x5254_4745_4f4d_4649; // "RTGEOMFI"

type Res<T = ()> = Result<T, fmi2Status>;

impl<M: Model> Instance<M> {
    /// fmi2Instantiate after the GUID and type checks: checks the variable table and makes the
    /// model. On failure the logger is handed back with the reason, so the caller can still log
    /// it to the instance's callbacks.
    pub fn new(ctx: &InstantiateContext, log: Logger) -> Result<Self, (Logger, String)> {
        let index = match VarIndex::new(M::variables()) {
            Ok(i) => i,
            Err(e) => return Err((log, format!("internal error in the variable table: {e}"))),
        };
        let model = match M::instantiate(ctx, &log) {
            Ok(m) => m,
            Err(e) => return Err((log, e)),
        };
        let fresh = Snapshot {
            state: State::Instantiated,
            values: Values::from_table(M::variables()),
            model,
            time: 0.0,
            start_time: 0.0,
            stop_time: None,
            parameters_dirty: false,
            initial_dirty: true,
            inputs_dirty: false,
            terminated: false,
        };
        Ok(Instance {
            log,
            index,
            sim: fresh.clone(),
            fresh,
            strings_out: vec![],
        })
    }

    /// Where the state machine stands.
    pub fn state(&self) -> State {
        self.sim.state
    }

    /// The current communication point in seconds.
    pub fn time(&self) -> f64 {
        self.sim.time
    }

    /// The FMI variables as they stand, without the outputs' recomputation a get would do.
    pub fn values(&self) -> &Values {
        &self.sim.values
    }

    fn fail(&self, message: &str) -> fmi2Status {
        self.log.error(message);
        fmi2Status::Error
    }

    /// Refuses the call unless the instance is in one of `allowed`.
    fn require(&self, function: &str, allowed: &[State]) -> Res {
        if allowed.contains(&self.sim.state) {
            return Ok(());
        }
        if self.sim.state == State::Fatal {
            return Err(self.fail(&format!(
                "{function}: the instance is in the fatal state; only fmi2FreeInstance is allowed"
            )));
        }
        let names: Vec<&str> = allowed.iter().map(|s| s.name()).collect();
        Err(self.fail(&format!(
            "{function} is not allowed in state '{}' (allowed in: {})",
            self.sim.state.name(),
            names.join(", ")
        )))
    }

    fn spec(&self, base: Base, vr: u32, function: &str) -> Res<&'static VarSpec> {
        match self.index.row(base, vr) {
            Some(row) => Ok(&M::variables()[row]),
            None => Err(self.fail(&format!(
                "{function}: unknown {} value reference {vr}",
                base.name()
            ))),
        }
    }

    /// fmi2SetupExperiment: refuses a non-finite start or a stop before it; the tolerance is
    /// not used.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Res {
        self.log
            .call(|| format!("fmi2SetupExperiment(startTime={start}, stopTime={stop:?})"));
        self.require("fmi2SetupExperiment", &[State::Instantiated])?;
        if !start.is_finite() {
            return Err(self.fail(&format!(
                "fmi2SetupExperiment: startTime {start} is not finite"
            )));
        }
        if let Some(stop) = stop
            && !(stop >= start)
        {
            return Err(self.fail(&format!(
                "fmi2SetupExperiment: stopTime {stop} is before startTime {start}"
            )));
        }
        self.sim.start_time = start;
        self.sim.time = start;
        self.sim.stop_time = stop;
        Ok(())
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization_mode(&mut self) -> Res {
        self.log.call(|| "fmi2EnterInitializationMode()".into());
        self.require("fmi2EnterInitializationMode", &[State::Instantiated])?;
        self.sim.state = State::InitializationMode;
        self.sim.initial_dirty = true;
        Ok(())
    }

    /// Checks every parameter against the table's bounds, naming the first one out of range.
    fn check_parameter_bounds(&self) -> Result<(), String> {
        for v in M::variables().iter().filter(|v| v.is_parameter()) {
            if let Start::Real(_) = v.start {
                let x = self.sim.values.real[v.vr as usize];
                if !x.is_finite() {
                    return Err(format!(
                        "parameter '{}' = {x} is not a finite number",
                        v.name
                    ));
                }
                if v.min.is_some_and(|m| x < m) || v.max.is_some_and(|m| x > m) {
                    return Err(format!(
                        "parameter '{}' = {x} is outside its range [{}, {}]",
                        v.name,
                        v.min.map_or("-inf".into(), |m| m.to_string()),
                        v.max.map_or("inf".into(), |m| m.to_string())
                    ));
                }
            }
            if let Start::Integer(_) = v.start {
                let x = self.sim.values.integer[v.vr as usize] as f64;
                if v.min.is_some_and(|m| x < m) || v.max.is_some_and(|m| x > m) {
                    return Err(format!("parameter '{}' = {x} is outside its range", v.name));
                }
            }
        }
        Ok(())
    }

    /// fmi2ExitInitializationMode: checks every parameter against its range (naming the first
    /// out of it), computes the initial values and lets the model check its parameters; a
    /// refusal leaves the instance in initialization mode.
    pub fn exit_initialization_mode(&mut self) -> Res {
        self.log.call(|| "fmi2ExitInitializationMode()".into());
        self.require("fmi2ExitInitializationMode", &[State::InitializationMode])?;
        if let Err(e) = self.check_parameter_bounds() {
            return Err(self.fail(&format!("fmi2ExitInitializationMode: {e}")));
        }
        self.sim.model.calculate_initial(&mut self.sim.values);
        let sim = &mut self.sim;
        match sim.model.exit_initialization(&mut sim.values, &self.log) {
            Ok(()) => {
                sim.state = State::StepComplete;
                sim.parameters_dirty = false;
                Ok(())
            }
            Err(e) => Err(self.fail(&format!("fmi2ExitInitializationMode: {e}"))),
        }
    }

    /// fmi2Terminate: lets the model finish; a second call is accepted and does nothing.
    pub fn terminate(&mut self) -> Res {
        self.log.call(|| "fmi2Terminate()".into());
        if self.sim.state == State::Terminated {
            return Ok(()); // a second Terminate is harmless
        }
        self.require("fmi2Terminate", &[State::StepComplete, State::StepFailed])?;
        let sim = &mut self.sim;
        sim.model.terminate(&mut sim.values, &self.log);
        self.sim.state = State::Terminated;
        Ok(())
    }

    /// Back to "as if just instantiated": time, every variable and the model (spec 2.1.6).
    pub fn reset(&mut self) -> Res {
        self.log.call(|| "fmi2Reset()".into());
        self.sim = self.fresh.clone();
        Ok(())
    }

    /// fmi2DoStep from `t` by `h` seconds. `t` must match the instance's time (to a relative
    /// 1e-9) and `h` be positive and finite; a refused call changes nothing. OK or Warning as
    /// the model says; Discard when the model ends the simulation within the step (the time is
    /// then where it ended); a model error moves the instance to the error state.
    pub fn do_step(&mut self, t: f64, h: f64) -> Res<fmi2Status> {
        self.log.call(|| {
            format!("fmi2DoStep(currentCommunicationPoint={t}, communicationStepSize={h})")
        });
        self.require("fmi2DoStep", &[State::StepComplete])?;
        if !(h > 0.0) || !h.is_finite() {
            return Err(self.fail(&format!(
                "fmi2DoStep: communicationStepSize {h} must be a positive finite number"
            )));
        }
        if !t.is_finite() {
            return Err(self.fail(&format!(
                "fmi2DoStep: currentCommunicationPoint {t} is not finite"
            )));
        }
        if !(t + h).is_finite() {
            // The time would overflow to infinity, and no later step could start from it.
            return Err(self.fail(&format!(
                "fmi2DoStep: the step from {t} by {h} ends beyond the largest representable time"
            )));
        }
        let tol = 1e-9 * t.abs().max(self.sim.time.abs()).max(1.0);
        if (t - self.sim.time).abs() > tol {
            return Err(self.fail(&format!(
                "fmi2DoStep: currentCommunicationPoint {t} does not match the FMU's time {}; \
                 restore an FMU state to step from another time",
                self.sim.time
            )));
        }
        let sim = &mut self.sim;
        if sim.parameters_dirty {
            if let Err(e) = sim.model.parameters_changed(&mut sim.values, &self.log) {
                sim.state = State::Error;
                return Err(self.fail(&format!("fmi2DoStep at t={t}: {e}")));
            }
            sim.parameters_dirty = false;
        }
        match sim.model.do_step(&mut sim.values, t, h, &self.log) {
            Ok(StepOutcome::Terminated { at }) => {
                let at = if at.is_nan() { t } else { at.clamp(t, t + h) };
                sim.time = at;
                sim.state = State::StepFailed;
                sim.terminated = true;
                self.log.warning(&format!(
                    "fmi2DoStep at t={t}: the model ended the simulation at t={at} (fmi2Terminated)"
                ));
                Ok(fmi2Status::Discard)
            }
            Ok(outcome) => {
                sim.time = t + h;
                Ok(if outcome == StepOutcome::Warning {
                    fmi2Status::Warning
                } else {
                    fmi2Status::OK
                })
            }
            Err(e) => {
                sim.state = State::Error;
                Err(self.fail(&format!("fmi2DoStep at t={t}: {e}")))
            }
        }
    }

    fn check_get(&mut self, function: &str) -> Res {
        self.require(
            function,
            &[
                State::InitializationMode,
                State::StepComplete,
                State::StepFailed,
                State::Terminated,
                State::Error,
            ],
        )?;
        if self.sim.state == State::InitializationMode && self.sim.initial_dirty {
            self.sim.model.calculate_initial(&mut self.sim.values);
            self.sim.initial_dirty = false;
        }
        if self.sim.inputs_dirty {
            self.sim.model.update_outputs(&mut self.sim.values);
            self.sim.inputs_dirty = false;
        }
        Ok(())
    }

    /// Whether `v` may be set now (spec table 4.2.4 "Set" row).
    fn check_set(&self, v: &VarSpec, function: &str) -> Res {
        let ok = match self.sim.state {
            State::Instantiated => {
                v.variability != Variability::Constant
                    && (v.causality == Causality::Input
                        || matches!(v.initial, Some(Initial::Exact | Initial::Approx)))
            }
            State::InitializationMode => {
                v.causality == Causality::Input || v.initial == Some(Initial::Exact)
            }
            State::StepComplete => {
                v.causality == Causality::Input
                    || (v.causality == Causality::Parameter
                        && v.variability == Variability::Tunable)
            }
            _ => false,
        };
        if ok {
            return Ok(());
        }
        let what = match (v.causality, v.variability) {
            (Causality::Output, _) => "it is an output".to_string(),
            (Causality::Parameter, Variability::Fixed) => {
                "it is a fixed parameter, settable only before initialization ends".into()
            }
            _ => "of its causality and variability".into(),
        };
        Err(self.fail(&format!(
            "{function}: variable '{}' cannot be set in state '{}' because {what}",
            v.name,
            self.sim.state.name()
        )))
    }

    /// The states in which fmi2Set* may be called at all, whatever the variables (also with
    /// nvr = 0, which used to pass in any state: found by fmi-fuzz).
    fn require_set_state(&self, function: &str) -> Res {
        self.require(
            function,
            &[
                State::Instantiated,
                State::InitializationMode,
                State::StepComplete,
            ],
        )
    }

    fn after_set(&mut self, v: &VarSpec) {
        if v.causality == Causality::Input {
            self.sim.inputs_dirty = true;
        }
        if v.causality == Causality::Parameter {
            match self.sim.state {
                State::StepComplete => self.sim.parameters_dirty = true,
                _ => self.sim.initial_dirty = true,
            }
        }
    }

    /// fmi2GetReal: `out[k]` gets the value of `vr[k]`, after recomputing the outputs if inputs
    /// were set (and the initial values, in initialization mode); an unknown reference is an
    /// error, though the values before it are already written.
    pub fn get_real(&mut self, vr: &[u32], out: &mut [f64]) -> Res {
        self.check_get("fmi2GetReal")?;
        for (r, o) in vr.iter().zip(out.iter_mut()) {
            let v = self.spec(Base::Real, *r, "fmi2GetReal")?;
            *o = self.sim.values.real[v.vr as usize];
        }
        Ok(())
    }

    /// fmi2GetInteger: `out[k]` gets the value of `vr[k]`, after recomputing the outputs if inputs
    /// were set (and the initial values, in initialization mode); an unknown reference is an
    /// error, though the values before it are already written.
    pub fn get_integer(&mut self, vr: &[u32], out: &mut [i32]) -> Res {
        self.check_get("fmi2GetInteger")?;
        for (r, o) in vr.iter().zip(out.iter_mut()) {
            let v = self.spec(Base::Integer, *r, "fmi2GetInteger")?;
            *o = self.sim.values.integer[v.vr as usize];
        }
        Ok(())
    }

    /// fmi2GetBoolean: `out[k]` gets the value of `vr[k]`, after recomputing the outputs if inputs
    /// were set (and the initial values, in initialization mode); an unknown reference is an
    /// error, though the values before it are already written.
    pub fn get_boolean(&mut self, vr: &[u32], out: &mut [bool]) -> Res {
        self.check_get("fmi2GetBoolean")?;
        for (r, o) in vr.iter().zip(out.iter_mut()) {
            let v = self.spec(Base::Boolean, *r, "fmi2GetBoolean")?;
            *o = self.sim.values.boolean[v.vr as usize];
        }
        Ok(())
    }

    /// Returns pointers that stay valid until the next fmi2GetString on this instance.
    pub fn get_string(&mut self, vr: &[u32]) -> Res<Vec<*const std::ffi::c_char>> {
        self.check_get("fmi2GetString")?;
        let mut strings = Vec::with_capacity(vr.len());
        for r in vr {
            let v = self.spec(Base::String, *r, "fmi2GetString")?;
            let s = &self.sim.values.string[v.vr as usize];
            strings.push(CString::new(s.replace('\0', "")).unwrap_or_default());
        }
        self.strings_out = strings;
        Ok(self.strings_out.iter().map(|s| s.as_ptr()).collect())
    }

    /// Checks every reference before changing anything, so a bad call changes nothing.
    fn set_generic<T: Copy>(
        &mut self,
        base: Base,
        function: &str,
        vr: &[u32],
        vals: &[T],
        store: fn(&mut Values, usize, T),
    ) -> Res {
        self.require_set_state(function)?;
        let mut rows = Vec::with_capacity(vr.len());
        for r in vr {
            let v = self.spec(base, *r, function)?;
            self.check_set(v, function)?;
            rows.push(v);
        }
        for (v, x) in rows.into_iter().zip(vals) {
            store(&mut self.sim.values, v.vr as usize, *x);
            self.after_set(v);
        }
        Ok(())
    }

    /// fmi2SetReal: every reference is checked (known, settable in this state) before any value
    /// changes, so a refused call changes nothing.
    pub fn set_real(&mut self, vr: &[u32], vals: &[f64]) -> Res {
        self.log
            .call(|| format!("fmi2SetReal(vr={vr:?}, value={vals:?})"));
        self.set_generic(Base::Real, "fmi2SetReal", vr, vals, |s, i, x| s.real[i] = x)
    }

    /// fmi2SetInteger: every reference is checked (known, settable in this state) before any value
    /// changes, so a refused call changes nothing.
    pub fn set_integer(&mut self, vr: &[u32], vals: &[i32]) -> Res {
        self.log
            .call(|| format!("fmi2SetInteger(vr={vr:?}, value={vals:?})"));
        self.set_generic(Base::Integer, "fmi2SetInteger", vr, vals, |s, i, x| {
            s.integer[i] = x
        })
    }

    /// fmi2SetBoolean: every reference is checked (known, settable in this state) before any value
    /// changes, so a refused call changes nothing.
    pub fn set_boolean(&mut self, vr: &[u32], vals: &[bool]) -> Res {
        self.log
            .call(|| format!("fmi2SetBoolean(vr={vr:?}, value={vals:?})"));
        self.set_generic(Base::Boolean, "fmi2SetBoolean", vr, vals, |s, i, x| {
            s.boolean[i] = x
        })
    }

    /// fmi2SetString: every reference is checked (known, settable in this state) before any value
    /// changes, so a refused call changes nothing.
    pub fn set_string(&mut self, vr: &[u32], vals: &[String]) -> Res {
        self.log
            .call(|| format!("fmi2SetString(vr={vr:?}, value={vals:?})"));
        self.require_set_state("fmi2SetString")?;
        let mut rows = Vec::with_capacity(vr.len());
        for r in vr {
            let v = self.spec(Base::String, *r, "fmi2SetString")?;
            self.check_set(v, "fmi2SetString")?;
            rows.push(v);
        }
        for (v, x) in rows.into_iter().zip(vals) {
            self.sim.values.string[v.vr as usize] = x.clone();
            self.after_set(v);
        }
        Ok(())
    }

    /// fmi2GetStatus and fmi2Get*Status are legal once stepping has begun: stepComplete,
    /// stepFailed and terminated (FMI 2.0 section 4.2.4; stepInProgress is never entered here).
    pub(crate) fn check_status_query(&self, function: &str) -> Res {
        self.require(
            function,
            &[State::StepComplete, State::StepFailed, State::Terminated],
        )
    }

    /// After fmi2Fatal only fmi2FreeInstance is allowed (FMI 2.0 section 2.1.3).
    pub(crate) fn refuse_if_fatal(&self, function: &str) -> Res {
        if self.sim.state == State::Fatal {
            return Err(self.fail(&format!(
                "{function}: the instance is in the fatal state; only fmi2FreeInstance is allowed"
            )));
        }
        Ok(())
    }

    /// fmi2GetRealStatus(fmi2LastSuccessfulTime): the time reached, also after a step the model
    /// ended early.
    pub fn last_successful_time(&self) -> f64 {
        self.sim.time
    }

    /// Whether the model ended the simulation (fmi2GetBooleanStatus(fmi2Terminated)).
    pub fn terminated(&self) -> bool {
        self.sim.terminated
    }

    /// fmi2GetFMUstate: a copy of everything the simulation depends on.
    pub fn snapshot(&self) -> Snapshot<M> {
        self.sim.clone()
    }

    /// fmi2SetFMUstate: the instance continues exactly as when `snap` was taken; refused once
    /// fatal, since a panic may have left the model inconsistent.
    pub fn restore(&mut self, snap: &Snapshot<M>) -> Res {
        if self.sim.state == State::Fatal {
            return Err(self.fail("fmi2SetFMUstate: the instance is in the fatal state"));
        }
        self.sim.clone_from(snap);
        Ok(())
    }

    /// Marks the instance fatal after a caught panic.
    pub(crate) fn poison(&mut self, message: &str) {
        self.sim.state = State::Fatal;
        self.log.fatal(message);
    }
}

/// The serialized FMU state: a header naming the FMU, the body's length and FNV-1a checksum,
/// then the snapshot in postcard format (little-endian IEEE doubles, so values come back bit
/// for bit). The header lets us refuse a state from another FMU or another build with a
/// message instead of decoding garbage; the length and checksum refuse a truncated, extended
/// or damaged copy, which postcard alone would often decode into wrong values (found by the
/// fmi-fuzz state-machine fuzzer). The checksum guards against accidents, not forgery.
pub fn serialize<M: Model>(snap: &Snapshot<M>) -> Result<Vec<u8>, String> {
    let body =
        postcard::to_stdvec(snap).map_err(|e| format!("cannot serialize the FMU state: {e}"))?;
    let mut out = state_header::<M>();
    out.reserve(16 + body.len());
    out.extend_from_slice(&(body.len() as u64).to_le_bytes());
    out.extend_from_slice(&fnv1a(&body).to_le_bytes());
    out.extend_from_slice(&body);
    Ok(out)
}

/// `RTGS3`, the GUID and the model's state layout, each NUL-terminated (`RTGS2` had no layout).
fn state_header<M: Model>() -> Vec<u8> {
    let mut header = b"RTGS3\0".to_vec();
    header.extend_from_slice(M::INFO.guid.as_bytes());
    header.push(0);
    header.extend_from_slice(M::STATE_LAYOUT.as_bytes());
    header.push(0);
    header
}

/// 64-bit FNV-1a.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The inverse of [`serialize`]: refuses, with a message naming the cause, bytes from another
/// FMU or build (header), truncated or extended (length), damaged (checksum), or of another
/// variable table.
pub fn deserialize<M: Model>(bytes: &[u8]) -> Result<Snapshot<M>, String> {
    let header = state_header::<M>();
    let Some(rest) = bytes.strip_prefix(header.as_slice()) else {
        return Err(format!(
            "the serialized state was not made by {} (GUID {}, state layout '{}') or by this build of it",
            M::INFO.model_name,
            M::INFO.guid,
            M::STATE_LAYOUT
        ));
    };
    let (Some(len), Some(sum)) = (rest.get(..8), rest.get(8..16)) else {
        return Err("the serialized state is truncated".into());
    };
    let len = u64::from_le_bytes(len.try_into().unwrap());
    let sum = u64::from_le_bytes(sum.try_into().unwrap());
    let body = &rest[16..];
    if body.len() as u64 != len {
        return Err(format!(
            "the serialized state is {} bytes, its header says {len}: truncated or extended",
            body.len()
        ));
    }
    if fnv1a(body) != sum {
        return Err("the serialized state is corrupt (checksum mismatch)".into());
    }
    let (snap, left): (Snapshot<M>, _) = postcard::take_from_bytes(body)
        .map_err(|e| format!("the serialized state is corrupt: {e}"))?;
    if !left.is_empty() {
        return Err("the serialized state has trailing bytes".into());
    }
    let expected = Values::from_table(M::variables());
    let same_shape = snap.values.real.len() == expected.real.len()
        && snap.values.integer.len() == expected.integer.len()
        && snap.values.boolean.len() == expected.boolean.len()
        && snap.values.string.len() == expected.string.len();
    if !same_shape {
        return Err("the serialized state has a different variable table".into());
    }
    Ok(snap)
}
