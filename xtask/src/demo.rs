//! `cargo xtask demo`: packages the FMUs, builds the binaries, runs the standard case with
//! `alignment-studies run` (through the master's library, loading the .fmu files; it writes
//! results.csv and metrics.json), the paper's studies and the variants on held-out track seeds,
//! then the fleet (the Python bindings, a synthetic fleet, the Dask pipeline); each step's
//! output goes to a log beside its results, the screen gets a line per step saying what it does
//! and about how long it takes, a heartbeat while it runs ([`progress`]), and at the end the
//! [`headline`] and where the full reports are.
//!
//! The durations announced are those of a run on 2 cores with the release build up to date.

use crate::progress::{self, logged};
use crate::workspace::{self, Profile};
use crate::{binaries, headline, headline_curves, package, python};
use anyhow::{Context, Result};
use std::path::Path;
use std::process::Command;

pub fn demo(extra: Vec<String>) -> Result<()> {
    progress::announce(
        "cargo build --release: the FMUs, packaged into .fmu archives, then the orchestrator and alignment-studies",
        "seconds when up to date, several minutes from a fresh clone; cargo shows its progress",
        None,
    );
    let packaged = package::build_and_package(Profile::Release)?;
    let find = |id: &str| {
        packaged
            .iter()
            .find(|p| p.model_identifier == id)
            .map(|p| p.path.clone())
            .with_context(|| format!("{id}.fmu was not packaged"))
    };
    let (vehicle, estimator) = (find("RailVehicle")?, find("AlignmentEstimator")?);
    let studies = binaries::build(Profile::Release)?.studies;
    let out = workspace::target_dir()?.join("demo");
    let study_dir = out.join("study");
    create_dir(&study_dir)?;
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
        "about 1 s",
        &mut run,
        &out.join("run.log"),
    )?;
    // The studies share the FMUs, the output directory and the extra arguments.
    let study = |command: &str, what: &str, takes: &str| {
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
            takes,
            &mut study,
            &study_dir.join(format!("{command}.log")),
        )
    };
    study(
        "all",
        "the paper's cases on held-out track seeds",
        "about 40 s",
    )?;
    study(
        "variants",
        "the estimator FMU's estimators and the filter's options",
        "about 1 min",
    )?;
    fleet(&vehicle, &out.join("fleet"))?;
    let json = study_dir.join("variants.json");
    print!(
        "{}",
        headline::headline(&read_json(&json)?).with_context(|| format!("{}", json.display()))?
    );
    let curves = study_dir.join("curves.json");
    print!(
        "{}",
        headline_curves::curves(&read_json(&curves)?)
            .with_context(|| format!("{}", curves.display()))?
    );
    println!(
        "\nFull reports: {} (the paper's cases) and {} (the estimators and options); the standard run: {}; the fleet map: {} and segments.parquet",
        study_dir.join("report.md").display(),
        study_dir.join("variants.md").display(),
        out.join("results.csv").display(),
        out.join("fleet").join("map.png").display()
    );
    Ok(())
}

/// A study's JSON output, parsed.
fn read_json(path: &Path) -> Result<serde_json::Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))
}

/// The fleet: the Python bindings, a synthetic fleet of vehicle passes, the Dask pipeline.
fn fleet(vehicle: &Path, fleet_dir: &Path) -> Result<()> {
    // The demo's own directory under target/, made anew: the Python commands refuse to replace
    // files no manifest of theirs lists, and a demo of an older version left such files here.
    if fleet_dir.is_dir() {
        std::fs::remove_dir_all(fleet_dir).with_context(|| {
            format!("cannot remove the previous demo's {}", fleet_dir.display())
        })?;
    }
    create_dir(fleet_dir)?;
    python::ensure_venv()?;
    logged(
        "maturin develop: the Python bindings (track_alignment) into .venv",
        "about 2.5 min on 2 cores: cargo compiles the bindings",
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
        .arg(vehicle)
        .arg("--out")
        .arg(fleet_dir.join("passes"));
    logged(
        "track_alignment.synthetic: 20 passes of the vehicle FMU over one 1 km track (Parquet)",
        "about 15 s",
        &mut synth,
        &fleet_dir.join("synthetic.log"),
    )?;
    let mut pipeline = Command::new(python::python());
    pipeline
        .args(["-m", "track_alignment.fleet", "--workers", "2", "--truth"])
        .arg(fleet_dir.join("passes").join("truth.parquet"))
        .arg(fleet_dir.join("passes"))
        .arg("--out")
        .arg(fleet_dir);
    logged(
        "track-alignment-fleet: the track-quality map on a 2-worker Dask LocalCluster",
        "about 10 s",
        &mut pipeline,
        &fleet_dir.join("fleet.log"),
    )
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))
}
