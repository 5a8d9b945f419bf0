//! `fmu-describe`: what `cargo xtask fmu` writes beside each FMU's shared library, printed on
//! stdout.
//!
//! | command line | prints |
//! |---|---|
//! | `fmu-describe <modelIdentifier> model-description` | its modelDescription.xml, after checking it against the standard's rules ([`ModelDescription::validate`]) and that it names that identifier |
//! | `fmu-describe <modelIdentifier> documentation` | its `documentation/index.html` |
//! | `fmu-describe fmi-functions` | the FMI 2.0 functions a co-simulation library must export, one per line |
//!
//! Why a program of its own: the packager (xtask) would otherwise link every FMU crate to call
//! its `model_description()`. Cargo resolves `cargo xtask`'s dependencies apart from the
//! workspace's builds, so it compiled those crates, and half of their dependencies, once more
//! with other features: about a minute of every fresh build. Built in the same cargo command as
//! the FMUs' libraries, this program shares their compiled crates.
//!
//! Exit codes: 0 printed; 1 the description breaks a rule or names another identifier; 2 a bad
//! command line (the usage on stderr).

use model_description::ModelDescription;
use std::process::ExitCode;

/// One FMU crate: what it is called and what describes it.
struct Fmu {
    model_identifier: &'static str,
    model_description: fn() -> ModelDescription,
    documentation: fn(&str) -> String,
    method_html: &'static str,
}

/// The FMUs this workspace ships (xtask's `fmus.rs` names their packages and libraries).
const FMUS: &[Fmu] = &[
    Fmu {
        model_identifier: "AlignmentEstimator",
        model_description: fmu_estimator::model_description,
        documentation: fmi_abi::description::documentation_html::<fmu_estimator::Estimator>,
        method_html: fmu_estimator::METHOD_HTML,
    },
    Fmu {
        model_identifier: "RailVehicle",
        model_description: fmu_vehicle::model_description,
        documentation: fmi_abi::description::documentation_html::<fmu_vehicle::RailVehicle>,
        method_html: fmu_vehicle::METHOD_HTML,
    },
    Fmu {
        model_identifier: "Dahlquist",
        model_description: fmu_dahlquist::model_description,
        documentation: fmi_abi::description::documentation_html::<fmu_dahlquist::Dahlquist>,
        method_html: fmu_dahlquist::METHOD_HTML,
    },
    Fmu {
        model_identifier: "Feedthrough",
        model_description: fmu_feedthrough::model_description,
        documentation: fmi_abi::description::documentation_html::<fmu_feedthrough::Feedthrough>,
        method_html: fmu_feedthrough::METHOD_HTML,
    },
];

const USAGE: &str = "usage: fmu-describe <modelIdentifier> (model-description | documentation)
       fmu-describe fmi-functions";

/// What went wrong, and the exit code it gets.
enum Failure {
    Usage(String),
    Invalid(String),
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match describe(&args) {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(Failure::Usage(why)) => {
            eprintln!("error: {why}\n{USAGE}");
            ExitCode::from(2)
        }
        Err(Failure::Invalid(why)) => {
            eprintln!("error: {why}");
            ExitCode::FAILURE
        }
    }
}

/// The text the command line asks for.
fn describe(args: &[String]) -> Result<String, Failure> {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    match args.as_slice() {
        ["fmi-functions"] => Ok(fmi_abi::export::FUNCTION_NAMES
            .iter()
            .map(|n| format!("{n}\n"))
            .collect()),
        [id, what] => {
            let fmu = FMUS
                .iter()
                .find(|f| f.model_identifier == *id)
                .ok_or_else(|| {
                    let known: Vec<&str> = FMUS.iter().map(|f| f.model_identifier).collect();
                    Failure::Usage(format!(
                        "no FMU has the modelIdentifier {id:?} (known: {})",
                        known.join(", ")
                    ))
                })?;
            match *what {
                "model-description" => checked_xml(fmu),
                "documentation" => Ok((fmu.documentation)(fmu.method_html)),
                other => Err(Failure::Usage(format!(
                    "unknown part {other:?}: model-description or documentation"
                ))),
            }
        }
        _ => Err(Failure::Usage(format!("{} argument(s) given", args.len()))),
    }
}

/// The FMU's modelDescription.xml, if it keeps the standard's rules and names its identifier.
fn checked_xml(fmu: &Fmu) -> Result<String, Failure> {
    let md = (fmu.model_description)();
    let violations = md.validate();
    if !violations.is_empty() {
        let list: Vec<String> = violations.iter().map(|v| format!("  - {v}")).collect();
        return Err(Failure::Invalid(format!(
            "the model description of {} breaks {} rule(s):\n{}",
            fmu.model_identifier,
            violations.len(),
            list.join("\n")
        )));
    }
    let named = md
        .co_simulation
        .as_ref()
        .map(|cs| cs.model_identifier.as_str());
    if named != Some(fmu.model_identifier) {
        return Err(Failure::Invalid(format!(
            "{}: the model description's modelIdentifier is {named:?}",
            fmu.model_identifier
        )));
    }
    Ok(md.to_xml())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(args: &[&str]) -> Result<String, Failure> {
        describe(&args.iter().map(|a| a.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn every_fmu_description_is_valid_and_names_its_identifier() {
        for f in FMUS {
            let xml = match run(&[f.model_identifier, "model-description"]) {
                Ok(x) => x,
                Err(Failure::Invalid(why) | Failure::Usage(why)) => panic!("{why}"),
            };
            let id = format!("modelIdentifier=\"{}\"", f.model_identifier);
            assert!(xml.starts_with("<?xml") && xml.contains(&id), "{xml:.300}");
            let html = run(&[f.model_identifier, "documentation"]).ok().unwrap();
            assert!(
                html.contains("<html") && html.contains(f.method_html),
                "{html:.300}"
            );
        }
    }

    #[test]
    fn a_description_that_breaks_a_rule_or_names_another_identifier_is_refused() {
        fn broken() -> ModelDescription {
            let mut md = fmu_dahlquist::model_description();
            md.fmi_version = "1.0".into();
            md
        }
        fn renamed() -> ModelDescription {
            let mut md = fmu_dahlquist::model_description();
            md.co_simulation.as_mut().unwrap().model_identifier = "Other".into();
            md
        }
        let fmu = |model_description| Fmu {
            model_identifier: "Dahlquist",
            model_description,
            documentation: |_| String::new(),
            method_html: "",
        };
        match checked_xml(&fmu(broken)) {
            Err(Failure::Invalid(why)) => assert!(why.contains("breaks 1 rule"), "{why}"),
            _ => panic!("a broken description passed"),
        }
        match checked_xml(&fmu(renamed)) {
            Err(Failure::Invalid(why)) => assert!(why.contains("\"Other\""), "{why}"),
            _ => panic!("a renamed description passed"),
        }
    }

    #[test]
    fn the_command_line_is_checked() {
        let names = run(&["fmi-functions"]).ok().unwrap();
        assert_eq!(names.lines().count(), fmi_abi::export::FUNCTION_NAMES.len());
        assert!(names.lines().any(|l| l == "fmi2DoStep"));
        for bad in [
            &[][..],
            &["Nope", "documentation"],
            &["Dahlquist", "nothing"],
            &["fmi-functions", "x", "y"],
        ] {
            assert!(matches!(run(bad), Err(Failure::Usage(_))), "{bad:?}");
        }
    }
}
