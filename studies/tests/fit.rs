//! `alignment-studies fit` end to end on a small bank (two speeds, one condition, three
//! sensors), so that the command cannot rot: the directory it writes holds a calibration and a
//! bank the estimator FMU takes, the report's figures show the fitted bank ahead of the paper's
//! filter on a held-out seed, and a fit that fails leaves nothing at `--out`.

mod common;

use alignment_studies::report::fit::{CALIBRATION, FILES, REPORT, TAPS};
use alignment_studies::study::cases::{Case, run_seed};
use fmu_estimator::learned::bank::Bank;
use orchestrator::system::Value;
use std::process::Command;

fn fit(out: &std::path::Path, more: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_alignment-studies"))
        .args(["fit", "--quiet", "--vehicle"])
        .arg(common::fmu("RailVehicle"))
        .arg("--estimator")
        .arg(common::fmu("AlignmentEstimator"))
        .args([
            "--speeds",
            "15,20",
            "--kalker-scales",
            "1",
            "--no-roll-rate",
            "--validation-seeds",
            "102,103",
        ])
        .args(more)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn a_small_fit_writes_files_the_estimator_takes_and_a_failed_one_leaves_nothing() {
    let parent = tempfile::tempdir().unwrap();
    let out = parent.path().join("ml95");
    let o = fit(&out, &["--evaluation-seeds", "3"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut written: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    let mut want: Vec<String> = FILES.iter().map(|f| f.to_string()).collect();
    want.sort();
    assert_eq!(written, want);
    // Nothing else in the parent: the staging directory was renamed, not copied.
    assert_eq!(std::fs::read_dir(parent.path()).unwrap().count(), 1);

    let bank = Bank::load(&out.join(TAPS)).unwrap();
    let mut speeds: Vec<f64> = bank.entries.iter().map(|e| e.speed).collect();
    speeds.dedup();
    assert_eq!(speeds, [15.0, 20.0]);
    // Causal and 10 m lag, three sensors, one condition: two entries per speed.
    assert_eq!(bank.entries.len(), 4);
    assert!(bank.entries.iter().all(|e| e.channels.len() == 4));

    // The report's table, and the same run done here with the files as a user gives them.
    let report = std::fs::read_to_string(out.join(REPORT)).unwrap();
    assert!(
        report.contains("learned filter, fitted bank and calibration"),
        "{report}"
    );
    let fmus = common::fmus();
    let file = |f: &str| Value::String(out.join(f).to_string_lossy().into_owned());
    let case = |estimator: Vec<(String, Value)>| Case {
        name: "fitted".into(),
        vehicle: vec![],
        estimator,
        paper: None,
    };
    let learned = run_seed(
        &fmus,
        &case(vec![
            ("estimator".into(), Value::Integer(2)),
            ("tap_file".into(), file(TAPS)),
            ("calibration_file".into(), file(CALIBRATION)),
        ]),
        3,
    )
    .unwrap();
    let paper = run_seed(
        &fmus,
        &case(vec![
            ("estimator".into(), Value::Integer(1)),
            ("calibration_file".into(), file(CALIBRATION)),
        ]),
        3,
    )
    .unwrap();
    let whole = |m: &alignment_studies::study::metrics::BandMetrics| m.get("whole").unwrap().jrel;
    // The learned filter's headline on the nominal vehicle is about 0.12, the paper's filter's
    // 0.45: a bank that did not reach the estimator, or a broken fit, fails this.
    assert!(whole(&learned) < 0.2, "{}", whole(&learned));
    assert!(
        whole(&learned) < 0.6 * whole(&paper),
        "{} vs {}",
        whole(&learned),
        whole(&paper)
    );
    let row = report
        .lines()
        .find(|l| l.starts_with("| learned filter, fitted bank"))
        .unwrap();
    assert!(
        row.contains(&format!("/ {:.2}±", whole(&learned))),
        "the report's figure is the run's: {row} vs {}",
        whole(&learned)
    );

    // A fit that fails after its checks (an evaluation seed among the validation seeds, found
    // when the fit starts) leaves no directory and no staging directory behind.
    let failed = parent.path().join("failed");
    let o = fit(&failed, &["--evaluation-seeds", "102"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!failed.exists());
    assert_eq!(std::fs::read_dir(parent.path()).unwrap().count(), 1);
    // An existing directory with files in it is refused before any work.
    let o = fit(&out, &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not empty"));
}

/// A vehicle FMU that lacks the fit's minimum interface (here the feedthrough test FMU, which
/// has none of its variables) is refused before any run, with exit 2, naming the file and every
/// variable missing, and nothing is written.
#[test]
fn a_vehicle_fmu_without_the_interface_is_refused_by_name() {
    let parent = tempfile::tempdir().unwrap();
    let out = parent.path().join("fitted");
    let vehicle = common::fmu("Feedthrough");
    let o = Command::new(env!("CARGO_BIN_EXE_alignment-studies"))
        .args(["fit", "--quiet", "--vehicle"])
        .arg(&vehicle)
        .arg("--estimator")
        .arg(common::fmu("AlignmentEstimator"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&vehicle.display().to_string()), "{err}");
    for missing in [
        "output ws_acc_y",
        "output ws_yaw_rate",
        "output frame_acc_y",
        "output alignment",
        "output distance",
        "input speed",
        "parameter track_seed",
    ] {
        assert!(err.contains(missing), "{missing}: {err}");
    }
    // The optional part is not asked for.
    assert!(!err.contains("kalker_scale"), "{err}");
    assert!(!out.exists());
    assert_eq!(std::fs::read_dir(parent.path()).unwrap().count(), 0);
}
