//! The command line under interruption and disk errors: Ctrl-C (SIGINT) keeps whole-line
//! results and exits 130; an unwritable destination or a full disk is reported before any FMU
//! runs; a write failing mid-run says where the run stopped and what is left. Linux only (it
//! uses kill, /dev/full, /proc and the shell's ulimit).
#![cfg(target_os = "linux")]

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn orchestrator() -> Command {
    Command::new(env!("CARGO_BIN_EXE_orchestrator"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Waits for `child` at most `limit`; kills it and fails if it is still running.
fn wait(mut child: Child, limit: Duration) -> Output {
    let started = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > limit {
            child.kill().unwrap();
            panic!("the orchestrator did not exit within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn size(path: &Path) -> u64 {
    std::fs::metadata(path).map(|m| m.len()).unwrap_or(0)
}

/// Checks that `path` is complete CSV: a header, then rows with as many numeric fields, every
/// line ended by a newline; returns the time column.
fn whole_lines(path: &Path) -> (String, Vec<f64>) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.ends_with('\n'), "the last line is cut");
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let width = header.split(',').count();
    let mut times = vec![];
    for (i, line) in lines.enumerate() {
        let fields: Vec<f64> = line
            .split(',')
            .map(|f| {
                f.parse()
                    .unwrap_or_else(|_| panic!("row {i}: '{f}' in '{line}'"))
            })
            .collect();
        assert_eq!(fields.len(), width, "row {i}: {line}");
        times.push(fields[0]);
    }
    (header, times)
}

/// The number after `prefix` in `text`.
fn number_after(text: &str, prefix: &str) -> f64 {
    let rest = &text[text
        .find(prefix)
        .unwrap_or_else(|| panic!("no '{prefix}' in {text}"))
        + prefix.len()..];
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
        .unwrap_or(rest.len());
    rest[..end].parse().unwrap()
}

#[test]
fn sigint_stops_at_a_step_boundary_and_keeps_whole_lines() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let child = orchestrator()
        .arg("simulate")
        .arg(common::fmu("Dahlquist"))
        // 1e8 steps (an estimated 4 GB, under the 10 GB limit): far more than the test waits for.
        .args(["--stop", "100000", "--step", "0.001", "--quiet", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let partial = out.join("results.csv.partial");
    let started = Instant::now();
    // Wait until rows have reached the file (the writer's buffer is 1 MiB).
    while size(&partial) <= 1 << 20 {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no rows written within 120 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // While the run goes on, only the partial file exists (the final name appears at the end).
    assert!(!out.join("results.csv").exists());
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let output = wait(child, Duration::from_secs(60));
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted: stopping at the next step boundary and keeping the results"),
        "{err}"
    );
    let results = out.join("results.csv");
    assert!(
        err.contains("error: interrupted at t = ")
            && err.contains(&format!(
                "rows recorded until then are in {}",
                results.display()
            )),
        "{err}"
    );
    assert!(!partial.exists(), "the partial file was renamed");
    let (header, times) = whole_lines(&results);
    assert_eq!(header, "time,Dahlquist.x");
    // One row at the start and one per step, each at its tick k * h, up to the stop.
    let rows = number_after(&err, "; the ") as usize;
    let steps = number_after(&err, ", after ") as usize;
    let t = number_after(&err, "interrupted at t = ");
    assert_eq!(times.len(), rows, "{err}");
    assert_eq!(rows, steps + 1, "{err}");
    assert!(rows > 20_000, "{rows} rows");
    for (k, time) in times.iter().enumerate() {
        assert_eq!(*time, k as f64 * 0.001, "row {k}");
    }
    assert_eq!(*times.last().unwrap(), t);
    eprintln!("interrupted after {steps} steps, {rows} rows");
}

#[test]
fn a_full_disk_is_reported_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let partial = out.join("results.csv.partial");
    std::os::unix::fs::symlink("/dev/full", &partial).unwrap();
    // fail_at = 0: had the FMU run a step, the exit code would be 3.
    let output = orchestrator()
        .arg("simulate")
        .arg(common::fmu("Feedthrough"))
        .args([
            "--stop",
            "1",
            "--step",
            "0.1",
            "--set",
            "fail_at=0",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "error: cannot write results in {} (nothing was run): cannot write {}: No space left on device",
            out.display(),
            partial.display()
        )),
        "{err}"
    );
    // The link is removed (not /dev/full), and nothing else is left.
    assert!(std::fs::symlink_metadata(&partial).is_err());
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0);
    assert!(Path::new("/dev/full").exists());
}

#[test]
fn unwritable_destinations_are_reported_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a_file");
    std::fs::write(&file, "").unwrap();
    let under_file = file.join("out");
    let in_proc = PathBuf::from("/proc/orchestrator-reliability-test/out");
    let read_only = dir.path().join("read_only");
    std::fs::create_dir(&read_only).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&read_only, std::fs::Permissions::from_mode(0o555)).unwrap();
    // Root ignores permission bits: then the read-only case cannot be checked.
    let probe = read_only.join("probe");
    let root = std::fs::write(&probe, "").is_ok();
    let _ = std::fs::remove_file(&probe);
    let mut cases = vec![
        (
            under_file.clone(),
            format!("cannot create the directory {}", under_file.display()),
        ),
        (
            in_proc.clone(),
            format!("cannot create the directory {}", in_proc.display()),
        ),
    ];
    if root {
        eprintln!("running as root: the read-only directory case is skipped");
    } else {
        cases.push((
            read_only.clone(),
            format!(
                "cannot create {}: Permission denied",
                read_only.join("results.csv.partial").display()
            ),
        ));
    }
    for (out, expected) in cases {
        let output = orchestrator()
            .arg("simulate")
            .arg(common::fmu("Feedthrough"))
            .args([
                "--stop",
                "1",
                "--step",
                "0.1",
                "--set",
                "fail_at=0",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        let err = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{}: {err}", out.display());
        assert!(
            err.contains(&format!(
                "error: cannot write results in {} (nothing was run): {expected}",
                out.display()
            )),
            "{err}"
        );
    }
    std::fs::set_permissions(&read_only, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// A write that fails mid-run (here the file-size limit of `ulimit -f`, EFBIG; a disk filling up
/// gives ENOSPC the same way): exit 1, the message names the file, where the run stopped, and
/// what is left.
#[test]
fn a_write_failing_mid_run_says_where_the_run_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // SIGXFSZ ignored, so that the write fails instead of killing the process. The limit (32768
    // blocks: 16 MiB in dash's 512-byte blocks, 32 MiB in bash's 1 KiB ones) must let the FMU's
    // library be unpacked (6.4 MB built in the dev profile, as `cargo xtask test` builds it) and
    // stop the results (27 bytes a row: 108 MB for the 4e6 rows asked) well before the end.
    let output = Command::new("sh")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 32768; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_orchestrator"))
        .arg("simulate")
        .arg(common::fmu("Dahlquist"))
        .args(["--stop", "4000", "--step", "0.001", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    let partial = out.join("results.csv.partial");
    assert!(
        err.contains(&format!(
            "error: cannot write {}: File too large",
            partial.display()
        )) && err.contains("; the run stopped at t = ")
            && err.contains(&format!(
                "the rows written until then are in {} (the last one may be incomplete)",
                partial.display()
            )),
        "{err}"
    );
    let t = number_after(&err, "the run stopped at t = ");
    assert!(t > 0.0 && t < 4000.0, "{err}");
    assert!(!out.join("results.csv").exists());
    let text = std::fs::read(&partial).unwrap();
    assert!(
        text.starts_with(b"time,Dahlquist.x\n0.0,"),
        "the header and row 0 are there"
    );
}

/// An FMU failing mid-run through the command line: exit 3, the rows until the failure as whole
/// lines under the final name.
#[test]
fn an_fmu_failure_keeps_whole_lines() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let output = orchestrator()
        .arg("simulate")
        .arg(common::fmu("Feedthrough"))
        .args([
            "--stop",
            "1",
            "--step",
            "0.1",
            "--set",
            "fail_at=0.5",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(3), "{err}");
    assert!(
        err.contains("Feedthrough.fmu")
            && err.contains("fmi2DoStep")
            && err.contains("at t = 0.5 s")
            && err.contains(&format!(
                "the results recorded until then are in {}",
                out.join("results.csv").display()
            )),
        "{err}"
    );
    let (_, times) = whole_lines(&out.join("results.csv"));
    let expected: Vec<f64> = (0..6).map(|k| k as f64 * 0.1).collect();
    assert_eq!(times, expected);
    assert!(!out.join("results.csv.partial").exists());
}

/// A stop time that is not finite, or more steps than the tick counter can count exactly, is
/// refused before the run (it used to start a run that would never end).
#[test]
fn endless_runs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (stop, expected) in [
        (
            "inf",
            "error: invalid value 'inf' for '--stop <STOP>': expected a finite time in s, not negative",
        ),
        (
            "1e300",
            "error: the run from 0 s to 1e300 s has 1e303 steps of 0.001 s, more than 2^53",
        ),
    ] {
        let output = orchestrator()
            .arg("simulate")
            .arg(common::fmu("Feedthrough"))
            .args(["--stop", stop, "--step", "0.001", "--quiet", "--out"])
            .arg(dir.path().join("out"))
            .output()
            .unwrap();
        let err = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{err}");
        assert!(err.contains(expected), "{err}");
        assert!(
            !dir.path().join("out").exists(),
            "a refused run leaves no --out directory"
        );
    }
}

/// Issue 14: an FMU that ends the simulation itself (fmi2DoStep returns fmi2Discard and
/// fmi2GetBooleanStatus(fmi2Terminated) answers true) ends the run cleanly, with every row
/// until then kept and one at the FMU's last successful time, as fmpy does.
#[test]
fn an_fmu_that_ends_the_simulation_ends_the_run_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let run = orchestrator()
        .arg("simulate")
        .arg(common::fmu("Dahlquist"))
        .args([
            "--stop",
            "1",
            "--step",
            "0.1",
            "--quiet",
            "--set",
            "end_at=0.55",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("ended the simulation at t = 0.55 s"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let rows: Vec<(f64, f64)> = text
        .lines()
        .skip(1)
        .map(|l| {
            let mut f = l.split(',').map(|v| v.parse::<f64>().unwrap());
            (f.next().unwrap(), f.next().unwrap())
        })
        .collect();
    // t = 0, 0.1, ..., 0.5, then the last successful time 0.55; x = exp(-t) with k = 1.
    assert_eq!(rows.len(), 7, "{rows:?}");
    assert!(
        (rows[5].0 - 0.5).abs() < 1e-12 && (rows[6].0 - 0.55).abs() < 1e-12,
        "{rows:?}"
    );
    for (t, x) in rows {
        assert!((x - (-t).exp()).abs() < 1e-12, "x({t}) = {x}");
    }
}
