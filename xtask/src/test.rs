//! `cargo xtask test`: the stages of the suite, each timed, run on even when an independent
//! one failed, and a summary with one line per stage.

use crate::binaries::{self, Binaries, FMU_DIR_ENV};
use crate::cli::TestOptions;
use crate::workspace::{self, Profile};
use crate::{package, python};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

enum Outcome {
    Passed,
    Failed(String),
    Skipped(String),
}

struct Stage {
    name: &'static str,
    outcome: Outcome,
    seconds: f64,
}

fn timed(name: &'static str, f: impl FnOnce() -> Result<()>) -> Stage {
    println!("\n==> {name}");
    let start = Instant::now();
    let outcome = match f() {
        Ok(()) => Outcome::Passed,
        Err(e) => {
            eprintln!("error: {e:#}");
            Outcome::Failed(
                format!("{e:#}")
                    .lines()
                    .next()
                    .unwrap_or_default()
                    .to_string(),
            )
        }
    };
    Stage {
        name,
        outcome,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// A cargo command of the Rust half, run from the workspace root.
fn cargo(args: &[&str]) -> Command {
    let mut cmd = workspace::cargo();
    cmd.args(args);
    cmd
}

/// Runs every selected stage (a failure does not stop the independent ones), prints a summary and
/// returns whether everything passed.
pub fn test(o: TestOptions) -> Result<bool> {
    let mut stages = Vec::new();
    // Every build below compiles the workspace's crates with clippy's lints (the lint stage at
    // the end reads what they found); without clippy the builds go on and that stage fails.
    let lints = workspace::lint_builds();
    // pip waits mostly on the network and the disk: it works while cargo compiles.
    let venv = o.python.then(|| {
        let log = workspace::target_dir()
            .unwrap_or_else(|_| workspace::root().join("target"))
            .join("xtask-venv.log");
        std::thread::spawn(move || python::ensure_venv_logged(&log))
    });
    // The FMUs and the two programs first: Rust integration tests and the Python harness both
    // load them (found through XTASK_FMU_DIR, ORCHESTRATOR and ALIGNMENT_STUDIES).
    let mut fmu_dir: Option<PathBuf> = None;
    stages.push(timed("package FMUs (dev profile)", || {
        let packaged = package::build_and_package(Profile::Dev)?;
        fmu_dir = packaged
            .first()
            .and_then(|p| p.path.parent())
            .map(PathBuf::from);
        Ok(())
    }));
    // `cargo test --no-run` also builds the two programs (the crates' integration tests run
    // them), in the dev profile's directory: a `cargo build` of them would compile the
    // workspace's crates a second time (cargo's units for a test build are not a plain build's).
    let mut binaries: Option<Binaries> = None;
    stages.push(timed(
        "build the Rust tests and the two programs (cargo test --no-run)",
        || {
            workspace::run(&mut test_build())?;
            binaries = Some(binaries::built(Profile::Dev)?);
            Ok(())
        },
    ));
    if o.rust {
        // Style is part of the suite: a change that breaks it fails CI.
        stages.push(timed("cargo fmt --all -- --check", || {
            workspace::run(&mut cargo(&["fmt", "--all", "--", "--check"]))
        }));
        // The crate docs hold the derivations: a broken link or a malformed doc comment fails.
        stages.push(timed(
            "cargo doc --workspace --no-deps (RUSTDOCFLAGS=-D warnings)",
            || {
                let mut cmd = cargo(&["doc", "--workspace", "--no-deps"]);
                workspace::run(cmd.env("RUSTDOCFLAGS", "-D warnings"))
            },
        ));
        stages.push(timed("cargo test --workspace", || {
            let mut cmd = cargo(&["test", "--workspace"]);
            if let Some(dir) = &fmu_dir {
                cmd.env(FMU_DIR_ENV, dir);
            }
            if let Some(b) = &binaries {
                b.env(&mut cmd);
            }
            workspace::run(&mut cmd)
        }));
    }
    let mut bindings_built = false;
    if let Some(venv) = venv {
        bindings_built =
            python_stages(&mut stages, venv, fmu_dir.as_deref(), binaries.as_ref(), &o);
    }
    if o.rust {
        // The builds above, run again (nothing to compile), print the warnings cargo kept: the
        // FMUs' build is the one that lints fmu-estimator without its default features, and
        // maturin's the one that lints the bindings. The benches are compiled here, last: built
        // with the tests, they changed how cargo compiled some libraries for the test run
        // (`--all-targets` made `cargo test` compile the workspace's crates again, 2 min).
        stages.push(timed(
            "lints: clippy and rustc warnings of every build (-D warnings)",
            || {
                lints?;
                let mut builds = vec![
                    package::build_command(Profile::Dev),
                    test_build(),
                    cargo(&["test", "--workspace", "--benches", "--no-run"]),
                ];
                if bindings_built {
                    builds.push(python::bindings_command());
                }
                crate::lints::check(builds)
            },
        ));
    }
    println!("\n==> summary");
    let (lines, all_passed) = summary(&stages);
    println!("{lines}");
    Ok(all_passed)
}

/// Compiles what `cargo test --workspace` runs (libraries, programs, tests, examples), the
/// programs the tests and the Python harness run among them.
fn test_build() -> Command {
    cargo(&["test", "--workspace", "--no-run"])
}

/// The venv (made in the background since the start), the bindings and pytest; pytest is
/// skipped (and counts as a failure) without the FMUs or the venv. Returns whether the bindings
/// were built.
fn python_stages(
    stages: &mut Vec<Stage>,
    venv: std::thread::JoinHandle<Result<PathBuf>>,
    fmu_dir: Option<&Path>,
    binaries: Option<&Binaries>,
    o: &TestOptions,
) -> bool {
    let mut venv_ok = false;
    stages.push(timed("python venv (.venv, tests/requirements.txt)", || {
        venv.join()
            .map_err(|_| anyhow::anyhow!("the thread making the venv panicked"))??;
        venv_ok = true;
        Ok(())
    }));
    let mut built = false;
    if venv_ok {
        stages.push(timed("python bindings (maturin develop)", || {
            venv_ok = false;
            python::install_bindings()?;
            venv_ok = true;
            built = true;
            Ok(())
        }));
    }
    let pytest = "pytest tests";
    let skipped = |why: &str| Stage {
        name: pytest,
        outcome: Outcome::Skipped(why.into()),
        seconds: 0.0,
    };
    stages.push(match (fmu_dir, venv_ok) {
        (Some(dir), true) => timed(pytest, || run_pytest(dir, binaries, &o.pytest_args)),
        (None, _) => skipped("no FMU was packaged"),
        (_, false) => skipped("no Python environment"),
    });
    built
}

/// One line per stage (ok, FAILED or SKIPPED, its time, why), then the verdict; and whether
/// every stage passed (a skipped stage did not).
fn summary(stages: &[Stage]) -> (String, bool) {
    let mut all_passed = true;
    let mut lines = String::new();
    for s in stages {
        let (word, detail) = match &s.outcome {
            Outcome::Passed => ("ok", String::new()),
            Outcome::Failed(why) => {
                all_passed = false;
                ("FAILED", format!(": {why}"))
            }
            Outcome::Skipped(why) => {
                all_passed = false;
                ("SKIPPED", format!(": {why}"))
            }
        };
        lines += &format!("  {word:<7} {:<46} {:>7.1} s{detail}\n", s.name, s.seconds);
    }
    lines += if all_passed { "all passed" } else { "FAILED" };
    (lines, all_passed)
}

fn run_pytest(fmu_dir: &Path, binaries: Option<&Binaries>, extra: &[String]) -> Result<()> {
    let mut cmd = Command::new(python::python());
    cmd.current_dir(workspace::root())
        .env(FMU_DIR_ENV, fmu_dir)
        .args(["-m", "pytest", "-q"]);
    if let Some(b) = binaries {
        b.env(&mut cmd);
    }
    // One pytest worker per core, each taking whole files (a file's module fixtures, such as
    // the Monte-Carlo study or the synthetic fleet, are made once), unless the extra arguments
    // choose the workers themselves: on 2 cores the harness took 228 s in one process.
    if !extra
        .iter()
        .any(|a| a.starts_with("-n") || a.starts_with("--numprocesses") || a == "no:xdist")
    {
        cmd.args(["-n", "auto", "--dist", "loadfile"]);
    }
    // `tests` unless the extra arguments name test files themselves (pytest would run both).
    if !extra
        .iter()
        .any(|a| a == "tests" || a.starts_with("tests/"))
    {
        cmd.arg("tests");
    }
    cmd.args(extra);
    let line = workspace::command_line(&cmd);
    let status = cmd
        .status()
        .with_context(|| format!("could not start `{line}`"))?;
    match status.code() {
        Some(0) => Ok(()),
        Some(5) => bail!("pytest collected no tests (exit code 5)"),
        _ => bail!("`{line}` failed ({status})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stage(name: &'static str, outcome: Outcome, seconds: f64) -> Stage {
        Stage {
            name,
            outcome,
            seconds,
        }
    }

    #[test]
    fn summary_lines_and_verdict() {
        let ok = [stage("cargo fmt", Outcome::Passed, 1.0)];
        let (text, passed) = summary(&ok);
        assert!(passed);
        assert_eq!(
            text,
            format!("  ok      {:<46}     1.0 s\nall passed", "cargo fmt")
        );
        // A skipped stage is not a pass: CI must not go green without the Python half.
        let skipped = [
            stage("cargo fmt", Outcome::Passed, 1.0),
            stage("pytest tests", Outcome::Skipped("no FMU".into()), 0.0),
        ];
        let (text, passed) = summary(&skipped);
        assert!(!passed);
        assert!(text.contains("SKIPPED pytest tests"));
        assert!(text.contains(" s: no FMU\nFAILED"));
        let failed = [stage("cargo test", Outcome::Failed("exit 101".into()), 2.0)];
        let (text, passed) = summary(&failed);
        assert!(!passed && text.starts_with("  FAILED  cargo test") && text.ends_with("FAILED"));
    }
}
