//! The random walk: which function comes next, on which component. Half of the calls follow an
//! instance's normal life cycle so that deep states are reached at all; the rest are any of
//! the 34 functions with hostile arguments.

use super::pointers::Comp;
use super::{Fuzzer, MAX_INSTANCES};
use crate::api::{Base, NAMES};
use crate::oracle::{Call, State, States};

impl Fuzzer<'_> {
    pub(super) fn one_call(&mut self) {
        if self.insts.is_empty() && self.rng.chance(85) {
            let valid = self.rng.chance(80);
            self.instantiate(valid);
            return;
        }
        // Half of the calls follow the normal life cycle of a random instance (with valid
        // arguments), so that deep states are reached; the rest are random functions with
        // hostile arguments.
        if !self.insts.is_empty() && self.rng.chance(50) {
            let i = self.rng.below(self.insts.len());
            self.progress(i);
            return;
        }
        // Weights per function, in NAMES order.
        const W: [u32; 34] = [
            1, 1, 3, 4, 2, 3, 3, 3, 3, 3, // ... Reset
            6, 3, 3, 3, 6, 3, 3, 3, // Get/Set
            4, 4, 3, 3, 4, 5, // FMU state
            1, 1, 1, 8, 1, 2, 3, 2, 2, 2,
        ];
        let f = self.rng.weighted(&W);
        self.call(f, true);
    }

    /// Calls function number `f` (NAMES order) on a random component.
    fn call(&mut self, f: usize, hostile: bool) {
        match NAMES[f] {
            "fmi2GetTypesPlatform" | "fmi2GetVersion" => self.version(f),
            "fmi2Instantiate" => {
                if self.insts.len() < MAX_INSTANCES {
                    let valid = !hostile || self.rng.chance(50);
                    self.instantiate(valid);
                }
            }
            "fmi2FreeInstance" => {
                let c = self.pick_comp();
                self.free_instance(c);
            }
            _ => {
                let c = self.pick_comp();
                if let Comp::Inst(i) = c
                    && self.insts[i].fatal
                {
                    // After fmi2Fatal only fmi2FreeInstance is allowed.
                    self.free_instance(c);
                    return;
                }
                self.call_on(f, c, hostile);
            }
        }
    }

    fn call_on(&mut self, f: usize, c: Comp, hostile: bool) {
        match NAMES[f] {
            "fmi2SetDebugLogging" => self.set_debug_logging(c, hostile),
            "fmi2SetupExperiment" => self.setup_experiment(c, hostile),
            "fmi2EnterInitializationMode" => self.simple(f, c, Call::EnterInitializationMode),
            "fmi2ExitInitializationMode" => self.simple(f, c, Call::ExitInitializationMode),
            "fmi2Terminate" => self.simple(f, c, Call::Terminate),
            "fmi2Reset" => self.simple(f, c, Call::Reset),
            "fmi2GetReal" => self.get(c, Base::Real, hostile),
            "fmi2GetInteger" => self.get(c, Base::Integer, hostile),
            "fmi2GetBoolean" => self.get(c, Base::Boolean, hostile),
            "fmi2GetString" => self.get(c, Base::String, hostile),
            "fmi2SetReal" => self.set(c, Base::Real, hostile),
            "fmi2SetInteger" => self.set(c, Base::Integer, hostile),
            "fmi2SetBoolean" => self.set(c, Base::Boolean, hostile),
            "fmi2SetString" => self.set(c, Base::String, hostile),
            "fmi2GetFMUstate" => self.get_fmu_state(c, hostile),
            "fmi2SetFMUstate" => self.set_fmu_state(c, hostile),
            "fmi2FreeFMUstate" => self.free_fmu_state(c, hostile),
            "fmi2SerializedFMUstateSize" => {
                self.serialized_size(c, hostile);
            }
            "fmi2SerializeFMUstate" => self.serialize(c, hostile),
            "fmi2DeSerializeFMUstate" => self.deserialize(c, hostile),
            "fmi2GetDirectionalDerivative" => self.directional(c),
            "fmi2SetRealInputDerivatives" => self.input_derivatives(c),
            "fmi2GetRealOutputDerivatives" => self.output_derivatives(c),
            "fmi2DoStep" => self.do_step(c, hostile),
            "fmi2CancelStep" => self.simple(f, c, Call::CancelStep),
            "fmi2GetStatus"
            | "fmi2GetRealStatus"
            | "fmi2GetIntegerStatus"
            | "fmi2GetBooleanStatus"
            | "fmi2GetStringStatus" => self.status(f, c, hostile),
            other => unreachable!("{other}"),
        }
    }

    /// The next step of the normal life cycle of instance `i`.
    fn progress(&mut self, i: usize) {
        let c = Comp::Inst(i);
        if self.insts[i].fatal {
            self.free_instance(c);
            return;
        }
        let p = self.insts[i].possible;
        let f = |n: &str| NAMES.iter().position(|x| *x == n).unwrap();
        let r = self.rng.below(100);
        if p == States::one(State::Instantiated) {
            match r {
                0..40 => self.setup_experiment(c, false),
                40..55 => {
                    let b = *self.rng.pick(&Base::ALL);
                    self.set(c, b, false)
                }
                _ => self.simple(
                    f("fmi2EnterInitializationMode"),
                    c,
                    Call::EnterInitializationMode,
                ),
            }
        } else if p == States::one(State::InitializationMode) {
            match r {
                0..20 => self.set(c, Base::Real, false),
                20..35 => {
                    let b = *self.rng.pick(&Base::ALL);
                    self.get(c, b, false)
                }
                _ => self.simple(
                    f("fmi2ExitInitializationMode"),
                    c,
                    Call::ExitInitializationMode,
                ),
            }
        } else if p == States::one(State::StepComplete) {
            match r {
                0..25 => self.set(c, Base::Real, false),
                25..40 => {
                    let b = *self.rng.pick(&Base::ALL);
                    self.get(c, b, false)
                }
                40..47 => self.get_fmu_state(c, false),
                47..52 => self.set_fmu_state(c, false),
                52..56 => self.serialize(c, false),
                56..59 => self.deserialize(c, false),
                59..61 => self.status(f("fmi2GetRealStatus"), c, false),
                61..63 => self.simple(f("fmi2Terminate"), c, Call::Terminate),
                _ => self.do_step(c, false),
            }
        } else if p.contains(State::Error) || p.contains(State::Terminated) {
            match r {
                0..30 => self.get(c, Base::Real, false),
                30..40 => self.set_fmu_state(c, false),
                40..50 => self.free_instance(c),
                _ => self.simple(f("fmi2Reset"), c, Call::Reset),
            }
        } else {
            // Unsure where it is: a getter or a reset.
            if r < 50 {
                self.get(c, Base::Real, false);
            } else {
                self.simple(f("fmi2Reset"), c, Call::Reset);
            }
        }
    }

    pub(super) fn cleanup(&mut self) {
        while !self.insts.is_empty() {
            self.free_instance(Comp::Inst(0));
        }
    }
}
