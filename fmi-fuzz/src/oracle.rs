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
    Instantiated = 1,
    InitializationMode = 2,
    StepComplete = 4,
    StepFailed = 8,
    Terminated = 16,
    Error = 32,
    Fatal = 64,
}

impl State {
    pub const ALL: [State; 7] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::Terminated,
        State::Error,
        State::Fatal,
    ];

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
    pub const NONE: States = States(0);

    pub fn of(states: &[State]) -> States {
        States(states.iter().fold(0, |m, s| m | *s as u8))
    }
    pub fn one(s: State) -> States {
        States(s as u8)
    }
    pub fn contains(self, s: State) -> bool {
        self.0 & s as u8 != 0
    }
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
    pub fn and(self, o: States) -> States {
        States(self.0 & o.0)
    }
    pub fn or(self, o: States) -> States {
        States(self.0 | o.0)
    }
    pub fn minus(self, o: States) -> States {
        States(self.0 & !o.0)
    }
    pub fn iter(self) -> impl Iterator<Item = State> {
        State::ALL.into_iter().filter(move |s| self.contains(*s))
    }
    pub fn names(self) -> String {
        let v: Vec<&str> = self.iter().map(State::name).collect();
        format!("{{{}}}", v.join(","))
    }
}

/// The functions whose legality depends on the state (the instance-less ones, fmi2GetVersion,
/// fmi2GetTypesPlatform and fmi2Instantiate, are always callable).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Call {
    SetDebugLogging,
    FreeInstance,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    Get,
    Set,
    FmuState,
    GetDirectionalDerivative,
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
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
