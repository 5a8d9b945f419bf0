//! Where the tests find the packaged FMUs: `$XTASK_FMU_DIR` (set by `cargo xtask test`) or
//! `<workspace>/target/fmu`, packaged once with `cargo xtask fmu` when missing.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

#[allow(dead_code)] // a test crate may include this module for its other helpers only
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

/// Makes a FIFO at `path`: an output the hostile-input tests must see refused, never opened.
#[allow(dead_code)] // not every test crate that includes this module writes outputs
pub fn mkfifo(path: &Path) {
    let made = std::process::Command::new("mkfifo").arg(path).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo {}", path.display());
}

/// The hidden files in `dir`: what a write through a temporary file leaves if it does not
/// clean up (the temporary files are named `.NAME...`).
#[allow(dead_code)]
pub fn hidden_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// A results CSV's rows (header skipped), every field a number.
#[allow(dead_code)] // only the master's tests read results this way
pub fn rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect()
}
