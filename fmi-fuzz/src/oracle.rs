//! The FMI 2.0 co-simulation state machine as the fuzzer's oracle, written from the standard
//! (section 4.2.4, "State Machine of Calling Sequence from Master to Slave"; the same masks as
//! the Modelica Association's Reference-FMUs), not from our export layer.
//!
//! The fuzzer cannot ask an FMU which state it is in, so it keeps the *set* of states the
//! instance may be in: a call that succeeds (OK, Warning, Discard) narrows the set to the
//! states where that call is legal and moves it on; fmi2Error adds the error state (the
//! standard's reaction) while keeping the old states (the lenient "refuse and change nothing"
//! reaction). A call whose every possible state forbids it must return fmi2Error.

/// States of an instance (stepInProgress and stepCanceled need asynchronous stepping, which
/// no FMU here declares; they are never entered).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum State {
    /// After fmi2Instantiate or fmi2Reset.
    Instantiated = 1,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode.
    InitializationMode = 2,
    /// Ready for fmi2DoStep.
    StepComplete = 4,
    /// After fmi2DoStep returned fmi2Discard: results may be read, no step taken.
    StepFailed = 8,
    /// After fmi2Terminate.
    Terminated = 16,
    /// After fmi2Error: reads, FMU states, fmi2Reset and fmi2FreeInstance remain legal.
    Error = 32,
    /// After fmi2Fatal: only fmi2FreeInstance.
    Fatal = 64,
}

impl State {
    /// Every state, in the standard's order (bit order of [`States`]).
    pub const ALL: [State; 7] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::Terminated,
        State::Error,
        State::Fatal,
    ];

    /// The standard's name for the state, as failure reports print it.
    pub fn name(self) -> &'static str {
        match self {
            State::Instantiated => "instantiated",
            State::InitializationMode => "initializationMode",
            State::StepComplete => "stepComplete",
            State::StepFailed => "stepFailed",
            State::Terminated => "terminated",
            State::Error => "error",
            State::Fatal => "fatal",
        }
    }
}

/// A set of states (bit mask of [`State`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct States(pub u8);

impl States {
    /// No state: a call allowed nowhere (fmi2CancelStep without asynchronous steps).
    pub const NONE: States = States(0);

    /// The set of the listed states.
    pub fn of(states: &[State]) -> States {
        States(states.iter().fold(0, |m, s| m | *s as u8))
    }
    /// The set holding only `s`: an instance whose state is known.
    pub fn one(s: State) -> States {
        States(s as u8)
    }
    /// Whether the instance may be in `s`.
    pub fn contains(self, s: State) -> bool {
        self.0 & s as u8 != 0
    }
    /// No state possible: a call was legal nowhere the instance might be.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
    /// Intersection: narrows the possible states to those where a call is legal.
    pub fn and(self, o: States) -> States {
        States(self.0 & o.0)
    }
    /// Union: keeps the old states beside a new one when the FMU's reaction is ambiguous.
    pub fn or(self, o: States) -> States {
        States(self.0 | o.0)
    }
    /// Difference: the possible states where a call is not legal.
    pub fn minus(self, o: States) -> States {
        States(self.0 & !o.0)
    }
    /// The states in the set, in [`State::ALL`] order.
    pub fn iter(self) -> impl Iterator<Item = State> {
        State::ALL.into_iter().filter(move |s| self.contains(*s))
    }
    /// The set as `{a,b}` with the standard's names, for failure reports.
    pub fn names(self) -> String {
        let v: Vec<&str> = self.iter().map(State::name).collect();
        format!("{{{}}}", v.join(","))
    }
}

/// The functions whose legality depends on the state (the instance-less ones, fmi2GetVersion,
/// fmi2GetTypesPlatform and fmi2Instantiate, are always callable).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Call {
    /// fmi2SetDebugLogging.
    SetDebugLogging,
    /// fmi2FreeInstance: the only call allowed in the fatal state.
    FreeInstance,
    /// fmi2SetupExperiment.
    SetupExperiment,
    /// fmi2EnterInitializationMode.
    EnterInitializationMode,
    /// fmi2ExitInitializationMode.
    ExitInitializationMode,
    /// fmi2Terminate.
    Terminate,
    /// fmi2Reset.
    Reset,
    /// fmi2GetReal, fmi2GetInteger, fmi2GetBoolean and fmi2GetString (one row of the table).
    Get,
    /// fmi2SetReal, fmi2SetInteger, fmi2SetBoolean and fmi2SetString (the state rule only; which
    /// variables are settable is `Var::settable`).
    Set,
    /// fmi2GetFMUstate, fmi2SetFMUstate, fmi2FreeFMUstate and the serialization functions.
    FmuState,
    /// fmi2GetDirectionalDerivative.
    GetDirectionalDerivative,
    /// fmi2SetRealInputDerivatives.
    SetRealInputDerivatives,
    /// fmi2GetRealOutputDerivatives.
    GetRealOutputDerivatives,
    /// fmi2DoStep.
    DoStep,
    /// fmi2CancelStep: legal only while an asynchronous step runs, so never here.
    CancelStep,
    /// fmi2GetStatus and the typed fmi2Get*Status functions.
    GetStatus,
}

/// The states in which the standard allows `call` (co-simulation columns of the table).
pub fn allowed(call: Call) -> States {
    use State::*;
    let all_but_fatal = States::of(&[
        Instantiated,
        InitializationMode,
        StepComplete,
        StepFailed,
        Terminated,
        Error,
    ]);
    match call {
        Call::SetDebugLogging | Call::Reset | Call::FmuState => all_but_fatal,
        Call::FreeInstance => all_but_fatal.or(States::one(Fatal)),
        Call::SetupExperiment | Call::EnterInitializationMode => States::one(Instantiated),
        Call::ExitInitializationMode => States::one(InitializationMode),
        Call::Terminate => States::of(&[StepComplete, StepFailed]),
        Call::Get | Call::GetDirectionalDerivative => States::of(&[
            InitializationMode,
            StepComplete,
            StepFailed,
            Terminated,
            Error,
        ]),
        Call::Set | Call::SetRealInputDerivatives => {
            States::of(&[Instantiated, InitializationMode, StepComplete])
        }
        Call::GetRealOutputDerivatives => {
            States::of(&[StepComplete, StepFailed, Terminated, Error])
        }
        Call::DoStep => States::one(StepComplete),
        // Only in stepInProgress, which is never entered here.
        Call::CancelStep => States::NONE,
        Call::GetStatus => States::of(&[StepComplete, StepFailed, Terminated]),
    }
}

/// Deliberate, documented leniencies of the FMUs under test that the oracle accepts instead of
/// demanding fmi2Error: a second fmi2Terminate returns fmi2OK (fmi-abi/src/lib.rs,
/// "tolerated deviations").
pub fn tolerated(call: Call, possible: States) -> States {
    match call {
        Call::Terminate => possible.and(States::one(State::Terminated)),
        _ => States::NONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_matches_the_standard_in_a_few_cells() {
        // GetReal is legal after Terminate (and in the error state), DoStep only in
        // stepComplete, nothing but FreeInstance in fatal.
        assert!(allowed(Call::Get).contains(State::Terminated));
        assert!(allowed(Call::Get).contains(State::Error));
        assert!(!allowed(Call::Get).contains(State::Instantiated));
        assert_eq!(allowed(Call::DoStep), States::one(State::StepComplete));
        for c in [
            Call::SetDebugLogging,
            Call::Reset,
            Call::FmuState,
            Call::Get,
            Call::Set,
            Call::DoStep,
            Call::GetStatus,
        ] {
            assert!(!allowed(c).contains(State::Fatal), "{c:?}");
        }
        assert!(allowed(Call::FreeInstance).contains(State::Fatal));
        assert_eq!(
            States::of(&[State::Error, State::Fatal]).names(),
            "{error,fatal}"
        );
    }
}
