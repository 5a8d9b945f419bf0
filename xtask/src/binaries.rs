//! The two programs the tests and the demo run (the master and the studies on top of
//! it), and the environment variables that tell the test suites where they and the FMUs are.

use crate::workspace::{self, Profile};
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

/// The cargo command that builds the two programs in `profile`.
pub fn build_command(profile: Profile) -> Command {
    let mut cmd = workspace::cargo();
    cmd.arg("build")
        .args(profile.flags())
        .args(["-p", "orchestrator", "-p", "alignment-studies"]);
    cmd
}

/// Builds the orchestrator and alignment-studies in `profile` and returns the binaries' paths.
pub fn build(profile: Profile) -> Result<Binaries> {
    workspace::run(&mut build_command(profile))?;
    let dir = workspace::target_dir()?.join(profile.dir());
    let b = Binaries {
        orchestrator: dir.join("orchestrator"),
        studies: dir.join("alignment-studies"),
    };
    for bin in [&b.orchestrator, &b.studies] {
        anyhow::ensure!(bin.exists(), "no binary at {}", bin.display());
    }
    Ok(b)
}
