//! The command line of `cargo xtask`: which command, with which options. Parsing only; the
//! commands are in their own modules.

use anyhow::{Result, bail};

pub const USAGE: &str = "\
usage: cargo xtask <command>

commands:
  fmu                          build (release) and package target/fmu/<id>.fmu
  test [--rust-only | --python-only] [-- <pytest args>]
                               packaging, cargo fmt --check, doc -D warnings, cargo test --workspace, pytest tests/ in .venv, clippy -D warnings
  demo [-- <study args>]       package the FMUs, run the standard case and the studies (alignment-studies)
  help                         this text";

/// What the command line asks for.
#[derive(Debug, PartialEq)]
pub enum Command {
    Fmu,
    Test(TestOptions),
    /// The extra arguments for the studies.
    Demo(Vec<String>),
    Help,
    /// No command, an unknown one, or arguments after `fmu`: the usage on stderr, exit code 2.
    Usage,
}

/// The command line after the program name. A command's bad options are an error (exit code
/// 1, as before the split); no command or an unknown one is [`Command::Usage`].
pub fn parse(args: &[String]) -> Result<Command> {
    Ok(match args.first().map(String::as_str) {
        Some("fmu") if args.len() == 1 => Command::Fmu,
        Some("test") => Command::Test(TestOptions::parse(&args[1..])?),
        Some("demo") => Command::Demo(passthrough(&args[1..])?),
        Some("help" | "-h" | "--help") => Command::Help,
        _ => Command::Usage,
    })
}

/// Arguments after a leading `--` (or none); anything else is a usage error.
fn passthrough(args: &[String]) -> Result<Vec<String>> {
    match args.split_first() {
        None => Ok(vec![]),
        Some((first, rest)) if first == "--" => Ok(rest.to_vec()),
        Some((first, _)) => {
            bail!("unexpected argument '{first}' (extra arguments go after `--`)\n\n{USAGE}")
        }
    }
}

/// `cargo xtask test`'s options: which halves of the suite, and pytest's extra arguments.
#[derive(Debug, PartialEq)]
pub struct TestOptions {
    pub rust: bool,
    pub python: bool,
    pub pytest_args: Vec<String>,
}

impl TestOptions {
    fn parse(args: &[String]) -> Result<TestOptions> {
        let mut o = TestOptions {
            rust: true,
            python: true,
            pytest_args: vec![],
        };
        let mut i = 0;
        while i < args.len() {
            match args[i].as_str() {
                "--rust-only" => o.python = false,
                "--python-only" => o.rust = false,
                "--" => {
                    o.pytest_args = args[i + 1..].to_vec();
                    break;
                }
                other => bail!(
                    "unknown option '{other}' for `test` (pytest arguments go after `--`)\n\n{USAGE}"
                ),
            }
            i += 1;
        }
        if !o.rust && !o.python {
            bail!("--rust-only and --python-only exclude each other");
        }
        Ok(o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Command> {
        super::parse(&args.iter().map(|a| a.to_string()).collect::<Vec<_>>())
    }

    fn error(args: &[&str]) -> String {
        format!("{:#}", parse(args).unwrap_err())
    }

    #[test]
    fn commands() {
        assert_eq!(parse(&["fmu"]).unwrap(), Command::Fmu);
        for help in ["help", "-h", "--help"] {
            assert_eq!(parse(&[help]).unwrap(), Command::Help);
        }
        assert_eq!(parse(&["demo"]).unwrap(), Command::Demo(vec![]));
        assert_eq!(
            parse(&["demo", "--", "--seeds", "1,2"]).unwrap(),
            Command::Demo(vec!["--seeds".into(), "1,2".into()])
        );
        let all = TestOptions {
            rust: true,
            python: true,
            pytest_args: vec![],
        };
        assert_eq!(parse(&["test"]).unwrap(), Command::Test(all));
        assert_eq!(
            parse(&["test", "--python-only", "--", "tests/test_parquet.py", "-x"]).unwrap(),
            Command::Test(TestOptions {
                rust: false,
                python: true,
                pytest_args: vec!["tests/test_parquet.py".into(), "-x".into()],
            })
        );
        let Command::Test(o) = parse(&["test", "--rust-only"]).unwrap() else {
            panic!("not test")
        };
        assert!(o.rust && !o.python);
    }

    #[test]
    fn no_command_or_an_unknown_one_is_the_usage() {
        assert_eq!(parse(&[]).unwrap(), Command::Usage);
        assert_eq!(parse(&["bogus"]).unwrap(), Command::Usage);
        assert_eq!(parse(&["fmu", "extra"]).unwrap(), Command::Usage);
    }

    #[test]
    fn bad_options_name_the_option() {
        assert!(error(&["test", "--bogus"]).starts_with("unknown option '--bogus' for `test`"));
        assert!(error(&["test", "--rust-only", "--python-only"]).contains("exclude each other"));
        // The pytest arguments need their `--`, the studies' arguments too.
        assert!(error(&["test", "-x"]).starts_with("unknown option '-x'"));
        assert!(error(&["demo", "--seeds"]).starts_with("unexpected argument '--seeds'"));
    }
}
