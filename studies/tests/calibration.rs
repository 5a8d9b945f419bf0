//! The estimator's shipped calibration file is reproducible: running the identification,
//! calibration and tuning of `alignment-studies calibrate` again, with the packaged FMUs,
//! gives the committed file to the byte.

mod common;

use alignment_studies::study::{calibrate, identify, runs};

#[test]
fn regenerating_the_calibration_reproduces_the_committed_file() {
    let fmus = common::fmus();
    let vehicle = fmu_vehicle::params::VehicleParams::ml95();
    let seed = 101; // the CLI's CALIBRATION_SEED
    let id = identify::identify(&fmus, &vehicle, seed, runs::STOP, runs::STEP).unwrap();
    let cal = calibrate::calibrate(&fmus, &id.params, seed, runs::STOP, runs::STEP).unwrap();
    let cal = calibrate::tune(&fmus, &cal, runs::STOP).unwrap();
    let cal = calibrate::tune_prior(&fmus, &cal).unwrap();
    let text = calibrate::to_toml(&cal, seed, calibrate::PROVENANCE);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fmu-estimator/resources/calibration.toml");
    let committed = std::fs::read_to_string(&path).unwrap();
    assert!(
        text == committed,
        "{} differs from a fresh `alignment-studies calibrate`; regenerate it (and rebuild the FMU) if the vehicle or the procedure changed",
        path.display()
    );
}

/// `alignment-studies calibrate --set vehicle.vehicle=manchester.toml` then the studies with
/// `--set estimator.calibration_file=...`: the calibration carries the other vehicle's fixed
/// parameters, and on that vehicle (held-out seed) the filter made for it beats the shipped one
/// (made for ML95).
#[test]
fn a_filter_calibrated_for_another_vehicle_beats_the_shipped_one_on_it() {
    use alignment_studies::study::cases;
    let mut fmus = common::fmus();
    fmus.set("vehicle", "vehicle", "manchester.toml").unwrap();
    let e = fmus.set("vehicle", "track_seed", "3").unwrap_err();
    assert_eq!(e.exit_code(), 2, "bad input: {e}");
    assert!(e.to_string().contains("set by the studies"), "{e}");
    let vehicle = fmus.vehicle_params().unwrap();
    let manchester = fmu_vehicle::params::VehicleParams::manchester();
    assert_eq!(vehicle.wheelset.mass, manchester.wheelset.mass);

    let seed = 101;
    let id = identify::identify(&fmus, &vehicle, seed, runs::STOP, runs::STEP).unwrap();
    let cal = calibrate::calibrate(&fmus, &id.params, seed, runs::STOP, runs::STEP).unwrap();
    let cal = calibrate::tune(&fmus, &cal, runs::STOP).unwrap();
    let cal = calibrate::tune_prior(&fmus, &cal).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("manchester.toml");
    std::fs::write(&path, calibrate::to_toml(&cal, seed, calibrate::PROVENANCE)).unwrap();
    let p = fmu_estimator::calibration::file_parameters(&path).unwrap();
    assert_eq!(p["m"], manchester.wheelset.mass);
    assert_eq!(p["alpha"], manchester.wheelset.conicity);

    let mut matched = fmus.clone();
    matched
        .set("estimator", "calibration_file", path.to_str().unwrap())
        .unwrap();
    // The file's parameters are set too, since the FMU reads only Q and R from it.
    assert_eq!(
        matched.estimator_number("m"),
        Some(manchester.wheelset.mass)
    );
    let held_out = 1;
    let own = cases::run_seed(&matched, &cases::standard(), held_out).unwrap();
    let shipped = cases::run_seed(&fmus, &cases::standard(), held_out).unwrap();
    assert!(
        own.whole.jrel < 0.8 * shipped.whole.jrel,
        "whole Jrel with its own calibration {}, with ML95's {}",
        own.whole.jrel,
        shipped.whole.jrel
    );
    // The study's settings come after the user's: the robustness case's conicity (0.9 times
    // the file's) must reach the filter, not the file's own alpha set with it.
    let alpha = matched.estimator_number("alpha").unwrap();
    assert_eq!(alpha, manchester.wheelset.conicity);
    let conicity = cases::robustness(alpha)
        .into_iter()
        .find(|c| c.name.starts_with("conicity -10 %"))
        .unwrap();
    let lowered = cases::run_seed(&matched, &conicity, held_out).unwrap();
    assert!(
        (lowered.whole.jrel - own.whole.jrel).abs() > 1e-6,
        "the conicity case gave the standard case's {}",
        own.whole.jrel
    );
    // Settings the studies control, or that would undo them, are refused.
    for name in ["track_file", "speed", "kalker_scale"] {
        assert!(fmus.clone().set("vehicle", name, "1").is_err(), "{name}");
    }
}
