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
    #[error(transparent)]
    Setting(#[from] SettingError),
    #[error(transparent)]
    Calibration(#[from] CalibrationError),
    #[error(transparent)]
    Gain(#[from] GainError),
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// Sample `index` (1-based) of a recording could not be processed.
    #[error("sample {index}: {source}")]
    AtSample {
        index: usize,
        #[source]
        source: SampleError,
    },
    /// A recording's column does not have as many samples as its `speed` column.
    #[error("column '{column}' has {len} samples, 'speed' has {speed_len}")]
    ColumnLength {
        column: &'static str,
        len: usize,
        speed_len: usize,
    },
    /// An offline run's sample step is not a positive number.
    #[error("step {0} s must be a positive number")]
    SampleStep(f64),
    /// The learned filter's tap bank cannot be read or used.
    #[error(transparent)]
    Bank(#[from] BankError),
    /// The learned filter of `tap_file` could not be built from its bank.
    #[error("tap_file '{tap_file}': {source}")]
    TapFile {
        tap_file: String,
        #[source]
        source: LearnedError,
    },
    /// `tap_file`'s contract names runtime constants or filter designs other than this build's:
    /// no parameter changes those, so the bank was fitted by another build.
    #[error(
        "tap_file '{tap_file}' was fitted for another build of the estimator: {differences}; fit it again with this build (alignment-studies taps)"
    )]
    OtherBuild {
        tap_file: String,
        differences: String,
    },
    /// `tap_file` was fitted with another Kalman channel than the one these parameters make, and
    /// `allow_other_kalman` is false.
    #[error(
        "{mismatch}. Set allow_other_kalman = true to run it approximately, use estimator = 1, or fit taps for this channel (alignment-studies taps)"
    )]
    OtherKalman { mismatch: String },
}

/// A setting (FMI parameter, or an offline override by FMI name) the estimator refuses.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingError {
    /// A model parameter that must be positive and finite.
    #[error("parameter '{name}' = {value} must be a positive finite number")]
    NotPositive { name: &'static str, value: f64 },
    /// A model parameter that must be non-negative and finite.
    #[error("parameter '{name}' = {value} must be a non-negative finite number")]
    Negative { name: &'static str, value: f64 },
    #[error(
        "parameter 'alpha' (conicity) = {0} must be positive: with zero conicity the wheelset has no guidance and the alignment does not enter the model"
    )]
    Conicity(f64),
    #[error(
        "parameter 'discretization' = {0}: use 1 (the paper's second-order Taylor scheme) or 2 (exact, matrix exponential)"
    )]
    Discretization(i32),
    #[error(
        "parameter 'alignment_model' = {0}: use 1 (the paper's random walk), 2 (integrated random walk) or 3 (shaping filter of the track spectrum)"
    )]
    AlignmentModel(i32),
    #[error(
        "alignment prior: prior_a = {a}, prior_omega_r = {omega_r}, prior_omega_c = {omega_c} must be positive finite numbers (omega_r may be 0)"
    )]
    Prior { a: f64, omega_r: f64, omega_c: f64 },
    #[error(
        "parameter 'gain' = {0}: use 0 (the estimator's own), 1 (time-varying Kalman gain) or 2 (steady-state gain from the Riccati equation, scheduled on speed)"
    )]
    Gain(i32),
    #[error("parameter 'estimator' = {0}: 1 (the paper's filter) or 2 (learned)")]
    Estimator(i32),
    #[error("parameter 'lag' = {0} m must be 0 (off) or a positive lag")]
    Lag(f64),
    #[error(
        "parameter 'design_speed' = {0} must be 0 (follow the speed input) or a positive speed"
    )]
    DesignSpeed(f64),
    #[error("parameter 'prior_sigma_xi' is NaN")]
    PriorSigmaNan,
    #[error(
        "the measurement noise sigmas (sigma_acc_ws, sigma_yaw_rate, sigma_acc_frame, sigma_xi) must be positive"
    )]
    Sigmas,
    /// A calibration file the user named does not exist (running on without it would give
    /// results for a calibration they did not ask for).
    #[error("parameter 'calibration_file' = '{name}': {} does not exist", path.display())]
    CalibrationMissing { name: String, path: PathBuf },
    #[error(
        "tap_file '{name}' is relative and the FMU has no resources directory: give an absolute path or a shipped bank ({})",
        crate::learned::SHIPPED.join(", ")
    )]
    TapFileRelative { name: String },
    /// An offline override names no variable of the estimator.
    #[error("the estimator has no variable '{0}'")]
    UnknownVariable(String),
    /// An offline override names a variable that is not a parameter.
    #[error("'{0}' is not a parameter of the estimator")]
    NotParameter(String),
    /// An offline override's value does not parse as the variable's type.
    #[error("'{name}' = '{text}': {expected}")]
    Value {
        name: String,
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
    Toml { file: PathBuf, message: String },
    #[error("{}: '{name}' must be {n} rows of {n} numbers", file.display())]
    Shape {
        file: PathBuf,
        name: &'static str,
        n: usize,
    },
    #[error("{}: '{name}' holds a non-finite number", file.display())]
    NonFinite { file: PathBuf, name: &'static str },
    #[error("{}: '{name}' is not symmetric", file.display())]
    NotSymmetric { file: PathBuf, name: &'static str },
    #[error("{}: '{name}' has a negative diagonal entry", file.display())]
    NegativeDiagonal { file: PathBuf, name: &'static str },
    #[error(
        "{}: 'step_size' (the step Q was computed for) must be a positive number",
        file.display()
    )]
    StepSize { file: PathBuf },
    #[error("{}: 'r' is not positive definite", file.display())]
    RNotPositiveDefinite { file: PathBuf },
    #[error("{}: give both 'q' and 'r', or neither", file.display())]
    Incomplete { file: PathBuf },
}

/// Why the steady-state gain (the DARE's solution, [`crate::engine::steady_state`]) could not be
/// computed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum GainError {
    #[error("steady-state gain: the measurement noise covariance R is singular")]
    SingularR,
    #[error(
        "steady-state gain: the doubling algorithm did not converge in {0} steps (is the system detectable?)"
    )]
    NotConverged(usize),
    #[error("steady-state gain: singular matrix in the doubling algorithm")]
    SingularDoubling,
    #[error(
        "steady-state gain: the doubling algorithm diverged (is the system stabilizable and detectable?)"
    )]
    Diverged,
    #[error("steady-state gain: the innovation covariance is not positive definite")]
    InnovationNotPositiveDefinite,
    #[error("steady-state gain: singular innovation covariance")]
    SingularInnovation,
    #[error(
        "steady-state gain: one Riccati step still changes P by {residual:.3e} (relative) after {iterations} doublings"
    )]
    Residual { residual: f64, iterations: usize },
}

/// One filter step that did not update: the measurement update was skipped (the prediction is
/// kept; not a failure), or the gain for the step's speed could not be computed (a failure).
/// Small and `Copy`, so the step's result costs no more than a tagged `f64`.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum StepError {
    #[error("measurement update skipped: {0}")]
    Skipped(Skip),
    #[error(transparent)]
    Gain(#[from] GainError),
}

/// One sample that cannot go through [`crate::step::step`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SampleError {
    #[error(
        "input 'speed' = {0} m/s is negative: the estimator is for forward running (give the speed's magnitude along the direction the sensors were mounted for)"
    )]
    NegativeSpeed(f64),
    #[error(transparent)]
    Gain(#[from] GainError),
}
