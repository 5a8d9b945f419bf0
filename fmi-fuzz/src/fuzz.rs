//! One fuzz sequence: a seeded random walk over the 34 functions of one FMU, with the
//! arguments a hostile or careless master might pass, checked against the oracle.
//!
//! What is checked on every call (a violation is a *failure*, reported with the seed and the
//! call sequence):
//! - the status is a valid fmi2Status for a synchronous co-simulation FMU (0..=4);
//! - fmi2Fatal is never returned (for these FMUs it means an internal panic was caught);
//! - a call that the state table forbids in every state the instance may be in, a NULL
//!   component, a pointer that is not an instance or state, a NULL array with nvr > 0, an
//!   unknown value reference, a variable not settable in the current state, a non-finite or
//!   non-positive step size, a step from the wrong time, a corrupt serialized state or an
//!   unsupported capability returns fmi2Error;
//! - a call that is legal in every possible state with valid arguments and that does not run
//!   the model (getters, setters, FMU-state functions, Reset, Setup/Enter, Terminate) succeeds:
//!   after fmi2Error the instance still answers;
//! - every fmi2Error of an instance that has a logger (with the error category on) is
//!   accompanied by a logged message; every logged message has a non-NULL instance name and
//!   category, a status in 0..=4 and a non-NULL, non-empty text; nothing is logged into
//!   another instance's environment;
//! - values read back are those written (bit for bit), also after restoring an FMU state or
//!   deserializing one; fmi2GetBoolean returns 0 or 1; getters write no element past nvr,
//!   fmi2SerializeFMUstate no byte past its size; fmi2FreeFMUstate sets the state to NULL;
//! - fmi2GetRealStatus(fmi2LastSuccessfulTime) is the time the steps reached;
//! - fmi2Instantiate returns NULL (with a logged message) for a wrong GUID or fmuType, an
//!   instance for the right ones.
//!
//! The fuzzer never passes a freed pointer (it keeps its own books: a double free or a
//! dangling pointer is undefined behaviour for any C API, not a test of the FMU), and after
//! fmi2Fatal it only calls fmi2FreeInstance on that instance.

use crate::api::{Base, NAMES, Target, Var, as_ptr, foreign_block};
use crate::log::{LogSink, Record};
use crate::oracle::{Call, State, States, allowed, tolerated};
use crate::rng::Rng;
use fmi_abi::types::{fmi2CallbackFunctions, fmi2Component, fmi2FMUstate, fmi2String};
use model_description::Causality;
use std::collections::BTreeMap;
use std::ffi::{CStr, CString, c_char, c_int};
use std::fmt::Write as _;
use std::io::Write as _;

/// Live instances per sequence at most.
const MAX_INSTANCES: usize = 3;
/// Saved FMU states per instance at most.
const MAX_STATES: usize = 4;
/// Sentinel written past the end of output arrays.
const CANARY_REAL: u64 = 0x7FF4_DEAD_BEEF_0001;
const CANARY_INT: i32 = 0x5A5A_5A5A;
const CANARY_BYTE: u8 = 0xA5;

/// Counts of returned statuses per function: `[function][status]`, status 6 = outside 0..=5.
#[derive(Clone)]
pub struct Stats {
    pub counts: Vec<[u64; 7]>,
}

impl Default for Stats {
    fn default() -> Self {
        Stats {
            counts: vec![[0; 7]; NAMES.len()],
        }
    }
}

impl Stats {
    fn add(&mut self, f: usize, status: c_int) {
        let col = if (0..=5).contains(&status) {
            status as usize
        } else {
            6
        };
        self.counts[f][col] += 1;
    }

    pub fn merge(&mut self, o: &Stats) {
        for (a, b) in self.counts.iter_mut().zip(&o.counts) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
    }

    pub fn total(&self) -> u64 {
        self.counts.iter().flatten().sum()
    }
}

/// How a sequence reports what it does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trace {
    /// Keep the lines, print them only with a failure.
    Collect,
    /// Also print every call to stderr *before* making it (to see the call that crashes).
    Stream,
}

#[derive(Debug, Clone)]
pub struct Config {
    pub max_len: usize,
    pub trace: Trace,
    /// Variable settings applied right after most instantiations (by name), to make an
    /// expensive initialization cheap, e.g. `lateral_irregularity=false`.
    pub presets: Vec<(String, String)>,
    /// Percentage of instances that get the presets.
    pub preset_percent: u32,
}

/// What one sequence did.
pub struct SeqResult {
    pub seed: u64,
    pub calls: u64,
    pub failures: Vec<String>,
    pub trace: Vec<String>,
}

/// What the fuzzer knows a variable holds.
#[derive(Debug, Clone, PartialEq)]
enum Known {
    Real(u64),
    Int(i32),
    Bool(bool),
    Str(String),
}

type KnownMap = BTreeMap<(u8, u32), Known>;

fn key(base: Base, vr: u32) -> (u8, u32) {
    (base as u8, vr)
}

struct SavedState {
    ptr: fmi2FMUstate,
    possible: States,
    time: Option<f64>,
    known: KnownMap,
    size: Option<usize>,
}

struct Blob {
    bytes: Vec<u8>,
    possible: States,
    time: Option<f64>,
    known: KnownMap,
}

struct Inst {
    id: usize,
    c: fmi2Component,
    sink: Box<LogSink>,
    _callbacks: Option<Box<fmi2CallbackFunctions>>,
    /// The name we passed (None: NULL).
    name: Option<String>,
    /// Logger and environment given: messages reach our sink.
    logs_to_us: bool,
    /// Whether the error category is on (fmi2SetDebugLogging may switch it off).
    errors_logged: bool,
    categories_off: std::collections::BTreeSet<String>,
    possible: States,
    time: Option<f64>,
    known: KnownMap,
    states: Vec<SavedState>,
    fatal: bool,
    /// Non-input variables were changed (or a state restored): initialization may fail.
    params_touched: bool,
    /// Instantiated without a usable resource location.
    no_resources: bool,
}

/// The component a call goes to.
#[derive(Clone, Copy)]
enum Comp {
    Inst(usize),
    Null,
    Foreign,
}

/// What the oracle demands of one call.
#[derive(Debug, Clone)]
enum Expect {
    Error(String),
    Ok(String),
    Any,
}

pub struct Fuzzer<'t> {
    t: &'t Target,
    cfg: &'t Config,
    rng: Rng,
    seed: u64,
    insts: Vec<Inst>,
    blobs: Vec<Blob>,
    next_id: usize,
    foreign: Box<[u64; 32]>,
    trace: Vec<String>,
    failures: Vec<String>,
    calls: u64,
    pub stats: Stats,
    caps: Caps,
}

struct Caps {
    directional: bool,
    interpolate: bool,
    output_derivatives: bool,
}

fn fmt_f(x: f64) -> String {
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

const REAL_EDGES: [f64; 15] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::MAX,
    f64::MIN,
    f64::MIN_POSITIVE,
    5e-324,
    1e300,
    -1e300,
    1e-300,
    1e6,
];

const INT_EDGES: [i32; 10] = [0, 1, -1, 2, 3, 4, 5, i32::MIN, i32::MAX, 1000];

fn string_edges() -> Vec<Vec<u8>> {
    vec![
        b"".to_vec(),
        b"ml95.toml".to_vec(),
        b"manchester.toml".to_vec(),
        b"no-such-file.toml".to_vec(),
        b"/nonexistent/dir/track.csv".to_vec(),
        b"%s%s%n%x%p 100%".to_vec(),
        "\u{fc}\u{20ac}\u{1d11e}".as_bytes().to_vec(),
        vec![b'a'; 10_000],
        vec![0xff, 0xfe, 0x80, b'x'],
        b"calibration.toml".to_vec(),
    ]
}

impl<'t> Fuzzer<'t> {
    pub fn new(t: &'t Target, cfg: &'t Config, seed: u64) -> Fuzzer<'t> {
        let md_caps = target_caps(t);
        Fuzzer {
            t,
            cfg,
            rng: Rng::new(seed),
            seed,
            insts: Vec::new(),
            blobs: Vec::new(),
            next_id: 0,
            foreign: foreign_block(0xC3),
            trace: Vec::new(),
            failures: Vec::new(),
            calls: 0,
            stats: Stats::default(),
            caps: md_caps,
        }
    }

    /// Runs one sequence of at most `max_len` calls (plus the clean-up calls), then frees
    /// everything still live.
    pub fn run(mut self) -> (SeqResult, Stats) {
        let len = self.rng.range(1, self.cfg.max_len.max(1));
        for _ in 0..len {
            self.one_call();
        }
        self.cleanup();
        let r = SeqResult {
            seed: self.seed,
            calls: self.calls,
            failures: std::mem::take(&mut self.failures),
            trace: std::mem::take(&mut self.trace),
        };
        (r, self.stats)
    }

    // ----- bookkeeping ---------------------------------------------------------------------

    fn fail(&mut self, msg: String) {
        let line = format!("  !! {msg}");
        if self.cfg.trace == Trace::Stream {
            eprintln!("{line}");
        }
        self.trace.push(line);
        self.failures.push(msg);
    }

    /// Records a call about to be made (printed first when streaming).
    fn begin(&mut self, who: &str, text: String) {
        let line = format!("[{}] {who} {text}", self.calls);
        if self.cfg.trace == Trace::Stream {
            eprint!("{line}");
            let _ = std::io::stderr().flush();
        }
        self.trace.push(line);
        self.calls += 1;
    }

    fn end(&mut self, result: String) {
        if self.cfg.trace == Trace::Stream {
            eprintln!(" -> {result}");
        }
        if let Some(l) = self.trace.last_mut() {
            let _ = write!(l, " -> {result}");
        }
    }

    fn who(&self, comp: Comp) -> String {
        match comp {
            Comp::Inst(i) => format!("i{}", self.insts[i].id),
            Comp::Null => "NULL".into(),
            Comp::Foreign => "FOREIGN".into(),
        }
    }

    fn comp_ptr(&self, comp: Comp) -> fmi2Component {
        match comp {
            Comp::Inst(i) => self.insts[i].c,
            Comp::Null => std::ptr::null_mut(),
            Comp::Foreign => as_ptr(&self.foreign),
        }
    }

    /// A live instance, NULL or a foreign pointer.
    fn pick_comp(&mut self) -> Comp {
        if !self.insts.is_empty() && self.rng.chance(92) {
            return Comp::Inst(self.rng.below(self.insts.len()));
        }
        if self.rng.chance(60) {
            Comp::Null
        } else {
            Comp::Foreign
        }
    }

    /// The checks common to every call that takes a component: status range, the oracle's
    /// demand, fatal, the logger contract, and the state transition. `next` maps a state in
    /// which the call is legal to the state after success.
    fn finish(
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

    fn check_records(&mut self, name: &str, i: usize, records: &[Record]) {
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
    fn demand(&self, i: usize, call: Call, if_legal: Expect) -> Expect {
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

    fn one_call(&mut self) {
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

    fn cleanup(&mut self) {
        while !self.insts.is_empty() {
            self.free_instance(Comp::Inst(0));
        }
    }

    // ----- the functions -------------------------------------------------------------------

    fn version(&mut self, f: usize) {
        self.begin("-", format!("{}()", NAMES[f]));
        let (p, want) = if NAMES[f] == "fmi2GetVersion" {
            // SAFETY: no arguments.
            (unsafe { (self.t.api.get_version)() }, "2.0")
        } else {
            (unsafe { (self.t.api.get_types_platform)() }, "default")
        };
        self.stats.add(f, 0);
        if p.is_null() {
            self.end("NULL".into());
            self.fail(format!("{} returned NULL", NAMES[f]));
            return;
        }
        // SAFETY: the standard says a static NUL-terminated string.
        let s = unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
        self.end(format!("{s:?}"));
        if s != want {
            self.fail(format!("{} returned {s:?}, not {want:?}", NAMES[f]));
        }
    }

    fn instantiate(&mut self, valid: bool) {
        let fidx = 3;
        let r = &mut self.rng;
        let id = self.next_id;
        let mut why_null: Vec<&str> = Vec::new();
        let name: Option<Vec<u8>> = if valid || r.chance(70) {
            Some(format!("fuzz{id}").into_bytes())
        } else {
            r.pick(&[
                None,
                Some(b"".to_vec()),
                Some(b"%s%n%x 100% \"quoted\"".to_vec()),
                Some(vec![b'n'; 5000]),
            ])
            .clone()
        };
        let fmu_type: c_int = if valid || r.chance(75) {
            1
        } else {
            *r.pick(&[0, 2, -1, i32::MAX])
        };
        if fmu_type != 1 {
            why_null.push("fmuType is not fmi2CoSimulation");
        }
        let guid_ok = self.t.guid.as_bytes().to_vec();
        let guid: Option<Vec<u8>> = if valid || r.chance(70) {
            Some(guid_ok.clone())
        } else {
            let g = r
                .pick(&[
                    None,
                    Some(b"".to_vec()),
                    Some(b"00000000-0000-0000-0000-000000000000".to_vec()),
                    Some(guid_ok[..guid_ok.len() - 1].to_vec()),
                    Some([&guid_ok[..], b"x"].concat()),
                ])
                .clone();
            why_null.push("the GUID is wrong or NULL");
            g
        };
        let resource_ok = self.t.resource_uri.as_bytes().to_vec();
        let resource: Option<Vec<u8>> = if valid || r.chance(70) {
            Some(resource_ok)
        } else {
            r.pick(&[
                None,
                Some(b"".to_vec()),
                Some(b"garbage".to_vec()),
                Some(b"file:///nonexistent/resources".to_vec()),
                Some(b"http://example.invalid/resources".to_vec()),
            ])
            .clone()
        };
        let no_resources = resource.as_deref() != Some(self.t.resource_uri.as_bytes());
        // Callbacks: 0 full, 1 NULL pointer, 2 NULL logger, 3 NULL environment.
        let cb_kind = if valid || r.chance(70) {
            0
        } else {
            r.range(1, 3)
        };
        let visible = *r.pick(&[0, 1, 2]);
        let logging_on = if r.chance(30) { 1 } else { 0 };

        let sink = Box::new(LogSink::default());
        let callbacks = match cb_kind {
            1 => None,
            2 => Some(Box::new(sink.callbacks(false, true))),
            3 => Some(Box::new(sink.callbacks(true, false))),
            _ => Some(Box::new(sink.callbacks(true, true))),
        };
        let cstr = |b: &Option<Vec<u8>>| b.as_ref().map(|v| CString::new(v.clone()).unwrap());
        let (c_name, c_guid, c_res) = (cstr(&name), cstr(&guid), cstr(&resource));
        let p = |c: &Option<CString>| c.as_ref().map_or(std::ptr::null(), |s| s.as_ptr());
        let show = |b: &Option<Vec<u8>>| match b {
            None => "NULL".to_string(),
            Some(v) if v.len() > 60 => format!("<{} bytes>", v.len()),
            Some(v) => format!("{:?}", String::from_utf8_lossy(v)),
        };
        let text = format!(
            "fmi2Instantiate(name={}, fmuType={fmu_type}, guid={}, resources={}, callbacks={}, visible={visible}, loggingOn={logging_on})",
            show(&name),
            show(&guid),
            show(&resource),
            ["full", "NULL", "NULL logger", "NULL environment"][cb_kind]
        );
        self.begin("-", text);
        let cb_ptr = callbacks
            .as_ref()
            .map_or(std::ptr::null(), |b| &**b as *const fmi2CallbackFunctions);
        // SAFETY: every pointer is NULL or a NUL-terminated string / callback struct that
        // lives until the call returns (the FMU must copy what it keeps).
        let c = unsafe {
            (self.t.api.instantiate)(
                p(&c_name),
                fmu_type,
                p(&c_guid),
                p(&c_res),
                cb_ptr,
                visible,
                logging_on,
            )
        };
        // The strings die here: an FMU that kept a pointer to them reads freed memory
        // (valgrind sees it; the fuzzer sees a wrong instance name in later messages).
        drop((c_name, c_guid, c_res));
        self.stats.add(fidx, if c.is_null() { 3 } else { 0 });
        self.end(if c.is_null() {
            "NULL".into()
        } else {
            format!("i{id}")
        });
        let records = sink.take();
        let logs_to_us = cb_kind == 0;
        let name_s = name.map(|v| String::from_utf8_lossy(&v).into_owned());
        for rec in &records {
            if rec.category.is_none()
                || rec.instance.is_none()
                || rec.message.as_ref().is_none_or(|m| m.is_empty())
                || !(0..=4).contains(&rec.status)
            {
                self.fail(format!("fmi2Instantiate: malformed logger call {rec:?}"));
            }
        }
        if !why_null.is_empty() {
            if !c.is_null() {
                self.fail(format!(
                    "fmi2Instantiate returned an instance although {}",
                    why_null.join(" and ")
                ));
                // It is live all the same: free it.
                // SAFETY: the pointer the FMU just returned.
                unsafe { (self.t.api.free_instance)(c) };
            } else if logs_to_us && !records.iter().any(|r| r.status >= 3) {
                self.fail(format!(
                    "fmi2Instantiate returned NULL ({}) without logging an error",
                    why_null.join(" and ")
                ));
            }
            return;
        }
        if c.is_null() {
            if !no_resources {
                self.fail(format!(
                    "fmi2Instantiate with valid arguments returned NULL; logged {records:?}"
                ));
            }
            return;
        }
        self.next_id += 1;
        self.insts.push(Inst {
            id,
            c,
            sink,
            _callbacks: callbacks,
            name: name_s,
            logs_to_us,
            errors_logged: true,
            categories_off: Default::default(),
            possible: States::one(State::Instantiated),
            time: Some(0.0),
            known: KnownMap::new(),
            states: Vec::new(),
            fatal: false,
            params_touched: false,
            no_resources,
        });
        let i = self.insts.len() - 1;
        if !self.cfg.presets.is_empty() && self.rng.chance(self.cfg.preset_percent) {
            self.apply_presets(i);
        }
    }

    /// Sets the configured presets one by one (traced like any other call).
    fn apply_presets(&mut self, i: usize) {
        let presets = self.cfg.presets.clone();
        for (name, value) in presets {
            let Some(v) = self.t.var_named(&name).cloned() else {
                continue;
            };
            let val = match v.base {
                Base::Real => Val::Real(value.parse().unwrap_or(0.0)),
                Base::Integer => Val::Int(value.parse().unwrap_or(0)),
                Base::Boolean => Val::Bool(matches!(value.as_str(), "true" | "1") as c_int),
                Base::String => Val::Str(Some(value.into_bytes())),
            };
            self.set_exact(i, &v, val);
        }
    }

    fn free_instance(&mut self, comp: Comp) {
        let fidx = 4;
        if let Comp::Inst(i) = comp {
            // Free its states first (the standard frees nothing for us).
            if !self.insts[i].fatal {
                while !self.insts[i].states.is_empty() {
                    self.free_state_at(i, 0);
                    if self.insts[i].fatal {
                        break;
                    }
                }
            }
        }
        let who = self.who(comp);
        self.begin(&who, "fmi2FreeInstance()".into());
        let c = self.comp_ptr(comp);
        // SAFETY: a live instance (then forgotten), NULL, or our foreign block.
        unsafe { (self.t.api.free_instance)(c) };
        self.stats.add(fidx, 0);
        self.end("done".into());
        if let Comp::Inst(i) = comp {
            let inst = self.insts.remove(i);
            for r in inst.sink.take() {
                if r.category.is_none() || r.instance.is_none() || r.message.is_none() {
                    self.fail(format!("logger call during fmi2FreeInstance: {r:?}"));
                }
            }
            // States the FMU could not free (fatal instance) are leaked on purpose.
        } else {
            for j in 0..self.insts.len() {
                let stray = self.insts[j].sink.take();
                if !stray.is_empty() {
                    self.fail(format!(
                        "fmi2FreeInstance({who}) logged into i{}: {stray:?}",
                        self.insts[j].id
                    ));
                }
            }
        }
    }

    /// EnterInitializationMode, ExitInitializationMode, Terminate, Reset, CancelStep.
    fn simple(&mut self, fidx: usize, comp: Comp, call: Call) {
        let who = self.who(comp);
        self.begin(&who, format!("{}()", NAMES[fidx]));
        let c = self.comp_ptr(comp);
        let api = &self.t.api;
        // SAFETY: component is live, NULL or foreign.
        let status = unsafe {
            match call {
                Call::EnterInitializationMode => (api.enter_initialization_mode)(c),
                Call::ExitInitializationMode => (api.exit_initialization_mode)(c),
                Call::Terminate => (api.terminate)(c),
                Call::Reset => (api.reset)(c),
                Call::CancelStep => (api.cancel_step)(c),
                _ => unreachable!(),
            }
        };
        let expect = match comp {
            Comp::Inst(i) => {
                let inst = &self.insts[i];
                let ok = match call {
                    Call::ExitInitializationMode => {
                        if inst.params_touched || inst.no_resources {
                            Expect::Any
                        } else {
                            Expect::Ok("initialization with the default parameters".into())
                        }
                    }
                    Call::CancelStep => Expect::Error("no asynchronous step to cancel".into()),
                    _ => Expect::Ok("a legal state change".into()),
                };
                self.demand(i, call, ok)
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, call, status, expect, |s| match call {
            Call::EnterInitializationMode => State::InitializationMode,
            Call::ExitInitializationMode => State::StepComplete,
            Call::Terminate => State::Terminated,
            Call::Reset => State::Instantiated,
            _ => s,
        });
        if let Comp::Inst(i) = comp
            && (0..=2).contains(&status)
            && call == Call::Reset
        {
            let inst = &mut self.insts[i];
            inst.time = Some(0.0);
            inst.known.clear();
            inst.params_touched = false;
        }
    }

    fn set_debug_logging(&mut self, comp: Comp, hostile: bool) {
        let fidx = 2;
        let cats: Vec<String> = self
            .t
            .log_categories
            .iter()
            .cloned()
            .chain(["noSuchCategory".to_string(), "".to_string()])
            .collect();
        let on = *self.rng.pick(&[0, 1, 1, 2]);
        let mut names: Vec<Option<CString>> = Vec::new();
        let null_array;
        let n;
        let r = self.rng.below(100);
        if hostile && r < 10 {
            null_array = true;
            n = self.rng.range(1, 4);
        } else if r < 40 {
            null_array = self.rng.chance(50);
            n = 0;
        } else {
            null_array = false;
            n = self.rng.range(1, 4);
            for _ in 0..n {
                if hostile && self.rng.chance(10) {
                    names.push(None);
                } else {
                    names.push(Some(CString::new(self.rng.pick(&cats).clone()).unwrap()));
                }
            }
        }
        let ptrs: Vec<fmi2String> = names
            .iter()
            .map(|s| s.as_ref().map_or(std::ptr::null(), |s| s.as_ptr()))
            .collect();
        let arr = if null_array {
            std::ptr::null()
        } else {
            ptrs.as_ptr()
        };
        let shown: Vec<String> = names
            .iter()
            .map(|s| s.as_ref().map_or("NULL".into(), |s| format!("{s:?}")))
            .collect();
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "fmi2SetDebugLogging(on={on}, n={n}, categories={})",
                if null_array {
                    "NULL".into()
                } else {
                    format!("[{}]", shown.join(", "))
                }
            ),
        );
        let c = self.comp_ptr(comp);
        // SAFETY: `arr` is NULL or holds `n` entries, each NULL or a C string.
        let status = unsafe { (self.t.api.set_debug_logging)(c, on, n, arr) };
        let expect = match comp {
            Comp::Inst(i) if null_array && n > 0 => {
                let _ = i;
                Expect::Error("categories is NULL with n > 0".into())
            }
            Comp::Inst(i) => self.demand(i, Call::SetDebugLogging, Expect::Ok("legal".into())),
            _ => Expect::Error("not an instance".into()),
        };
        // Categories switched off: an error is only demanded to be logged while the
        // categories of errors are on.
        if let Comp::Inst(i) = comp
            && (0..=2).contains(&status)
        {
            let all = &self.t.log_categories;
            let off = &mut self.insts[i].categories_off;
            if n == 0 {
                if on != 0 {
                    off.clear();
                } else {
                    off.extend(all.iter().cloned());
                }
            } else {
                for name in names.iter().flatten() {
                    let name = name.to_string_lossy().into_owned();
                    if all.contains(&name) {
                        if on != 0 {
                            off.remove(&name);
                        } else {
                            off.insert(name);
                        }
                    }
                }
            }
            let errors_off = off
                .iter()
                .any(|c| c.contains("Error") || c.contains("error"));
            self.insts[i].errors_logged = !errors_off;
        }
        self.finish(fidx, comp, Call::SetDebugLogging, status, expect, |s| s);
    }

    fn setup_experiment(&mut self, comp: Comp, hostile: bool) {
        let fidx = 5;
        let r = &mut self.rng;
        let tol_defined = *r.pick(&[0, 1]);
        let tol = if hostile { *r.pick(&REAL_EDGES) } else { 1e-6 };
        let start = if !hostile || r.chance(60) {
            0.0
        } else if r.chance(40) {
            (r.unit() - 0.5) * 2000.0
        } else {
            *r.pick(&REAL_EDGES)
        };
        let stop_defined = *r.pick(&[0, 1]);
        let stop = if !hostile || r.chance(60) {
            start + 10.0
        } else if r.chance(30) {
            start - 1.0
        } else {
            *r.pick(&REAL_EDGES)
        };
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "fmi2SetupExperiment(toleranceDefined={tol_defined}, tolerance={}, startTime={}, stopTimeDefined={stop_defined}, stopTime={})",
                fmt_f(tol),
                fmt_f(start),
                fmt_f(stop)
            ),
        );
        let c = self.comp_ptr(comp);
        // SAFETY: scalar arguments.
        let status = unsafe {
            (self.t.api.setup_experiment)(c, tol_defined, tol, start, stop_defined, stop)
        };
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(i, Call::SetupExperiment, Expect::Ok("legal".into()));
                if matches!(d, Expect::Error(_)) {
                    d
                } else if !start.is_finite() {
                    Expect::Error("startTime is not finite".into())
                } else if stop_defined != 0 && !(stop >= start) {
                    Expect::Error("stopTime is before startTime or NaN".into())
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, Call::SetupExperiment, status, expect, |s| s);
        if let Comp::Inst(i) = comp
            && (0..=2).contains(&status)
        {
            self.insts[i].time = Some(start);
        }
    }

    fn do_step(&mut self, comp: Comp, hostile: bool) {
        let fidx = 27;
        let known_time = match comp {
            Comp::Inst(i) => self.insts[i].time,
            _ => None,
        };
        let r = &mut self.rng;
        let base_t = known_time.unwrap_or(0.0);
        let t = if !hostile || r.chance(80) {
            base_t
        } else if r.chance(50) {
            base_t + *r.pick(&[1.0, -1.0, 1e-3, 0.5])
        } else {
            *r.pick(&REAL_EDGES)
        };
        let h = if !hostile || r.chance(65) {
            r.log_uniform(1e-5, 0.05)
        } else {
            *r.pick(&[
                0.0,
                -0.0,
                -1e-3,
                f64::NAN,
                f64::INFINITY,
                f64::NEG_INFINITY,
                5e-324,
                f64::MIN_POSITIVE,
                1e-300,
                1e300,
                f64::MAX,
                1e9,
                1.0,
            ])
        };
        let no_prior = *r.pick(&[0, 1, 2]);
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "fmi2DoStep(currentCommunicationPoint={}, communicationStepSize={}, noSetFMUStatePriorToCurrentPoint={no_prior})",
                fmt_f(t),
                fmt_f(h)
            ),
        );
        let c = self.comp_ptr(comp);
        // SAFETY: scalar arguments.
        let status = unsafe { (self.t.api.do_step)(c, t, h, no_prior) };
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(i, Call::DoStep, Expect::Any);
                let off = known_time
                    .is_some_and(|k| (t - k).abs() > 1e-6 * k.abs().max(1.0) || t.is_nan());
                if matches!(d, Expect::Error(_)) {
                    d
                } else if !(h > 0.0) || !h.is_finite() {
                    Expect::Error("the step size is not a positive finite number".into())
                } else if !t.is_finite() {
                    Expect::Error("the communication point is not finite".into())
                } else if !(t + h).is_finite() {
                    Expect::Error("the step would end beyond the largest finite time".into())
                } else if off {
                    Expect::Error(format!(
                        "the communication point is not the FMU's time {}",
                        fmt_f(known_time.unwrap_or(f64::NAN))
                    ))
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, Call::DoStep, status, expect, |s| s);
        if let Comp::Inst(i) = comp
            && (0..=2).contains(&status)
        {
            self.insts[i].time = Some(t + h);
        }
    }

    /// Value references for a getter or setter: mostly known ones of `base`, sometimes an
    /// unknown one (returned as `Some(reason)`).
    fn vrs(&mut self, base: Base, hostile: bool, settable_only: Option<States>) -> Vec<u32> {
        let vars: Vec<&Var> = self
            .t
            .vars_of(base)
            .filter(|v| settable_only.is_none_or(|p| p.iter().all(|s| v.settable(s))))
            .collect();
        let n = if vars.is_empty() || self.rng.chance(10) {
            0
        } else if self.rng.chance(10) {
            vars.len()
        } else {
            self.rng.range(1, vars.len().min(6))
        };
        let mut out: Vec<u32> = (0..n).map(|_| self.rng.pick(&vars).vr).collect();
        if hostile && self.rng.chance(15) {
            let max = self.t.vars_of(base).map(|v| v.vr).max().unwrap_or(0);
            let unknown = *self.rng.pick(&[
                max.wrapping_add(1),
                max.wrapping_add(1000),
                u32::MAX,
                u32::MAX - 1,
                1 << 31,
            ]);
            let at = self.rng.below(out.len() + 1);
            out.insert(at, unknown);
        } else if hostile && self.rng.chance(10) {
            // A variable of the right type that may not be settable now.
            let any: Vec<u32> = self.t.vars_of(base).map(|v| v.vr).collect();
            if !any.is_empty() {
                out.push(*self.rng.pick(&any));
            }
        }
        out
    }

    fn get(&mut self, comp: Comp, base: Base, hostile: bool) {
        let fidx = match base {
            Base::Real => 10,
            Base::Integer => 11,
            Base::Boolean => 12,
            Base::String => 13,
        };
        let mut vrs = self.vrs(base, hostile, None);
        let mut n = vrs.len();
        let (mut null_vr, mut null_val) = (false, false);
        if hostile {
            match self.rng.below(100) {
                0..5 => null_vr = true,
                5..10 => null_val = true,
                10..13 => {
                    null_vr = true;
                    null_val = true;
                    n = *self.rng.pick(&[1, usize::MAX, usize::MAX / 8]);
                }
                13..18 => {
                    // Arrays longer than nvr: the FMU must touch only the first nvr.
                    n = self.rng.below(n + 1);
                }
                _ => {}
            }
        }
        if null_vr || null_val {
            n = n.max(1);
            if !null_vr && vrs.len() < n {
                vrs.resize(n, 0);
            }
        }
        let unknown: Vec<u32> = vrs[..n.min(vrs.len())]
            .iter()
            .copied()
            .filter(|vr| self.t.var(base, *vr).is_none())
            .collect();
        let room = if null_val { 0 } else { n + 3 };
        let mut reals =
            vec![f64::from_bits(CANARY_REAL); if base == Base::Real { room } else { 0 }];
        let mut ints = vec![CANARY_INT; if base != Base::Real { room } else { 0 }];
        let mut strs: Vec<*const c_char> = vec![
            CANARY_REAL as usize as *const c_char;
            if base == Base::String { room } else { 0 }
        ];
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "{}(vr={}, nvr={n}, value={})",
                NAMES[fidx],
                if null_vr {
                    "NULL".into()
                } else {
                    format!("{:?}", &vrs[..n.min(vrs.len())])
                },
                if null_val {
                    "NULL".into()
                } else {
                    format!("[{} slots]", room)
                }
            ),
        );
        let c = self.comp_ptr(comp);
        let vr_p = if null_vr {
            std::ptr::null()
        } else {
            vrs.as_ptr()
        };
        let api = &self.t.api;
        // SAFETY: the arrays hold at least `n` elements unless NULL.
        let status = unsafe {
            match base {
                Base::Real => (api.get_real)(
                    c,
                    vr_p,
                    n,
                    if null_val {
                        std::ptr::null_mut()
                    } else {
                        reals.as_mut_ptr()
                    },
                ),
                Base::Integer => (api.get_integer)(
                    c,
                    vr_p,
                    n,
                    if null_val {
                        std::ptr::null_mut()
                    } else {
                        ints.as_mut_ptr()
                    },
                ),
                Base::Boolean => (api.get_boolean)(
                    c,
                    vr_p,
                    n,
                    if null_val {
                        std::ptr::null_mut()
                    } else {
                        ints.as_mut_ptr()
                    },
                ),
                Base::String => (api.get_string)(
                    c,
                    vr_p,
                    n,
                    if null_val {
                        std::ptr::null_mut()
                    } else {
                        strs.as_mut_ptr()
                    },
                ),
            }
        };
        // Nothing written past nvr.
        if !null_val {
            let bad = match base {
                Base::Real => reals[n..].iter().any(|x| x.to_bits() != CANARY_REAL),
                Base::String => strs[n..]
                    .iter()
                    .any(|p| *p as usize != CANARY_REAL as usize),
                _ => ints[n..].iter().any(|x| *x != CANARY_INT),
            };
            if bad {
                self.fail(format!("{} wrote past element nvr={n}", NAMES[fidx]));
            }
        }
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(i, Call::Get, Expect::Ok("legal, known references".into()));
                if matches!(d, Expect::Error(_)) {
                    d
                } else if (null_vr || null_val) && n > 0 {
                    Expect::Error("NULL array with nvr > 0".into())
                } else if !unknown.is_empty() {
                    Expect::Error(format!("unknown value reference(s) {unknown:?}"))
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, Call::Get, status, expect, |s| s);
        // Values: booleans 0/1, strings readable, and what was written comes back.
        let Comp::Inst(i) = comp else { return };
        if !(0..=1).contains(&status) || null_val || null_vr {
            return;
        }
        for (k, vr) in vrs[..n].iter().enumerate() {
            let got = match base {
                Base::Real => Known::Real(reals[k].to_bits()),
                Base::Integer => Known::Int(ints[k]),
                Base::Boolean => {
                    if ints[k] != 0 && ints[k] != 1 {
                        self.fail(format!(
                            "fmi2GetBoolean returned {} for vr {vr}, not fmi2True/fmi2False",
                            ints[k]
                        ));
                    }
                    Known::Bool(ints[k] != 0)
                }
                Base::String => {
                    if strs[k].is_null() {
                        self.fail(format!("fmi2GetString returned NULL for vr {vr}"));
                        continue;
                    }
                    // SAFETY: valid until the next call on this instance (the standard).
                    let s = unsafe { CStr::from_ptr(strs[k]) };
                    Known::Str(s.to_string_lossy().into_owned())
                }
            };
            if let Some(want) = self.insts[i].known.get(&key(base, *vr))
                && !same(want, &got)
            {
                let msg = format!(
                    "{} read vr {vr} as {got:?} but {want:?} was written (or restored)",
                    NAMES[fidx]
                );
                self.fail(msg);
            }
        }
    }

    fn set(&mut self, comp: Comp, base: Base, hostile: bool) {
        let possible = match comp {
            Comp::Inst(i) => Some(self.insts[i].possible),
            _ => None,
        };
        let settable = if hostile { None } else { possible };
        let vrs = self.vrs(base, hostile, settable);
        let vals: Vec<Val> = vrs
            .iter()
            .map(|vr| {
                let var = self.t.var(base, *vr).cloned();
                self.value_for(base, var.as_ref(), hostile)
            })
            .collect();
        self.set_raw(comp, base, vrs, vals, hostile);
    }

    /// Sets one variable with a chosen value (presets).
    fn set_exact(&mut self, i: usize, v: &Var, val: Val) {
        self.set_raw(Comp::Inst(i), v.base, vec![v.vr], vec![val], false);
    }

    fn value_for(&mut self, base: Base, var: Option<&Var>, hostile: bool) -> Val {
        let r = &mut self.rng;
        let edge = hostile && r.chance(40);
        match base {
            Base::Real => Val::Real(if edge {
                *r.pick(&REAL_EDGES)
            } else if var.is_some_and(|v| v.name.contains("speed")) {
                r.unit() * 40.0
            } else if var.is_some_and(|v| v.causality == Causality::Input) {
                (r.unit() - 0.5) * 2.0
            } else {
                // A parameter: keep it near its plausible range (positive, moderate).
                *r.pick(&[0.5, 1.0, 2.0, 0.1])
            }),
            Base::Integer => Val::Int(if edge {
                *r.pick(&INT_EDGES)
            } else {
                r.range(1, 4) as i32
            }),
            Base::Boolean => Val::Bool(if edge {
                *r.pick(&[2, -1, i32::MIN, 255])
            } else {
                r.below(2) as i32
            }),
            Base::String => Val::Str(if hostile && r.chance(10) {
                None
            } else if edge {
                Some(r.pick(&string_edges()).clone())
            } else {
                Some(r.pick(&[b"ml95.toml".to_vec(), b"".to_vec()]).clone())
            }),
        }
    }

    fn set_raw(
        &mut self,
        comp: Comp,
        base: Base,
        mut vrs: Vec<u32>,
        vals: Vec<Val>,
        hostile: bool,
    ) {
        let fidx = match base {
            Base::Real => 14,
            Base::Integer => 15,
            Base::Boolean => 16,
            Base::String => 17,
        };
        let mut n = vrs.len();
        let (mut null_vr, mut null_val) = (false, false);
        if hostile {
            match self.rng.below(100) {
                0..5 => null_vr = true,
                5..10 => null_val = true,
                10..13 => {
                    null_vr = true;
                    null_val = true;
                    n = *self.rng.pick(&[1, usize::MAX, usize::MAX / 8]);
                }
                13..18 => n = self.rng.below(n + 1),
                _ => {}
            }
        }
        if null_vr || null_val {
            n = n.max(1);
            if !null_vr && vrs.len() < n {
                vrs.resize(n, 0);
            }
        }
        let mut vals = vals;
        if !null_val {
            while vals.len() < n {
                vals.push(self.value_for(base, None, false));
            }
        }
        let used_vrs: Vec<u32> = if null_vr {
            vec![]
        } else {
            vrs[..n.min(vrs.len())].to_vec()
        };
        let used_vals: Vec<Val> = if null_val {
            vec![]
        } else {
            vals[..n.min(vals.len())].to_vec()
        };
        // Arrays (one extra element, which the FMU must not read as a value).
        let reals: Vec<f64> = vals
            .iter()
            .map(|v| if let Val::Real(x) = v { *x } else { 0.0 })
            .chain([1234.5])
            .collect();
        let ints: Vec<c_int> = vals
            .iter()
            .map(|v| match v {
                Val::Int(x) | Val::Bool(x) => *x,
                _ => 0,
            })
            .chain([77])
            .collect();
        let cstrings: Vec<Option<CString>> = vals
            .iter()
            .map(|v| match v {
                Val::Str(Some(b)) => Some(CString::new(b.clone()).unwrap()),
                _ => None,
            })
            .collect();
        let mut sptrs: Vec<fmi2String> = cstrings
            .iter()
            .map(|s| s.as_ref().map_or(std::ptr::null(), |s| s.as_ptr()))
            .collect();
        sptrs.push(std::ptr::null());
        let who = self.who(comp);
        let shown: Vec<String> = used_vals.iter().map(Val::show).collect();
        self.begin(
            &who,
            format!(
                "{}(vr={}, nvr={n}, value={})",
                NAMES[fidx],
                if null_vr {
                    "NULL".into()
                } else {
                    format!("{used_vrs:?}")
                },
                if null_val {
                    "NULL".into()
                } else {
                    format!("[{}]", shown.join(", "))
                }
            ),
        );
        let c = self.comp_ptr(comp);
        let vr_p = if null_vr {
            std::ptr::null()
        } else {
            vrs.as_ptr()
        };
        let api = &self.t.api;
        // SAFETY: arrays hold at least `n` elements unless NULL.
        let status = unsafe {
            match base {
                Base::Real => (api.set_real)(
                    c,
                    vr_p,
                    n,
                    if null_val {
                        std::ptr::null()
                    } else {
                        reals.as_ptr()
                    },
                ),
                Base::Integer => (api.set_integer)(
                    c,
                    vr_p,
                    n,
                    if null_val {
                        std::ptr::null()
                    } else {
                        ints.as_ptr()
                    },
                ),
                Base::Boolean => (api.set_boolean)(
                    c,
                    vr_p,
                    n,
                    if null_val {
                        std::ptr::null()
                    } else {
                        ints.as_ptr()
                    },
                ),
                Base::String => (api.set_string)(
                    c,
                    vr_p,
                    n,
                    if null_val {
                        std::ptr::null()
                    } else {
                        sptrs.as_ptr()
                    },
                ),
            }
        };
        drop(cstrings);
        let expect = match comp {
            Comp::Inst(i) => {
                let possible = self.insts[i].possible;
                let d = self.demand(i, Call::Set, Expect::Ok("legal, settable".into()));
                let unknown: Vec<u32> = used_vrs
                    .iter()
                    .copied()
                    .filter(|vr| self.t.var(base, *vr).is_none())
                    .collect();
                let never: Vec<String> = used_vrs
                    .iter()
                    .filter_map(|vr| self.t.var(base, *vr))
                    .filter(|v| possible.iter().all(|s| !v.settable(s)))
                    .map(|v| v.name.clone())
                    .collect();
                let sometimes = used_vrs
                    .iter()
                    .filter_map(|vr| self.t.var(base, *vr))
                    .any(|v| possible.iter().any(|s| !v.settable(s)));
                if matches!(d, Expect::Error(_)) {
                    d
                } else if (null_vr || null_val) && n > 0 {
                    Expect::Error("NULL array with nvr > 0".into())
                } else if !unknown.is_empty() {
                    Expect::Error(format!("unknown value reference(s) {unknown:?}"))
                } else if !never.is_empty() {
                    Expect::Error(format!("not settable in {}: {never:?}", possible.names()))
                } else if used_vals.iter().any(|v| matches!(v, Val::Str(None))) {
                    Expect::Error("a NULL string".into())
                } else if sometimes {
                    Expect::Any
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        let refused = matches!(expect, Expect::Error(_));
        self.finish(fidx, comp, Call::Set, status, expect, |s| s);
        let Comp::Inst(i) = comp else { return };
        if (0..=1).contains(&status) && !refused {
            for (vr, v) in used_vrs.iter().zip(&used_vals) {
                let Some(var) = self.t.var(base, *vr) else {
                    continue;
                };
                if var.causality != Causality::Input {
                    self.insts[i].params_touched = true;
                }
                let k = key(base, *vr);
                if !matches!(var.causality, Causality::Input | Causality::Parameter) {
                    self.insts[i].known.remove(&k);
                    continue;
                }
                match v.known() {
                    Some(x) => self.insts[i].known.insert(k, x),
                    None => self.insts[i].known.remove(&k),
                };
            }
        } else if status == 3 && !refused {
            // Unpredicted refusal: what was written is uncertain.
            for vr in &used_vrs {
                self.insts[i].known.remove(&key(base, *vr));
            }
        }
    }

    // ----- FMU state -----------------------------------------------------------------------

    /// A state of instance `i` to use, or NULL / foreign (hostile).
    fn pick_state(
        &mut self,
        comp: Comp,
        hostile: bool,
    ) -> (fmi2FMUstate, Option<usize>, &'static str) {
        if let Comp::Inst(i) = comp
            && !self.insts[i].states.is_empty()
            && (!hostile || self.rng.chance(75))
        {
            let k = self.rng.below(self.insts[i].states.len());
            return (self.insts[i].states[k].ptr, Some(k), "state");
        }
        if self.rng.chance(60) {
            (std::ptr::null_mut(), None, "NULL")
        } else {
            (as_ptr(&self.foreign), None, "FOREIGN")
        }
    }

    fn get_fmu_state(&mut self, comp: Comp, hostile: bool) {
        let fidx = 18;
        let can_add = matches!(comp, Comp::Inst(i) if self.insts[i].states.len() < MAX_STATES);
        // 0 new (slot NULL), 1 reuse a state, 2 NULL slot pointer, 3 foreign in slot.
        let mode = if hostile {
            self.rng.weighted(&[5, 3, 1, 1])
        } else {
            self.rng.weighted(&[5, 3, 0, 0])
        };
        let mode = match (mode, comp) {
            (1, Comp::Inst(i)) if self.insts[i].states.is_empty() => 0,
            (1, Comp::Inst(_)) => 1,
            (1, _) => 0,
            (m, _) => m,
        };
        if mode == 0 && !can_add && matches!(comp, Comp::Inst(_)) {
            return;
        }
        let mut slot: fmi2FMUstate = std::ptr::null_mut();
        let mut reuse = None;
        if mode == 1
            && let Comp::Inst(i) = comp
        {
            let k = self.rng.below(self.insts[i].states.len());
            slot = self.insts[i].states[k].ptr;
            reuse = Some(k);
        }
        if mode == 3 {
            slot = as_ptr(&self.foreign);
        }
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "fmi2GetFMUstate(FMUstate={})",
                ["&NULL", "&existing", "NULL", "&FOREIGN"][mode]
            ),
        );
        let c = self.comp_ptr(comp);
        let slot_p: *mut fmi2FMUstate = if mode == 2 {
            std::ptr::null_mut()
        } else {
            &mut slot
        };
        // SAFETY: slot_p is NULL or points to our slot.
        let status = unsafe { (self.t.api.get_fmu_state)(c, slot_p) };
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(i, Call::FmuState, Expect::Ok("legal".into()));
                if matches!(d, Expect::Error(_)) {
                    d
                } else if mode == 2 {
                    Expect::Error("FMUstate pointer is NULL".into())
                } else if mode == 3 {
                    Expect::Error("*FMUstate is not a state of this FMU".into())
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        let before = match comp {
            Comp::Inst(i) => Some((
                self.insts[i].possible,
                self.insts[i].time,
                self.insts[i].known.clone(),
            )),
            _ => None,
        };
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        let Comp::Inst(i) = comp else {
            if !slot.is_null() && mode == 0 {
                self.fail("fmi2GetFMUstate on a non-instance wrote a state".into());
            }
            return;
        };
        let (possible, time, known) = before.unwrap();
        if (0..=1).contains(&status) && (mode == 0 || mode == 1) {
            if slot.is_null() {
                self.fail("fmi2GetFMUstate succeeded but returned a NULL state".into());
                return;
            }
            let rec = SavedState {
                ptr: slot,
                possible: possible.minus(States::one(State::Fatal)),
                time,
                known,
                size: None,
            };
            match reuse {
                Some(k) => {
                    if self.insts[i].states[k].ptr != slot {
                        // A new allocation replaced ours: the old one is the FMU's to free.
                        self.fail(
                            "fmi2GetFMUstate with a non-NULL *FMUstate did not reuse it".into(),
                        );
                    }
                    self.insts[i].states[k] = rec;
                }
                None => self.insts[i].states.push(rec),
            }
        } else if mode == 0 && !slot.is_null() {
            self.fail("fmi2GetFMUstate failed but wrote a state pointer".into());
        }
    }

    fn set_fmu_state(&mut self, comp: Comp, hostile: bool) {
        let fidx = 19;
        let (s, k, kind) = self.pick_state(comp, hostile);
        let who = self.who(comp);
        self.begin(&who, format!("fmi2SetFMUstate({kind})"));
        let c = self.comp_ptr(comp);
        // SAFETY: `s` is a live state of this instance, NULL or foreign.
        let status = unsafe { (self.t.api.set_fmu_state)(c, s) };
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(i, Call::FmuState, Expect::Ok("legal".into()));
                if matches!(d, Expect::Error(_)) {
                    d
                } else if k.is_none() {
                    Expect::Error(format!("FMUstate is {kind}"))
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        if let (Comp::Inst(i), Some(k)) = (comp, k)
            && (0..=1).contains(&status)
        {
            let inst = &mut self.insts[i];
            let rec = &inst.states[k];
            inst.possible = rec.possible;
            inst.time = rec.time;
            inst.known = rec.known.clone();
            inst.params_touched = true;
        }
    }

    fn free_state_at(&mut self, i: usize, k: usize) {
        let fidx = 20;
        let who = self.who(Comp::Inst(i));
        self.begin(&who, "fmi2FreeFMUstate(&state)".into());
        let c = self.insts[i].c;
        let mut slot = self.insts[i].states[k].ptr;
        // SAFETY: a live state of this instance.
        let status = unsafe { (self.t.api.free_fmu_state)(c, &mut slot) };
        let expect = self.demand(i, Call::FmuState, Expect::Ok("legal".into()));
        self.finish(fidx, Comp::Inst(i), Call::FmuState, status, expect, |s| s);
        if (0..=1).contains(&status) && !slot.is_null() {
            self.fail("fmi2FreeFMUstate succeeded but did not set *FMUstate to NULL".into());
        }
        // Forget it whatever the outcome: freed, or refused (then it is leaked rather than
        // risk a second free, which would be undefined behaviour).
        if self.insts[i].fatal {
            self.insts[i].states.clear();
        } else {
            self.insts[i].states.remove(k);
        }
    }

    fn free_fmu_state(&mut self, comp: Comp, hostile: bool) {
        let fidx = 20;
        if let Comp::Inst(i) = comp
            && !self.insts[i].states.is_empty()
            && (!hostile || self.rng.chance(70))
        {
            let k = self.rng.below(self.insts[i].states.len());
            self.free_state_at(i, k);
            return;
        }
        // NULL pointer, pointer to NULL, or foreign state.
        let mode = self.rng.below(3);
        let mut slot: fmi2FMUstate = if mode == 2 {
            as_ptr(&self.foreign)
        } else {
            std::ptr::null_mut()
        };
        let who = self.who(comp);
        self.begin(
            &who,
            format!("fmi2FreeFMUstate({})", ["NULL", "&NULL", "&FOREIGN"][mode]),
        );
        let c = self.comp_ptr(comp);
        let p: *mut fmi2FMUstate = if mode == 0 {
            std::ptr::null_mut()
        } else {
            &mut slot
        };
        // SAFETY: NULL, or our slot holding NULL or the foreign block (never freed by a
        // conforming FMU: it is not one of its states).
        let status = unsafe { (self.t.api.free_fmu_state)(c, p) };
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(
                    i,
                    Call::FmuState,
                    Expect::Ok("freeing NULL is a no-op".into()),
                );
                if matches!(d, Expect::Error(_)) {
                    d
                } else if mode == 2 {
                    Expect::Error("not a state of this FMU".into())
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
    }

    fn serialized_size(&mut self, comp: Comp, hostile: bool) -> Option<usize> {
        let fidx = 21;
        let (s, k, kind) = self.pick_state(comp, hostile);
        let null_size = hostile && self.rng.chance(8);
        let mut size: usize = 0xDEAD;
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "fmi2SerializedFMUstateSize({kind}, size={})",
                if null_size { "NULL" } else { "&size" }
            ),
        );
        let c = self.comp_ptr(comp);
        let p: *mut usize = if null_size {
            std::ptr::null_mut()
        } else {
            &mut size
        };
        // SAFETY: live state / NULL / foreign; p is NULL or ours.
        let status = unsafe { (self.t.api.serialized_fmu_state_size)(c, s, p) };
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(i, Call::FmuState, Expect::Ok("legal".into()));
                if matches!(d, Expect::Error(_)) {
                    d
                } else if k.is_none() {
                    Expect::Error(format!("FMUstate is {kind}"))
                } else if null_size {
                    Expect::Error("size is NULL".into())
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        if let (Comp::Inst(i), Some(k)) = (comp, k)
            && (0..=1).contains(&status)
            && !null_size
        {
            self.insts[i].states[k].size = Some(size);
            return Some(size);
        }
        None
    }

    fn serialize(&mut self, comp: Comp, hostile: bool) {
        // Ask for the size first (a call of its own), as a master does.
        let size = if let Comp::Inst(i) = comp
            && !self.insts[i].states.is_empty()
        {
            self.serialized_size(comp, false)
        } else {
            None
        };
        let Comp::Inst(i) = comp else {
            self.serialize_call(comp, std::ptr::null_mut(), None, 16, false, hostile);
            return;
        };
        let (s, k) = match (
            size,
            self.insts[i].states.iter().position(|r| r.size == size),
        ) {
            (Some(_), Some(k)) if !hostile || self.rng.chance(80) => {
                (self.insts[i].states[k].ptr, Some(k))
            }
            _ => {
                let (s, k, _) = self.pick_state(comp, hostile);
                (s, k)
            }
        };
        let need = k.and_then(|k| self.insts[i].states[k].size);
        let buf_len = match need {
            Some(n) if !hostile || self.rng.chance(60) => n + *self.rng.pick(&[0, 0, 1, 100]),
            Some(n) => *self.rng.pick(&[0, n.saturating_sub(1), n / 2]),
            None => *self.rng.pick(&[0, 16, 4096]),
        };
        let null_buf = hostile && self.rng.chance(8);
        self.serialize_call(comp, s, k, buf_len, null_buf, hostile);
    }

    fn serialize_call(
        &mut self,
        comp: Comp,
        s: fmi2FMUstate,
        k: Option<usize>,
        buf_len: usize,
        null_buf: bool,
        _hostile: bool,
    ) {
        let fidx = 22;
        let need = match comp {
            Comp::Inst(i) => k.and_then(|k| self.insts[i].states[k].size),
            _ => None,
        };
        let mut buf = vec![CANARY_BYTE; buf_len + 8];
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "fmi2SerializeFMUstate({}, buffer={}, size={buf_len}) [needs {need:?}]",
                if k.is_some() {
                    "state"
                } else if s.is_null() {
                    "NULL"
                } else {
                    "FOREIGN"
                },
                if null_buf { "NULL" } else { "&buffer" }
            ),
        );
        let c = self.comp_ptr(comp);
        let p = if null_buf {
            std::ptr::null_mut()
        } else {
            buf.as_mut_ptr() as *mut c_char
        };
        // SAFETY: the buffer holds buf_len (+8 canary) bytes unless NULL.
        let status = unsafe { (self.t.api.serialize_fmu_state)(c, s, p, buf_len) };
        if buf[buf_len..].iter().any(|b| *b != CANARY_BYTE) {
            self.fail(format!(
                "fmi2SerializeFMUstate wrote past the {buf_len} bytes it was given"
            ));
        }
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(
                    i,
                    Call::FmuState,
                    Expect::Ok("legal, buffer large enough".into()),
                );
                if matches!(d, Expect::Error(_)) {
                    d
                } else if k.is_none() {
                    Expect::Error("FMUstate is not a state".into())
                } else if null_buf {
                    Expect::Error("buffer is NULL".into())
                } else if need.is_some_and(|n| buf_len < n) {
                    Expect::Error("buffer smaller than fmi2SerializedFMUstateSize".into())
                } else if need.is_none() {
                    Expect::Any
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        if let (Comp::Inst(i), Some(k), Some(n)) = (comp, k, need)
            && (0..=1).contains(&status)
            && !null_buf
            && buf_len >= n
        {
            let rec = &self.insts[i].states[k];
            let blob = Blob {
                bytes: buf[..n].to_vec(),
                possible: rec.possible,
                time: rec.time,
                known: rec.known.clone(),
            };
            if self.blobs.len() >= 4 {
                self.blobs.remove(0);
            }
            self.blobs.push(blob);
        }
    }

    fn deserialize(&mut self, comp: Comp, hostile: bool) {
        let fidx = 23;
        // The bytes: a genuine serialized state, or a corrupted one.
        let genuine = (!self.blobs.is_empty()).then(|| self.rng.below(self.blobs.len()));
        let mut bytes: Vec<u8>;
        let mut corrupt: Option<String> = None;
        let mut null_bytes = false;
        match genuine {
            Some(b) => {
                bytes = self.blobs[b].bytes.clone();
                if hostile && self.rng.chance(50) {
                    let how = self.corrupt(&mut bytes);
                    if bytes != self.blobs[b].bytes {
                        corrupt = Some(how);
                    }
                }
            }
            None => {
                bytes = (0..self.rng.range(0, 300))
                    .map(|_| self.rng.u64() as u8)
                    .collect();
                corrupt = Some("random bytes".into());
                if hostile && self.rng.chance(20) {
                    null_bytes = true;
                }
            }
        }
        let size = if null_bytes {
            *self.rng.pick(&[0, 16, usize::MAX])
        } else {
            bytes.len()
        };
        // The slot: new (NULL), an existing state of the instance, or a NULL pointer.
        let can_add = matches!(comp, Comp::Inst(i) if self.insts[i].states.len() < MAX_STATES);
        let mut reuse = None;
        let mut slot: fmi2FMUstate = std::ptr::null_mut();
        let null_slot = hostile && self.rng.chance(8);
        if let Comp::Inst(i) = comp
            && !self.insts[i].states.is_empty()
            && (!can_add || self.rng.chance(40))
        {
            let k = self.rng.below(self.insts[i].states.len());
            slot = self.insts[i].states[k].ptr;
            reuse = Some(k);
        }
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "fmi2DeSerializeFMUstate(bytes={}, size={size}, FMUstate={})",
                if null_bytes {
                    "NULL".to_string()
                } else {
                    format!(
                        "<{} bytes{}>",
                        bytes.len(),
                        corrupt.as_ref().map_or(String::new(), |c| format!(", {c}"))
                    )
                },
                if null_slot {
                    "NULL"
                } else if reuse.is_some() {
                    "&existing"
                } else {
                    "&NULL"
                }
            ),
        );
        let c = self.comp_ptr(comp);
        let bp = if null_bytes {
            std::ptr::null()
        } else {
            bytes.as_ptr() as *const c_char
        };
        let sp: *mut fmi2FMUstate = if null_slot {
            std::ptr::null_mut()
        } else {
            &mut slot
        };
        // SAFETY: `bytes` holds `size` bytes unless NULL; the slot is ours or NULL.
        let status = unsafe { (self.t.api.deserialize_fmu_state)(c, bp, size, sp) };
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(i, Call::FmuState, Expect::Ok("legal, genuine bytes".into()));
                if matches!(d, Expect::Error(_)) {
                    d
                } else if null_slot {
                    Expect::Error("FMUstate pointer is NULL".into())
                } else if null_bytes && size > 0 {
                    Expect::Error("serializedState is NULL".into())
                } else if let Some(how) = &corrupt {
                    Expect::Error(format!("corrupt serialized state ({how})"))
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        let refused = matches!(expect, Expect::Error(_));
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        let Comp::Inst(i) = comp else { return };
        if !(0..=1).contains(&status) || null_slot {
            return;
        }
        if slot.is_null() {
            self.fail("fmi2DeSerializeFMUstate succeeded but returned a NULL state".into());
            return;
        }
        let (possible, time, known) = match (genuine, refused) {
            (Some(b), false) => (
                self.blobs[b].possible,
                self.blobs[b].time,
                self.blobs[b].known.clone(),
            ),
            // Accepted corrupt bytes (already reported): anything may be in there.
            _ => (
                States::of(&State::ALL).minus(States::one(State::Fatal)),
                None,
                KnownMap::new(),
            ),
        };
        let rec = SavedState {
            ptr: slot,
            possible,
            time,
            known,
            size: None,
        };
        match reuse {
            Some(k) => {
                if self.insts[i].states[k].ptr != slot {
                    self.fail("fmi2DeSerializeFMUstate did not reuse the given state".into());
                }
                self.insts[i].states[k] = rec;
            }
            None => self.insts[i].states.push(rec),
        }
    }

    /// Corrupts serialized bytes in one of several ways; returns how.
    fn corrupt(&mut self, b: &mut Vec<u8>) -> String {
        let n = b.len();
        match self.rng.below(6) {
            0 if n > 0 => {
                let k = self.rng.below(n);
                let bit = self.rng.below(8);
                b[k] ^= 1 << bit;
                format!("bit {bit} of byte {k} flipped")
            }
            1 if n > 0 => {
                let keep = self.rng.below(n);
                b.truncate(keep);
                format!("truncated to {keep} bytes")
            }
            2 => {
                let extra = self.rng.range(1, 64);
                b.extend((0..extra).map(|_| self.rng.u64() as u8));
                format!("{extra} bytes appended")
            }
            3 if n > 0 => {
                let flips = self.rng.range(2, 20);
                for _ in 0..flips {
                    let k = self.rng.below(n);
                    b[k] = self.rng.u64() as u8;
                }
                format!("{flips} bytes overwritten")
            }
            4 if n > 8 => {
                // Past the header: damage the body only.
                let k = self.rng.range(n / 2, n - 1);
                b[k] = b[k].wrapping_add(1);
                format!("byte {k} incremented")
            }
            _ => {
                b.clear();
                "empty".into()
            }
        }
    }

    // ----- unsupported capabilities and status ----------------------------------------------

    fn directional(&mut self, comp: Comp) {
        let fidx = 24;
        let vrs: Vec<u32> = self.t.vars_of(Base::Real).map(|v| v.vr).take(3).collect();
        let known = vec![1.0; vrs.len()];
        let mut out = vec![0.0; vrs.len()];
        let null = self.rng.chance(30);
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "fmi2GetDirectionalDerivative(nUnknown={}, nKnown={}, arrays={})",
                vrs.len(),
                vrs.len(),
                if null { "NULL" } else { "valid" }
            ),
        );
        let c = self.comp_ptr(comp);
        let (vp, kp, op) = if null {
            (std::ptr::null(), std::ptr::null(), std::ptr::null_mut())
        } else {
            (vrs.as_ptr(), known.as_ptr(), out.as_mut_ptr())
        };
        // SAFETY: arrays hold vrs.len() elements unless NULL.
        let status = unsafe {
            (self.t.api.get_directional_derivative)(c, vp, vrs.len(), vp, vrs.len(), kp, op)
        };
        let expect = self.capability_expect(
            comp,
            Call::GetDirectionalDerivative,
            self.caps.directional,
            "providesDirectionalDerivative is false",
        );
        self.finish(
            fidx,
            comp,
            Call::GetDirectionalDerivative,
            status,
            expect,
            |s| s,
        );
    }

    fn input_derivatives(&mut self, comp: Comp) {
        let fidx = 25;
        let vrs: Vec<u32> = self
            .t
            .vars_of(Base::Real)
            .filter(|v| v.causality == Causality::Input)
            .map(|v| v.vr)
            .collect();
        let order = vec![1; vrs.len()];
        let vals = vec![0.5; vrs.len()];
        let who = self.who(comp);
        self.begin(
            &who,
            format!("fmi2SetRealInputDerivatives(nvr={})", vrs.len()),
        );
        let c = self.comp_ptr(comp);
        // SAFETY: arrays hold vrs.len() elements.
        let status = unsafe {
            (self.t.api.set_real_input_derivatives)(
                c,
                vrs.as_ptr(),
                vrs.len(),
                order.as_ptr(),
                vals.as_ptr(),
            )
        };
        let expect = self.capability_expect(
            comp,
            Call::SetRealInputDerivatives,
            self.caps.interpolate,
            "canInterpolateInputs is false",
        );
        self.finish(
            fidx,
            comp,
            Call::SetRealInputDerivatives,
            status,
            expect,
            |s| s,
        );
    }

    fn output_derivatives(&mut self, comp: Comp) {
        let fidx = 26;
        let vrs: Vec<u32> = self
            .t
            .vars_of(Base::Real)
            .filter(|v| v.causality == Causality::Output)
            .map(|v| v.vr)
            .take(4)
            .collect();
        let order = vec![1; vrs.len()];
        let mut vals = vec![0.0; vrs.len()];
        let who = self.who(comp);
        self.begin(
            &who,
            format!("fmi2GetRealOutputDerivatives(nvr={})", vrs.len()),
        );
        let c = self.comp_ptr(comp);
        // SAFETY: arrays hold vrs.len() elements.
        let status = unsafe {
            (self.t.api.get_real_output_derivatives)(
                c,
                vrs.as_ptr(),
                vrs.len(),
                order.as_ptr(),
                vals.as_mut_ptr(),
            )
        };
        let expect = self.capability_expect(
            comp,
            Call::GetRealOutputDerivatives,
            self.caps.output_derivatives,
            "maxOutputDerivativeOrder is 0",
        );
        self.finish(
            fidx,
            comp,
            Call::GetRealOutputDerivatives,
            status,
            expect,
            |s| s,
        );
    }

    fn capability_expect(&self, comp: Comp, call: Call, supported: bool, why: &str) -> Expect {
        match comp {
            Comp::Inst(i) => {
                let d = self.demand(i, call, Expect::Any);
                if supported || matches!(d, Expect::Error(_)) {
                    d
                } else {
                    Expect::Error(why.into())
                }
            }
            _ => Expect::Error("not an instance".into()),
        }
    }

    fn status(&mut self, fidx: usize, comp: Comp, hostile: bool) {
        let kind: c_int = if hostile {
            *self.rng.pick(&[0, 1, 2, 3, -1, 99])
        } else {
            *self.rng.pick(&[2, 3])
        };
        let null = hostile && self.rng.chance(10);
        let mut real = f64::from_bits(CANARY_REAL);
        let mut int: c_int = CANARY_INT;
        let mut string: fmi2String = std::ptr::null();
        let who = self.who(comp);
        self.begin(
            &who,
            format!(
                "{}(kind={kind}, value={})",
                NAMES[fidx],
                if null { "NULL" } else { "&value" }
            ),
        );
        let c = self.comp_ptr(comp);
        let api = &self.t.api;
        // SAFETY: the out pointer is NULL or ours.
        let status = unsafe {
            match NAMES[fidx] {
                "fmi2GetStatus" => {
                    (api.get_status)(c, kind, if null { std::ptr::null_mut() } else { &mut int })
                }
                "fmi2GetRealStatus" => (api.get_real_status)(
                    c,
                    kind,
                    if null {
                        std::ptr::null_mut()
                    } else {
                        &mut real
                    },
                ),
                "fmi2GetIntegerStatus" => (api.get_integer_status)(
                    c,
                    kind,
                    if null { std::ptr::null_mut() } else { &mut int },
                ),
                "fmi2GetBooleanStatus" => (api.get_boolean_status)(
                    c,
                    kind,
                    if null { std::ptr::null_mut() } else { &mut int },
                ),
                _ => (api.get_string_status)(
                    c,
                    kind,
                    if null {
                        std::ptr::null_mut()
                    } else {
                        &mut string
                    },
                ),
            }
        };
        let expect = match comp {
            Comp::Inst(i) => {
                let d = self.demand(
                    i,
                    Call::GetStatus,
                    Expect::Ok("legal (Discard for an unsupported kind)".into()),
                );
                if matches!(d, Expect::Error(_)) {
                    d
                } else if null {
                    Expect::Error("value is NULL".into())
                } else {
                    d
                }
            }
            _ => Expect::Error("not an instance".into()),
        };
        self.finish(fidx, comp, Call::GetStatus, status, expect, |s| s);
        let Comp::Inst(i) = comp else { return };
        if null || !(0..=1).contains(&status) {
            return;
        }
        if NAMES[fidx] == "fmi2GetRealStatus"
            && kind == 2
            && let Some(t) = self.insts[i].time
            && real != t
            && !((real - t).abs() <= 1e-9 * t.abs().max(1.0))
        {
            self.fail(format!(
                "fmi2GetRealStatus(fmi2LastSuccessfulTime) = {} but the steps reached {}",
                fmt_f(real),
                fmt_f(t)
            ));
        }
        if NAMES[fidx] == "fmi2GetBooleanStatus" && kind == 3 && int != 0 && int != 1 {
            self.fail(format!(
                "fmi2GetBooleanStatus(fmi2Terminated) returned {int}"
            ));
        }
    }
}

/// Equal as written: bit-identical reals, except that any NaN reads back as a NaN.
fn same(a: &Known, b: &Known) -> bool {
    match (a, b) {
        (Known::Real(x), Known::Real(y)) => {
            x == y || (f64::from_bits(*x).is_nan() && f64::from_bits(*y).is_nan())
        }
        _ => a == b,
    }
}

/// A value to set.
#[derive(Debug, Clone)]
enum Val {
    Real(f64),
    Int(c_int),
    Bool(c_int),
    Str(Option<Vec<u8>>),
}

impl Val {
    fn show(&self) -> String {
        match self {
            Val::Real(x) => fmt_f(*x),
            Val::Int(x) => x.to_string(),
            Val::Bool(x) => format!("b{x}"),
            Val::Str(None) => "NULL".into(),
            Val::Str(Some(b)) if b.len() > 40 => format!("<{} bytes>", b.len()),
            Val::Str(Some(b)) => format!("{:?}", String::from_utf8_lossy(b)),
        }
    }

    /// What a getter must return after this was set (None: not predictable, e.g. a string
    /// that is not UTF-8).
    fn known(&self) -> Option<Known> {
        match self {
            Val::Real(x) => Some(Known::Real(x.to_bits())),
            Val::Int(x) => Some(Known::Int(*x)),
            Val::Bool(x) => Some(Known::Bool(*x != 0)),
            Val::Str(Some(b)) => std::str::from_utf8(b).ok().map(|s| Known::Str(s.into())),
            Val::Str(None) => None,
        }
    }
}

fn target_caps(t: &Target) -> Caps {
    Caps {
        directional: t.caps.0,
        interpolate: t.caps.1,
        output_derivatives: t.caps.2,
    }
}

/// Runs sequences `first .. first + count` in this process.
pub fn run_range(
    t: &Target,
    cfg: &Config,
    first: u64,
    count: u64,
    mut on_start: impl FnMut(u64),
    mut on_result: impl FnMut(&SeqResult),
) -> Stats {
    let mut stats = Stats::default();
    for k in 0..count {
        let seed = first.wrapping_add(k);
        on_start(seed);
        let (r, s) = Fuzzer::new(t, cfg, seed).run();
        stats.merge(&s);
        on_result(&r);
    }
    stats
}
