//! The studies' error. Its kind decides the exit code, by `orchestrator`'s convention
//! (docs/orchestrator.md): a run of the master that failed keeps its [`RunError`] (so an FMU
//! that fails mid-study exits 3, as `orchestrator run` does; an FMU that cannot be loaded, 2),
//! a vehicle that left the track is a [`Error::Derailed`] run (3), the estimator's own errors
//! and every other bad input exit 2, and results or figures that cannot be written exit 1.

use orchestrator::master::RunError;
use std::path::PathBuf;

/// Why a study, a run or a command of `alignment-studies` failed; [`Error::exit_code`] maps
/// it to the process's exit code.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A run through the master failed: the FMU, the system or the options.
    #[error(transparent)]
    Run(RunError),
    /// The vehicle FMU stopped a run because its wheelset left the track
    /// ([`fmu_vehicle::fmu::is_derailment`]): the vehicle is unstable in that running
    /// condition. A study that sweeps conditions treats it as a result, not a failure.
    #[error(transparent)]
    Derailed(RunError),
    /// The estimator refused a setting, its calibration file or a recording, or its filter
    /// could not step.
    #[error(transparent)]
    Estimator(#[from] fmu_estimator::error::Error),
    /// A run's signals do not suffice for the metric (too short for a band's filter, a grid
    /// too coarse).
    #[error(transparent)]
    Metric(#[from] crate::study::metrics::MetricError),
    /// A recording `smooth` cannot read.
    #[error(transparent)]
    Recording(#[from] crate::smooth::RecordingError),
    /// Bad input: an option, a file, a setting, a case the vehicle cannot run, a run whose
    /// results lack what the study needs.
    #[error("{0}")]
    Input(String),
    /// Results cannot be written.
    #[error("{0}")]
    Io(String),
    /// A figure cannot be drawn or written.
    #[error("cannot draw {}: {message}", path.display())]
    Draw {
        /// The figure's file.
        path: PathBuf,
        /// The plotting library's or the file system's error.
        message: String,
    },
    /// `source`, about `context` (the option, case or file it concerns); exits as `source`.
    #[error("{context}: {source}")]
    Context {
        /// What the error concerns, e.g. `--set vehicle.x=1` or a case's name.
        context: String,
        /// The error itself.
        #[source]
        source: Box<Error>,
    },
}

impl Error {
    /// The exit code, by `orchestrator`'s convention (docs/orchestrator.md): 0 success, 1 results
    /// cannot be written, 2 bad input, 3 an FMU failed during a run (a derailment is one), 130
    /// interrupted.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Run(e) => e.exit_code(),
            Error::Derailed(_) => 3,
            Error::Estimator(_) | Error::Metric(_) | Error::Recording(_) | Error::Input(_) => 2,
            Error::Io(_) | Error::Draw { .. } => 1,
            Error::Context { source, .. } => source.exit_code(),
        }
    }

    /// Whether a run derailed, here or in the error this one gives context to.
    pub fn is_derailment(&self) -> bool {
        match self {
            Error::Derailed(_) => true,
            Error::Context { source, .. } => source.is_derailment(),
            _ => false,
        }
    }

    /// This error about `context` (e.g. `--set X=1`, a case and seed): the message gains
    /// `context: ` in front, the kind stays.
    pub fn context(self, context: impl std::fmt::Display) -> Error {
        Error::Context {
            context: context.to_string(),
            source: Box::new(self),
        }
    }

    /// `cannot write PATH: e`.
    pub fn write(path: &std::path::Path, e: impl std::fmt::Display) -> Error {
        Error::Io(format!("cannot write {}: {e}", path.display()))
    }

    /// Bad input, in `message`'s words.
    pub fn input(message: impl Into<String>) -> Error {
        Error::Input(message.into())
    }
}

/// A run that failed because the vehicle derailed is [`Error::Derailed`]. The vehicle FMU can
/// tell its importer only through FMI: `fmi2DoStep` returns fmi2Error and the reason is the
/// message it logged, which the master keeps in the [`fmi_import::FmiError`]. That text is
/// read in one place, [`fmu_vehicle::fmu::is_derailment`].
impl From<RunError> for Error {
    fn from(e: RunError) -> Error {
        let derailed = matches!(
            &e,
            RunError::Fmi { error, .. }
                if error.function == "fmi2DoStep"
                    && error.messages.iter().any(|m| fmu_vehicle::fmu::is_derailment(m))
        );
        if derailed {
            Error::Derailed(e)
        } else {
            Error::Run(e)
        }
    }
}

impl From<fmu_estimator::error::SettingError> for Error {
    fn from(e: fmu_estimator::error::SettingError) -> Error {
        Error::Estimator(e.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmi_abi::types::fmi2Status;
    use fmi_import::FmiError;

    /// A failed fmi2DoStep of the vehicle, as the master reports it, the FMU having logged
    /// `message` (the export layer's prefix and the model's text).
    fn step_failed(message: &str) -> RunError {
        RunError::Fmi {
            error: FmiError {
                instance: "vehicle".into(),
                fmu: "RailVehicle.fmu".into(),
                function: "fmi2DoStep",
                status: fmi2Status::Error,
                time: Some(12.5),
                last_successful_time: None,
                terminated: false,
                messages: vec![message.into()],
            },
            results: None,
        }
    }

    #[test]
    fn a_derailment_is_its_own_kind_and_exits_as_a_failed_run() {
        // The text the vehicle FMU logs (fmu_vehicle::fmu's do_step, behind fmi-abi's prefix).
        let derailed = step_failed(
            "fmi2DoStep at t=12.5: derailed: the leading wheelset is 39.4 mm off the track centre line at distance 375.0 m (flange clearance 9.0 mm + 30 mm of flange): the vehicle is unstable at 30 m/s with these parameters (hunting), and the model cannot go on",
        );
        let text = derailed.to_string();
        let e = Error::from(derailed);
        assert!(matches!(e, Error::Derailed(_)), "{e:?}");
        assert!(e.is_derailment());
        assert_eq!(e.exit_code(), 3);
        assert_eq!(
            e.to_string(),
            text,
            "the message is the master's, unchanged"
        );
        let e = e.context("case x, seed 1");
        assert!(e.is_derailment());
        assert_eq!(e.exit_code(), 3);
        assert_eq!(e.to_string(), format!("case x, seed 1: {text}"));
        // Another failure of the same step, or the word elsewhere in a message, is not one.
        for other in [
            "fmi2DoStep at t=1: the vehicle state became non-finite at distance 3 m",
            "fmi2DoStep at t=1: the track model derailed nothing: a comment",
        ] {
            let e = Error::from(step_failed(other));
            assert!(matches!(e, Error::Run(_)), "{other}");
            assert!(!e.is_derailment(), "{other}");
            assert_eq!(e.exit_code(), 3, "{other}");
        }
    }

    #[test]
    fn exit_codes_follow_the_kind() {
        let setting = fmu_estimator::error::SettingError::Lag(-1.0);
        let cases: [(Error, i32); 7] = [
            (Error::input("--seeds: none"), 2),
            (setting.clone().into(), 2),
            (
                crate::study::metrics::MetricError::NotEnoughSamples.into(),
                2,
            ),
            (
                crate::study::learned::decimation(20.0, 100.0).unwrap_err(),
                2,
            ),
            (
                Error::write(std::path::Path::new("/x/report.md"), "disk full"),
                1,
            ),
            (RunError::Config("--stop -1".into()).into(), 2),
            (Error::input("--set a=b: no component 'a'").context("x"), 2),
        ];
        for (e, code) in cases {
            assert_eq!(e.exit_code(), code, "{e}");
            assert!(!e.is_derailment(), "{e}");
        }
        // The estimator's message is its own, unchanged.
        assert_eq!(
            Error::from(setting).to_string(),
            "parameter 'lag' = -1 m must be 0 (off) or a positive lag"
        );
    }
}
