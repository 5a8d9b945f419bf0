//! The estimator's errors, typed by concern so that a caller (the FMU's export, the studies, the
//! Python bindings) can tell a refused setting from a bad calibration file or a filter that
//! cannot step without reading text. Each variant carries the facts its message names (the
//! parameter and its value, the file and entry, the sample); the FMU's export logs the message
//! with `fmi2Error`.
//!
//! | type | what failed |
//! |---|---|
//! | [`SettingError`] | an FMI parameter or an offline `--set` the estimator refuses |
//! | [`CalibrationError`] | the calibration file (`calibration.toml`) |
//! | [`GainError`] | the steady-state gain's Riccati solution |
//! | [`StepError`] | one filter step: the update skipped ([`Skip`]), or the gain failed |
//! | [`SampleError`] | one sample through [`crate::step`]: a negative speed, or the filter failed |
//! | [`BankError`], [`LearnedError`] | the learned filter's tap bank, and its taps for the chosen sensors and lag (`learned::error`) |
//! | [`Error`] | any of these, and a recording's columns |

use crate::engine::Skip;
use crate::learned::error::{BankError, LearnedError};
use std::path::PathBuf;

/// Any error of the estimator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A setting the estimator refuses.
    #[error(transparent)]
    Setting(#[from] SettingError),
    /// The calibration file cannot be used.
    #[error(transparent)]
    Calibration(#[from] CalibrationError),
    /// The steady-state gain could not be computed (at initialization, for the start speed).
    #[error(transparent)]
    Gain(#[from] GainError),
    /// One sample cannot be processed (outside a recording, which says which:
    /// [`Error::AtSample`]).
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// Sample `index` (1-based) of a recording could not be processed.
    #[error("sample {index}: {source}")]
    AtSample {
        /// 1-based, as a user counts a recording's rows.
        index: usize,
        /// Why that sample failed.
        #[source]
        source: SampleError,
    },
    /// A recording's column does not have as many samples as its `speed` column.
    #[error("column '{column}' has {len} samples, 'speed' has {speed_len}")]
    ColumnLength {
        /// The column whose length differs.
        column: &'static str,
        /// Its samples.
        len: usize,
        /// The `speed` column's samples.
        speed_len: usize,
    },
    /// An offline run's sample step is not a positive number.
    #[error("step {0} s must be a positive number")]
    SampleStep(f64),
    /// The learned filter's tap bank cannot be read or used.
    #[error(transparent)]
    Bank(#[from] BankError),
    /// `design_response_file` could not be read or is inconsistent.
    #[error("{0}")]
    DesignFile(String),
    /// `line_file` is missing, malformed, or given without a design response to remove.
    #[error("{0}")]
    LineFile(String),
    /// The learned filter of `tap_file` could not be built from its bank.
    #[error("tap_file '{tap_file}': {source}")]
    TapFile {
        /// The `tap_file` parameter as given.
        tap_file: String,
        /// Why the bank gives no filter for the chosen sensors and lag.
        #[source]
        source: LearnedError,
    },
    /// `tap_file`'s contract names runtime constants or filter designs other than this build's:
    /// no parameter changes those, so the bank was fitted by another build.
    #[error(
        "tap_file '{tap_file}' was fitted for another build of the estimator: {differences}; fit it again with this build (alignment-studies taps)"
    )]
    OtherBuild {
        /// The `tap_file` parameter as given.
        tap_file: String,
        /// Each differing constant with the bank's and this build's values, `; `-separated.
        differences: String,
    },
    /// `tap_file` was fitted with another Kalman channel than the one these parameters make, and
    /// `allow_other_kalman` is false.
    #[error(
        "{mismatch}. Set allow_other_kalman = true to run it approximately, use estimator = 1, or fit taps for this channel (alignment-studies taps)"
    )]
    OtherKalman {
        /// The bank, the matrices that differ and the parameters not at their defaults.
        mismatch: String,
    },
}

/// A setting (FMI parameter, or an offline override by FMI name) the estimator refuses.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingError {
    /// A model parameter that must be positive and finite.
    #[error("parameter '{name}' = {value} must be a positive finite number")]
    NotPositive {
        /// The parameter's FMI name.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A model parameter that must be non-negative and finite.
    #[error("parameter '{name}' = {value} must be a non-negative finite number")]
    Negative {
        /// The parameter's FMI name.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// The conicity `alpha` is not positive (the value given).
    #[error(
        "parameter 'alpha' (conicity) = {0} must be positive: with zero conicity the wheelset has no guidance and the alignment does not enter the model"
    )]
    Conicity(f64),
    /// `discretization` is not one of the schemes' codes (the code given).
    #[error(
        "parameter 'discretization' = {0}: use 1 (the paper's second-order Taylor scheme) or 2 (exact, matrix exponential)"
    )]
    Discretization(i32),
    /// `alignment_model` is not one of the priors' codes (the code given).
    #[error(
        "parameter 'alignment_model' = {0}: use 1 (the paper's random walk), 2 (integrated random walk) or 3 (shaping filter of the track spectrum)"
    )]
    AlignmentModel(i32),
    /// The shaping filter's spectrum parameters are not positive finite numbers (`omega_r`
    /// may be 0).
    #[error(
        "alignment prior: prior_a = {a}, prior_omega_r = {omega_r}, prior_omega_c = {omega_c} must be positive finite numbers (omega_r may be 0)"
    )]
    Prior {
        /// `prior_a`, the spectrum's amplitude A \[m rad\].
        a: f64,
        /// `prior_omega_r` \[rad/m\].
        omega_r: f64,
        /// `prior_omega_c` \[rad/m\].
        omega_c: f64,
    },
    /// `gain` is not one of the gains' codes (the code given).
    #[error(
        "parameter 'gain' = {0}: use 0 (the estimator's own), 1 (time-varying Kalman gain) or 2 (steady-state gain from the Riccati equation, scheduled on speed)"
    )]
    Gain(i32),
    /// `estimator` is neither 1 nor 2 (the code given).
    #[error("parameter 'estimator' = {0}: 1 (the paper's filter) or 2 (learned)")]
    Estimator(i32),
    /// `lag` \[m\] is negative or not finite (the value given).
    #[error("parameter 'lag' = {0} m must be 0 (off) or a positive lag")]
    Lag(f64),
    /// `conicity` is negative or not finite (the value given).
    #[error("parameter 'conicity' = {0} must be 0 (estimate it) or a positive equivalent conicity")]
    TapConicity(f64),
    /// `kalker_scale` is negative or not finite (the value given).
    #[error(
        "parameter 'kalker_scale' = {0} must be 0 (estimate it) or a positive Kalker-coefficient scale"
    )]
    TapKalker(f64),
    /// `design_speed` \[m/s\] is negative or not finite (the value given).
    #[error(
        "parameter 'design_speed' = {0} must be 0 (follow the speed input) or a positive speed"
    )]
    DesignSpeed(f64),
    /// `line_rounding` \[m\] is outside its range (the value given).
    #[error(
        "parameter 'line_rounding' = {0} m must lie in 1-100 m (the design line's rounding, as the vehicle FMU's)"
    )]
    LineRounding(f64),
    /// `line_start` \[m\] is not finite (the value given).
    #[error("parameter 'line_start' = {0} m must be a finite distance along the line")]
    LineStart(f64),
    /// `prior_sigma_xi` is NaN (0 is allowed: it switches the prior's virtual measurement off).
    #[error("parameter 'prior_sigma_xi' is NaN")]
    PriorSigmaNan,
    /// A measurement noise sigma is zero, negative or not a number, and no calibration file
    /// gives R: the diagonal R would not be positive definite.
    #[error(
        "the measurement noise sigmas (sigma_acc_ws, sigma_yaw_rate, sigma_acc_frame, sigma_xi) must be positive"
    )]
    Sigmas,
    /// A calibration file the user named does not exist (running on without it would give
    /// results for a calibration they did not ask for).
    #[error("parameter 'calibration_file' = '{name}': {} does not exist{}", path.display(), nor_here(name))]
    CalibrationMissing {
        /// The `calibration_file` parameter as given.
        name: String,
        /// Where it was looked for (resolved against the resources directory).
        path: PathBuf,
    },
    /// The offline entry points were given a calibration file twice, as their own argument and
    /// as the `calibration_file` setting, naming different files: which one was meant is not
    /// known.
    #[error(
        "the calibration is named twice: '{argument}' (calibration) and '{setting}' (setting calibration_file); give one"
    )]
    CalibrationTwice {
        /// The calibration argument (the `--calibration` option, `calibration=` in Python).
        argument: PathBuf,
        /// The `calibration_file` setting as given.
        setting: String,
    },
    /// A `tap_file` the user named does not exist where it was looked for.
    #[error("parameter 'tap_file' = '{name}': {} does not exist{}", path.display(), nor_here(name))]
    TapFileMissing {
        /// The `tap_file` parameter as given.
        name: String,
        /// Where it was looked for (resolved against the resources directory).
        path: PathBuf,
    },
    /// A relative `tap_file` that is no bank built into the library and no file in the working
    /// directory, with no resources directory to look in (the FMU's shared library builds no bank
    /// in: it needs the importer's `fmuResourceLocation` for its shipped banks).
    #[cfg_attr(
        feature = "builtin-banks",
        error(
            "tap_file '{name}' is relative and not in the working directory: give an absolute path or a shipped bank ({})",
            crate::learned::SHIPPED.join(", ")
        )
    )]
    #[cfg_attr(
        not(feature = "builtin-banks"),
        error(
            "tap_file '{name}' is relative, not in the working directory, and there is no resources directory (no fmuResourceLocation) to look in: give an absolute path, or instantiate the FMU with its resources location"
        )
    )]
    TapFileRelative {
        /// The `tap_file` parameter as given.
        name: String,
    },
    /// An offline override names no variable of the estimator.
    #[error("the estimator has no variable '{0}'")]
    UnknownVariable(String),
    /// An offline override names a variable that is not a parameter.
    #[error("'{0}' is not a parameter of the estimator")]
    NotParameter(String),
    /// An offline override's value does not parse as the variable's type.
    #[error("'{name}' = '{text}': {expected}")]
    Value {
        /// The variable's FMI name.
        name: String,
        /// The value as given.
        text: String,
        /// What it must be, e.g. "not a number".
        expected: &'static str,
    },
}

/// A calibration file that cannot be used; every variant names the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    /// The file could not be read (missing, too large, not text), in `fmi_abi::resource`'s words.
    #[error("{0}")]
    Read(String),
    /// Not TOML, or entries the format does not have.
    #[error("calibration file {}: {message}", file.display())]
    Toml {
        /// The calibration file.
        file: PathBuf,
        /// The TOML reader's message, or the entry it does not know.
        message: String,
    },
    /// A matrix that is not square of the expected size.
    #[error("{}: '{name}' must be {n} rows of {n} numbers", file.display())]
    Shape {
        /// The calibration file.
        file: PathBuf,
        /// The matrix's entry name (`q` or `r`).
        name: &'static str,
        /// Its required size (7 for Q, 4 for R).
        n: usize,
    },
    /// A matrix with a NaN or infinite entry.
    #[error("{}: '{name}' holds a non-finite number", file.display())]
    NonFinite {
        /// The calibration file.
        file: PathBuf,
        /// The matrix's entry name (`q` or `r`).
        name: &'static str,
    },
    /// A covariance that is not symmetric.
    #[error("{}: '{name}' is not symmetric", file.display())]
    NotSymmetric {
        /// The calibration file.
        file: PathBuf,
        /// The matrix's entry name (`q` or `r`).
        name: &'static str,
    },
    /// A covariance with a negative variance on its diagonal.
    #[error("{}: '{name}' has a negative diagonal entry", file.display())]
    NegativeDiagonal {
        /// The calibration file.
        file: PathBuf,
        /// The matrix's entry name (`q` or `r`).
        name: &'static str,
    },
    /// `step_size` is missing, or outside 0.1 ms to 0.1 s.
    #[error(
        "{}: 'step_size' (the step Q and R were computed for, which the Kalman filter runs at) must be a number from 1e-4 to 0.1 s",
        file.display()
    )]
    StepSize {
        /// The calibration file.
        file: PathBuf,
    },
    /// R has no Cholesky factor: the update would divide by a singular innovation.
    #[error("{}: 'r' is not positive definite", file.display())]
    RNotPositiveDefinite {
        /// The calibration file.
        file: PathBuf,
    },
    /// Only one of Q and R is given: the two are estimated together and used together.
    #[error("{}: give both 'q' and 'r', or neither", file.display())]
    Incomplete {
        /// The calibration file.
        file: PathBuf,
    },
}

/// Why the steady-state gain (the DARE's solution, [`crate::engine::steady_state`]) could not be
/// computed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum GainError {
    /// R has no inverse, which the doubling's `H^T R^-1 H` needs.
    #[error("steady-state gain: the measurement noise covariance R is singular")]
    SingularR,
    /// The doubling did not settle within the given number of doublings.
    #[error(
        "steady-state gain: the doubling algorithm did not converge in {0} steps (is the system detectable?)"
    )]
    NotConverged(usize),
    /// `I + G X` had no inverse in a doubling step.
    #[error("steady-state gain: singular matrix in the doubling algorithm")]
    SingularDoubling,
    /// The doubling's covariance grew to a non-finite value.
    #[error(
        "steady-state gain: the doubling algorithm diverged (is the system stabilizable and detectable?)"
    )]
    Diverged,
    /// A polishing step's innovation covariance `H P H^T + R` had no Cholesky factor.
    #[error("steady-state gain: the innovation covariance is not positive definite")]
    InnovationNotPositiveDefinite,
    /// The final innovation covariance, whose inverse the gain needs, is singular.
    #[error("steady-state gain: singular innovation covariance")]
    SingularInnovation,
    /// The solution is not a fixed point: one more step of the filter's own recursion still
    /// changes it by more than 1e-8 (relative).
    #[error(
        "steady-state gain: one Riccati step still changes P by {residual:.3e} (relative) after {iterations} doublings"
    )]
    Residual {
        /// The largest change of P in that step, relative to P's largest entry.
        residual: f64,
        /// The doublings done.
        iterations: usize,
    },
}

/// One filter step that did not update: the measurement update was skipped (the prediction is
/// kept; not a failure), or the gain for the step's speed could not be computed (a failure).
/// Small and `Copy`, so the step's result costs no more than a tagged `f64`.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The update was skipped for this reason; the prediction stands and the filter goes on.
    #[error("measurement update skipped: {0}")]
    Skipped(Skip),
    /// The steady-state gain for the step's speed could not be computed: the step failed.
    #[error(transparent)]
    Gain(#[from] GainError),
}

/// One sample that cannot go through [`crate::step::step`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// The speed input is negative (the value given, m/s).
    #[error(
        "input 'speed' = {0} m/s is negative: the estimator is for forward running (give the speed's magnitude along the direction the sensors were mounted for)"
    )]
    NegativeSpeed(f64),
    /// The sample step is longer than [`crate::plausible::MAX_SAMPLE_STEP`] (the value, s).
    #[error(
        "step {0:e} s is longer than 1 s: the estimator takes sensor samples every 0.5 ms to 1 s (its Kalman filter runs 1 ms steps through each)"
    )]
    StepTooLong(f64),
    /// The steady-state gain for the sample's speed could not be computed.
    #[error(transparent)]
    Gain(#[from] GainError),
}

/// For a relative file name, the second place it was looked for: the working directory.
fn nor_here(name: &str) -> String {
    let path = std::path::Path::new(name);
    match std::path::absolute(path) {
        Ok(here) if path.is_relative() => format!(", nor does {}", here.display()),
        _ => String::new(),
    }
}
