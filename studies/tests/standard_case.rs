//! The standard case (studies/standard.ssd through the master's SSP reader): its connections
//! and a run through the master.

mod common;

use alignment_studies::study::standard_case;
use orchestrator::master::{Algorithm, Cosimulation, RunOptions};
use orchestrator::system::Endpoint;

fn options(dir: &std::path::Path, stop: f64, step: f64, algorithm: Algorithm) -> RunOptions {
    RunOptions {
        algorithm,
        out_dir: Some(dir.to_path_buf()),
        record: Some(vec![Endpoint::new("vehicle", "ws_acc_y")]),
        ..RunOptions::new(0.0, stop, step)
    }
}

#[test]
fn the_standard_case_connects_the_roll_rate_gyro_only_when_both_fmus_have_it() {
    let linked = |vehicle: &str| -> Vec<String> {
        standard_case::system(&common::fmu(vehicle), &common::fmu("AlignmentEstimator"))
            .unwrap()
            .connections
            .iter()
            .map(|c| c.to.variable.clone())
            .collect()
    };
    let full = linked("RailVehicle");
    assert!(full.contains(&"ws_roll_rate".to_string()), "{full:?}");
    assert_eq!(full.len(), 5);
    // Any FMU without ws_roll_rate in the vehicle's place: the paper's three sensors and speed.
    let without = linked("Feedthrough");
    assert_eq!(
        without,
        ["ws_acc_y", "ws_yaw_rate", "frame_acc_y", "speed"],
        "{without:?}"
    );
}

#[test]
fn the_standard_case_runs_through_the_master() {
    let cosim = Cosimulation::load(
        standard_case::system(
            &common::fmu("RailVehicle"),
            &common::fmu("AlignmentEstimator"),
        )
        .unwrap(),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut opts = options(dir.path(), 1.0, 1e-3, Algorithm::GaussSeidel);
    opts.record = None;
    let summary = cosim.run(&opts).unwrap();
    assert_eq!(summary.rows, 1001);
    let text = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert_eq!(header[0], "time");
    for col in [
        "vehicle.ws_acc_y",
        "vehicle.alignment",
        "estimator.alignment",
        "estimator.alignment_std",
    ] {
        assert!(header.contains(&col), "{col} missing from {header:?}");
    }
    // The estimator received the vehicle's speed through the forward_speed connection.
    let speed_col = header
        .iter()
        .position(|c| *c == "vehicle.forward_speed")
        .unwrap();
    let last: Vec<f64> = text
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|f| f.parse().unwrap())
        .collect();
    assert_eq!(last[speed_col], 20.0);
    let dist = header
        .iter()
        .position(|c| *c == "estimator.distance")
        .unwrap();
    assert!(
        (last[dist] - 20.0).abs() < 1e-9,
        "estimator distance {}",
        last[dist]
    );
}
