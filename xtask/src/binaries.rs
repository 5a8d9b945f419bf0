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

/// Builds the orchestrator and alignment-studies in `profile` and returns the binaries' paths.
pub fn build(profile: Profile) -> Result<Binaries> {
    let mut cmd = workspace::cargo();
    cmd.arg("build").args(profile.flags());
    workspace::run(cmd.args(["-p", "orchestrator", "-p", "alignment-studies"]))?;
    built(profile)
}

/// The two programs a build in `profile` made (`cargo test --no-run` makes them too, in the
/// dev profile's directory, for the crates' integration tests), checked to exist.
pub fn built(profile: Profile) -> Result<Binaries> {
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
