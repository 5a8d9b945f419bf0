//! Issue 25: what `alignment-studies` writes and what it refuses, from the command line:
//! `smooth` never replaces its input or someone else's file, refuses FIFOs and read-only
//! directories with one line, leaves the old output whole when the disk fills, reads every row
//! (CSV and Parquet) and refuses a recording with no sample at a working speed; `learn`, `taps`,
//! `calibrate` and `--doc` check their file before any work; no help text shows a rustdoc
//! escape. Linux only (FIFOs, permissions, the shell's ulimit).
#![cfg(target_os = "linux")]

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn studies() -> Command {
    Command::new(env!("CARGO_BIN_EXE_alignment-studies"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn clean(o: &Output) {
    let err = stderr(o);
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
}

/// A recording of `n` rows at 1 ms, speed `v`, small signals.
fn recording(dir: &Path, n: usize, v: f64) -> PathBuf {
    let mut text = String::from("time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n");
    for k in 0..n {
        let t = k as f64 * 1e-3;
        let s = (7.0 * t).sin();
        text.push_str(&format!("{t},{v},{},{},{}\n", 0.1 * s, 0.01 * s, 0.05 * s));
    }
    let p = dir.join(format!("rec{n}_{v}.csv"));
    std::fs::write(&p, text).unwrap();
    p
}

fn smooth(input: &Path, out: &Path, more: &[&str]) -> Output {
    studies()
        .arg("smooth")
        .arg(input)
        .arg("--out")
        .arg(out)
        .args(more)
        .output()
        .unwrap()
}

fn data_rows(csv: &Path) -> usize {
    std::fs::read_to_string(csv).unwrap().lines().count() - 1
}

#[test]
fn smooth_never_replaces_its_input_even_forced_or_by_another_name() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path(), 500, 20.0);
    let before = std::fs::read(&rec).unwrap();
    for out in [
        rec.clone(),
        dir.path().join(".").join(rec.file_name().unwrap()),
    ] {
        for more in [&[][..], &["--force"]] {
            let o = smooth(&rec, &out, more);
            assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
            assert!(stderr(&o).contains("is the input"), "{}", stderr(&o));
            clean(&o);
            assert_eq!(
                std::fs::read(&rec).unwrap(),
                before,
                "the recording is intact"
            );
        }
    }
}

#[test]
fn smooth_replaces_its_own_output_but_not_another_file_without_force() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path(), 500, 20.0);
    let other = dir.path().join("existing.txt");
    std::fs::write(&other, "someone's notes\n").unwrap();
    let o = smooth(&rec, &other, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--force"), "{}", stderr(&o));
    clean(&o);
    assert_eq!(
        std::fs::read_to_string(&other).unwrap(),
        "someone's notes\n"
    );
    // Its own output is replaced on a second run; --force replaces another file.
    let out = dir.path().join("smoothed.csv");
    assert!(smooth(&rec, &out, &[]).status.success());
    let o = smooth(&rec, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = smooth(&rec, &other, &["--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(data_rows(&other), 500);
    // No temporary file is left anywhere.
    let hidden = common::hidden_files(dir.path());
    assert!(hidden.is_empty(), "{hidden:?}");
}

#[test]
fn smooth_refuses_a_fifo_and_a_read_only_directory_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path(), 500, 20.0);
    let fifo = dir.path().join("fifo.csv");
    common::mkfifo(&fifo);
    let o = smooth(&rec, &fifo, &["--force"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("FIFO"), "{}", stderr(&o));
    clean(&o);
    let ro = dir.path().join("ro");
    std::fs::create_dir(&ro).unwrap();
    std::fs::set_permissions(&ro, std::os::unix::fs::PermissionsExt::from_mode(0o555)).unwrap();
    let o = smooth(&rec, &ro.join("out.csv"), &[]);
    std::fs::set_permissions(&ro, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    // Root writes anyway; the refusal is for an ordinary user.
    if !o.status.success() {
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains("out.csv"), "{}", stderr(&o));
        clean(&o);
        assert_eq!(std::fs::read_dir(&ro).unwrap().count(), 0);
    }
}

#[test]
fn a_full_disk_leaves_the_previous_output_whole_and_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path(), 3000, 20.0);
    let out = dir.path().join("smoothed.csv");
    assert!(smooth(&rec, &out, &[]).status.success());
    let before = std::fs::read(&out).unwrap();
    // A file size limit of 64 kB (the output is about 300 kB): writes past it fail with EFBIG,
    // as on a full disk (SIGXFSZ ignored, so the write returns the error).
    let o = Command::new("sh")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 64; exec \"$0\" smooth \"$1\" --out \"$2\"")
        .arg(env!("CARGO_BIN_EXE_alignment-studies"))
        .arg(&rec)
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("left as it was"), "{}", stderr(&o));
    clean(&o);
    assert_eq!(
        std::fs::read(&out).unwrap(),
        before,
        "the previous output is whole"
    );
    let hidden = common::hidden_files(dir.path());
    assert!(hidden.is_empty(), "{hidden:?}");
}

#[test]
fn smooth_reads_every_row_of_csv_and_parquet() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path(), 5000, 20.0);
    let out = dir.path().join("smoothed.csv");
    let o = smooth(&rec, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).starts_with("5000 samples"), "{}", stderr(&o));
    assert_eq!(data_rows(&out), 5000);
    let first = std::fs::read_to_string(&out).unwrap();
    let first = first
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .to_string();
    assert_eq!(first, "0.0", "the first row's time is kept");
    // The same recording as Parquet, and a Parquet output.
    let cols = orchestrator::csv::Csv::read(&rec).unwrap();
    let names: Vec<String> = ["time", "speed", "ws_acc_y", "ws_yaw_rate", "frame_acc_y"]
        .map(String::from)
        .to_vec();
    let values: Vec<&[f64]> = names
        .iter()
        .map(|n| cols.column(&[n.as_str()]).unwrap())
        .collect();
    let units = vec![String::new(); names.len()];
    let pq = dir.path().join("rec.parquet");
    orchestrator::parquet::write(&pq, &names, &units, &values, "{}").unwrap();
    let out_pq = dir.path().join("smoothed.parquet");
    let o = smooth(&pq, &out_pq, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).starts_with("5000 samples"), "{}", stderr(&o));
    let table = orchestrator::csv::Csv::read_any(&out_pq).unwrap();
    assert_eq!(table.column(&["time"]).unwrap().len(), 5000);
    assert_eq!(table.column(&["time"]).unwrap()[0], 0.0);
}

#[test]
fn smooth_refuses_a_recording_with_no_sample_at_a_working_speed() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path(), 500, 0.0);
    let out = dir.path().join("smoothed.csv");
    let o = smooth(&rec, &out, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("min_speed") && stderr(&o).contains("nothing written"),
        "{}",
        stderr(&o)
    );
    clean(&o);
    assert!(!out.exists());
}

#[test]
fn file_writers_check_out_before_any_work() {
    // Absent FMUs: a command that did its work first would fail on them (exit 2); the refused
    // --out comes first (exit 1).
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let other = d.join("notes.txt");
    std::fs::write(&other, "mine\n").unwrap();
    let fmus = [
        "--vehicle",
        "absent-vehicle.fmu",
        "--estimator",
        "absent-estimator.fmu",
    ];
    let runs: [&[&str]; 4] = [
        &["learn", "--out"],
        &["taps", "--out"],
        &["calibrate", "--out"],
        &["standard", "--quiet", "--out", "unused", "--doc"],
    ];
    for args in runs {
        let o = studies()
            .current_dir(d)
            .args(args)
            .arg(&other)
            .args(fmus)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("not written by this command"),
            "{}",
            stderr(&o)
        );
        clean(&o);
        assert_eq!(std::fs::read_to_string(&other).unwrap(), "mine\n");
    }
    assert!(!d.join("unused").exists());
    // A file the command wrote (its mark) passes the check: the shipped tap bank and
    // calibration are regenerated in place as docs/studies.md says; here the absent FMUs stop
    // the work after the check.
    for (cmd, mark) in [
        ("taps", "learned-taps 2 0123\nformat = 2\n"),
        (
            "calibrate",
            "# Calibration of the AlignmentEstimator FMU, written by `alignment-studies calibrate`.\n",
        ),
    ] {
        let own = d.join(format!("{cmd}.out"));
        std::fs::write(&own, mark).unwrap();
        let o = studies()
            .current_dir(d)
            .args([cmd, "--out"])
            .arg(&own)
            .args(fmus)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", stderr(&o));
        assert!(stderr(&o).contains("absent-"), "{cmd}: {}", stderr(&o));
        assert_eq!(std::fs::read_to_string(&own).unwrap(), mark);
    }
}

#[test]
fn study_directories_keep_files_no_study_wrote() {
    // Someone's report.md (or figure) where a study would write its own: refused before any
    // work (the absent FMUs would fail with exit 2 after it), unless --force; a name listed in
    // the directory's record (a study wrote it) passes the check.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fmus = [
        "--vehicle",
        "absent-vehicle.fmu",
        "--estimator",
        "absent-estimator.fmu",
    ];
    let runs: [(&[&str], &str); 4] = [
        (&["standard", "--quiet", "--out", "study"], "report.md"),
        (
            &["robustness", "--quiet", "--out", "study"],
            "robustness.svg",
        ),
        (&["variants", "--out", "study"], "variants.json"),
        (
            &["calibrate", "--out", "cal.toml", "--plots", "study"],
            "model_adjustment.svg",
        ),
    ];
    std::fs::create_dir(d.join("study")).unwrap();
    for (args, name) in runs {
        let mine = d.join("study").join(name);
        std::fs::write(&mine, "mine\n").unwrap();
        let run = |more: &[&str]| {
            studies()
                .current_dir(d)
                .args(args)
                .args(fmus)
                .args(more)
                .output()
                .unwrap()
        };
        let o = run(&[]);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("no study wrote it"), "{}", stderr(&o));
        clean(&o);
        assert_eq!(std::fs::read_to_string(&mine).unwrap(), "mine\n");
        // Forced, the check passes and the absent FMUs stop the work.
        let o = run(&["--force"]);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        std::fs::remove_file(&mine).unwrap();
    }
    // Listed in the record: the check passes without --force.
    std::fs::write(d.join("study/report.md"), "a study's\n").unwrap();
    std::fs::write(d.join("study/.alignment-studies-written"), "report.md\n").unwrap();
    let o = studies()
        .current_dir(d)
        .args(["standard", "--quiet", "--out", "study"])
        .args(fmus)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("absent-"), "{}", stderr(&o));
}

#[test]
fn no_help_text_shows_a_rustdoc_escape() {
    let subs = [
        "run",
        "calibrate",
        "standard",
        "robustness",
        "resonance",
        "all",
        "variants",
        "learn",
        "taps",
        "smooth",
    ];
    for sub in std::iter::once(None).chain(subs.map(Some)) {
        let o = studies().args(sub).arg("--help").output().unwrap();
        assert!(o.status.success());
        let help = String::from_utf8_lossy(&o.stdout);
        for line in help.lines() {
            assert!(
                !line.contains('\\'),
                "alignment-studies {sub:?} --help: {line}"
            );
        }
    }
}

#[test]
fn fit_speeds_lags_and_contact_scales_are_checked_as_they_are_parsed() {
    // Before, `taps --speeds 0` or `learn --lag nan` reached the fit (minutes of training runs
    // with a meaningless condition); now the parser refuses them by option, before any work.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bank.taps");
    for (args, option, words) in [
        (&["taps", "--speeds", "20,0"][..], "--speeds", "above zero"),
        (&["taps", "--speeds", "nan"], "--speeds", "finite speed"),
        (&["taps", "--lags", "-1"], "--lags", "not negative"),
        (
            &["taps", "--kalker-scales", "1,0"],
            "--kalker-scales",
            "above zero",
        ),
        (&["learn", "--lag", "inf"], "--lag", "finite look-ahead"),
        (&["learn", "--speed", "-5"], "--speed", "above zero"),
        (
            &["learn", "--kalker-scales", "x"],
            "--kalker-scales",
            "a number",
        ),
    ] {
        let o = studies()
            .args(args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(option) && err.contains(words),
            "{args:?}: {err}"
        );
        // clap's own usage error: the message and its "try '--help'" line, no panic.
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists());
    }
}
