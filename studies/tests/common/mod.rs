//! Where the tests find the packaged FMUs: `$XTASK_FMU_DIR` (set by `cargo xtask test`) or
//! `<workspace>/target/fmu`, packaged once with `cargo xtask fmu` when missing.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

pub fn fmu(name: &str) -> PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .unwrap()
            .to_path_buf();
        let dir = std::env::var_os("XTASK_FMU_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| root.join("target/fmu"));
        let wanted = [
            "Dahlquist",
            "Feedthrough",
            "RailVehicle",
            "AlignmentEstimator",
        ];
        if wanted
            .iter()
            .any(|n| !dir.join(format!("{n}.fmu")).exists())
        {
            let status = std::process::Command::new(env!("CARGO"))
                .args(["xtask", "fmu"])
                .current_dir(&root)
                .status()
                .expect("cargo xtask fmu");
            assert!(status.success(), "cargo xtask fmu failed");
        }
        dir
    });
    dir.join(format!("{name}.fmu"))
}
