//! The two release programs the tests and the demo run (the master and the studies on top of
//! it), and the environment variables that tell the test suites where they and the FMUs are.

use crate::workspace;
use anyhow::Result;
use std::path::PathBuf;
use std::process::Command;

/// Where the orchestrator binary is, for the tests that run it.
const ORCHESTRATOR_ENV: &str = "ORCHESTRATOR";
/// Where the studies' binary is, for the tests that run it.
const STUDIES_ENV: &str = "ALIGNMENT_STUDIES";

/// The environment variable telling the test suites where the packaged FMUs are (the target
/// directory may be moved by CARGO_TARGET_DIR or cargo config).
pub const FMU_DIR_ENV: &str = "XTASK_FMU_DIR";

/// The two programs: the master and the studies on top of it.
pub struct Binaries {
    pub orchestrator: PathBuf,
    pub studies: PathBuf,
}

impl Binaries {
    /// Tells a test run where they are.
    pub fn env(&self, cmd: &mut Command) {
        cmd.env(ORCHESTRATOR_ENV, &self.orchestrator)
            .env(STUDIES_ENV, &self.studies);
    }
}

/// Builds the orchestrator and alignment-studies in release and returns the binaries' paths.
pub fn build() -> Result<Binaries> {
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
