//! The Python environment of the test harness: `<workspace>/.venv` with the pinned
//! `tests/requirements.txt`. Created on first use (CI machines start without it) and reinstalled
//! only when the requirements change, detected by a stamp file holding their hash.

use crate::workspace::{command_line, root, run};
use anyhow::{Context, Result, bail};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

const STAMP: &str = ".xtask-requirements-hash";

/// The oldest Python the pinned packages support (numpy 2.4 and scipy 1.17 need 3.11).
const MIN_PYTHON: (u32, u32) = (3, 11);

pub fn venv_dir() -> PathBuf {
    root().join(".venv")
}

/// The venv's interpreter.
pub fn python() -> PathBuf {
    if cfg!(windows) {
        venv_dir().join("Scripts").join("python.exe")
    } else {
        venv_dir().join("bin").join("python")
    }
}

/// Makes sure `.venv` exists and holds the pinned requirements; returns its interpreter.
pub fn ensure_venv() -> Result<PathBuf> {
    ensure_venv_into(None)
}

/// [`ensure_venv`] with every output in `log` (created anew) and nothing on screen: the suite
/// makes the venv while cargo compiles (pip mostly waits on the network and the disk), and its
/// output would cut into cargo's.
pub fn ensure_venv_logged(log: &Path) -> Result<PathBuf> {
    ensure_venv_into(Some(log))
}

fn ensure_venv_into(log: Option<&Path>) -> Result<PathBuf> {
    let requirements = root().join("tests").join("requirements.txt");
    let text =
        fs::read(&requirements).with_context(|| format!("reading {}", requirements.display()))?;
    let hash = format!("{:016x}", fnv1a64(&text));
    let venv = venv_dir();
    let stamp = venv.join(STAMP);
    let mut out = Output::new(log)?;

    if !runs(&python()) {
        create_venv(&mut out)?;
    } else if fs::read_to_string(&stamp).is_ok_and(|s| s.trim() == hash) {
        return Ok(python());
    }
    let mut pip = Command::new(python());
    pip.current_dir(root())
        .args([
            "-m",
            "pip",
            "install",
            "--disable-pip-version-check",
            "--quiet",
            "-r",
        ])
        .arg(&requirements);
    let why = "installing the Python test requirements (is the package index reachable?)";
    match &mut out {
        Output::Screen => {
            // pip is quiet for minutes on a first install: the heartbeat shows it works.
            crate::progress::announce(
                "installing tests/requirements.txt into .venv",
                "pip, about 1 min on a first install",
                None,
            );
            crate::progress::watched(&mut pip, None).context(why)?;
        }
        Output::Log(..) => out.run(&mut pip).context(why)?,
    }
    fs::write(&stamp, format!("{hash}\n"))
        .with_context(|| format!("writing {}", stamp.display()))?;
    Ok(python())
}

/// Where the venv's steps write: the screen, or a log file.
enum Output {
    Screen,
    Log(PathBuf, fs::File),
}

impl Output {
    fn new(log: Option<&Path>) -> Result<Self> {
        Ok(match log {
            None => Output::Screen,
            Some(p) => Output::Log(
                p.to_path_buf(),
                fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
            ),
        })
    }

    fn say(&mut self, text: &str) -> Result<()> {
        match self {
            Output::Screen => println!("{text}"),
            Output::Log(p, f) => {
                writeln!(f, "{text}").with_context(|| format!("writing {}", p.display()))?
            }
        }
        Ok(())
    }

    /// Runs `cmd` to its end, its output here; fails with the command line (and the log's
    /// path) if it does not succeed.
    fn run(&mut self, cmd: &mut Command) -> Result<()> {
        match self {
            Output::Screen => run(cmd),
            Output::Log(p, f) => {
                cmd.stdout(f.try_clone()?).stderr(f.try_clone()?);
                run(cmd).with_context(|| format!("its output is in {}", p.display()))
            }
        }
    }
}

/// Builds the Python bindings (`bindings/`, PyO3) and installs them into `.venv` as the package
/// `track_alignment`, with the pinned maturin. The dev profile (optimized, see Cargo.toml) reuses
/// the libraries `cargo test` compiled, where a release build would compile the workspace again
/// (minutes of CI); benchmarks build with `maturin develop --release`.
pub fn install_bindings() -> Result<()> {
    let mut cmd = bindings_command();
    let line = command_line(&cmd);
    run(&mut cmd).with_context(|| format!("`{line}` could not build the Python bindings"))
}

/// The `maturin develop` command of [`install_bindings`], for a caller that logs its output.
pub fn bindings_command() -> Command {
    let bin = if cfg!(windows) { "Scripts" } else { "bin" };
    let maturin = venv_dir().join(bin).join("maturin");
    let mut cmd = Command::new(&maturin);
    cmd.current_dir(root())
        .env("VIRTUAL_ENV", venv_dir())
        .args(["develop", "--manifest-path"])
        .arg(root().join("bindings").join("Cargo.toml"));
    // The same compiler as the suite's other builds, so the workspace's crates are reused.
    crate::workspace::with_lints(&mut cmd);
    cmd
}

/// Whether an interpreter starts at all (a venv whose base Python was removed does not).
fn runs(python: &std::path::Path) -> bool {
    Command::new(python)
        .args(["-c", "pass"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// `python3 -m venv .venv`, with clear messages for the usual reasons it fails. The base
/// interpreter is `$PYTHON` if set, else `python3`.
fn create_venv(out: &mut Output) -> Result<()> {
    let base = std::env::var_os("PYTHON").unwrap_or_else(|| "python3".into());
    let shown = base.to_string_lossy().into_owned();
    let version = Command::new(&base)
        .args(["-c", "import sys; print(sys.version_info[0], sys.version_info[1])"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .with_context(|| format!("`{shown}` does not run: install Python {}.{} or newer, or set PYTHON to an interpreter", MIN_PYTHON.0, MIN_PYTHON.1))?;
    let version = String::from_utf8_lossy(&version.stdout).into_owned();
    let parsed: Vec<u32> = version
        .split_whitespace()
        .filter_map(|s| s.parse().ok())
        .collect();
    if parsed.len() != 2 || (parsed[0], parsed[1]) < MIN_PYTHON {
        bail!(
            "`{shown}` is Python {}, the test requirements need {}.{} or newer (set PYTHON to another interpreter)",
            version.trim(),
            MIN_PYTHON.0,
            MIN_PYTHON.1
        );
    }
    let ensurepip = Command::new(&base)
        .args(["-c", "import ensurepip, venv"])
        .output();
    if !ensurepip.is_ok_and(|o| o.status.success()) {
        bail!(
            "`{shown}` lacks the ensurepip/venv modules, so it cannot create .venv with pip in it.\n\
             On Debian/Ubuntu install them with `apt-get install python{}.{}-venv` (or `python3-venv`), then rerun.",
            parsed[0],
            parsed[1]
        );
    }
    out.say(&format!(
        "creating .venv with {shown} (Python {}.{})",
        parsed[0], parsed[1]
    ))?;
    let mut cmd = Command::new(&base);
    cmd.current_dir(root()).args(["-m", "venv"]).arg(venv_dir());
    let line = command_line(&cmd);
    out.run(&mut cmd).with_context(|| {
        format!(
            "`{line}` could not create the virtual environment (if the output above mentions ensurepip, \
             install python{}.{}-venv or python3-venv and rerun)",
            parsed[0], parsed[1]
        )
    })?;
    if !runs(&python()) {
        bail!(
            "{} was created but its interpreter {} does not run",
            venv_dir().display(),
            python().display()
        );
    }
    Ok(())
}

/// FNV-1a, 64 bit: a stable hash (unlike std's, which may change between Rust releases), enough
/// to notice an edited requirements file.
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn fnv1a64_reference_values() {
        // Published test vectors of FNV-1a 64.
        assert_eq!(super::fnv1a64(b""), 0xcbf29ce484222325);
        assert_eq!(super::fnv1a64(b"a"), 0xaf63dc4c8601ec8c);
        assert_eq!(super::fnv1a64(b"foobar"), 0x85944171f73967e8);
    }
}
