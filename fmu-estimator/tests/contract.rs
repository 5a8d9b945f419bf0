//! The tap bank's contract through the FMU's initialization (`fmi2ExitInitializationMode`): the
//! shipped banks pass with the shipped FMU's settings; a bank whose contract states another
//! runtime constant is refused naming it; a bank used with another Kalman channel than it was
//! fitted with fails, unless `allow_other_kalman` asks for approximate use.
//!
//! Each case runs twice: through [`Instance`] (the export layer's state machine, whose status
//! `fmi2ExitInitializationMode` returns) and through the model's own `exit_initialization`,
//! which that calls, for the message the logger would get.

use fmi_abi::instance::Instance;
use fmi_abi::{InstantiateContext, Logger, Model, Values};
use fmu_estimator::Estimator;
use fmu_estimator::fmu::{VARIABLES, vr};
use fmu_estimator::learned::bank::Bank;
use fmu_estimator::learned::contract::Contract;
use std::path::{Path, PathBuf};

/// The FMU's resources as packaged: the shipped calibration and banks.
fn resources() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("resources")
}

/// A fresh scratch directory for this test's files.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("contract-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Settings of one initialization.
#[derive(Default, Clone)]
struct Set {
    reals: Vec<(u32, f64)>,
    integers: Vec<(u32, i32)>,
    booleans: Vec<(u32, bool)>,
    strings: Vec<(u32, String)>,
}

/// Initializes the FMU with `set` through the export layer's instance: `Ok` or the error status.
fn through_instance(set: &Set) -> Result<(), fmi_abi::types::fmi2Status> {
    let ctx = InstantiateContext {
        instance_name: "contract".into(),
        resources: Some(resources()),
    };
    let mut inst = Instance::<Estimator>::new(&ctx, Logger::silent())
        .map_err(|(_, e)| e)
        .unwrap();
    for (r, x) in &set.reals {
        inst.set_real(&[*r], &[*x]).unwrap();
    }
    for (r, x) in &set.integers {
        inst.set_integer(&[*r], &[*x]).unwrap();
    }
    for (r, x) in &set.booleans {
        inst.set_boolean(&[*r], &[*x]).unwrap();
    }
    for (r, x) in &set.strings {
        inst.set_string(&[*r], std::slice::from_ref(x)).unwrap();
    }
    inst.setup_experiment(0.0, None).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode()
}

/// The model's initialization, as `fmi2ExitInitializationMode` calls it: its message.
fn message(set: &Set) -> Result<(), String> {
    let ctx = InstantiateContext {
        instance_name: "contract".into(),
        resources: Some(resources()),
    };
    let log = Logger::silent();
    let mut e = Estimator::instantiate(&ctx, &log).unwrap();
    let mut v = Values::from_table(VARIABLES);
    for (r, x) in &set.reals {
        v.real[*r as usize] = *x;
    }
    for (r, x) in &set.integers {
        v.integer[*r as usize] = *x;
    }
    for (r, x) in &set.booleans {
        v.boolean[*r as usize] = *x;
    }
    for (r, x) in &set.strings {
        v.string[*r as usize] = x.clone();
    }
    e.calculate_initial(&mut v);
    e.exit_initialization(&mut v, &log)
}

/// Both ways: the instance's status agrees with the model's result, which is returned.
fn initialize(set: &Set) -> Result<(), String> {
    let m = message(set);
    assert_eq!(through_instance(set).is_ok(), m.is_ok(), "{m:?}");
    m
}

fn with_tap_file(path: &Path) -> Set {
    Set {
        strings: vec![(vr::TAP_FILE, path.to_str().unwrap().into())],
        ..Set::default()
    }
}

#[test]
fn the_shipped_banks_pass_with_the_shipped_settings() {
    for name in fmu_estimator::learned::SHIPPED {
        for roll in [false, true] {
            let set = Set {
                booleans: vec![(vr::USE_ROLL_RATE, roll)],
                strings: vec![(vr::TAP_FILE, name.into())],
                ..Set::default()
            };
            initialize(&set).unwrap_or_else(|e| panic!("{name}, roll rate {roll}: {e}"));
        }
    }
}

/// Oracle: the contract the shipped FMU computes for a bank is the one the bank carries, field
/// by field, so the shipped banks were fitted with this build's constants and Kalman channel.
#[test]
fn the_shipped_banks_carry_this_builds_contract() {
    let values = fmu_estimator::offline::settings(&[]).unwrap();
    let (config, _) = fmu_estimator::offline::config(&values, None).unwrap();
    for name in fmu_estimator::learned::SHIPPED {
        let bank = Bank::load(&resources().join(name)).unwrap();
        let here = Contract::expected(
            &config,
            bank.grid,
            bank.kalman_highpass,
            bank.kalman_shelf,
            bank.contact.as_ref().map(|c| c.band),
            bank.provenance.sample_step,
        );
        assert_eq!(bank.contract, here, "{name}");
    }
}

#[test]
fn a_bank_made_for_another_runtime_is_refused_naming_the_constant() {
    let dir = scratch("runtime");
    let bank = Bank::load(&resources().join("learned.taps")).unwrap();
    type Change = fn(&mut Contract);
    let cases: [(&str, &str, Change); 7] = [
        ("TAP_SPEED_POWER", "[2.0, 1.0, 1.5, 1.0, 0.0]", |c| {
            c.tap_speed_power[0] = 2.0
        }),
        ("EDGE", "1e-6", |c| c.grid_edge = 1e-6),
        ("CONTACT_SPEED_POWER", "[1.0, 1.0, 2.0]", |c| {
            c.contact_speed_power[0] = 1
        }),
        ("MIN_SPEED", "0.5", |c| c.contact_min_speed = 0.5),
        ("MIN_MODEL_ERROR", "0.01", |c| {
            c.contact_min_model_error = 0.01
        }),
        ("high-pass design", "0.5", |c| {
            c.kalman_highpass_design[0] = 0.5
        }),
        ("band-pass design", "0.25", |c| {
            c.contact_band_design.as_mut().unwrap()[1][0] = 0.25
        }),
    ];
    for (k, (name, shown, change)) in cases.iter().enumerate() {
        let mut other = bank.clone();
        change(&mut other.contract);
        let path = dir.join(format!("{k}.taps"));
        std::fs::write(&path, other.to_bytes()).unwrap();
        let e = initialize(&with_tap_file(&path)).unwrap_err();
        assert!(
            e.contains(name) && e.contains(shown) && e.contains("another build"),
            "{name}: {e}"
        );
        // A runtime constant is never a matter of approximate use.
        let mut allowed = with_tap_file(&path);
        allowed.booleans.push((vr::ALLOW_OTHER_KALMAN, true));
        assert!(initialize(&allowed).is_err(), "{name}");
    }
    // The unchanged bank, written the same way, passes: the file itself is not the cause.
    let path = dir.join("same.taps");
    std::fs::write(&path, bank.to_bytes()).unwrap();
    initialize(&with_tap_file(&path)).unwrap();
    std::fs::remove_dir_all(dir).unwrap();
}

/// Instances share a bank parsed from the same bytes (`fmu_estimator::parsed`): one rewritten
/// in place between two initializations, even to the same length, is read again.
#[test]
fn a_bank_rewritten_between_two_initializations_is_read_again() {
    let dir = scratch("rewritten");
    let bank = Bank::load(&resources().join("learned-nominal.taps")).unwrap();
    let mut other = bank.clone();
    other.contract.contact_min_speed = 0.5;
    let (good, bad) = (bank.to_bytes(), other.to_bytes());
    assert_eq!(
        good.len(),
        bad.len(),
        "the same length: a size check could not tell them"
    );
    let path = dir.join("bank.taps");
    for (bytes, passes) in [(&good, true), (&good, true), (&bad, false), (&good, true)] {
        std::fs::write(&path, bytes).unwrap();
        let e = initialize(&with_tap_file(&path));
        assert_eq!(e.is_ok(), passes, "{e:?}");
        if !passes {
            assert!(e.unwrap_err().contains("another build"));
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_bank_used_with_another_kalman_channel_fails_initialization() {
    let dir = scratch("kalman");
    // The shipped calibration with another Q[7,7]: R the same.
    let shipped = std::fs::read_to_string(resources().join("calibration.toml")).unwrap();
    let other = shipped.replacen("1.0889672112641672e-6]", "2e-6]", 1);
    assert_ne!(other, shipped);
    let calibration = dir.join("other-q.toml");
    std::fs::write(&calibration, other).unwrap();
    let cases: Vec<(Set, &[&str])> = vec![
        (
            Set {
                reals: vec![(vr::M, 1500.0)],
                ..Set::default()
            },
            &["F (", "m = 1500 (default 1109)"],
        ),
        (
            Set {
                strings: vec![(vr::CALIBRATION_FILE, calibration.to_str().unwrap().into())],
                ..Set::default()
            },
            &["Q (", "calibration_file = '"],
        ),
        (
            Set {
                booleans: vec![(vr::USE_CALIBRATION_FILE, false)],
                ..Set::default()
            },
            &["Q (", "R (", "use_calibration_file = false (default true)"],
        ),
        (
            Set {
                integers: vec![(vr::ALIGNMENT_MODEL, 2)],
                reals: vec![(vr::PRIOR_SIGMA_XI, 0.01)],
                ..Set::default()
            },
            &["8 here", "alignment_model = 2 (default 1)"],
        ),
        (
            Set {
                reals: vec![(vr::DESIGN_SPEED, 20.0)],
                ..Set::default()
            },
            &["design_speed 0 m/s in the bank's, 20 here"],
        ),
        (
            Set {
                reals: vec![(vr::MIN_SPEED, 2.0)],
                ..Set::default()
            },
            &["min_speed 0.5 m/s in the bank's, 2 here"],
        ),
    ];
    for (set, named) in &cases {
        let e = initialize(set).unwrap_err();
        assert!(e.contains("another Kalman channel"), "{e}");
        for n in *named {
            assert!(e.contains(n), "'{n}' not in: {e}");
        }
        let mut allowed = set.clone();
        allowed.booleans.push((vr::ALLOW_OTHER_KALMAN, true));
        initialize(&allowed).unwrap();
    }
    // The gain and the initial covariance are no part of the contract (the fit's time-varying
    // channel equals the FMU's steady-state one after the start-up), and the paper's filter
    // alone reads no bank.
    for set in [
        Set {
            integers: vec![(vr::GAIN, 1)],
            reals: vec![(vr::P0_XI, 0.02)],
            ..Set::default()
        },
        Set {
            integers: vec![(vr::ESTIMATOR, 1)],
            reals: vec![(vr::M, 1500.0)],
            ..Set::default()
        },
    ] {
        initialize(&set).unwrap();
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A bank of the format before the contract says why it is refused.
#[test]
fn a_bank_without_a_contract_is_refused_with_the_reason() {
    let dir = scratch("format2");
    let bytes = std::fs::read(resources().join("learned-nominal.taps")).unwrap();
    let nl = bytes.iter().position(|b| *b == b'\n').unwrap();
    let first = String::from_utf8(bytes[..nl].to_vec()).unwrap();
    let shipped = format!("learned-taps {} ", fmu_estimator::learned::bank::FORMAT);
    assert!(first.starts_with(&shipped), "{first}");
    let mut old = first.replacen(&shipped, "learned-taps 2 ", 1).into_bytes();
    old.extend_from_slice(&bytes[nl..]);
    let path = dir.join("old.taps");
    std::fs::write(&path, old).unwrap();
    let e = initialize(&with_tap_file(&path)).unwrap_err();
    assert!(e.contains("format 2") && e.contains("no contract"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}
