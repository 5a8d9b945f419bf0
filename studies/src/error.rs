//! The studies' error: a run of the master that failed keeps its [`RunError`] (so an FMU that
//! fails mid-study exits 3, as `orchestrator run` does), everything else says whether the input
//! was wrong (2) or the results could not be written (1).

use orchestrator::master::RunError;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A run through the master failed: the FMU, the system or the options.
    #[error(transparent)]
    Run(#[from] RunError),
    /// Bad input: an option, a file, a setting, a case the vehicle cannot run.
    #[error("{0}")]
    Input(String),
    /// Results cannot be written.
    #[error("{0}")]
    Io(String),
}

impl Error {
    /// The exit code, by `orchestrator`'s convention (docs/orchestrator.md): 0 success, 1 results
    /// cannot be written, 2 bad input, 3 an FMU failed during a run, 130 interrupted.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Run(e) => e.exit_code(),
            Error::Input(_) => 2,
            Error::Io(_) => 1,
        }
    }

    /// `cannot write PATH: e`.
    pub fn write(path: &std::path::Path, e: impl std::fmt::Display) -> Error {
        Error::Io(format!("cannot write {}: {e}", path.display()))
    }
}

impl From<String> for Error {
    fn from(message: String) -> Error {
        Error::Input(message)
    }
}

impl From<&str> for Error {
    fn from(message: &str) -> Error {
        Error::Input(message.to_string())
    }
}
