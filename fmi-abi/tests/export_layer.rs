//! The export layer driven through its C entry points with a toy model: the state machine,
//! argument checks, FMU state, reset, panic containment and the logger contract.

use fmi_abi::export as x;
use fmi_abi::types::*;
use fmi_abi::{InstantiateContext, Logger, Model, ModelInfo, StepOutcome, Values, VarSpec};
use serde::{Deserialize, Serialize};
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::sync::Mutex;

/// dx/dt = -k x + u; y = x. A step with u = 99 panics, to test containment.
#[derive(Clone, Serialize, Deserialize)]
struct Toy {
    x: f64,
}

const U: u32 = 0;
const Y: u32 = 1;
const K: u32 = 2;
const GAIN: u32 = 3;

static VARS: &[VarSpec] = &[
    VarSpec::real_input(U, "u", "1", 0.0, "input"),
    VarSpec::real_output(Y, "y", "1", 1.0, "state"),
    VarSpec::real_parameter(K, "k", "1", 2.0, "rate").min(0.0),
    VarSpec::real_parameter(GAIN, "gain", "1", 1.0, "tunable gain").tunable(),
];

impl Model for Toy {
    const INFO: ModelInfo = ModelInfo {
        model_name: "Toy",
        model_identifier: "Toy",
        guid: "toy-guid-1",
        description: "test model",
        author: "tests",
        version: "0",
        default_start: 0.0,
        default_stop: 1.0,
        default_step: 0.1,
    };
    const STATE_LAYOUT: &'static str = "toy-layout-1";
    fn variables() -> &'static [VarSpec] {
        VARS
    }
    fn instantiate(_: &InstantiateContext, _: &Logger) -> Result<Self, String> {
        Ok(Toy { x: 1.0 })
    }
    fn exit_initialization(&mut self, v: &mut Values, _: &Logger) -> Result<(), String> {
        if v.real[K as usize] == 0.0 {
            return Err("parameter 'k' must not be zero".into());
        }
        Ok(())
    }
    fn do_step(
        &mut self,
        v: &mut Values,
        _t: f64,
        h: f64,
        log: &Logger,
    ) -> Result<StepOutcome, String> {
        let u = v.real[U as usize];
        if u == 99.0 {
            panic!("toy model asked to panic");
        }
        if u.is_nan() {
            log.warning("u is NaN: 100% ignored");
            return Ok(StepOutcome::Warning);
        }
        self.x += h * (-v.real[K as usize] * self.x + v.real[GAIN as usize] * u);
        v.real[Y as usize] = self.x;
        Ok(StepOutcome::Ok)
    }
}

/// What the logger received: (instance name, status, category, message).
type Logged = Vec<(String, i32, String, String)>;

// A C-compatible logger with the fixed arguments of the variadic signature. We only ever call
// it with "%s" and one string argument, which is read as the sixth fixed argument.
unsafe extern "C" fn logger(
    env: *mut c_void,
    name: *const c_char,
    status: c_int,
    cat: *const c_char,
    fmt: *const c_char,
    msg: *const c_char,
) {
    // SAFETY: `env` is the component environment `Fmu::new` registered: a `Mutex<Logged>` in a Box
    // the `Fmu` keeps alive as long as the instance.
    let log = unsafe { &*(env as *const Mutex<Logged>) };
    // SAFETY: the layer passes NUL-terminated strings for the name, category, format and the "%s"
    // argument.
    let s = |p: *const c_char| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
    assert_eq!(s(fmt), "%s");
    log.lock().unwrap().push((s(name), status, s(cat), s(msg)));
}

struct Fmu {
    c: fmi2Component,
    log: Box<Mutex<Logged>>,
    _callbacks: Box<fmi2CallbackFunctions>,
}

impl Fmu {
    fn new(guid: &str) -> Option<Fmu> {
        let log: Box<Mutex<Logged>> = Box::new(Mutex::new(vec![]));
        let callbacks = Box::new(fmi2CallbackFunctions {
            // SAFETY: see `logger`: the layer always passes exactly (…, "%s", message).
            logger: unsafe {
                std::mem::transmute::<*const (), fmi2CallbackLogger>(logger as *const ())
            },
            allocate_memory: None,
            free_memory: None,
            step_finished: None,
            component_environment: &*log as *const Mutex<Logged> as *mut c_void,
        });
        let name = CString::new("toy #1 100%").unwrap();
        let guid = CString::new(guid).unwrap();
        let res = CString::new("file:///tmp/toy%20dir/resources/").unwrap();
        // SAFETY: the strings are NUL-terminated and live through the call (the layer copies what
        // it keeps); `callbacks` is boxed and kept in the `Fmu` for the instance's life.
        let c = unsafe {
            x::instantiate::<Toy>(
                name.as_ptr(),
                FMI2_CO_SIMULATION,
                guid.as_ptr(),
                res.as_ptr(),
                &*callbacks,
                0,
                1,
            )
        };
        // name and guid are dropped here: the layer must have copied what it keeps.
        drop(name);
        (!c.is_null()).then_some(Fmu {
            c,
            log,
            _callbacks: callbacks,
        })
    }
    fn init(&self) {
        // SAFETY: `self.c` is a live instance of `Fmu::new` (freed only by Drop).
        unsafe {
            assert_eq!(
                x::setup_experiment::<Toy>(self.c, 0, 0.0, 0.0, 0, 0.0),
                fmi2Status::OK
            );
            assert_eq!(x::enter_initialization_mode::<Toy>(self.c), fmi2Status::OK);
            assert_eq!(x::exit_initialization_mode::<Toy>(self.c), fmi2Status::OK);
        }
    }
    fn set(&self, vr: u32, v: f64) -> fmi2Status {
        // SAFETY: `self.c` is live; `vr` and `v` are one element each, as n = 1 says.
        unsafe { x::set_real::<Toy>(self.c, &vr, 1, &v) }
    }
    fn get(&self, vr: u32) -> (fmi2Status, f64) {
        let mut v = f64::NAN;
        // SAFETY: `self.c` is live; `vr` and `v` are one element each, as n = 1 says.
        let s = unsafe { x::get_real::<Toy>(self.c, &vr, 1, &mut v) };
        (s, v)
    }
    fn step(&self, t: f64, h: f64) -> fmi2Status {
        // SAFETY: `self.c` is live (freed only by Drop).
        unsafe { x::do_step::<Toy>(self.c, t, h, 1) }
    }
    fn last(&self) -> (String, i32, String, String) {
        self.log
            .lock()
            .unwrap()
            .last()
            .cloned()
            .expect("something was logged")
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        // SAFETY: `self.c` came from fmi2Instantiate and is freed here once; `Fmu::new` never
        // builds an `Fmu` from a NULL instance.
        unsafe { x::free_instance::<Toy>(self.c) }
    }
}

#[test]
fn a_normal_run_follows_the_exact_solution_of_the_euler_scheme() {
    let f = Fmu::new("toy-guid-1").unwrap();
    f.init();
    let h = 0.01;
    let mut want = 1.0;
    for k in 0..100 {
        assert_eq!(f.step(k as f64 * h, h), fmi2Status::OK);
        want += h * (-2.0 * want);
    }
    assert_eq!(f.get(Y), (fmi2Status::OK, want));
}

#[test]
fn wrong_guid_and_model_exchange_are_refused_with_a_message() {
    assert!(Fmu::new("another-guid").is_none());
    // SAFETY: the strings are NUL-terminated literals; NULL resources and callbacks are allowed by
    // the layer (crate docs).
    let c = unsafe {
        x::instantiate::<Toy>(
            c"n".as_ptr(),
            FMI2_MODEL_EXCHANGE,
            c"toy-guid-1".as_ptr(),
            std::ptr::null(),
            std::ptr::null(),
            0,
            0,
        )
    };
    assert!(c.is_null());
    // NULL instance name, NULL resources and NULL callbacks are tolerated.
    // SAFETY: the GUID is a NUL-terminated literal; NULL name, resources and callbacks are allowed
    // by the layer (crate docs).
    let c = unsafe {
        x::instantiate::<Toy>(
            std::ptr::null(),
            FMI2_CO_SIMULATION,
            c"toy-guid-1".as_ptr(),
            std::ptr::null(),
            std::ptr::null(),
            0,
            0,
        )
    };
    assert!(!c.is_null());
    // SAFETY: `c` came from fmi2Instantiate above and is freed once.
    unsafe { x::free_instance::<Toy>(c) };
    // SAFETY: fmi2FreeInstance accepts NULL and does nothing.
    unsafe { x::free_instance::<Toy>(std::ptr::null_mut()) };
}

#[test]
fn illegal_calls_return_error_with_a_reason_and_change_nothing() {
    let f = Fmu::new("toy-guid-1").unwrap();
    assert_eq!(f.step(0.0, 0.1), fmi2Status::Error);
    let (name, status, cat, msg) = f.last();
    assert_eq!(
        (name.as_str(), status, cat.as_str()),
        ("toy #1 100%", 3, "logStatusError")
    );
    assert!(
        msg.contains("fmi2DoStep") && msg.contains("instantiated"),
        "{msg}"
    );
    // Parameters and inputs before SetupExperiment are fine.
    assert_eq!(f.set(K, 3.0), fmi2Status::OK);
    assert_eq!(f.set(U, 0.5), fmi2Status::OK);
    // An output with initial="exact" may have its start value set before initialization
    // (FMI 2.0 section 4.2.4), but never afterwards.
    assert_eq!(f.set(Y, 0.5), fmi2Status::OK);
    f.init();
    assert_eq!(
        f.set(Y, 0.5),
        fmi2Status::Error,
        "an output is not settable after initialization"
    );
    assert!(
        f.last().3.contains("'y'") && f.last().3.contains("output"),
        "{}",
        f.last().3
    );
    assert_eq!(
        f.set(K, 4.0),
        fmi2Status::Error,
        "a fixed parameter after initialization"
    );
    assert!(f.last().3.contains("fixed parameter"));
    assert_eq!(
        f.set(GAIN, 2.0),
        fmi2Status::OK,
        "a tunable parameter after initialization"
    );
    assert_eq!(f.get(9999).0, fmi2Status::Error);
    assert!(f.last().3.contains("unknown Real value reference 9999"));
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `Y` is one reference
    // as n = 1 says; the NULL value array is the case under test and the layer checks it before
    // writing.
    let null = unsafe { x::get_real::<Toy>(f.c, &Y, 1, std::ptr::null_mut()) };
    assert_eq!(null, fmi2Status::Error);
    assert!(f.last().3.contains("NULL"));
    for (t, h) in [
        (0.0, -0.1),
        (0.0, 0.0),
        (0.0, f64::NAN),
        (0.0, f64::INFINITY),
        (5.0, 0.1),
    ] {
        assert_eq!(f.step(t, h), fmi2Status::Error, "t={t} h={h}");
    }
    // Still usable: the state did not change.
    assert_eq!(f.step(0.0, 0.1), fmi2Status::OK);
    // A step whose end overflows to infinity is refused (the instance could never step again).
    let g = Fmu::new("toy-guid-1").unwrap();
    // SAFETY: `g.c` is a live instance of `Fmu::new` (freed only by its Drop).
    unsafe {
        assert_eq!(
            x::setup_experiment::<Toy>(g.c, 0, 0.0, f64::MAX, 0, 0.0),
            fmi2Status::OK
        );
        assert_eq!(x::enter_initialization_mode::<Toy>(g.c), fmi2Status::OK);
        assert_eq!(x::exit_initialization_mode::<Toy>(g.c), fmi2Status::OK);
    }
    assert_eq!(g.step(f64::MAX, f64::MAX), fmi2Status::Error);
    assert!(
        g.last().3.contains("largest representable time"),
        "{}",
        g.last().3
    );
    assert_eq!(
        g.step(f64::MAX, 1.0),
        fmi2Status::OK,
        "MAX + 1 rounds to MAX"
    );
    // A set with one bad reference among good ones changes nothing.
    let vrs = [U, 9999];
    let vals = [7.0, 8.0];
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `vrs` and `vals`
        // both hold the 2 elements passed.
        unsafe { x::set_real::<Toy>(f.c, vrs.as_ptr(), 2, vals.as_ptr()) },
        fmi2Status::Error
    );
    assert_eq!(f.get(U).1, 0.5);
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop).
    assert_eq!(unsafe { x::terminate::<Toy>(f.c) }, fmi2Status::OK);
    // No set after Terminate, even of nothing (nvr = 0).
    let none: [u32; 0] = [];
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); with n = 0 no
        // element is read, so the empty and NULL arrays are never dereferenced.
        unsafe { x::set_real::<Toy>(f.c, none.as_ptr(), 0, std::ptr::null()) },
        fmi2Status::Error
    );
    assert!(
        f.last()
            .3
            .contains("fmi2SetReal is not allowed in state 'terminated'")
    );
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); with n = 0 no
        // element is read, so the empty and NULL arrays are never dereferenced.
        unsafe { x::set_string::<Toy>(f.c, none.as_ptr(), 0, std::ptr::null()) },
        fmi2Status::Error
    );
    assert_eq!(
        f.step(0.1, 0.1),
        fmi2Status::Error,
        "no step after Terminate"
    );
    assert_eq!(
        f.get(Y).0,
        fmi2Status::OK,
        "final values may be read after Terminate (FMI 2.0 4.2.4)"
    );
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop).
    assert_eq!(unsafe { x::cancel_step::<Toy>(f.c) }, fmi2Status::Error);
    assert_eq!(
        // SAFETY: a NULL instance is refused by the layer's check before any use.
        unsafe { x::enter_initialization_mode::<Toy>(std::ptr::null_mut()) },
        fmi2Status::Error
    );
}

#[test]
fn warnings_pass_percent_signs_intact() {
    let f = Fmu::new("toy-guid-1").unwrap();
    f.init();
    f.set(U, f64::NAN);
    assert_eq!(f.step(0.0, 0.1), fmi2Status::Warning);
    let (_, status, cat, msg) = f.last();
    assert_eq!(
        (status, cat.as_str(), msg.as_str()),
        (1, "logStatusWarning", "u is NaN: 100% ignored")
    );
}

#[test]
fn a_panic_is_contained_and_the_instance_becomes_fatal() {
    let f = Fmu::new("toy-guid-1").unwrap();
    f.init();
    f.set(U, 99.0);
    assert_eq!(f.step(0.0, 0.1), fmi2Status::Fatal);
    let (_, status, cat, msg) = f.last();
    assert_eq!((status, cat.as_str()), (4, "logStatusFatal"));
    assert!(msg.contains("toy model asked to panic"), "{msg}");
    assert_eq!(f.step(0.0, 0.1), fmi2Status::Error);
    assert_eq!(f.set(U, 1.0), fmi2Status::Error);
    // Another instance is unaffected.
    let g = Fmu::new("toy-guid-1").unwrap();
    g.init();
    assert_eq!(g.step(0.0, 0.1), fmi2Status::OK);
}

#[test]
fn after_fatal_only_free_instance_is_accepted() {
    let f = Fmu::new("toy-guid-1").unwrap();
    f.init();
    f.set(U, 99.0);
    assert_eq!(f.step(0.0, 0.1), fmi2Status::Fatal);
    // Reset would otherwise resurrect an instance whose model panicked mid-step.
    let mut s: fmi2FMUstate = std::ptr::null_mut();
    let mut t = 0.0;
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `s` and `t` are
    // locals the layer writes one value to.
    unsafe {
        assert_eq!(x::reset::<Toy>(f.c), fmi2Status::Error);
        assert_eq!(
            x::set_debug_logging::<Toy>(f.c, 1, 0, std::ptr::null()),
            fmi2Status::Error
        );
        assert_eq!(x::get_fmu_state::<Toy>(f.c, &mut s), fmi2Status::Error);
        assert_eq!(
            x::get_real_status::<Toy>(f.c, FMI2_LAST_SUCCESSFUL_TIME, &mut t),
            fmi2Status::Error
        );
    }
    assert!(s.is_null());
    assert!(
        f.last().3.contains("only fmi2FreeInstance"),
        "{}",
        f.last().3
    );
}

#[test]
fn status_queries_are_refused_before_stepping_begins() {
    let f = Fmu::new("toy-guid-1").unwrap();
    let (mut t, mut b, mut i) = (f64::NAN, 7, 7);
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); each status is
    // written to one live `&mut`.
    let query = |t: &mut f64, b: &mut c_int, i: &mut c_int| unsafe {
        [
            x::get_real_status::<Toy>(f.c, FMI2_LAST_SUCCESSFUL_TIME, t),
            x::get_boolean_status::<Toy>(f.c, FMI2_TERMINATED, b),
            x::get_status::<Toy>(f.c, FMI2_DO_STEP_STATUS, i),
        ]
    };
    // Instantiated and initialization mode: not allowed (FMI 2.0 section 4.2.4).
    assert_eq!(query(&mut t, &mut b, &mut i), [fmi2Status::Error; 3]);
    assert!(
        f.last().3.contains("not allowed in state 'instantiated'"),
        "{}",
        f.last().3
    );
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop).
    unsafe {
        assert_eq!(
            x::setup_experiment::<Toy>(f.c, 0, 0.0, 0.0, 0, 0.0),
            fmi2Status::OK
        );
        assert_eq!(x::enter_initialization_mode::<Toy>(f.c), fmi2Status::OK);
    }
    assert_eq!(query(&mut t, &mut b, &mut i), [fmi2Status::Error; 3]);
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop).
    unsafe { assert_eq!(x::exit_initialization_mode::<Toy>(f.c), fmi2Status::OK) };
    assert_eq!(f.step(0.0, 0.25), fmi2Status::OK);
    assert_eq!(
        query(&mut t, &mut b, &mut i),
        [fmi2Status::OK, fmi2Status::OK, fmi2Status::Discard]
    );
    assert_eq!((t, b), (0.25, FMI2_FALSE));
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop).
    unsafe { assert_eq!(x::terminate::<Toy>(f.c), fmi2Status::OK) };
    assert_eq!(query(&mut t, &mut b, &mut i)[0], fmi2Status::OK);
}

#[test]
fn every_damaged_copy_of_a_serialized_state_is_refused() {
    let f = Fmu::new("toy-guid-1").unwrap();
    f.init();
    f.set(U, 0.3);
    assert_eq!(f.step(0.0, 0.1), fmi2Status::OK);
    let mut s: fmi2FMUstate = std::ptr::null_mut();
    let mut size = 0usize;
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `s` and `size` are
    // locals the layer writes one value to; `s` is then a state of this instance.
    unsafe {
        assert_eq!(x::get_fmu_state::<Toy>(f.c, &mut s), fmi2Status::OK);
        assert_eq!(
            x::serialized_fmu_state_size::<Toy>(f.c, s, &mut size),
            fmi2Status::OK
        );
    }
    let mut good = vec![0 as c_char; size];
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `good` holds `size`
    // bytes, as passed; `s` is a live state of this instance, freed once here.
    unsafe {
        assert_eq!(
            x::serialize_fmu_state::<Toy>(f.c, s, good.as_mut_ptr(), size),
            fmi2Status::OK
        );
        assert_eq!(x::free_fmu_state::<Toy>(f.c, &mut s), fmi2Status::OK);
    }
    let try_bytes = |b: &[c_char]| {
        let mut st: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `b` is a live
        // slice of `b.len()` bytes; `st` is a local the layer writes to.
        let status = unsafe { x::deserialize_fmu_state::<Toy>(f.c, b.as_ptr(), b.len(), &mut st) };
        if !st.is_null() {
            // SAFETY: `st` is a state the layer just made for this instance and is freed once.
            unsafe { x::free_fmu_state::<Toy>(f.c, &mut st) };
        }
        status
    };
    assert_eq!(try_bytes(&good), fmi2Status::OK);
    // Every single-bit flip, every truncation and an extension: all refused. Before the
    // length and checksum, a flip in a value byte decoded into a different state.
    for k in 0..size {
        for bit in 0..8 {
            let mut bad = good.clone();
            bad[k] ^= 1 << bit;
            assert_eq!(
                try_bytes(&bad),
                fmi2Status::Error,
                "bit {bit} of byte {k} of {size}"
            );
        }
    }
    for n in 0..size {
        assert_eq!(try_bytes(&good[..n]), fmi2Status::Error, "truncated to {n}");
    }
    let mut longer = good.clone();
    longer.push(0);
    assert_eq!(try_bytes(&longer), fmi2Status::Error);
    assert!(
        f.last().3.contains("truncated or extended"),
        "{}",
        f.last().3
    );
}

#[test]
fn reset_gives_a_fresh_instance() {
    let f = Fmu::new("toy-guid-1").unwrap();
    f.set(K, 5.0);
    f.init();
    f.set(U, 1.0);
    for k in 0..10 {
        f.step(k as f64 * 0.1, 0.1);
    }
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop).
    assert_eq!(unsafe { x::reset::<Toy>(f.c) }, fmi2Status::OK);
    // Back in "instantiated": k and u have their start values again, time is 0.
    f.init();
    let (g, h) = (Fmu::new("toy-guid-1").unwrap(), 0.1);
    g.init();
    for k in 0..10 {
        assert_eq!(f.step(k as f64 * h, h), fmi2Status::OK);
        g.step(k as f64 * h, h);
        assert_eq!(f.get(Y).1.to_bits(), g.get(Y).1.to_bits());
    }
}

#[test]
fn fmu_state_and_its_serialization_replay_bit_for_bit() {
    let f = Fmu::new("toy-guid-1").unwrap();
    f.init();
    let h = 0.1;
    for k in 0..5 {
        f.set(U, (k as f64).sin());
        f.step(k as f64 * h, h);
    }
    let mut s: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `s` is a local
        // the layer writes the new state to.
        unsafe { x::get_fmu_state::<Toy>(f.c, &mut s) },
        fmi2Status::OK
    );
    let run = |f: &Fmu| -> Vec<u64> {
        (5..15)
            .map(|k| {
                f.set(U, (k as f64).sin());
                assert_eq!(f.step(k as f64 * h, h), fmi2Status::OK);
                f.get(Y).1.to_bits()
            })
            .collect()
    };
    let first = run(&f);
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `s` is a live state
    // of this instance from fmi2GetFMUstate.
    assert_eq!(unsafe { x::set_fmu_state::<Toy>(f.c, s) }, fmi2Status::OK);
    assert_eq!(run(&f), first);
    // Serialize, free, deserialize into a new state, restore, replay.
    let mut size = 0usize;
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `s` is a live
        // state of this instance; `size` is a local written once.
        unsafe { x::serialized_fmu_state_size::<Toy>(f.c, s, &mut size) },
        fmi2Status::OK
    );
    let mut bytes = vec![0 as c_char; size];
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `bytes` holds
        // `size` bytes, as passed; `s` is a live state of this instance.
        unsafe { x::serialize_fmu_state::<Toy>(f.c, s, bytes.as_mut_ptr(), size) },
        fmi2Status::OK
    );
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `bytes` holds
        // `size` bytes, more than the `size - 1` passed; `s` is a live state of this instance.
        unsafe { x::serialize_fmu_state::<Toy>(f.c, s, bytes.as_mut_ptr(), size - 1) },
        fmi2Status::Error
    );
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `s` is a live
        // state of this instance, freed once (the layer sets it to NULL).
        unsafe { x::free_fmu_state::<Toy>(f.c, &mut s) },
        fmi2Status::OK
    );
    assert!(s.is_null());
    let mut s2: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `bytes` holds
        // the `size` bytes passed; `s2` is a local the layer writes to.
        unsafe { x::deserialize_fmu_state::<Toy>(f.c, bytes.as_ptr(), size, &mut s2) },
        fmi2Status::OK
    );
    // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `s2` is a live state
    // of this instance from fmi2DeSerializeFMUstate.
    assert_eq!(unsafe { x::set_fmu_state::<Toy>(f.c, s2) }, fmi2Status::OK);
    assert_eq!(run(&f), first);
    // A state of another layout (another build of the same FMU) is refused, naming the layout.
    let mut other = bytes.clone();
    let text: Vec<u8> = other.iter().map(|c| *c as u8).collect();
    let at = text
        .windows(b"toy-layout-1".len())
        .position(|w| w == b"toy-layout-1")
        .expect("the header carries the layout");
    other[at + b"toy-layout-".len()] = b'2' as c_char;
    let mut s4: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `other` is a
        // copy of `bytes`, `size` bytes long; `s4` is a local the layer writes to.
        unsafe { x::deserialize_fmu_state::<Toy>(f.c, other.as_ptr(), size, &mut s4) },
        fmi2Status::Error
    );
    assert!(
        f.last().3.contains("state layout 'toy-layout-1'"),
        "{}",
        f.last().3
    );
    assert!(s4.is_null());
    // Corrupt bytes are refused with a message.
    bytes[0] = b'X' as c_char;
    let mut s3: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `bytes` holds
        // the `size` bytes passed; `s3` is a local the layer writes to.
        unsafe { x::deserialize_fmu_state::<Toy>(f.c, bytes.as_ptr(), size, &mut s3) },
        fmi2Status::Error
    );
    assert!(f.last().3.contains("not made by Toy"));
    assert!(s3.is_null());
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); `s2` is a live
        // state of this instance, freed once.
        unsafe { x::free_fmu_state::<Toy>(f.c, &mut s2) },
        fmi2Status::OK
    );
    assert_eq!(
        // SAFETY: `f.c` is a live instance of `Fmu::new` (freed only by its Drop); a NULL state is
        // refused by the layer's check before any use.
        unsafe { x::set_fmu_state::<Toy>(f.c, std::ptr::null_mut()) },
        fmi2Status::Error
    );
}

#[test]
fn instances_in_parallel_threads_match_sequential_runs() {
    let run = |gain: f64| -> Vec<u64> {
        let f = Fmu::new("toy-guid-1").unwrap();
        f.init();
        f.set(GAIN, gain);
        f.set(U, 1.0);
        (0..20_000)
            .map(|k| {
                f.step(k as f64 * 1e-3, 1e-3);
                f.get(Y).1.to_bits()
            })
            .collect()
    };
    let sequential: Vec<_> = (0..4).map(|i| run(i as f64)).collect();
    let parallel: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..4).map(|i| s.spawn(move || run(i as f64))).collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(sequential, parallel);
}

#[test]
fn generated_model_description_is_valid() {
    let md = fmi_abi::description::model_description::<Toy>();
    assert_eq!(md.validate(), vec![]);
    let xml = md.to_xml();
    let back = model_description::ModelDescription::from_xml(&xml).unwrap();
    assert_eq!(back, md);
    assert!(xml.contains("canGetAndSetFMUstate=\"true\""));
    assert!(xml.contains("canNotUseMemoryManagementFunctions=\"true\""));
    assert!(xml.contains("canHandleVariableCommunicationStepSize=\"true\""));
}
