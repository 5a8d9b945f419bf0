//! Issue 25: what `orchestrator` writes and what it refuses, from the command line. Arguments
//! are checked before anything is created (a refused run leaves no `--out` directory), a run
//! too large for the limit or the disk is refused with its estimated size, `export-ssp` never
//! replaces its input or someone else's file, and no help text shows a rustdoc escape. Linux
//! only (FIFOs, permissions, ulimit).
#![cfg(target_os = "linux")]

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn orchestrator(args: &[&dyn AsRef<std::ffi::OsStr>]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_orchestrator"));
    for a in args {
        c.arg(a);
    }
    c.output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// One line of error, no panic.
fn clean(err: &str) {
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{err}"
    );
}

#[test]
fn negative_and_non_finite_times_are_refused_by_option_before_anything_is_created() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let fmu = common::fmu("Feedthrough");
    for (args, words) in [
        (
            &["--stop", "-1", "--step", "0.1"][..],
            &["'-1'", "--stop", "not negative"][..],
        ),
        (
            &["--stop", "1", "--step", "0"],
            &["'0'", "--step", "above zero"],
        ),
        (&["--stop", "1", "--step", "nan"], &["'nan'", "--step"]),
        (&["--stop", "inf", "--step", "0.1"], &["'inf'", "--stop"]),
        (&["--stop", "1", "--step", "-0.1"], &["'-0.1'", "--step"]),
        (
            &["--stop", "1", "--step", "0.1", "--interval", "-1"],
            &["--interval"],
        ),
        // Accepted by the parser, refused by the grid: still before the directory is made.
        (
            &["--start", "2", "--stop", "1", "--step", "0.1"],
            &["before the start time"],
        ),
        (&["--stop", "1", "--step", "0.3"], &["whole number"]),
    ] {
        let mut a: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"simulate", &fmu];
        for x in args {
            a.push(x);
        }
        a.extend([&"--quiet" as &dyn AsRef<std::ffi::OsStr>, &"--out", &out]);
        let o = orchestrator(&a);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{err}");
        for w in words {
            assert!(err.contains(w), "{args:?}: {w:?} not in {err}");
        }
        clean(&err);
        assert!(!out.exists(), "{args:?} left {}", out.display());
    }
}

#[test]
fn a_run_over_the_size_limit_is_refused_with_its_size_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let fmu = common::fmu("Feedthrough");
    // The issue's typo: --stop 1e12 at 1 ms.
    let o = orchestrator(&[
        &"simulate",
        &fmu,
        &"--stop",
        &"1e12",
        &"--step",
        &"0.001",
        &"--quiet",
        &"--out",
        &out,
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("the results file results.csv would be about")
            && err.contains("PB")
            && err.contains("--max-output-size"),
        "{err}"
    );
    clean(&err);
    assert!(!out.exists(), "the refused run left {}", out.display());
    // A small limit refuses a small run; --no-record is not affected by it.
    let small = [
        &"simulate" as &dyn AsRef<std::ffi::OsStr>,
        &fmu,
        &"--stop",
        &"1",
        &"--step",
        &"0.001",
        &"--quiet",
        &"--max-output-size",
        &"1k",
        &"--out",
        &out,
    ];
    let o = orchestrator(&small);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("over the 1.0 kB limit"),
        "{}",
        stderr(&o)
    );
    let mut unrecorded = small.to_vec();
    unrecorded.push(&"--no-record");
    let o = orchestrator(&unrecorded);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = orchestrator(&[
        &"simulate",
        &fmu,
        &"--stop",
        &"1",
        &"--step",
        &"0.001",
        &"--quiet",
        &"--max-output-size",
        &"1M",
        &"--out",
        &out,
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(out.join("results.csv").exists());
}

#[test]
fn a_size_over_the_free_space_is_refused_as_an_io_error() {
    // /dev/shm is a tmpfs of a bounded size on Linux; a run of 1e15 values cannot fit.
    let Ok(dir) = tempfile::tempdir_in("/dev/shm") else {
        return;
    };
    let out = dir.path().join("out");
    let o = orchestrator(&[
        &"simulate",
        &common::fmu("Feedthrough"),
        &"--stop",
        &"1e9",
        &"--step",
        &"0.001",
        &"--quiet",
        &"--max-output-size",
        &"1000P",
        &"--out",
        &out,
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("free on its disk") && err.contains("nothing was run"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn export_ssp_never_replaces_its_input_or_another_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ssd = Path::new(env!("CARGO_MANIFEST_DIR")).join("../studies/standard.ssd");
    let veh = format!("vehicle={}", common::fmu("RailVehicle").display());
    let est = format!("estimator={}", common::fmu("AlignmentEstimator").display());
    let export = |out: &Path, more: &[&str]| {
        let mut a: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![
            &"export-ssp",
            &out,
            &"--system",
            &ssd,
            &"--fmu",
            &veh,
            &"--fmu",
            &est,
        ];
        for m in more {
            a.push(m);
        }
        orchestrator(&a)
    };
    // Its input: a copy of the system given as both.
    let sys = d.join("sys.ssd");
    std::fs::copy(&ssd, &sys).unwrap();
    let before = std::fs::read(&sys).unwrap();
    let o = orchestrator(&[
        &"export-ssp",
        &sys,
        &"--system",
        &sys,
        &"--fmu",
        &veh,
        &"--fmu",
        &est,
        &"--force",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("is the input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&sys).unwrap(), before);
    // An FMU it packs, even forced.
    let fmu_copy = d.join("Vehicle.fmu");
    std::fs::copy(common::fmu("RailVehicle"), &fmu_copy).unwrap();
    let fmu_bytes = std::fs::read(&fmu_copy).unwrap();
    let veh_copy = format!("vehicle={}", fmu_copy.display());
    let o = orchestrator(&[
        &"export-ssp",
        &fmu_copy,
        &"--system",
        &ssd,
        &"--fmu",
        &veh_copy,
        &"--fmu",
        &est,
        &"--force",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("is the input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&fmu_copy).unwrap(), fmu_bytes);
    // Someone's file: refused without --force, replaced with it.
    let notes = d.join("notes.ssp");
    std::fs::write(&notes, "mine").unwrap();
    let o = export(&notes, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--force"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "mine");
    let o = export(&notes, &["--force"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(std::fs::read(&notes).unwrap().starts_with(b"PK"));
    // A FIFO: refused at once (never opened, so nothing blocks), even forced.
    let fifo = d.join("fifo.ssp");
    common::mkfifo(&fifo);
    let o = export(&fifo, &["--force"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("FIFO"), "{}", stderr(&o));
    // A read-only directory: an I/O error naming the file, nothing left.
    let ro = d.join("ro");
    std::fs::create_dir(&ro).unwrap();
    std::fs::set_permissions(&ro, std::os::unix::fs::PermissionsExt::from_mode(0o555)).unwrap();
    let o = export(&ro.join("sys.ssp"), &[]);
    let err = stderr(&o);
    std::fs::set_permissions(&ro, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    // Root writes anyway; the refusal is for an ordinary user.
    if o.status.code() != Some(0) {
        assert!(err.contains("ro"), "{err}");
        clean(&err);
        assert_eq!(std::fs::read_dir(&ro).unwrap().count(), 0);
    }
}

#[test]
fn no_help_text_shows_a_rustdoc_escape() {
    let top = orchestrator(&[&"--help"]);
    let text = String::from_utf8_lossy(&top.stdout).into_owned();
    assert!(!text.contains('\\'), "{text}");
    for sub in ["run", "simulate", "info", "export-ssp"] {
        assert!(text.contains(sub), "{sub} missing from\n{text}");
        let o = orchestrator(&[&sub, &"--help"]);
        let help = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success());
        for line in help.lines() {
            assert!(!line.contains('\\'), "orchestrator {sub} --help: {line}");
        }
    }
    let sim = orchestrator(&[&"simulate", &"--help"]);
    let sim = String::from_utf8_lossy(&sim.stdout);
    assert!(
        sim.contains("for `simulate`: the input's last time"),
        "{sim}"
    );
}

#[test]
fn info_does_not_call_the_learned_filter_a_kalman_filter_estimate() {
    let o = orchestrator(&[&"info", &common::fmu("AlignmentEstimator")]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert!(!text.contains("Kalman filter estimate"), "{text}");
    assert!(text.contains("by default the learned filter"), "{text}");
}

#[test]
fn run_starts_at_the_system_start_time_unless_start_is_given() {
    // The SSP DefaultExperiment's startTime is where the run starts (it was read, checked and
    // written back by export-ssp, but the run started at 0 regardless).
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ssd = d.join("sys.ssd");
    std::fs::write(
        &ssd,
        format!(
            r#"<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="s"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription">
  <ssd:System name="root">
    <ssd:Elements>
      <ssd:Component name="dq" source="{}"/>
    </ssd:Elements>
  </ssd:System>
  <ssd:DefaultExperiment startTime="5" stopTime="5.5"/>
</ssd:SystemStructureDescription>
"#,
            common::fmu("Dahlquist").display()
        ),
    )
    .unwrap();
    let first_and_last = |extra: &[&str]| {
        let out = d.join("out");
        let mut a: Vec<&dyn AsRef<std::ffi::OsStr>> =
            vec![&"run", &ssd, &"--step", &"0.1", &"--quiet", &"--out", &out];
        for x in extra {
            a.push(x);
        }
        let o = orchestrator(&a);
        assert!(o.status.success(), "{}", stderr(&o));
        let rows = common::rows(&out.join("results.csv"));
        (rows[0][0], rows[rows.len() - 1][0])
    };
    let (first, last) = first_and_last(&[]);
    assert!(
        (first - 5.0).abs() < 1e-12 && (last - 5.5).abs() < 1e-12,
        "{first}..{last}"
    );
    let (first, last) = first_and_last(&["--start", "5.2"]);
    assert!(
        (first - 5.2).abs() < 1e-12 && (last - 5.5).abs() < 1e-12,
        "{first}..{last}"
    );
}
