//! Per-step cost of `Instance::do_step` + `Instance::get_real` (one value), against the same
//! two calls made directly through raw function pointers on a second instance of the same
//! library: the difference is what this crate adds. Two FMUs: the C test FMU (a step is a
//! multiply-add, so the numbers are almost pure call overhead) and AlignmentEstimator.fmu.
//! Prints medians of several runs; asserts nothing (timings on a shared 2-core machine are
//! noisy).

#[path = "../tests/common/mod.rs"]
mod common;

use common::*;
use fmi_abi::types::{FMI2_CO_SIMULATION, FMI2_FALSE, fmi2CallbackFunctions};
use fmi_import::Fmu;
use std::ffi::{CString, c_char, c_int, c_void};
use std::hint::black_box;
use std::time::Instant;

unsafe extern "C" {
    fn calloc(n: usize, size: usize) -> *mut c_void;
    fn free(p: *mut c_void);
}

type Instantiate = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const fmi2CallbackFunctions,
    c_int,
    c_int,
) -> *mut c_void;
type Setup = unsafe extern "C" fn(*mut c_void, c_int, f64, f64, c_int, f64) -> c_int;
type Mode = unsafe extern "C" fn(*mut c_void) -> c_int;
type DoStep = unsafe extern "C" fn(*mut c_void, f64, f64, c_int) -> c_int;
type GetReal = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64) -> c_int;
type Free = unsafe extern "C" fn(*mut c_void);

const RUNS: usize = 7;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// ns per (do_step + get_real) through raw pointers.
fn raw(fmu: &Fmu, vr: u32, h: f64, steps: usize) -> f64 {
    let id = fmu.model_identifier();
    let path = fmu
        .unpacked_dir()
        .join(format!("binaries/{PLATFORM}/{id}.{EXT}"));
    // SAFETY: the library is the FMU this bench built and `Fmu::load` unpacked; loading it runs
    // only the Rust or C runtime's initializers, which have no preconditions.
    let lib = unsafe { libloading::Library::new(&path) }.unwrap();
    // SAFETY: the symbols are resolved with their FMI 2.0 signatures (the type aliases above)
    // and `lib` outlives every call; the strings are NUL-terminated and live through
    // fmi2Instantiate; `c` is checked non-NULL and freed once at the end; `vr` and `y` are one
    // element each, as n = 1 says; calloc/free are the allocator pair FMI asks for.
    unsafe {
        let instantiate = *lib.get::<Instantiate>("fmi2Instantiate").unwrap();
        let setup = *lib.get::<Setup>("fmi2SetupExperiment").unwrap();
        let enter = *lib.get::<Mode>("fmi2EnterInitializationMode").unwrap();
        let exit = *lib.get::<Mode>("fmi2ExitInitializationMode").unwrap();
        let do_step = *lib.get::<DoStep>("fmi2DoStep").unwrap();
        let get_real = *lib.get::<GetReal>("fmi2GetReal").unwrap();
        let free_instance = *lib.get::<Free>("fmi2FreeInstance").unwrap();
        let callbacks = fmi2CallbackFunctions {
            logger: None,
            allocate_memory: Some(calloc),
            free_memory: Some(free),
            step_finished: None,
            component_environment: std::ptr::null_mut(),
        };
        let name = CString::new("raw").unwrap();
        let guid = CString::new(fmu.model_description().guid.clone()).unwrap();
        let res = CString::new(fmu.resource_uri()).unwrap();
        let c = instantiate(
            name.as_ptr(),
            FMI2_CO_SIMULATION,
            guid.as_ptr(),
            res.as_ptr(),
            &callbacks,
            FMI2_FALSE,
            FMI2_FALSE,
        );
        assert!(!c.is_null());
        assert_eq!(setup(c, 0, 0.0, 0.0, 0, 0.0), 0);
        assert_eq!(enter(c), 0);
        assert_eq!(exit(c), 0);
        let mut t = 0.0;
        let mut y = 0.0;
        let mut per_run = Vec::new();
        for _ in 0..RUNS {
            let start = Instant::now();
            for _ in 0..steps {
                let s = do_step(c, t, h, FMI2_FALSE);
                let g = get_real(c, &vr, 1, &mut y);
                if s > 1 || g > 1 {
                    panic!("raw call failed");
                }
                t += h;
                black_box(y);
            }
            per_run.push(start.elapsed().as_nanos() as f64 / steps as f64);
        }
        free_instance(c);
        median(per_run)
    }
}

/// ns per (do_step + get_real) through `Instance`.
fn wrapped(fmu: &Fmu, vr: u32, h: f64, steps: usize) -> f64 {
    let mut inst = fmu.instantiate("wrapped", quiet()).unwrap();
    inst.setup_experiment(0.0, None, None).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    let mut t = 0.0;
    let mut y = [0.0];
    let mut per_run = Vec::new();
    for _ in 0..RUNS {
        let start = Instant::now();
        for _ in 0..steps {
            inst.do_step(t, h).unwrap();
            inst.get_real(&[vr], &mut y).unwrap();
            t += h;
            black_box(y);
        }
        per_run.push(start.elapsed().as_nanos() as f64 / steps as f64);
    }
    median(per_run)
}

fn report(label: &str, fmu: &Fmu, vr: u32, h: f64, steps: usize) {
    // Interleave to share the machine's noise fairly; warm up once.
    wrapped(fmu, vr, h, steps / 10);
    let mut r = Vec::new();
    let mut w = Vec::new();
    for _ in 0..3 {
        r.push(raw(fmu, vr, h, steps));
        w.push(wrapped(fmu, vr, h, steps));
    }
    let (r, w) = (median(r), median(w));
    println!(
        "{label:<20} raw {r:9.1} ns/step   Instance {w:9.1} ns/step   overhead {:+7.1} ns/step ({} steps x {RUNS} runs x 3)",
        w - r,
        steps
    );
}

fn main() {
    let dir = scratch();
    let test = Fmu::open(&test_fmu(dir.path(), "TestFmu", &[])).unwrap();
    report("C test FMU", &test, 0, 1e-3, 1_000_000);
    let estimator = Fmu::open(&our_fmu("AlignmentEstimator")).unwrap();
    let (_, alignment) = estimator.value_reference("alignment").unwrap();
    report("AlignmentEstimator", &estimator, alignment, 1e-3, 20_000);
}
