//! The importer against a small C FMU (tests/c/testfmu.c): logging through the variadic
//! shim, every failure status, what Drop calls, and the value and state functions.

mod common;

use common::*;
use fmi_import::{Fmu, ImportError, Instance, LogConfig, fmi2Status};
use std::path::Path;

const X: u32 = 0;
const U: u32 = 1;
const TIME: u32 = 2;
const MODE: u32 = 0;
const STEPS: u32 = 1;

fn open(dir: &Path) -> Fmu {
    Fmu::open(&test_fmu(dir, "TestFmu", &[])).unwrap()
}

fn start(fmu: &Fmu, name: &str, config: LogConfig) -> Instance {
    let mut inst = fmu.instantiate(name, config).unwrap();
    inst.setup_experiment(0.0, None, None).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    inst
}

#[test]
fn values_round_trip() {
    let dir = scratch();
    let fmu = open(dir.path());
    let mut inst = start(&fmu, "t", quiet());
    inst.set_real(&[U], &[2.0]).unwrap();
    for k in 0..10 {
        inst.do_step(k as f64 * 0.5, 0.5).unwrap();
    }
    let mut out = [0.0; 3];
    inst.get_real(&[X, U, TIME], &mut out).unwrap();
    assert_eq!(out, [10.0, 2.0, 5.0]);
    assert_eq!(inst.time(), Some(5.0));
    let mut n = [0; 2];
    inst.get_integer(&[MODE, STEPS], &mut n).unwrap();
    assert_eq!(n, [0, 10]);
    inst.set_boolean(&[0], &[true]).unwrap();
    let mut b = [false];
    inst.get_boolean(&[0], &mut b).unwrap();
    assert!(b[0]);
    inst.set_string(&[0], &["héllo %s"]).unwrap();
    assert_eq!(inst.get_string(&[0]).unwrap(), ["héllo %s"]);
    assert_eq!(inst.last_successful_time(), Some(5.0));
}

#[test]
fn mismatched_slices_and_nul_are_refused_without_calling_the_fmu() {
    let dir = scratch();
    let fmu = open(dir.path());
    let mut inst = start(&fmu, "t", quiet());
    let e = inst.get_real(&[X, U], &mut [0.0]).unwrap_err();
    assert_eq!(e.function, "fmi2GetReal");
    assert!(e.messages[0].contains("same length"), "{e}");
    let e = inst.set_string(&[0], &["a\0b"]).unwrap_err();
    assert!(e.to_string().contains("NUL"), "{e}");
    // The instance is still fine.
    inst.do_step(0.0, 1.0).unwrap();
    let err = fmu.instantiate("bad\0name", quiet()).unwrap_err();
    assert!(
        matches!(err, ImportError::InvalidInstanceName { .. }),
        "{err:?}"
    );
}

#[test]
fn unknown_value_reference_is_the_fmus_error() {
    let dir = scratch();
    let fmu = open(dir.path());
    let mut inst = start(&fmu, "t", quiet());
    let e = inst.get_real(&[99], &mut [0.0]).unwrap_err();
    assert_eq!(e.status, fmi2Status::Error);
    assert_eq!(e.messages, ["fmi2GetReal: unknown value reference 99"]);
    assert_eq!(e.time, Some(0.0));
}

#[test]
fn log_records_carry_instance_category_and_intact_percent() {
    let dir = scratch();
    let fmu = open(dir.path());
    let (config, records) = capture(fmi2Status::Warning);
    let mut inst = start(&fmu, "inst 1", config);
    inst.set_integer(&[MODE], &[2]).unwrap();
    let e = inst.do_step(0.0, 0.1).unwrap_err();
    assert_eq!(e.function, "fmi2DoStep");
    assert_eq!(e.status, fmi2Status::Error);
    let expected = "step 0 failed at t=0: 100% sure (%s%d)";
    assert_eq!(e.messages, [expected]);
    assert!(
        e.to_string()
            .ends_with(&format!("returned fmi2Error at t = 0 s: {expected}")),
        "{e}"
    );
    let records = records.lock().unwrap();
    assert_eq!(records.len(), 1, "{records:?}");
    assert_eq!(records[0].instance, "inst 1");
    assert_eq!(records[0].category, "logStatusError");
    assert_eq!(records[0].status, fmi2Status::Error);
    assert_eq!(records[0].message, expected);
}

#[test]
fn below_min_status_is_dropped() {
    let dir = scratch();
    let fmu = open(dir.path());
    // Debug logging on: the FMU logs an fmi2OK "step" message every step.
    let (mut config, records) = capture(fmi2Status::OK);
    config.debug_logging = true;
    let mut inst = start(&fmu, "verbose", config);
    inst.do_step(0.0, 0.5).unwrap();
    {
        let r = records.lock().unwrap();
        assert!(
            r.iter()
                .any(|r| r.message == "step 1 to t=0.5" && r.category == "logStep")
        );
        // fmi2Instantiate's OK message with the resource location.
        let res = r
            .iter()
            .find(|r| r.message.starts_with("resource location: "))
            .unwrap();
        assert_eq!(
            res.message,
            format!("resource location: {}", fmu.resource_uri())
        );
        assert_eq!(res.category, "logInfo");
    }

    let (mut config, records) = capture(fmi2Status::Warning);
    config.debug_logging = true;
    let mut inst = start(&fmu, "filtered", config);
    inst.do_step(0.0, 0.5).unwrap();
    inst.set_integer(&[MODE], &[7]).unwrap();
    inst.do_step(0.5, 0.5).unwrap();
    let r = records.lock().unwrap();
    assert_eq!(r.len(), 1, "{r:?}");
    assert_eq!(r[0].status, fmi2Status::Warning);
    assert_eq!(r[0].message, "just a warning at step 1");

    let (config, records) = capture(fmi2Status::Error);
    let mut inst = start(&fmu, "errors only", config);
    inst.set_integer(&[MODE], &[7]).unwrap();
    inst.do_step(0.0, 0.5).unwrap();
    assert!(records.lock().unwrap().is_empty());
}

#[test]
fn long_messages_and_null_category_arrive_whole() {
    let dir = scratch();
    let fmu = open(dir.path());
    let (config, records) = capture(fmi2Status::Warning);
    let mut inst = start(&fmu, "long", config);
    inst.set_integer(&[MODE], &[4]).unwrap();
    inst.do_step(0.0, 0.5).unwrap();
    inst.set_integer(&[MODE], &[5]).unwrap();
    inst.do_step(0.5, 0.5).unwrap();
    let r = records.lock().unwrap();
    assert_eq!(r[0].message, format!("long:{}|42", "x".repeat(5000)));
    assert_eq!(r[1].message, "null instance and category 7");
    assert_eq!(r[1].category, "");
    assert_eq!(r[1].instance, "long");
}

#[test]
fn categories_are_passed_to_set_debug_logging() {
    let dir = scratch();
    let fmu = open(dir.path());
    let (mut config, records) = capture(fmi2Status::Warning);
    config.categories = Some(vec!["logStep".into(), "noSuchCategory".into()]);
    let _inst = fmu.instantiate("cats", config).unwrap();
    let r = records.lock().unwrap();
    assert_eq!(r.len(), 1, "{r:?}");
    assert!(r[0].message.contains("'noSuchCategory'"));
}

#[test]
fn discard_reports_the_last_successful_time() {
    let dir = scratch();
    let fmu = open(dir.path());
    let mut inst = start(&fmu, "d", quiet());
    inst.do_step(0.0, 0.25).unwrap();
    inst.set_integer(&[MODE], &[1]).unwrap();
    let e = inst.do_step(0.25, 0.25).unwrap_err();
    assert_eq!(e.status, fmi2Status::Discard);
    assert_eq!(e.time, Some(0.25));
    assert_eq!(e.last_successful_time, Some(0.25));
    assert_eq!(e.messages, ["cannot step past t=0.25: discarding"]);
    assert!(
        e.to_string().contains("(last successful time 0.25 s)"),
        "{e}"
    );
    drop(inst);
    // stepFailed allows fmi2Terminate, and Drop calls it.
    let calls = recorded_calls(&fmu);
    assert_eq!(
        calls[calls.len() - 2..],
        ["fmi2Terminate", "fmi2FreeInstance"]
    );
}

#[test]
fn drop_terminates_only_when_it_is_legal() {
    let dir = scratch();
    let fmu = open(dir.path());
    let tail = |n: usize| {
        let c = recorded_calls(&fmu);
        c[c.len() - n..].to_vec()
    };

    // Initialized: Terminate, then FreeInstance.
    drop(start(&fmu, "a", quiet()));
    assert_eq!(tail(2), ["fmi2Terminate", "fmi2FreeInstance"]);

    // Terminated explicitly: no second Terminate.
    let mut inst = start(&fmu, "b", quiet());
    inst.terminate().unwrap();
    drop(inst);
    assert_eq!(tail(2), ["fmi2Terminate", "fmi2FreeInstance"]);
    assert_eq!(tail(3)[0], "fmi2ExitInitializationMode");

    // Never initialized: only FreeInstance.
    drop(fmu.instantiate("c", quiet()).unwrap());
    assert_eq!(tail(2), ["fmi2Instantiate", "fmi2FreeInstance"]);

    // After fmi2Error: FreeInstance without Terminate.
    let mut inst = start(&fmu, "d", quiet());
    inst.set_integer(&[MODE], &[2]).unwrap();
    inst.do_step(0.0, 1.0).unwrap_err();
    drop(inst);
    assert_eq!(tail(2), ["fmi2ExitInitializationMode", "fmi2FreeInstance"]);

    // fmi2Reset leaves the error state: Drop terminates again after re-initialization.
    let mut inst = start(&fmu, "e", quiet());
    inst.set_integer(&[MODE], &[2]).unwrap();
    inst.do_step(0.0, 1.0).unwrap_err();
    inst.reset().unwrap();
    assert_eq!(inst.time(), None);
    inst.setup_experiment(0.0, None, None).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    inst.do_step(0.0, 1.0).unwrap();
    drop(inst);
    assert_eq!(tail(2), ["fmi2Terminate", "fmi2FreeInstance"]);

    // After fmi2Fatal: nothing at all.
    let mut inst = start(&fmu, "f", quiet());
    inst.set_integer(&[MODE], &[3]).unwrap();
    let e = inst.do_step(0.0, 1.0).unwrap_err();
    assert_eq!(e.status, fmi2Status::Fatal);
    assert_eq!(e.messages, ["fatal at t=0"]);
    drop(inst);
    assert_eq!(tail(1), ["fmi2ExitInitializationMode"]);

    // A status outside the enum counts as fatal.
    let mut inst = start(&fmu, "g", quiet());
    inst.set_integer(&[MODE], &[6]).unwrap();
    let e = inst.do_step(0.0, 1.0).unwrap_err();
    assert_eq!(e.status, fmi2Status::Fatal);
    drop(inst);
    assert_eq!(tail(1), ["fmi2ExitInitializationMode"]);
}

#[test]
fn fmu_states_are_freed_by_their_instance() {
    let dir = scratch();
    let fmu = open(dir.path());
    let frees = || {
        recorded_calls(&fmu)
            .iter()
            .filter(|c| *c == "fmi2FreeFMUstate")
            .count()
    };
    let mut inst = start(&fmu, "s", quiet());
    inst.set_real(&[U], &[1.0]).unwrap();
    let a = inst.get_fmu_state().unwrap();
    inst.do_step(0.0, 1.0).unwrap();
    let b = inst.get_fmu_state().unwrap();
    assert_eq!(b.time(), Some(1.0));
    inst.do_step(1.0, 1.0).unwrap();
    inst.set_fmu_state(&a).unwrap();
    let mut x = [0.0];
    inst.get_real(&[X], &mut x).unwrap();
    assert_eq!(x[0], 0.0);
    assert_eq!(inst.time(), Some(0.0));

    // Dropping a state (even on another thread) does not call the FMU...
    std::thread::spawn(move || drop(a)).join().unwrap();
    assert_eq!(frees(), 0);
    // ...its instance frees it at the next state operation.
    let c = inst.get_fmu_state().unwrap();
    assert_eq!(frees(), 1);

    // A state moved to another instance is refused.
    let mut other = start(&fmu, "other", quiet());
    let e = other.set_fmu_state(&b).unwrap_err();
    assert!(e.messages[0].contains("another instance"));

    let bytes = inst.serialize_fmu_state(&b).unwrap();
    let e = other.deserialize_fmu_state(&bytes[1..]).unwrap_err();
    assert_eq!(e.function, "fmi2DeSerializeFMUstate");
    let d = other.deserialize_fmu_state(&bytes).unwrap();
    other.set_fmu_state(&d).unwrap();
    other.get_real(&[X], &mut x).unwrap();
    assert_eq!(x[0], 1.0);
    drop(other);

    // The instance frees the states still held when it goes; the values become inert.
    let before = frees();
    drop(inst);
    assert_eq!(frees(), before + 2);
    drop(b);
    drop(c);
    drop(d);
    assert_eq!(frees(), before + 2);
}

#[test]
fn only_once_per_process_is_enforced() {
    let dir = scratch();
    let path = dir.path().join("Once.fmu");
    let lib = std::fs::read(test_library(&[])).unwrap();
    let xml = test_model_description(TEST_GUID).replace(
        "canHandleVariableCommunicationStepSize=\"true\"",
        "canHandleVariableCommunicationStepSize=\"true\" canBeInstantiatedOnlyOncePerProcess=\"true\"",
    );
    write_zip(
        &path,
        &[
            file("modelDescription.xml", xml),
            Entry::Mode(format!("binaries/{PLATFORM}/TestFmu.{EXT}"), lib, 0o755),
        ],
    );
    let fmu = Fmu::open(&path).unwrap();
    let first = fmu.instantiate("first", quiet()).unwrap();
    let err = fmu.instantiate("second", quiet()).unwrap_err();
    assert!(err.to_string().contains("'first'"), "{err}");
    drop(first);
    fmu.instantiate("third", quiet()).unwrap();
}

#[test]
fn guid_mismatch_in_c() {
    let dir = scratch();
    let path = dir.path().join("Guid.fmu");
    let lib = std::fs::read(test_library(&[])).unwrap();
    write_zip(
        &path,
        &[
            file(
                "modelDescription.xml",
                test_model_description("{other-guid}"),
            ),
            Entry::Mode(format!("binaries/{PLATFORM}/TestFmu.{EXT}"), lib, 0o755),
        ],
    );
    let fmu = Fmu::open(&path).unwrap();
    let (config, records) = capture(fmi2Status::Warning);
    let err = fmu.instantiate("g", config).unwrap_err();
    let expected = format!(
        "fmi2Instantiate: GUID '{{other-guid}}' does not match the binary's GUID '{TEST_GUID}'"
    );
    match &err {
        ImportError::Instantiate { messages, .. } => {
            assert_eq!(messages, std::slice::from_ref(&expected))
        }
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().ends_with(&expected), "{err}");
    assert_eq!(records.lock().unwrap()[0].message, expected);
}

#[test]
fn instances_of_one_fmu_run_in_parallel_threads() {
    let dir = scratch();
    let fmu = open(dir.path());
    let results: Vec<f64> = std::thread::scope(|s| {
        let hs: Vec<_> = (0..4)
            .map(|i| {
                let fmu = &fmu;
                s.spawn(move || {
                    let mut inst = start(fmu, &format!("p{i}"), quiet());
                    inst.set_real(&[U], &[i as f64]).unwrap();
                    for k in 0..1000 {
                        inst.do_step(k as f64 * 1e-3, 1e-3).unwrap();
                    }
                    let mut x = [0.0];
                    inst.get_real(&[X], &mut x).unwrap();
                    x[0]
                })
            })
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (i, x) in results.iter().enumerate() {
        assert!((x - i as f64).abs() < 1e-9, "{results:?}");
    }
}
