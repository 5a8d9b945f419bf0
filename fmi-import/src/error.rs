//! The two error types: [`ImportError`] (the FMU cannot be opened or instantiated) and
//! [`FmiError`] (an FMI call on a live instance did not succeed).

use fmi_abi::types::fmi2Status;
use model_description::ParseError;
use std::fmt;
use std::path::PathBuf;

/// Why an FMU could not be opened or instantiated. Every variant names the `.fmu` file, and
/// where it applies the archive entry, the library, the missing symbols or the variable.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImportError {
    /// A file-system operation failed (opening the .fmu, creating the temporary directory,
    /// reading modelDescription.xml).
    #[error("{}: {action}: {source}", path.display())]
    Io {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// What we were doing, e.g. "cannot open the file".
        action: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },

    /// The file is not a readable zip archive (corrupt, truncated, not a zip at all).
    #[error("{}: not a valid FMU archive (zip): {source}", path.display())]
    Archive {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The zip reader's error (bad signature, truncated central directory...).
        #[source]
        source: zip::result::ZipError,
    },

    /// An entry could not be decompressed or written.
    #[error("{}: cannot extract entry '{entry}': {source}", path.display())]
    Extract {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The entry name as stored in the archive.
        entry: String,
        /// The decompressor's or the file system's error.
        #[source]
        source: std::io::Error,
    },

    /// An entry would land outside the unpack directory, or is not a plain file or directory.
    /// Nothing has been extracted when this is returned.
    #[error("{}: refusing to unpack the archive: entry '{entry}' {reason}", path.display())]
    UnsafeEntry {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The entry name as stored (NUL shown as `\0`).
        entry: String,
        /// Why, e.g. "contains a '..' component".
        reason: &'static str,
    },

    /// The archive has more entries, or unpacks to more bytes, than
    /// [`UnpackLimits`](crate::UnpackLimits) allow (a zip bomb), or an entry decompresses to
    /// more than the size it declares. Nothing beyond the declared sizes has been written.
    #[error("{}: refusing to unpack the archive: {what}", path.display())]
    TooLarge {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The entry that crossed the limit (none when the entry count did).
        entry: Option<String>,
        /// What was too large, with the sizes and the limit.
        what: String,
    },

    /// The archive has no `modelDescription.xml` at its root.
    #[error("{}: the archive has no modelDescription.xml at its root", path.display())]
    MissingModelDescription {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
    },

    /// `modelDescription.xml` could not be parsed; the source gives line and column.
    #[error("{}: modelDescription.xml: {source}", path.display())]
    ModelDescription {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The parser's error, with line and column in the XML.
        #[source]
        source: ParseError,
    },

    /// `fmiVersion` is not 2.x.
    #[error(
        "{}: modelDescription.xml declares fmiVersion=\"{version}\"; only FMI 2.0 is supported",
        path.display()
    )]
    UnsupportedFmiVersion {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The `fmiVersion` attribute as written (e.g. "1.0", "3.0").
        version: String,
    },

    /// The FMU has no `<CoSimulation>` element (model exchange only).
    #[error(
        "{}: modelDescription.xml has no <CoSimulation> element{}; only co-simulation FMUs can be imported",
        path.display(),
        model_exchange_note(.model_exchange)
    )]
    NotCoSimulation {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The FMU has a `<ModelExchange>` element instead, so the message can say it is a
        /// model-exchange-only FMU rather than a broken one.
        model_exchange: bool,
    },

    /// `modelIdentifier` cannot name a file inside the archive.
    #[error(
        "{}: modelIdentifier \"{identifier}\" is not usable as a file name (empty, '.', '..', or contains '/', '\\\\', ':' or NUL)",
        path.display()
    )]
    InvalidModelIdentifier {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The `modelIdentifier` of `<CoSimulation>` as written.
        identifier: String,
    },

    /// This crate was built for a platform FMI 2.0 has no binaries folder for.
    #[error("{}: FMI 2.0 defines no binaries/ folder for this platform ({os}, {arch})", path.display())]
    UnsupportedPlatform {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// `std::env::consts::OS` of this build.
        os: &'static str,
        /// `std::env::consts::ARCH` of this build.
        arch: &'static str,
    },

    /// No shared library for this platform in the archive.
    #[error(
        "{}: no binary for this platform: expected {expected} in the archive; it has {}",
        path.display(),
        platform_list(.available)
    )]
    MissingBinary {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The path inside the archive, e.g. `binaries/linux64/Model.so`.
        expected: String,
        /// The folders under `binaries/` the archive does have.
        available: Vec<String>,
    },

    /// The dynamic loader refused the library (undefined symbol, wrong architecture, not a
    /// shared library...); `message` is the loader's own text.
    #[error("{}: cannot load {library}: {message}", path.display())]
    Load {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The path inside the archive.
        library: String,
        /// The dynamic loader's message (dlerror / FormatMessage).
        message: String,
    },

    /// The library lacks some of the 34 functions FMI 2.0 co-simulation requires.
    #[error(
        "{}: {library} does not export {} of the 34 FMI 2.0 co-simulation functions: {}",
        path.display(),
        missing.len(),
        missing.join(", ")
    )]
    MissingFunctions {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The path inside the archive.
        library: String,
        /// The FMI names of the functions not found, in the order they are resolved.
        missing: Vec<&'static str>,
    },

    /// `fmi2GetVersion` or `fmi2GetTypesPlatform` returned something else than FMI 2.0's
    /// "2.0" / "default".
    #[error("{}: {function}() returned {found}, expected \"{expected}\"", path.display())]
    Incompatible {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// `"fmi2GetVersion"` or `"fmi2GetTypesPlatform"`.
        function: &'static str,
        /// What FMI 2.0 requires it to return.
        expected: &'static str,
        /// What it returned, quoted, or NULL.
        found: String,
    },

    /// The instance name contains a NUL character.
    #[error("{}: the instance name {name:?} contains a NUL character", path.display())]
    InvalidInstanceName {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The name as the caller gave it (C strings cannot carry it).
        name: String,
    },

    /// The FMU declares `canBeInstantiatedOnlyOncePerProcess` and already has a live instance.
    #[error(
        "{}: the FMU declares canBeInstantiatedOnlyOncePerProcess and instance '{existing}' is still alive",
        path.display()
    )]
    InstantiatedOnlyOnce {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The name of the live instance that must be dropped first.
        existing: String,
    },

    /// `fmi2Instantiate` returned NULL; `messages` quotes what the FMU logged meanwhile.
    #[error(
        "{}: fmi2Instantiate of instance '{instance}' returned NULL{}",
        path.display(),
        quoted_messages(.messages)
    )]
    Instantiate {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The instance name passed to fmi2Instantiate.
        instance: String,
        /// The warnings and errors the FMU logged during fmi2Instantiate, in order: usually
        /// the only clue to why it refused.
        messages: Vec<String>,
    },

    /// A variable name that the model description does not declare.
    #[error("{}: the FMU has no variable named '{name}'", path.display())]
    UnknownVariable {
        /// The `.fmu` file, as passed to [`Fmu::open`](crate::Fmu::open).
        path: PathBuf,
        /// The name looked up, as the caller wrote it.
        name: String,
    },

    /// An FMI call made while setting up the instance (e.g. fmi2SetDebugLogging) failed.
    #[error(transparent)]
    Fmi(#[from] FmiError),
}

impl ImportError {
    /// The `.fmu` file the error is about.
    pub fn fmu_path(&self) -> &std::path::Path {
        match self {
            ImportError::Io { path, .. }
            | ImportError::Archive { path, .. }
            | ImportError::Extract { path, .. }
            | ImportError::UnsafeEntry { path, .. }
            | ImportError::TooLarge { path, .. }
            | ImportError::MissingModelDescription { path }
            | ImportError::ModelDescription { path, .. }
            | ImportError::UnsupportedFmiVersion { path, .. }
            | ImportError::NotCoSimulation { path, .. }
            | ImportError::InvalidModelIdentifier { path, .. }
            | ImportError::UnsupportedPlatform { path, .. }
            | ImportError::MissingBinary { path, .. }
            | ImportError::Load { path, .. }
            | ImportError::MissingFunctions { path, .. }
            | ImportError::Incompatible { path, .. }
            | ImportError::InvalidInstanceName { path, .. }
            | ImportError::InstantiatedOnlyOnce { path, .. }
            | ImportError::Instantiate { path, .. }
            | ImportError::UnknownVariable { path, .. } => path,
            ImportError::Fmi(e) => &e.fmu,
        }
    }
}

fn model_exchange_note(model_exchange: &bool) -> &'static str {
    if *model_exchange {
        " (it is a model-exchange-only FMU)"
    } else {
        ""
    }
}

fn platform_list(available: &[String]) -> String {
    if available.is_empty() {
        "no binaries/ folder at all".to_string()
    } else {
        format!("binaries for: {}", available.join(", "))
    }
}

fn quoted_messages(messages: &[String]) -> String {
    if messages.is_empty() {
        " (the FMU logged no warning or error)".to_string()
    } else {
        format!("; the FMU logged: {}", messages.join("; "))
    }
}

/// An FMI function of a live instance returned fmi2Discard, fmi2Error, fmi2Fatal or
/// fmi2Pending (fmi2OK and fmi2Warning are success; warnings went to the log sink).
///
/// Display: `fmi2DoStep of instance 'vehicle' (/path/RailVehicle.fmu) returned fmi2Error at
/// t = 1.234 s: <messages joined by "; ">`.
#[derive(Debug, Clone)]
pub struct FmiError {
    /// The instance name given to [`Fmu::instantiate`](crate::Fmu::instantiate).
    pub instance: String,
    /// The `.fmu` file.
    pub fmu: PathBuf,
    /// The FMI function, e.g. `"fmi2DoStep"`.
    pub function: &'static str,
    /// What it returned (a status outside the enum counts as fmi2Fatal).
    pub status: fmi2Status,
    /// For fmi2DoStep the communication point `t` of the call; otherwise the instance's current
    /// communication point as far as the importer knows it (None before fmi2SetupExperiment or
    /// after fmi2Reset / restoring a deserialized state).
    pub time: Option<f64>,
    /// After fmi2DoStep returned fmi2Discard: what fmi2GetRealStatus(fmi2LastSuccessfulTime)
    /// reported, if the FMU answered.
    pub last_successful_time: Option<f64>,
    /// After fmi2DoStep returned fmi2Discard: fmi2GetBooleanStatus(fmi2Terminated) answered
    /// true, i.e. the FMU ended the simulation itself (a model reaching its end, as fmpy reads
    /// it). A master stops there without an error.
    pub terminated: bool,
    /// The warning and error messages the FMU logged during this call, in order. Calls the
    /// importer refused without calling the FMU (e.g. slices of different lengths) carry the
    /// importer's reason here.
    pub messages: Vec<String>,
}

impl fmt::Display for FmiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} of instance '{}' ({}) returned {}",
            self.function,
            self.instance,
            self.fmu.display(),
            self.status.name()
        )?;
        if let Some(t) = self.time {
            write!(f, " at t = {t} s")?;
        }
        if let Some(t) = self.last_successful_time {
            write!(f, " (last successful time {t} s)")?;
        }
        if self.messages.is_empty() {
            write!(f, " (the FMU logged no message)")
        } else {
            write!(f, ": {}", self.messages.join("; "))
        }
    }
}

impl std::error::Error for FmiError {}
