//! The importer against the project's own FMUs (AlignmentEstimator.fmu, RailVehicle.fmu).

mod common;

use common::*;
use fmi_import::{Fmu, ImportError, Instance, fmi2Status};

const H: f64 = 1e-3;

fn start(fmu: &Fmu, name: &str) -> Instance {
    let mut inst = fmu.instantiate(name, quiet()).unwrap();
    inst.setup_experiment(0.0, Some(100.0), None).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    inst
}

fn vr(fmu: &Fmu, name: &str) -> u32 {
    fmu.value_reference(name).unwrap().1
}

/// Steps `n` times from `t0`, returning the output `vr` after each step.
fn run(inst: &mut Instance, vr: u32, t0: f64, n: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(n);
    let mut y = [0.0];
    for k in 0..n {
        inst.do_step(t0 + k as f64 * H, H).unwrap();
        inst.get_real(&[vr], &mut y).unwrap();
        out.push(y[0]);
    }
    out
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn both_fmus_open_and_run_1000_steps() {
    let vehicle = Fmu::open(&our_fmu("RailVehicle")).unwrap();
    assert_eq!(vehicle.model_identifier(), "RailVehicle");
    assert!(
        vehicle
            .unpacked_dir()
            .join("modelDescription.xml")
            .is_file()
    );
    let mut v = start(&vehicle, "vehicle");
    let acc = run(&mut v, vr(&vehicle, "ws_acc_y"), 0.0, 1000);
    assert!(acc.iter().all(|x| x.is_finite()));
    assert!(
        acc.iter().any(|&x| x != 0.0),
        "the vehicle output never moved"
    );
    v.terminate().unwrap();

    let estimator = Fmu::open(&our_fmu("AlignmentEstimator")).unwrap();
    let mut e = start(&estimator, "estimator");
    let align = run(&mut e, vr(&estimator, "alignment"), 0.0, 1000);
    assert!(align.iter().all(|x| x.is_finite()));
    // Integer, Boolean and String getters on a real FMU.
    let (_, rebuilds) = estimator.value_reference("rebuilds").unwrap();
    let mut n = [0];
    e.get_integer(&[rebuilds], &mut n).unwrap();
    assert!(n[0] >= 1);
    let (_, updated) = estimator.value_reference("updated").unwrap();
    let mut b = [false];
    e.get_boolean(&[updated], &mut b).unwrap();
    let (_, file) = estimator.value_reference("calibration_file").unwrap();
    assert_eq!(e.get_string(&[file]).unwrap().len(), 1);
}

#[test]
fn vehicle_drives_estimator() {
    let vehicle = Fmu::open(&our_fmu("RailVehicle")).unwrap();
    let estimator = Fmu::open(&our_fmu("AlignmentEstimator")).unwrap();
    let outs: Vec<u32> = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y"]
        .iter()
        .map(|n| vr(&vehicle, n))
        .collect();
    let ins: Vec<u32> = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y"]
        .iter()
        .map(|n| vr(&estimator, n))
        .collect();
    let mut v = start(&vehicle, "vehicle");
    let mut e = start(&estimator, "estimator");
    let speed = vr(&estimator, "speed");
    e.set_real(&[speed], &[20.0]).unwrap();
    let alignment = vr(&estimator, "alignment");
    let mut y = [0.0; 3];
    let mut a = [0.0];
    for k in 0..1000 {
        let t = k as f64 * H;
        v.do_step(t, H).unwrap();
        v.get_real(&outs, &mut y).unwrap();
        e.set_real(&ins, &y).unwrap();
        e.do_step(t, H).unwrap();
        e.get_real(&[alignment], &mut a).unwrap();
        assert!(a[0].is_finite());
    }
}

#[test]
fn fmu_state_replays_bit_identically_and_serializes() {
    let vehicle = Fmu::open(&our_fmu("RailVehicle")).unwrap();
    let acc = vr(&vehicle, "ws_acc_y");
    let mut v = start(&vehicle, "vehicle");
    run(&mut v, acc, 0.0, 100);
    let t0 = 100.0 * H;
    let saved = v.get_fmu_state().unwrap();
    let first = run(&mut v, acc, t0, 200);
    v.set_fmu_state(&saved).unwrap();
    assert_eq!(v.time(), Some(t0));
    let again = run(&mut v, acc, t0, 200);
    assert_eq!(bits(&first), bits(&again));

    let bytes = v.serialize_fmu_state(&saved).unwrap();
    assert!(!bytes.is_empty());
    let restored = v.deserialize_fmu_state(&bytes).unwrap();
    assert_eq!(v.serialize_fmu_state(&restored).unwrap(), bytes);
    v.set_fmu_state(&restored).unwrap();
    assert_eq!(bits(&run(&mut v, acc, t0, 200)), bits(&first));

    // The bytes move to another instance of the same FMU.
    let mut w = vehicle.instantiate("other", quiet()).unwrap();
    let moved = w.deserialize_fmu_state(&bytes).unwrap();
    w.set_fmu_state(&moved).unwrap();
    assert_eq!(bits(&run(&mut w, acc, t0, 200)), bits(&first));

    // A state object does not: using it with another instance is refused.
    let e = w.set_fmu_state(&saved).unwrap_err();
    assert_eq!(e.function, "fmi2SetFMUstate");
    assert!(e.to_string().contains("another instance"), "{e}");

    // Updating a state in place.
    let mut s = v.get_fmu_state().unwrap();
    let t1 = v.time().unwrap();
    run(&mut v, acc, t1, 10);
    v.update_fmu_state(&mut s).unwrap();
    let t2 = v.time().unwrap();
    let a = run(&mut v, acc, t2, 10);
    v.set_fmu_state(&s).unwrap();
    assert_eq!(bits(&run(&mut v, acc, t2, 10)), bits(&a));

    // States dropped, then the instance dropped with a state still alive: no crash.
    drop(saved);
    drop(restored);
    let _again = v.get_fmu_state().unwrap();
    drop(v);
    drop(s);
}

#[test]
fn two_instances_in_two_threads_equal_sequential_runs() {
    let vehicle = Fmu::open(&our_fmu("RailVehicle")).unwrap();
    let acc = vr(&vehicle, "ws_acc_y");
    let sequential: Vec<Vec<f64>> = (0..2)
        .map(|i| run(&mut start(&vehicle, &format!("seq{i}")), acc, 0.0, 500))
        .collect();
    assert_eq!(bits(&sequential[0]), bits(&sequential[1]));
    let parallel: Vec<Vec<f64>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..2)
            .map(|i| {
                let vehicle = &vehicle;
                s.spawn(move || run(&mut start(vehicle, &format!("par{i}")), acc, 0.0, 500))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (p, q) in parallel.iter().zip(&sequential) {
        assert_eq!(bits(p), bits(q));
    }
    // An instance created here, stepped on another thread.
    let mut inst = start(&vehicle, "moved");
    let moved = std::thread::spawn(move || run(&mut inst, acc, 0.0, 500))
        .join()
        .unwrap();
    assert_eq!(bits(&moved), bits(&sequential[0]));
}

#[test]
fn negative_step_is_an_fmi_error_with_the_fmus_message() {
    let estimator = Fmu::open(&our_fmu("AlignmentEstimator")).unwrap();
    let mut e = start(&estimator, "estimator");
    run(&mut e, vr(&estimator, "alignment"), 0.0, 10);
    let t = 10.0 * H;
    let err = e.do_step(t, -H).unwrap_err();
    assert_eq!(err.function, "fmi2DoStep");
    assert_eq!(err.status, fmi2Status::Error);
    assert_eq!(err.time, Some(t));
    assert_eq!(err.instance, "estimator");
    assert!(
        err.messages
            .iter()
            .any(|m| m.contains("communicationStepSize") && m.contains("-0.001")),
        "{err:?}"
    );
    let text = err.to_string();
    assert!(
        text.starts_with("fmi2DoStep of instance 'estimator' ("),
        "{text}"
    );
    assert!(text.contains("AlignmentEstimator.fmu) returned fmi2Error at t = 0.01 s: "));
    // Dropping after fmi2Error frees without fmi2Terminate (the FMU would complain).
}

#[test]
fn guid_mismatch_quotes_the_fmus_message() {
    let dir = scratch();
    let src = our_fmu("AlignmentEstimator");
    let original = Fmu::open(&src).unwrap().model_description().guid.clone();
    let edited = dir.path().join("EditedGuid.fmu");
    rewrite_fmu(&src, &edited, |name, data| {
        (name == "modelDescription.xml").then(|| {
            let text = String::from_utf8(data.to_vec()).unwrap();
            Some(
                text.replace(&original, "00000000-0000-0000-0000-000000000000")
                    .into_bytes(),
            )
        })
    });
    let fmu = Fmu::open(&edited).unwrap();
    let err = fmu.instantiate("estimator", quiet()).unwrap_err();
    let ImportError::Instantiate {
        path,
        instance,
        messages,
    } = &err
    else {
        panic!("expected ImportError::Instantiate, got {err:?}");
    };
    assert_eq!(path, &edited);
    assert_eq!(instance, "estimator");
    assert!(
        messages
            .iter()
            .any(|m| m.contains("00000000-0000-0000-0000-000000000000") && m.contains(&original)),
        "{messages:?}"
    );
    let text = err.to_string();
    assert!(text.contains("EditedGuid.fmu"), "{text}");
    assert!(text.contains("does not match"), "{text}");
}

#[test]
fn resource_uri_survives_spaces_and_percent_in_the_path() {
    let dir = scratch();
    let parent = dir.path().join("with space%25 and %");
    std::fs::create_dir_all(&parent).unwrap();
    let fmu = Fmu::open_in(&our_fmu("AlignmentEstimator"), &parent).unwrap();
    let uri = fmu.resource_uri();
    assert!(uri.starts_with("file:///"), "{uri}");
    assert!(!uri.ends_with('/'), "{uri}");
    assert!(!uri.contains(' '), "{uri}");
    let back = url::Url::parse(uri).unwrap().to_file_path().unwrap();
    assert_eq!(back, fmu.unpacked_dir().join("resources"));
    // The FMU itself finds its resources: it would warn otherwise.
    let (config, records) = capture(fmi2Status::Warning);
    let mut e = fmu.instantiate("estimator", config).unwrap();
    e.setup_experiment(0.0, None, None).unwrap();
    e.enter_initialization_mode().unwrap();
    e.exit_initialization_mode().unwrap();
    e.do_step(0.0, H).unwrap();
    let records = records.lock().unwrap();
    assert!(
        records
            .iter()
            .all(|r| !r.message.contains("fmuResourceLocation")),
        "{records:?}"
    );
}

#[test]
fn debug_logging_reaches_the_sink_with_name_and_category() {
    let fmu = Fmu::open(&our_fmu("AlignmentEstimator")).unwrap();
    let (mut config, records) = capture(fmi2Status::OK);
    config.debug_logging = true;
    config.categories = Some(vec!["logCalls".into()]);
    let mut e = fmu.instantiate("est%s", config).unwrap();
    e.setup_experiment(0.0, None, None).unwrap();
    let records = records.lock().unwrap();
    let call = records
        .iter()
        .find(|r| r.message.contains("fmi2SetupExperiment"))
        .unwrap_or_else(|| panic!("no logCalls record in {records:?}"));
    assert_eq!(call.instance, "est%s");
    assert_eq!(call.category, "logCalls");
    assert_eq!(call.status, fmi2Status::OK);
}

#[test]
fn unknown_variable_names_fmu_and_variable() {
    let fmu = Fmu::open(&our_fmu("RailVehicle")).unwrap();
    let err = fmu.value_reference("no_such_thing").unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("RailVehicle.fmu") && text.contains("no_such_thing"),
        "{text}"
    );
}

/// `open_shared` gives the FMU opened before from the same file while a clone of it lives (one
/// unpacked directory, one library), two independent instances of it, and a fresh one once
/// every clone is gone or the file has changed.
#[test]
fn a_shared_fmu_is_loaded_once_while_held_and_its_instances_are_independent() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("Estimator.fmu");
    std::fs::copy(our_fmu("AlignmentEstimator"), &path).unwrap();
    let a = Fmu::open_shared(&path).unwrap();
    let b = Fmu::open_shared(&path).unwrap();
    assert_eq!(a.unpacked_dir(), b.unpacked_dir());
    // `open` always loads anew.
    let c = Fmu::open(&path).unwrap();
    assert_ne!(c.unpacked_dir(), a.unpacked_dir());
    // Two instances of the shared library, fed differently, keep their own states.
    let (mut x, mut y) = (start(&a, "x"), start(&b, "y"));
    let (acc, out) = (vr(&a, "ws_acc_y"), vr(&a, "alignment_kalman"));
    for k in 0..200 {
        x.set_real(&[acc], &[0.5 * (k as f64 * 0.05).sin()])
            .unwrap();
        x.do_step(k as f64 * H, H).unwrap();
        y.do_step(k as f64 * H, H).unwrap();
    }
    let (mut ox, mut oy) = ([0.0], [0.0]);
    x.get_real(&[out], &mut ox).unwrap();
    y.get_real(&[out], &mut oy).unwrap();
    assert!(ox[0] != 0.0 && oy[0] == 0.0, "{ox:?} {oy:?}");
    let first = a.unpacked_dir().to_path_buf();
    drop((x, y, a, b));
    // Gone: the next shared open unpacks anew.
    let d = Fmu::open_shared(&path).unwrap();
    assert_ne!(d.unpacked_dir(), first);
    assert!(
        !first.exists(),
        "the last clone's drop removed its directory"
    );
    // The file rewritten (another size): another FMU, although `d` is held.
    let mut bytes = std::fs::read(&path).unwrap();
    bytes.extend_from_slice(b"\0");
    std::fs::write(&path, &bytes).unwrap();
    let e = Fmu::open_shared(&path);
    if let Ok(e) = e {
        assert_ne!(e.unpacked_dir(), d.unpacked_dir());
    }
}
