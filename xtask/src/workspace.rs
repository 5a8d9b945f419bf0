//! Where things are: the workspace root, cargo, the target directory; and running commands.

use anyhow::{Context, Result, bail};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The workspace root (xtask lives one level below it).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask is inside the workspace")
        .to_path_buf()
}

/// The cargo that runs us (`cargo xtask` sets `CARGO`), so nested builds use the same toolchain.
/// Once [`lint_builds`] was called, its builds also lint the workspace's crates.
pub fn cargo() -> Command {
    let mut cmd = Command::new(cargo_program());
    cmd.current_dir(root());
    with_lints(&mut cmd);
    cmd
}

fn cargo_program() -> std::ffi::OsString {
    std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into())
}

/// The clippy driver every later cargo command compiles the workspace's crates with.
static LINT_DRIVER: OnceLock<PathBuf> = OnceLock::new();

/// From now on, every cargo command of [`cargo`] (and maturin's, through [`with_lints`])
/// compiles the workspace's own crates with clippy's driver, which is rustc plus clippy's lints:
/// the builds the suite needs anyway report clippy's warnings, and no separate `cargo clippy`
/// checks every crate and dependency once more (145 s of a cold suite on 2 cores). Dependencies
/// are compiled by rustc as before and shared with any build. Every build of the suite must see
/// the same driver, or cargo compiles the workspace's crates again for the one that does not.
pub fn lint_builds() -> Result<()> {
    let driver = clippy_driver()?;
    // A second call (none today) keeps the first driver: the builds stay consistent.
    let _ = LINT_DRIVER.set(driver);
    Ok(())
}

/// Adds the clippy driver of [`lint_builds`], if one was chosen, to a command that runs cargo.
pub fn with_lints(cmd: &mut Command) {
    if let Some(driver) = LINT_DRIVER.get() {
        cmd.env("RUSTC_WORKSPACE_WRAPPER", driver);
    }
}

/// `clippy-driver` of the toolchain that runs us: beside its cargo, else on PATH; checked to run.
fn clippy_driver() -> Result<PathBuf> {
    let cargo = PathBuf::from(cargo_program());
    let beside = cargo.with_file_name(format!("clippy-driver{}", std::env::consts::EXE_SUFFIX));
    let driver = if cargo.parent().is_some_and(|p| !p.as_os_str().is_empty()) && beside.is_file() {
        beside
    } else {
        PathBuf::from("clippy-driver")
    };
    let runs = Command::new(&driver)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !runs {
        bail!(
            "`{}` does not run: the suite lints with clippy (`rustup component add clippy`)",
            driver.display()
        );
    }
    Ok(driver)
}

/// The cargo profile a build uses.
///
/// Why two: the demo, `cargo xtask fmu` and the benchmarks build what ships, in release (thin LTO,
/// one codegen unit: the fastest code, the slowest build). The test suite builds its FMUs and
/// programs in the dev profile (every crate at opt-level 2, Cargo.toml), the one `cargo test`
/// compiles the workspace in anyway, so the dependencies are compiled once, not twice (a cold
/// suite spent about 5 of its 27 minutes on the release build). Neither profile lets LLVM
/// reorder floating-point operations or contract them into FMAs, so both give the same numbers:
/// the golden references (`tests/test_golden.py`, made with release FMUs) check that.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    Release,
    Dev,
}

impl Profile {
    /// The flag `cargo build` takes for it.
    pub fn flags(self) -> &'static [&'static str] {
        match self {
            Profile::Release => &["--release"],
            Profile::Dev => &[],
        }
    }

    /// Its output directory under the target directory.
    pub fn dir(self) -> &'static str {
        match self {
            Profile::Release => "release",
            Profile::Dev => "debug",
        }
    }

    /// Where its packaged FMUs go under the target directory: `fmu` for release (what users
    /// and `tests/project.py` take by default), `fmu-dev` for the test suite's.
    pub fn fmu_dir(self) -> &'static str {
        match self {
            Profile::Release => "fmu",
            Profile::Dev => "fmu-dev",
        }
    }
}

/// Cargo's target directory, as cargo itself resolves it (CARGO_TARGET_DIR, `build.target-dir`
/// in a config file, or `<workspace>/target`).
pub fn target_dir() -> Result<PathBuf> {
    let out = cargo()
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .output()
        .context("running cargo metadata")?;
    if !out.status.success() {
        bail!(
            "cargo metadata failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let json = String::from_utf8(out.stdout).context("cargo metadata printed non-UTF-8")?;
    json_string_field(&json, "target_directory")
        .map(PathBuf::from)
        .context("cargo metadata's output has no \"target_directory\"")
}

/// The string value of the first `"key":"..."` in a JSON text (enough for cargo metadata's
/// top-level `target_directory`, which comes after the packages but is the only key of that name).
fn json_string_field(json: &str, key: &str) -> Option<String> {
    let pattern = format!("\"{key}\":\"");
    let start = json.rfind(&pattern)? + pattern.len();
    let mut out = String::new();
    let mut chars = json[start..].chars();
    while let Some(c) = chars.next() {
        match c {
            '"' => return Some(out),
            '\\' => match chars.next()? {
                'n' => out.push('\n'),
                't' => out.push('\t'),
                'r' => out.push('\r'),
                'b' => out.push('\u{8}'),
                'f' => out.push('\u{c}'),
                'u' => {
                    let hex: String = chars.by_ref().take(4).collect();
                    out.push(char::from_u32(u32::from_str_radix(&hex, 16).ok()?)?);
                }
                other => out.push(other), // \" \\ \/
            },
            c => out.push(c),
        }
    }
    None
}

/// Runs a command with inherited stdio, failing with the command line if it does not succeed.
pub fn run(cmd: &mut Command) -> Result<()> {
    let line = command_line(cmd);
    let status = cmd
        .status()
        .with_context(|| format!("could not start `{line}`"))?;
    if !status.success() {
        bail!("`{line}` failed ({status})");
    }
    Ok(())
}

/// A command as a readable line, for messages.
pub fn command_line(cmd: &Command) -> String {
    let program = Path::new(cmd.get_program())
        .file_name()
        .unwrap_or(OsStr::new("?"))
        .to_string_lossy()
        .into_owned();
    std::iter::once(program)
        .chain(cmd.get_args().map(|a| a.to_string_lossy().into_owned()))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_target_directory_with_escapes() {
        let json = r#"{"packages":[],"target_directory":"/a \"b\"\\c\u00e9","version":1}"#;
        assert_eq!(
            json_string_field(json, "target_directory").unwrap(),
            "/a \"b\"\\c\u{e9}"
        );
        assert_eq!(json_string_field(json, "missing"), None);
    }
}
