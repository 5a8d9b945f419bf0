//! Project automation, run as `cargo xtask <command>` (an alias in .cargo/config.toml):
//!
//! - `fmu`: build the FMU crates in release and package `<target>/fmu/<modelIdentifier>.fmu`;
//! - `test [--rust-only | --python-only] [-- <pytest args>]`: cargo fmt --check, cargo clippy
//!   and cargo doc with warnings denied, cargo test, packaging, the Python harness (tests/, run
//!   with pytest in `.venv`, created on demand), and a summary;
//! - `demo [-- <study args>]`: package the FMUs, run the standard case, the paper's studies and
//!   the estimator variants with `alignment-studies` (the studies on top of the orchestrator).

mod fmus;
mod package;
mod python;
mod workspace;

use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use std::process::{Command, ExitCode};
use std::time::Instant;

const USAGE: &str = "\
usage: cargo xtask <command>

commands:
  fmu                          build (release) and package target/fmu/<id>.fmu
  test [--rust-only | --python-only] [-- <pytest args>]
                               cargo fmt --check, clippy and doc -D warnings, cargo test --workspace, packaging, pytest tests/ in .venv
  demo [-- <study args>]       package the FMUs, run the standard case and the studies (alignment-studies)
  help                         this text";

/// Where the orchestrator binary is, for the tests that run it.
const ORCHESTRATOR_ENV: &str = "ORCHESTRATOR";
/// Where the studies' binary is, for the tests that run it.
const STUDIES_ENV: &str = "ALIGNMENT_STUDIES";

/// The environment variable telling the Python harness where the packaged FMUs are (the target
/// directory may be moved by CARGO_TARGET_DIR or cargo config).
const FMU_DIR_ENV: &str = "XTASK_FMU_DIR";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("fmu") if args.len() == 1 => package::build_and_package().map(|_| true),
        Some("test") => TestOptions::parse(&args[1..]).and_then(test),
        Some("demo") => passthrough(&args[1..]).and_then(demo).map(|_| true),
        Some("help" | "-h" | "--help") => {
            println!("{USAGE}");
            Ok(true)
        }
        _ => {
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Arguments after a leading `--` (or none); anything else is a usage error.
fn passthrough(args: &[String]) -> Result<Vec<String>> {
    match args.split_first() {
        None => Ok(vec![]),
        Some((first, rest)) if first == "--" => Ok(rest.to_vec()),
        Some((first, _)) => {
            bail!("unexpected argument '{first}' (extra arguments go after `--`)\n\n{USAGE}")
        }
    }
}

struct TestOptions {
    rust: bool,
    python: bool,
    pytest_args: Vec<String>,
}

impl TestOptions {
    fn parse(args: &[String]) -> Result<TestOptions> {
        let mut o = TestOptions {
            rust: true,
            python: true,
            pytest_args: vec![],
        };
        let mut i = 0;
        while i < args.len() {
            match args[i].as_str() {
                "--rust-only" => o.python = false,
                "--python-only" => o.rust = false,
                "--" => {
                    o.pytest_args = args[i + 1..].to_vec();
                    break;
                }
                other => bail!(
                    "unknown option '{other}' for `test` (pytest arguments go after `--`)\n\n{USAGE}"
                ),
            }
            i += 1;
        }
        if !o.rust && !o.python {
            bail!("--rust-only and --python-only exclude each other");
        }
        Ok(o)
    }
}

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

/// Runs every selected stage (a failure does not stop the independent ones), prints a summary and
/// returns whether everything passed.
fn test(o: TestOptions) -> Result<bool> {
    let mut stages = Vec::new();
    // The FMUs and the orchestrator first: Rust integration tests and the Python harness both
    // load them (found through XTASK_FMU_DIR and ORCHESTRATOR).
    let mut fmu_dir: Option<PathBuf> = None;
    stages.push(timed("package FMUs (release build)", || {
        let packaged = package::build_and_package()?;
        fmu_dir = packaged
            .first()
            .and_then(|p| p.path.parent())
            .map(PathBuf::from);
        Ok(())
    }));
    let mut binaries: Option<Binaries> = None;
    stages.push(timed(
        "build the orchestrator and alignment-studies (release)",
        || {
            binaries = Some(build_binaries()?);
            Ok(())
        },
    ));
    let env = |cmd: &mut Command| {
        if let Some(dir) = &fmu_dir {
            cmd.env(FMU_DIR_ENV, dir);
        }
        if let Some(b) = &binaries {
            b.env(cmd);
        }
    };
    if o.rust {
        // Style and lints are part of the suite: a change that breaks them fails CI.
        stages.push(timed("cargo fmt --all -- --check", || {
            let mut cmd = workspace::cargo();
            cmd.args(["fmt", "--all", "--", "--check"]);
            workspace::run(&mut cmd)
        }));
        stages.push(timed(
            "cargo clippy --workspace --all-targets -- -D warnings",
            || {
                let mut cmd = workspace::cargo();
                cmd.args([
                    "clippy",
                    "--workspace",
                    "--all-targets",
                    "--",
                    "-D",
                    "warnings",
                ]);
                workspace::run(&mut cmd)
            },
        ));
        // The crate docs hold the derivations: a broken link or a malformed doc comment fails.
        stages.push(timed(
            "cargo doc --workspace --no-deps (RUSTDOCFLAGS=-D warnings)",
            || {
                let mut cmd = workspace::cargo();
                cmd.args(["doc", "--workspace", "--no-deps"])
                    .env("RUSTDOCFLAGS", "-D warnings");
                workspace::run(&mut cmd)
            },
        ));
        stages.push(timed("cargo test --workspace", || {
            let mut cmd = workspace::cargo();
            cmd.args(["test", "--workspace"]);
            env(&mut cmd);
            workspace::run(&mut cmd)
        }));
    }
    if o.python {
        let mut venv_ok = false;
        stages.push(timed("python venv (.venv, tests/requirements.txt)", || {
            python::ensure_venv()?;
            venv_ok = true;
            Ok(())
        }));
        if venv_ok {
            stages.push(timed("python bindings (maturin develop)", || {
                venv_ok = false;
                python::install_bindings()?;
                venv_ok = true;
                Ok(())
            }));
        }
        let pytest = "pytest tests";
        match (&fmu_dir, venv_ok) {
            (Some(dir), true) => stages.push(timed(pytest, || {
                run_pytest(dir, binaries.as_ref(), &o.pytest_args)
            })),
            (None, _) => stages.push(Stage {
                name: pytest,
                outcome: Outcome::Skipped("no FMU was packaged".into()),
                seconds: 0.0,
            }),
            (_, false) => stages.push(Stage {
                name: pytest,
                outcome: Outcome::Skipped("no Python environment".into()),
                seconds: 0.0,
            }),
        }
    }

    println!("\n==> summary");
    let mut all_passed = true;
    for s in &stages {
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
        println!("  {word:<7} {:<46} {:>7.1} s{detail}", s.name, s.seconds);
    }
    println!("{}", if all_passed { "all passed" } else { "FAILED" });
    Ok(all_passed)
}

/// The two programs: the master and the studies on top of it.
struct Binaries {
    orchestrator: PathBuf,
    studies: PathBuf,
}

impl Binaries {
    /// Tells a test run where they are.
    fn env(&self, cmd: &mut Command) {
        cmd.env(ORCHESTRATOR_ENV, &self.orchestrator)
            .env(STUDIES_ENV, &self.studies);
    }
}

/// Builds the orchestrator and alignment-studies in release and returns the binaries' paths.
fn build_binaries() -> Result<Binaries> {
    workspace::run(workspace::cargo().args([
        "build",
        "--release",
        "-p",
        "orchestrator",
        "-p",
        "alignment-studies",
    ]))?;
    let release = workspace::target_dir()?.join("release");
    let b = Binaries {
        orchestrator: release.join("orchestrator"),
        studies: release.join("alignment-studies"),
    };
    for bin in [&b.orchestrator, &b.studies] {
        anyhow::ensure!(bin.exists(), "no binary at {}", bin.display());
    }
    Ok(b)
}

fn run_pytest(
    fmu_dir: &std::path::Path,
    binaries: Option<&Binaries>,
    extra: &[String],
) -> Result<()> {
    let mut cmd = Command::new(python::python());
    cmd.current_dir(workspace::root())
        .env(FMU_DIR_ENV, fmu_dir)
        .args(["-m", "pytest", "-q"]);
    if let Some(b) = binaries {
        b.env(&mut cmd);
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

/// The main job: packages the FMUs, builds the binaries, runs the standard case with
/// `alignment-studies run` (through the master's library, loading the .fmu files; it writes
/// results.csv and metrics.json), the paper's studies and
/// the variants on held-out track seeds, each command's output in a log beside its results;
/// then prints one table, the headline: the estimator FMU's estimators beside the paper, mean
/// over the held-out seeds, and where the full reports are.
fn demo(extra: Vec<String>) -> Result<()> {
    let packaged = package::build_and_package()?;
    let find = |id: &str| {
        packaged
            .iter()
            .find(|p| p.model_identifier == id)
            .map(|p| p.path.clone())
            .with_context(|| format!("{id}.fmu was not packaged"))
    };
    let (vehicle, estimator) = (find("RailVehicle")?, find("AlignmentEstimator")?);
    let studies = build_binaries()?.studies;
    let out = workspace::target_dir()?.join("demo");
    let study_dir = out.join("study");
    std::fs::create_dir_all(&study_dir)
        .with_context(|| format!("cannot create {}", study_dir.display()))?;
    // Each step's own output goes to a log; the screen gets one line per step.
    let logged = |what: &str, cmd: &mut Command, log: &std::path::Path| -> Result<()> {
        println!("==> {what} (log: {})", log.display());
        let file = std::fs::File::create(log)
            .with_context(|| format!("cannot create {}", log.display()))?;
        cmd.stdout(file.try_clone()?).stderr(file);
        workspace::run(cmd).with_context(|| format!("see {}", log.display()))
    };
    let mut run = Command::new(&studies);
    run.arg("run")
        .arg("--vehicle")
        .arg(&vehicle)
        .arg("--estimator")
        .arg(&estimator)
        .arg("--out")
        .arg(&out)
        .arg("--quiet");
    logged(
        "alignment-studies run: the standard case (studies/standard.ssd), RailVehicle.fmu -> AlignmentEstimator.fmu, 20 s at 1 ms",
        &mut run,
        &out.join("run.log"),
    )?;
    // The studies share the FMUs, the output directory and the extra arguments.
    let study = |command: &str, what: &str| {
        let mut study = Command::new(&studies);
        study
            .arg(command)
            .arg("--vehicle")
            .arg(&vehicle)
            .arg("--estimator")
            .arg(&estimator)
            .arg("--out")
            .arg(&study_dir)
            .arg("--quiet")
            .args(&extra);
        logged(
            &format!("alignment-studies {command}: {what}"),
            &mut study,
            &study_dir.join(format!("{command}.log")),
        )
    };
    study("all", "the paper's cases on held-out track seeds")?;
    study(
        "variants",
        "the estimator FMU's estimators and the filter's options",
    )?;
    // The fleet: the Python bindings, a synthetic fleet of vehicle passes, the Dask pipeline.
    let fleet_dir = out.join("fleet");
    std::fs::create_dir_all(&fleet_dir)
        .with_context(|| format!("cannot create {}", fleet_dir.display()))?;
    python::ensure_venv()?;
    logged(
        "maturin develop: the Python bindings (track_alignment) into .venv",
        &mut python::bindings_command(),
        &fleet_dir.join("bindings.log"),
    )?;
    let mut synth = Command::new(python::python());
    synth
        .args([
            "-m",
            "track_alignment.synthetic",
            "--passes",
            "20",
            "--vehicle-fmu",
        ])
        .arg(&vehicle)
        .arg("--out")
        .arg(fleet_dir.join("passes"));
    logged(
        "track_alignment.synthetic: 20 passes of the vehicle FMU over one 1 km track (Parquet)",
        &mut synth,
        &fleet_dir.join("synthetic.log"),
    )?;
    let mut pipeline = Command::new(python::python());
    pipeline
        .args(["-m", "track_alignment.fleet", "--workers", "2", "--truth"])
        .arg(fleet_dir.join("passes").join("truth.parquet"))
        .arg(fleet_dir.join("passes"))
        .arg("--out")
        .arg(&fleet_dir);
    logged(
        "track-alignment-fleet: the track-quality map on a 2-worker Dask LocalCluster",
        &mut pipeline,
        &fleet_dir.join("fleet.log"),
    )?;
    headline(&study_dir.join("variants.json"))?;
    println!(
        "\nFull reports: {} (the paper's cases) and {} (the estimators and options); the standard run: {}; the fleet map: {} and segments.parquet",
        study_dir.join("report.md").display(),
        study_dir.join("variants.md").display(),
        out.join("results.csv").display(),
        fleet_dir.join("map.png").display()
    );
    Ok(())
}

/// The paper's Jrel for the standard case, whole / D1 / D2 / D3 (its results table).
const PAPER: [f64; 4] = [0.25, 0.48, 0.26, 0.15];

/// Prints the headline table from `alignment-studies variants`' JSON: the standard case's estimator-FMU rows
/// (mean Jrel over the held-out seeds) under the paper's.
fn headline(json: &std::path::Path) -> Result<()> {
    let text =
        std::fs::read_to_string(json).with_context(|| format!("cannot read {}", json.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", json.display()))?;
    let seeds: Vec<String> = v["seeds"]
        .as_array()
        .map(|a| a.iter().map(|s| s.to_string()).collect())
        .unwrap_or_default();
    let rows = v["estimator_fmu"]["standard"]
        .as_array()
        .with_context(|| format!("{}: no estimator_fmu.standard table", json.display()))?;
    println!(
        "\nAlignment accuracy, standard case (20 s at 20 m/s), Jrel mean over held-out track seeds {}:\n",
        seeds.join(", ")
    );
    println!("| estimator | whole 3-200 m | D1 3-25 m | D2 25-70 m | D3 70-200 m |");
    println!("|---|---|---|---|---|");
    let fmt = |x: &[f64]| {
        x.iter()
            .map(|j| format!("{j:.3}"))
            .collect::<Vec<_>>()
            .join(" | ")
    };
    println!("| the paper (its own vehicle) | {} |", fmt(&PAPER));
    for r in rows {
        let name = r["name"].as_str().unwrap_or("?");
        let bands: Vec<f64> = r["bands"]
            .as_array()
            .map(|b| b.iter().filter_map(|x| x[1].as_f64()).collect())
            .unwrap_or_default();
        println!("| {name} | {} |", fmt(&bands));
    }
    Ok(())
}
