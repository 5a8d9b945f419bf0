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
//!
//! One concern per file: `books` holds what the fuzzer knows of each instance, `check` the
//! checks every call goes through, `pointers` the NULL and foreign pointer cases the functions
//! share, `walk` the choice of the next call, and one file per group of functions:
//! `lifecycle`, `values`, `fmu_state`, `status` (with the unsupported capabilities).

mod books;
mod check;
mod fmu_state;
mod lifecycle;
mod pointers;
mod status;
mod values;
mod walk;

use crate::api::{NAMES, Target, foreign_block};
use crate::rng::Rng;
use books::{Blob, Inst};
use std::ffi::c_int;

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
    /// Indexed by the function's position in `NAMES`; columns fmi2OK..fmi2Pending and one for any
    /// other value.
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

    /// Adds another sequence's or worker's counts.
    pub fn merge(&mut self, o: &Stats) {
        for (a, b) in self.counts.iter_mut().zip(&o.counts) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
    }

    /// All calls counted.
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

/// What every sequence of a run shares (the seed is per sequence).
#[derive(Debug, Clone)]
pub struct Config {
    /// The longest sequence, in calls before the clean-up.
    pub max_len: usize,
    /// Whether calls are printed as they are made.
    pub trace: Trace,
    /// Variable settings applied right after most instantiations (by name), to make an
    /// expensive initialization cheap, e.g. `lateral_irregularity=false`.
    pub presets: Vec<(String, String)>,
    /// Percentage of instances that get the presets.
    pub preset_percent: u32,
}

/// What one sequence did.
pub struct SeqResult {
    /// The seed that replays the sequence (`--seed S --sequences 1 --trace`).
    pub seed: u64,
    /// FMI calls made, clean-up included.
    pub calls: u64,
    /// One line per broken expectation: the call, what the oracle expected and what came back.
    pub failures: Vec<String>,
    /// Every call made, in order, for the failure report.
    pub trace: Vec<String>,
}

/// One sequence in progress: random FMI calls on up to `MAX_INSTANCES` instances, each checked
/// against the state-machine oracle. It keeps books of its instances, saved states and
/// serialized blobs, so it passes NULL and foreign pointers on purpose but never a freed one.
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
    /// The statuses each function returned, merged into the run's table by the runner.
    pub stats: Stats,
    caps: Caps,
}

/// The optional capabilities the model description declares: a call to one it does not
/// declare must be refused.
struct Caps {
    directional: bool,
    interpolate: bool,
    output_derivatives: bool,
}

fn target_caps(t: &Target) -> Caps {
    Caps {
        directional: t.caps.0,
        interpolate: t.caps.1,
        output_derivatives: t.caps.2,
    }
}

impl<'t> Fuzzer<'t> {
    /// A sequence determined by `seed` alone: the same seed replays the same calls.
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
