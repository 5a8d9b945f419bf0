//! The suite's lint stage: a warning of clippy or rustc in any of the workspace's crates fails it,
//! as `cargo clippy --all-targets -- -D warnings` did.
//!
//! Why no `cargo clippy`: the suite's builds compile the workspace's crates with clippy's driver
//! ([`crate::workspace::lint_builds`]), so they print clippy's warnings as they compile. Cargo
//! keeps every crate's compiler messages and prints them again when it finds the crate fresh, so
//! running the same builds a second time (nothing left to compile) lists every warning of every
//! crate in a few seconds, without checking each crate and dependency once more.

use crate::workspace::command_line;
use anyhow::{Context, Result, bail};
use std::process::Command;

/// Runs each build again and fails, with the builds' messages, if cargo reports a warning in
/// any crate. A build that fails (a compile error) fails the stage with its output.
pub fn check(builds: Vec<Command>) -> Result<()> {
    let mut units = Vec::new();
    let mut messages = String::new();
    for mut cmd in builds {
        let line = command_line(&cmd);
        let out = cmd
            .output()
            .with_context(|| format!("could not start `{line}`"))?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        if !out.status.success() {
            eprint!("{stderr}");
            bail!("`{line}` failed ({})", out.status);
        }
        let warned = warned_units(&stderr);
        if !warned.is_empty() {
            messages += &stderr;
            units.extend(warned);
        }
    }
    if units.is_empty() {
        println!("no warning in any crate");
        return Ok(());
    }
    eprint!("{messages}");
    units.sort();
    units.dedup();
    bail!(
        "{} unit(s) have warnings, which the suite takes as errors (clippy or rustc): {}",
        units.len(),
        units.join(", ")
    )
}

/// The units cargo's summary lines name as having warnings: from
/// ``warning: `crate` (lib test) generated 2 warnings (run `cargo clippy --fix ...`)``,
/// ``crate (lib test)``. Cargo's own warnings (about a manifest, say) have no such line.
fn warned_units(stderr: &str) -> Vec<String> {
    stderr
        .lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("warning: `")?;
            let (unit, tail) = rest.split_once(") generated ")?;
            let count = tail.split_whitespace().next()?;
            count.parse::<u32>().ok()?;
            Some(format!("{})", unit.replacen('`', "", 1)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::warned_units;

    #[test]
    fn finds_the_units_cargo_says_warned() {
        // Lines as cargo 1.95 prints them (the first replayed from its cache).
        let stderr = "warning: the vector is useless\n --> src/main.rs:2:13\n\n\
            warning: `cw` (bin \"cw\") generated 2 warnings (run `cargo clippy --fix --bin \"cw\" -p cw` to apply 2 suggestions)\n\
            warning: `alignment-studies` (lib test) generated 1 warning (1 duplicate)\n\
            warning: unused manifest key: package.foo\n\
            warning: `x` (lib) generated many warnings\n\
                Finished `dev` profile [unoptimized + debuginfo] target(s) in 0.01s\n";
        assert_eq!(
            warned_units(stderr),
            ["cw (bin \"cw\")", "alignment-studies (lib test)"]
        );
        assert!(warned_units("    Finished `dev` profile\n").is_empty());
    }
}
