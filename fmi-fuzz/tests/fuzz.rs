//! The fuzzer in CI: a deterministic sample of hostile call sequences against our two FMUs,
//! and the fuzzer's own detection checked against an independent C FMU, correct and with one
//! deliberate bug at a time.

mod common;

use common::*;
use std::process::Output;

/// The vehicle's initialization synthesizes track irregularities (tens of milliseconds);
/// most of its instances skip that (see docs/reliability.md).
const VEHICLE_PRESETS: [&str; 4] = [
    "--preset",
    "lateral_irregularity=false",
    "--preset",
    "vertical_irregularity=false",
];

/// Checks the summary of one FMU: all sequences run, none failed, and every one of the 34
/// functions was called.
fn assert_clean(out: &Output, fmu: &str, sequences: u64) {
    let t = text(out);
    assert!(out.status.success(), "the fuzzer failed on {fmu}:\n{t}");
    let summary = t
        .lines()
        .find(|l| l.contains(fmu) && l.contains("sequences (seeds"))
        .unwrap_or_else(|| panic!("no summary for {fmu}:\n{t}"));
    assert!(
        summary.contains(&format!(": {sequences} sequences"))
            && summary.ends_with(" 0 failing sequence(s)"),
        "{summary}"
    );
    let table: Vec<&str> = t
        .lines()
        .skip_while(|l| !l.contains(fmu) || !l.contains("sequences (seeds"))
        .skip(2)
        .take(34)
        .collect();
    assert_eq!(table.len(), 34, "{t}");
    for row in table {
        let cells: Vec<&str> = row.split_whitespace().collect();
        assert!(cells[0].starts_with("fmi2"), "{row}");
        let calls: u64 = cells[1].parse().unwrap();
        assert!(calls > 0, "{} was never called:\n{t}", cells[0]);
    }
}

#[test]
fn our_fmus_survive_2000_hostile_sequences_each() {
    let est = fmu("AlignmentEstimator");
    let out = fuzzer(&[
        "--fmu",
        est.to_str().unwrap(),
        "--sequences",
        "2000",
        "--seed",
        "700000",
        "--batch",
        "1000",
        "--timeout",
        "60",
    ]);
    assert_clean(&out, "AlignmentEstimator.fmu", 2000);
    let veh = fmu("RailVehicle");
    let mut args = vec![
        "--fmu",
        veh.to_str().unwrap(),
        "--sequences",
        "2000",
        "--seed",
        "700000",
        "--batch",
        "1000",
        "--timeout",
        "60",
    ];
    args.extend(VEHICLE_PRESETS);
    let out = fuzzer(&args);
    assert_clean(&out, "RailVehicle.fmu", 2000);
}

#[test]
fn a_correct_independent_fmu_raises_no_false_alarm() {
    let f = strict_fmu(None);
    let out = fuzzer(&[
        "--fmu",
        f.to_str().unwrap(),
        "--sequences",
        "3000",
        "--seed",
        "1",
    ]);
    assert_clean(&out, "StrictFmu.fmu", 3000);
}

/// The first failing seed the fuzzer names.
fn failing_seed(t: &str) -> u64 {
    let line = t
        .lines()
        .find_map(|l| l.strip_prefix("FAILED: seeds "))
        .unwrap_or_else(|| panic!("no failing seed reported:\n{t}"));
    line.split(',').next().unwrap().trim().parse().unwrap()
}

#[test]
fn a_segfault_is_caught_with_its_seed_and_the_call_that_crashed() {
    let f = strict_fmu(Some("FAULT_SEGV"));
    let path = f.to_str().unwrap();
    let out = fuzzer(&[
        "--fmu",
        path,
        "--sequences",
        "400",
        "--seed",
        "1",
        "--batch",
        "100",
    ]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(
        t.contains("crash: the worker process killed by signal 11 (SIGSEGV)"),
        "{t}"
    );
    // After each crash the rest of its batch runs in a new worker: all 400 are accounted for.
    assert!(t.contains(": 400 sequences (seeds 1..=400)"), "{t}");
    // The replay ends with the call that crashed: fmi2GetReal with a NULL value array.
    let seed = failing_seed(&t);
    let block = t.split(&format!("--- seed {seed} ---")).nth(1).unwrap();
    let last_call = block
        .lines()
        .rfind(|l| l.trim_start().starts_with('['))
        .unwrap();
    assert!(
        last_call.contains("fmi2GetReal(")
            && last_call.contains("value=NULL")
            && !last_call.contains("->"),
        "{last_call}"
    );
    // The seed reproduces the crash on its own.
    let again = fuzzer(&[
        "worker",
        "--fmu",
        path,
        "--first",
        &seed.to_string(),
        "--count",
        "1",
    ]);
    assert_eq!(again.status.code(), None, "seed {seed} did not crash again");
}

#[test]
fn a_hang_is_caught_with_the_call_that_hangs() {
    let f = strict_fmu(Some("FAULT_HANG"));
    let out = fuzzer(&[
        "--fmu",
        f.to_str().unwrap(),
        "--sequences",
        "300",
        "--seed",
        "1",
        "--batch",
        "300",
        "--timeout",
        "3",
        "--jobs",
        "1",
        "--max-failures",
        "1",
    ]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(
        t.contains("hang: sequence ") && t.contains(" did not finish within 3 s"),
        "{t}"
    );
    assert!(t.contains("replay killed after 3 s"), "{t}");
    let seed = failing_seed(&t);
    let block = t.split(&format!("--- seed {seed} ---")).nth(1).unwrap();
    let last_call = block
        .lines()
        .rfind(|l| l.trim_start().starts_with('['))
        .unwrap();
    assert!(last_call.contains("fmi2DoStep("), "{last_call}");
    assert!(t.contains("stopped after 1 failing sequence(s)"), "{t}");
}

#[test]
fn an_illegal_call_that_succeeds_is_reported() {
    let f = strict_fmu(Some("FAULT_LENIENT"));
    let out = fuzzer(&[
        "--fmu",
        f.to_str().unwrap(),
        "--sequences",
        "300",
        "--seed",
        "1",
    ]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(
        t.contains("fmi2DoStep returned OK but must return Error: illegal in {instantiated}"),
        "{t}"
    );
}

#[test]
fn an_error_without_a_logged_message_is_reported() {
    let f = strict_fmu(Some("FAULT_SILENT"));
    let out = fuzzer(&[
        "--fmu",
        f.to_str().unwrap(),
        "--sequences",
        "100",
        "--seed",
        "1",
    ]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(
        t.contains("returned Error but logged no error message"),
        "{t}"
    );
}
