//! Issue 26: `alignment-studies` exits by the kind of its error, not by its text
//! (`studies/src/error.rs`, docs/studies.md): a setting the estimator refuses and an unreadable
//! recording are bad input (2), an FMU that cannot be loaded is bad input (2), a run in which
//! the vehicle derails is a failed run (3), each with its message on one line (the derailment's
//! the master's own: the step, the time and the vehicle's words).

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn studies() -> Command {
    Command::new(env!("CARGO_BIN_EXE_alignment-studies"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The error line: `error: ...`, and no panic.
fn error_line(o: &Output) -> String {
    let err = stderr(o);
    assert!(!err.contains("panicked"), "{err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("error: "))
        .unwrap_or_else(|| panic!("no error line: {err}"));
    line.to_string()
}

/// A recording of 500 rows at `step` s (the third row `uneven` s late), 20 m/s.
fn recording(dir: &Path, uneven: f64) -> PathBuf {
    let mut text = String::from("time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n");
    for k in 0..500 {
        let t = k as f64 * 1e-3 + if k >= 2 { uneven } else { 0.0 };
        text.push_str(&format!("{t},20,0.01,0.001,0.005\n"));
    }
    let p = dir.join("rec.csv");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn a_setting_the_estimator_refuses_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path(), 0.0);
    let out = dir.path().join("smoothed.csv");
    for (set, message) in [
        ("nope=1", "error: the estimator has no variable 'nope'"),
        (
            "design_speed=-1",
            "error: parameter 'design_speed' = -1 must be 0 (follow the speed input) or a positive speed",
        ),
        (
            "discretization=7",
            "error: parameter 'discretization' = 7: use 1 (the paper's second-order Taylor scheme) or 2 (exact, matrix exponential)",
        ),
    ] {
        let o = studies()
            .arg("smooth")
            .arg(&rec)
            .arg("--out")
            .arg(&out)
            .args(["--set", set])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{set}: {}", stderr(&o));
        assert_eq!(error_line(&o), message);
        assert!(!out.exists());
    }
}

#[test]
fn an_unreadable_recording_is_bad_input_named_by_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path(), 5e-4);
    let out = dir.path().join("smoothed.csv");
    let o = studies()
        .arg("smooth")
        .arg(&rec)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let line = error_line(&o);
    assert!(
        line.starts_with(&format!(
            "error: {}: the time step changes at line 4 (",
            rec.display()
        )) && line.ends_with("s instead of 0.001 s): the filter needs a constant step"),
        "{line}"
    );
    assert!(!out.exists());
}

#[test]
fn an_fmu_that_cannot_be_loaded_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let fake = dir.path().join("RailVehicle.fmu");
    std::fs::write(&fake, "not a zip archive").unwrap();
    let o = studies()
        .args(["run", "--stop", "1", "--no-record", "--vehicle"])
        .arg(&fake)
        .arg("--estimator")
        .arg(common::fmu("AlignmentEstimator"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let line = error_line(&o);
    assert!(
        line.contains(&fake.display().to_string()) && line.contains("not a valid FMU archive"),
        "{line}"
    );
}

/// The ML95 with its Kalker coefficients halved hunts at 30 m/s until its wheelset climbs the
/// rail (`fmu_vehicle::fmu::DERAILMENT_MARGIN`): the vehicle FMU stops the run with fmi2Error.
#[test]
fn a_derailment_is_a_failed_run_with_the_vehicles_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = studies()
        .args(["run", "--stop", "20", "--out"])
        .arg(&out)
        .args([
            "--set",
            "vehicle.kalker_scale=0.5",
            "--set",
            "vehicle.speed=30",
            "--vehicle",
        ])
        .arg(common::fmu("RailVehicle"))
        .arg("--estimator")
        .arg(common::fmu("AlignmentEstimator"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let line = error_line(&o);
    assert!(
        line.starts_with("error: fmi2DoStep of instance 'vehicle' (")
            && line.contains(": derailed: the leading wheelset is ")
            && line.contains("the vehicle is unstable at 30 m/s with these parameters (hunting)"),
        "{line}"
    );
    // The rows until then are kept, as for any failed run; no metrics of a broken run.
    assert!(
        stderr(&o).contains("the results recorded until then are in"),
        "{}",
        stderr(&o)
    );
    assert!(out.join("results.csv").exists());
    assert!(!out.join("metrics.json").exists());
}
