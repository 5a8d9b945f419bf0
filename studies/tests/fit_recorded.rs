//! `alignment-studies fit --recordings` end to end on passes of the vehicle FMU with odometry
//! errors of their own (a start offset and a distance scale, as a real train's): the placement
//! recovers them, the bank fitted from the passes beats the paper's filter on a held-out track,
//! and bad input (a reference with a gap, passes that do not overlap the reference) stops with
//! the file named and nothing written.

mod common;

use alignment_studies::study::cases::{Case, run_seed};
use alignment_studies::study::learned::recorded::synthetic::{write_pass, write_reference};
use alignment_studies::study::records::{Record, record};
use alignment_studies::study::runs::seeded;
use fmu_estimator::learned::bank::Bank;
use orchestrator::system::Value;
use std::process::Command;

/// A run of `seconds` at 20 m/s on track `seed` with sensor noise `noise`.
fn run(seed: u32, noise: i32, seconds: f64) -> Record {
    let mut s = seeded(seed);
    s[1].1 = Value::Integer(noise);
    record(&common::fmus(), s, seconds, None).unwrap()
}

fn fit(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_alignment-studies"))
        .args(["fit", "--quiet"])
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn a_bank_is_fitted_from_passes_placed_on_a_reference() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n);
    // The line: track seed 101 (training), 2.6 km; two passes with their own noise.
    let truth = run(101, 5001, 130.0);
    write_reference(&truth, None, &p("reference.csv")).unwrap();
    let odometry = [(12.3, 1.004), (-7.9, 0.997)];
    for (i, (offset, scale)) in odometry.iter().enumerate() {
        let pass = run(101, 6000 + i as i32, 120.0);
        write_pass(&pass, *offset, *scale, &p(&format!("pass{i}.csv"))).unwrap();
    }
    let out = p("fitted");
    let o = fit(&[
        "--recordings".as_ref(),
        p("pass0.csv").as_os_str(),
        p("pass1.csv").as_os_str(),
        "--reference".as_ref(),
        p("reference.csv").as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The placements: reference position = recorded start + offset + scale x odometry from
    // the start, and the recorded odometry is offset + scale x the true position.
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for (i, (offset, scale)) in odometry.iter().enumerate() {
        let row = report
            .lines()
            .find(|l| l.starts_with("| ") && l.contains(&format!("pass{i}.csv")))
            .unwrap();
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let (found_offset, found_scale): (f64, f64) =
            (cells[2].parse().unwrap(), cells[3].parse().unwrap());
        // Recorded start `offset` at true 0, recorded steps `scale` times the true: the true
        // position is the recorded start - offset + (odometry from the start) / scale.
        let want_offset = -offset;
        let want_scale = (1.0 / scale - 1.0) * 100.0;
        assert!(
            (found_offset - want_offset).abs() < 0.5,
            "{row}: offset {want_offset}"
        );
        assert!(
            (found_scale - want_scale).abs() < 0.02,
            "{row}: scale {want_scale} %"
        );
    }
    let bank = Bank::load(&out.join("fitted.taps")).unwrap();
    // Passes at 20 m/s: the 20 m/s taps, held over 18.75-21.25 m/s (no neighbouring speed).
    let mut speeds: Vec<f64> = bank.entries.iter().map(|e| e.speed).collect();
    speeds.dedup();
    assert_eq!(speeds, [18.75, 20.0, 21.25]);
    let taps = |v: f64| -> Vec<Vec<f64>> {
        bank.entries
            .iter()
            .filter(|e| e.speed == v)
            .map(|e| e.windows.last().unwrap().taps.clone())
            .collect()
    };
    assert_eq!(taps(18.75), taps(20.0));
    assert_eq!(taps(21.25), taps(20.0));
    // The provenance names the recordings, no seeds, and the training parts' length: 70 % of
    // two 2.4 km passes, less what lies past the reference's end.
    let prov = &bank.provenance;
    assert!(
        prov.vehicle.contains("pass0.csv") && prov.vehicle.contains("recordings"),
        "{}",
        prov.vehicle
    );
    assert!(prov.validation_seeds.is_empty());
    assert!(prov.contact_validation_seeds.is_empty());
    assert!(
        (2.0 * 1500.0..2.0 * 1900.0).contains(&prov.training_distance),
        "{}",
        prov.training_distance
    );

    // The bank on a held-out track, against the paper's filter.
    let fmus = common::fmus();
    let case = |estimator: Vec<(String, Value)>| Case {
        name: "recorded".into(),
        vehicle: vec![],
        estimator,
        paper: None,
    };
    let tap_file = Value::String(out.join("fitted.taps").to_string_lossy().into_owned());
    let learned = run_seed(
        &fmus,
        &case(vec![
            ("estimator".into(), Value::Integer(2)),
            ("tap_file".into(), tap_file),
        ]),
        3,
    )
    .unwrap();
    let paper = run_seed(
        &fmus,
        &case(vec![("estimator".into(), Value::Integer(1))]),
        3,
    )
    .unwrap();
    let whole = |m: &alignment_studies::study::metrics::BandMetrics| m.get("whole").unwrap().jrel;
    assert!(
        whole(&learned) < 0.6 * whole(&paper),
        "{} vs {}",
        whole(&learned),
        whole(&paper)
    );

    // Refused with exit code 2 and nothing written: the message for the checks.
    let refused = |reference: &str, out: &str| -> String {
        let o = fit(&[
            "--recordings".as_ref(),
            p("pass0.csv").as_os_str(),
            "--reference".as_ref(),
            p(reference).as_os_str(),
            "--out".as_ref(),
            p(out).as_os_str(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(!p(out).exists());
        err
    };
    // A reference with a gap is named with its line.
    write_reference(&truth, Some((1000.0, 1010.0)), &p("gap.csv")).unwrap();
    let err = refused("gap.csv", "gap-out");
    assert!(
        err.contains("gap.csv") && err.contains("gap of") && err.contains("line"),
        "{err}"
    );
    // Passes of another line: no overlap found, named.
    let other = run(7, 5001, 130.0);
    write_reference(&other, None, &p("other.csv")).unwrap();
    let err = refused("other.csv", "other-out");
    assert!(
        err.contains("pass0.csv") && err.contains("no overlap"),
        "{err}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".fit-"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}
