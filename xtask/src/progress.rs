//! Progress on screen for the long steps: a line before each saying what it does and about
//! how long it takes, then, while it runs, a heartbeat every [`HEARTBEAT`] with the elapsed
//! time and the last line the step wrote to its log, so a silent minute is not taken for a
//! hang; the step's own output stays in its log.

use crate::workspace::command_line;
use anyhow::{Context, Result, bail};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use std::process::{Child, Command, ExitStatus};
use std::time::{Duration, Instant};

/// Often enough to show that a step lives, seldom enough that maturin's 2.5 min make 7 lines.
pub const HEARTBEAT: Duration = Duration::from_secs(20);

/// The longest heartbeat line, so that it fits an 80-column terminal.
const WIDTH: usize = 78;

/// Announces a step: what it does, about how long it takes, and where its log is.
pub fn announce(what: &str, takes: &str, log: Option<&Path>) {
    match log {
        Some(log) => println!("==> {what} ({takes}; log: {})", log.display()),
        None => println!("==> {what} ({takes})"),
    }
}

/// Runs `cmd` with its output in `log` (created anew), after announcing it, with a heartbeat
/// while it runs and its time when it ends.
pub fn logged(what: &str, takes: &str, cmd: &mut Command, log: &Path) -> Result<()> {
    announce(what, takes, Some(log));
    let file = File::create(log).with_context(|| format!("cannot create {}", log.display()))?;
    cmd.stdout(file.try_clone()?).stderr(file);
    watched(cmd, Some(log)).with_context(|| format!("see {}", log.display()))
}

/// Runs `cmd` to its end with a heartbeat (quoting `log`'s last line if given), then prints
/// its time; fails with the command line if it does not succeed.
pub fn watched(cmd: &mut Command, log: Option<&Path>) -> Result<()> {
    let line = command_line(cmd);
    let start = Instant::now();
    let child = cmd
        .spawn()
        .with_context(|| format!("could not start `{line}`"))?;
    let status = wait(child, start, log)?;
    println!("    {} done", clock(start.elapsed()));
    if !status.success() {
        bail!("`{line}` failed ({status})");
    }
    Ok(())
}

fn wait(mut child: Child, start: Instant, log: Option<&Path>) -> Result<ExitStatus> {
    let mut next = HEARTBEAT;
    loop {
        if let Some(status) = child.try_wait().context("waiting for a child process")? {
            return Ok(status);
        }
        let elapsed = start.elapsed();
        if elapsed >= next {
            let last = log.and_then(last_line);
            println!("{}", heartbeat(elapsed, last.as_deref()));
            next += HEARTBEAT;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// `m:ss`.
pub fn clock(d: Duration) -> String {
    let s = d.as_secs();
    format!("{}:{:02}", s / 60, s % 60)
}

/// One heartbeat line: the elapsed time and, if there is one, the log's last line, cut to
/// fit [`WIDTH`].
fn heartbeat(elapsed: Duration, last: Option<&str>) -> String {
    let line = format!("    {} running", clock(elapsed));
    match last {
        Some(text) => {
            let room = WIDTH.saturating_sub(line.len() + 3);
            let cut: String = if text.chars().count() > room {
                let mut s: String = text.chars().take(room.saturating_sub(3)).collect();
                s.push_str("...");
                s
            } else {
                text.to_string()
            };
            format!("{line}: {cut}")
        }
        None => line,
    }
}

/// The last non-blank line of a log (its last 4 KiB read; a progress bar's `\r` also ends a
/// line), in plain text.
fn last_line(log: &Path) -> Option<String> {
    let mut file = File::open(log).ok()?;
    let len = file.metadata().ok()?.len();
    file.seek(SeekFrom::Start(len.saturating_sub(4096))).ok()?;
    let mut bytes = vec![];
    file.read_to_end(&mut bytes).ok()?;
    last_of(&String::from_utf8_lossy(&bytes))
}

fn last_of(text: &str) -> Option<String> {
    text.split(['\n', '\r']).map(plain).rfind(|l| !l.is_empty())
}

/// A line without ANSI sequences (`ESC [ ... letter`: colours) and control characters, trimmed.
fn plain(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            if chars.clone().next() == Some('[') {
                chars.find(char::is_ascii_alphabetic);
            }
        } else if !c.is_control() {
            out.push(c);
        }
    }
    out.trim().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clock_is_minutes_and_seconds() {
        assert_eq!(clock(Duration::from_millis(59_999)), "0:59");
        assert_eq!(clock(Duration::from_secs(150)), "2:30");
        assert_eq!(clock(Duration::from_secs(3725)), "62:05");
    }

    #[test]
    fn heartbeat_quotes_the_log_within_the_width() {
        let d = Duration::from_secs(40);
        assert_eq!(heartbeat(d, None), "    0:40 running");
        assert_eq!(
            heartbeat(d, Some("Compiling pyo3 v0.23.1")),
            "    0:40 running: Compiling pyo3 v0.23.1"
        );
        let long = heartbeat(d, Some(&"x".repeat(200)));
        assert_eq!(long.chars().count(), WIDTH - 1);
        assert!(long.ends_with("x..."));
    }

    #[test]
    fn last_line_of_a_log() {
        assert_eq!(last_of(""), None);
        assert_eq!(last_of("a\nb\n\n  \n"), Some("b".into()));
        // A progress bar redrawn with carriage returns, in colour.
        assert_eq!(
            last_of(
                "one\n\u{1b}[1m\u{1b}[32mBuilding\u{1b}[0m 10%\r\u{1b}[32mBuilding\u{1b}[0m 20%"
            ),
            Some("Building 20%".into())
        );
        assert_eq!(last_of("[2/5] step\n"), Some("[2/5] step".into()));
    }

    #[cfg(unix)]
    #[test]
    fn a_logged_step_fails_with_its_command_line() {
        let dir = std::env::temp_dir().join(format!("xtask-progress-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let log = dir.join("step.log");
        let mut ok = Command::new("sh");
        ok.args(["-c", "echo first; echo last"]);
        logged("a step", "instant", &mut ok, &log).unwrap();
        assert_eq!(std::fs::read_to_string(&log).unwrap(), "first\nlast\n");
        assert_eq!(last_line(&log), Some("last".into()));
        let mut bad = Command::new("sh");
        bad.args(["-c", "echo why >&2; exit 3"]);
        let e = format!(
            "{:#}",
            logged("a step", "instant", &mut bad, &log).unwrap_err()
        );
        assert!(
            e.starts_with(&format!("see {}: `sh -c echo why", log.display())),
            "{e}"
        );
        assert!(e.contains("exit status: 3"), "{e}");
        assert_eq!(std::fs::read_to_string(&log).unwrap(), "why\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
