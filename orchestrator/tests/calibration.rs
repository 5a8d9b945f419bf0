//! The estimator's shipped calibration file is reproducible: running the identification,
//! calibration and tuning of `orchestrator study calibrate` again, with the packaged FMUs,
//! gives the committed file to the byte.

mod common;

use orchestrator::study::{calibrate, identify, runs};

#[test]
fn regenerating_the_calibration_reproduces_the_committed_file() {
    let fmus = runs::Fmus {
        vehicle: common::fmu("RailVehicle"),
        estimator: common::fmu("AlignmentEstimator"),
    };
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
        "{} differs from a fresh `orchestrator study calibrate`; regenerate it (and rebuild the FMU) if the vehicle or the procedure changed",
        path.display()
    );
}
