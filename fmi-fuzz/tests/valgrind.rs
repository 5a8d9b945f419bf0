//! Memory: instantiate / initialize / step / FMU-state / free cycles of each FMU under
//! valgrind's memcheck, with no definitely or indirectly lost byte and no invalid access.
//! A C FMU that forgets to free its FMU states shows that the check catches a leak.

mod common;

use common::*;
use std::process::{Command, Output};

fn valgrind(args: &[&str]) -> Output {
    let found = Command::new("valgrind").arg("--version").output();
    assert!(
        found.as_ref().is_ok_and(|o| o.status.success()),
        "valgrind is not on PATH: this test needs it (Debian/Ubuntu: apt-get install valgrind)"
    );
    Command::new("valgrind")
        .args([
            "--tool=memcheck",
            "--error-exitcode=99",
            "--leak-check=full",
            "--show-leak-kinds=definite,indirect",
            "--errors-for-leak-kinds=definite,indirect",
            "--num-callers=40",
        ])
        .arg(env!("CARGO_BIN_EXE_fmi-fuzz"))
        .args(args)
        .output()
        .expect("cannot run valgrind")
}

/// Bytes valgrind reports as `kind` lost ("definitely", "indirectly"); 0 when it says all
/// heap blocks were freed.
fn lost(stderr: &str, kind: &str) -> u64 {
    if stderr.contains("All heap blocks were freed -- no leaks are possible") {
        return 0;
    }
    let line = stderr
        .lines()
        .find(|l| l.contains(&format!("{kind} lost:")))
        .unwrap_or_else(|| panic!("no '{kind} lost' line in valgrind's output:\n{stderr}"));
    let n = line.split(&format!("{kind} lost:")).nth(1).unwrap();
    n.split_whitespace()
        .next()
        .unwrap()
        .replace(',', "")
        .parse()
        .unwrap()
}

fn clean_cycles(fmu_path: &str, presets: &[&str]) {
    let mut args = vec!["cycles", "--fmu", fmu_path, "--cycles", "20"];
    args.extend(presets);
    let out = valgrind(&args);
    let err = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "valgrind or the cycles failed:\n{stdout}\n{err}"
    );
    assert!(stdout.contains(": 20 cycles"), "{stdout}");
    assert!(err.contains("ERROR SUMMARY: 0 errors"), "{err}");
    assert_eq!(lost(&err, "definitely"), 0, "{err}");
    assert_eq!(lost(&err, "indirectly"), 0, "{err}");
    // The summary, for the log.
    for l in err.lines().filter(|l| {
        l.contains("lost:") || l.contains("ERROR SUMMARY") || l.contains("in use at exit")
    }) {
        eprintln!("{fmu_path}: {l}");
    }
}

#[test]
fn twenty_estimator_cycles_leak_nothing_under_valgrind() {
    clean_cycles(fmu("AlignmentEstimator").to_str().unwrap(), &[]);
}

#[test]
fn twenty_vehicle_cycles_leak_nothing_under_valgrind() {
    clean_cycles(
        fmu("RailVehicle").to_str().unwrap(),
        &[
            "--preset",
            "lateral_irregularity=false",
            "--preset",
            "vertical_irregularity=false",
        ],
    );
}

#[test]
fn a_leaking_fmu_fails_the_same_check() {
    let good = strict_fmu(None);
    let out = valgrind(&["cycles", "--fmu", good.to_str().unwrap(), "--cycles", "5"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert_eq!(lost(&err, "definitely"), 0, "{err}");
    let leaky = strict_fmu(Some("FAULT_LEAK"));
    let out = valgrind(&["cycles", "--fmu", leaky.to_str().unwrap(), "--cycles", "5"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(99), "{err}");
    assert!(lost(&err, "definitely") > 0, "{err}");
    // The leaked blocks were allocated during the cycles' FMU-state calls (the FMU's own
    // frames show as ??? because its unpacked library is gone when valgrind reports).
    assert!(
        err.contains("are definitely lost") && err.contains("fmi_fuzz::cycles::one_cycle"),
        "{err}"
    );
}
