//! The checks every call goes through: the trace, the oracle's demand (the state table and the
//! argument checks), and after the call the status, the logger contract and the state
//! transition. A violation is a failure of the sequence.

use super::pointers::Comp;
use super::{Fuzzer, Trace};
use crate::api::NAMES;
use crate::log::Record;
use crate::oracle::{Call, State, States, allowed, tolerated};
use std::ffi::c_int;
use std::fmt::Write as _;
use std::io::Write as _;

/// What the oracle demands of one call.
#[derive(Debug, Clone)]
pub(super) enum Expect {
    Error(String),
    Ok(String),
    Any,
}

pub(super) fn fmt_f(x: f64) -> String {
    format!("{x:e}")
}

fn status_name(s: c_int) -> String {
    match s {
        0 => "OK".into(),
        1 => "Warning".into(),
        2 => "Discard".into(),
        3 => "Error".into(),
        4 => "Fatal".into(),
        5 => "Pending".into(),
        x => format!("invalid({x})"),
    }
}

impl Fuzzer<'_> {
    pub(super) fn fail(&mut self, msg: String) {
        let line = format!("  !! {msg}");
        if self.cfg.trace == Trace::Stream {
            eprintln!("{line}");
        }
        self.trace.push(line);
        self.failures.push(msg);
    }

    /// Records a call about to be made (printed first when streaming).
    pub(super) fn begin(&mut self, who: &str, text: String) {
        let line = format!("[{}] {who} {text}", self.calls);
        if self.cfg.trace == Trace::Stream {
            eprint!("{line}");
            let _ = std::io::stderr().flush();
        }
        self.trace.push(line);
        self.calls += 1;
    }

    pub(super) fn end(&mut self, result: String) {
        if self.cfg.trace == Trace::Stream {
            eprintln!(" -> {result}");
        }
        if let Some(l) = self.trace.last_mut() {
            let _ = write!(l, " -> {result}");
        }
    }

    /// The checks common to every call that takes a component: status range, the oracle's
    /// demand, fatal, the logger contract, and the state transition. `next` maps a state in
    /// which the call is legal to the state after success.
    pub(super) fn finish(
        &mut self,
        fidx: usize,
        comp: Comp,
        call: Call,
        status: c_int,
        expect: Expect,
        next: impl Fn(State) -> State,
    ) {
        self.stats.add(fidx, status);
        let name = NAMES[fidx];
        let mut note = status_name(status);
        match &expect {
            Expect::Error(why) => {
                let _ = write!(note, " (must be Error: {why})");
            }
            Expect::Ok(_) => note.push_str(" (must succeed)"),
            Expect::Any => {}
        }
        self.end(note);
        if !(0..=4).contains(&status) {
            self.fail(format!("{name} returned {status}, not a valid fmi2Status"));
        }
        // Messages must go to the instance called, and only there.
        for j in 0..self.insts.len() {
            if matches!(comp, Comp::Inst(i) if i == j) {
                continue;
            }
            let stray = self.insts[j].sink.take();
            if !stray.is_empty() {
                let id = self.insts[j].id;
                self.fail(format!(
                    "{name} on {} logged {} message(s) into i{id}'s environment: {:?}",
                    self.who(comp),
                    stray.len(),
                    stray[0]
                ));
            }
        }
        let Comp::Inst(i) = comp else {
            if status != 3 {
                self.fail(format!(
                    "{name} on a {} component returned {}, not Error",
                    self.who(comp),
                    status_name(status)
                ));
            }
            return;
        };
        let records = self.insts[i].sink.take();
        self.check_records(name, i, &records);
        if status == 3 && self.insts[i].logs_to_us && self.insts[i].errors_logged {
            let logged = records
                .iter()
                .any(|r| r.status >= 3 && r.message.as_ref().is_some_and(|m| !m.is_empty()));
            if !logged {
                self.fail(format!(
                    "{name} returned Error but logged no error message (got {records:?})"
                ));
            }
        }
        match &expect {
            Expect::Error(why) if status != 3 => {
                self.fail(format!(
                    "{name} returned {} but must return Error: {why} (possible states {})",
                    status_name(status),
                    self.insts[i].possible.names()
                ));
            }
            Expect::Ok(why) if !(0..=2).contains(&status) => {
                self.fail(format!(
                    "{name} returned {} but must succeed: {why} (possible states {})",
                    status_name(status),
                    self.insts[i].possible.names()
                ));
            }
            _ => {}
        }
        let inst = &mut self.insts[i];
        if status == 4 {
            inst.fatal = true;
            inst.possible = States::one(State::Fatal);
            let msg = format!(
                "{name} returned Fatal (for these FMUs: an internal panic was caught); logged: {records:?}"
            );
            self.fail(msg);
            return;
        }
        let legal = inst.possible.and(allowed(call));
        let lenient = tolerated(call, inst.possible);
        if (0..=2).contains(&status) {
            let mut after = States::NONE;
            for s in legal.iter() {
                after = after.or(States::one(next(s)));
            }
            after = after.or(lenient);
            if after.is_empty() {
                let msg = format!(
                    "{name} succeeded in possible states {} where it is illegal",
                    inst.possible.names()
                );
                self.fail(msg);
            } else {
                self.insts[i].possible = after;
            }
        } else if status == 3 && matches!(expect, Expect::Any) {
            // An error we could not predict (the model refused): the standard's error state,
            // or unchanged (the layer's "refuse and change nothing").
            inst.possible = inst.possible.or(States::one(State::Error));
        }
    }

    pub(super) fn check_records(&mut self, name: &str, i: usize, records: &[Record]) {
        let want_name = self.insts[i].name.clone();
        for r in records {
            let mut problems = Vec::new();
            if r.category.is_none() {
                problems.push("NULL category");
            }
            if r.instance.is_none() {
                problems.push("NULL instance name");
            }
            if !(0..=4).contains(&r.status) {
                problems.push("status outside 0..=4");
            }
            match &r.message {
                None => problems.push("NULL message format"),
                Some(m) if m.is_empty() => problems.push("empty message"),
                _ => {}
            }
            if let (Some(want), Some(got)) = (&want_name, &r.instance)
                && want != got
            {
                problems.push("instance name is not the one given to fmi2Instantiate");
            }
            if !problems.is_empty() {
                self.fail(format!(
                    "logger call during {name}: {}: {r:?}",
                    problems.join(", ")
                ));
            }
        }
    }

    /// Demand for a state-dependent call: Error if illegal in every possible state (and not a
    /// tolerated leniency there), else `if_legal` when legal in every possible state, else
    /// Any.
    pub(super) fn demand(&self, i: usize, call: Call, if_legal: Expect) -> Expect {
        let p = self.insts[i].possible;
        let legal = p.and(allowed(call));
        if legal.or(tolerated(call, p)).is_empty() {
            Expect::Error(format!("illegal in {}", p.names()))
        } else if legal == p {
            if_legal
        } else {
            Expect::Any
        }
    }

    // ----- the random walk -----------------------------------------------------------------

    /// What the oracle demands of a call on `comp`: fmi2Error on anything but an instance; on
    /// an instance, the state table's demand (`if_legal` where the call is legal in every
    /// possible state), unless the table allows the call and `args`, the argument checks in
    /// the order the FMU must apply them, demand more.
    pub(super) fn expect(
        &self,
        comp: Comp,
        call: Call,
        if_legal: Expect,
        args: impl FnOnce(usize) -> Option<Expect>,
    ) -> Expect {
        let Comp::Inst(i) = comp else {
            return Expect::Error("not an instance".into());
        };
        let d = self.demand(i, call, if_legal);
        if matches!(d, Expect::Error(_)) {
            return d;
        }
        args(i).unwrap_or(d)
    }
}
