//! Offline processing of recorded sensor signals: the FMU's filter run over a whole record, and
//! the Rauch-Tung-Striebel smoother ([`crate::smoother`]) on top of it.
//!
//! The filter is configured exactly as the FMU is, by FMI parameter names and values
//! ([`settings`]), starting from the FMU's defaults, and steps exactly as `fmi2DoStep` does:
//! sample `k` holds the sensors and speed at the end of step `k`; the distance is the rectangle
//! rule of the speed; below `min_speed` the estimate is held. So the filtered output of
//! [`process`] equals the FMU's output on the same samples, bit for bit (a test).

use crate::calibration::{self, SHIPPED};
use crate::config::{Config, Note};
use crate::core::Core;
use crate::error::{Error, SettingError};
use crate::learned::{Estimate, Learned};
use crate::step;
use crate::variables::{VARIABLES, vr};
use fmi_abi::Values;
use fmi_abi::variables::Start;
use std::path::Path;

pub mod fitted;

/// One recorded step: the speed and the sensor samples at its end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Forward speed \[m/s\] (the FMU's `speed` input): not negative.
    pub speed: f64,
    /// Wheelset lateral acceleration \[m/s2\] (`ws_acc_y`).
    pub ws_acc_y: f64,
    /// Wheelset yaw rate \[rad/s\] (`ws_yaw_rate`).
    pub ws_yaw_rate: f64,
    /// Bogie frame lateral acceleration \[m/s2\] (`frame_acc_y`).
    pub frame_acc_y: f64,
    /// The wheelset roll-rate gyroscope (0 when the record has none; only the learned filter's
    /// four-sensor taps read it).
    pub ws_roll_rate: f64,
    /// The design line at the wheelset: curvature \[1/m\] and cant \[m\] (0 on straight
    /// track), [`crate::design`].
    pub design: [f64; 2],
}

impl Sample {
    /// One sample per row of a recording's four signal columns (of equal length).
    pub fn from_columns(
        speed: &[f64],
        ws_acc_y: &[f64],
        ws_yaw_rate: &[f64],
        frame_acc_y: &[f64],
    ) -> Vec<Sample> {
        debug_assert!(
            [ws_acc_y.len(), ws_yaw_rate.len(), frame_acc_y.len()]
                .iter()
                .all(|&n| n == speed.len())
        );
        (0..speed.len())
            .map(|k| Sample {
                speed: speed[k],
                ws_acc_y: ws_acc_y[k],
                ws_yaw_rate: ws_yaw_rate[k],
                frame_acc_y: frame_acc_y[k],
                ws_roll_rate: 0.0,
                design: [0.0; 2],
            })
            .collect()
    }

    /// These samples with the roll-rate gyroscope's column.
    pub fn with_roll_rate(mut samples: Vec<Sample>, ws_roll_rate: &[f64]) -> Vec<Sample> {
        debug_assert_eq!(samples.len(), ws_roll_rate.len());
        for (s, r) in samples.iter_mut().zip(ws_roll_rate) {
            s.ws_roll_rate = *r;
        }
        samples
    }
}

/// Estimates per sample.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Processed {
    /// Distance travelled at each sample \[m\].
    pub distance: Vec<f64>,
    /// The causal filter's alignment estimate and its standard deviation \[m\].
    pub filtered: Vec<(f64, f64)>,
    /// The smoothed estimate and its standard deviation (when asked for).
    pub smoothed: Option<Vec<(f64, f64)>>,
    /// Samples whose measurement update was skipped (non-finite values).
    pub skipped: usize,
    /// The FMU's outputs with the learned filter (when one is given): `alignment`,
    /// `alignment_lagged` and their standard deviations, `active_estimator`.
    pub learned: Option<Vec<Estimate>>,
    /// The FMU's `contact_scale` output per sample (with the learned filter).
    pub contact_scale: Option<Vec<f64>>,
    /// The FMU's `ws_acc_y_bias`, `ws_yaw_rate_bias`, `frame_acc_y_bias`, `ws_roll_rate_bias`
    /// outputs per sample, when a `bias_sigma_*` parameter is set (else every one is 0).
    pub bias: Option<Vec<[f64; 4]>>,
    /// The FMU's `conicity_estimate` output per sample (with the learned filter).
    pub conicity: Option<Vec<f64>>,
    /// The FMU's `novelty` output per sample (with the learned filter).
    pub novelty: Option<Vec<f64>>,
    /// The FMU's `outside_training` output per sample.
    pub outside_training: Vec<bool>,
    /// The FMU's `heading_change` \[rad\], `relative_velocity_change` \[m/s\] and
    /// `heading_level` \[rad\] outputs per sample ([`crate::integrals`]); the standard
    /// deviations above are grown by them as the FMU's are ([`crate::integrals::growth`]), bar
    /// `filtered`'s, the Kalman filter's own.
    pub changes: Vec<[f64; 3]>,
    /// The filter covariance checked after every step (when asked for: an eigen-decomposition
    /// per step, [`process_columns_checked`]).
    pub covariance: Option<CovarianceCheck>,
}

/// The filter covariance `P` over a run, after every filter step (samples below `min_speed`
/// do not step the filter). P is symmetric positive semi-definite if `max_asymmetry` is 0,
/// `not_positive_definite` is 0 (or the eigenvalues there are 0 up to rounding) and
/// `min_relative` is above about `-1e-15` (the eigenvalues' own rounding).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CovarianceCheck {
    /// Filter steps checked.
    pub steps: usize,
    /// Steps after which P's Cholesky factorization failed (P not positive definite).
    pub not_positive_definite: usize,
    /// Steps whose eigenvalues were computed: every [`EIGEN_EVERY`]-th, and every one whose
    /// factorization failed.
    pub eigen_steps: usize,
    /// The smallest eigenvalue of P over the eigen steps.
    pub min_eigenvalue: f64,
    /// The smallest ratio of P's smallest to its largest eigenvalue over the eigen steps.
    pub min_relative: f64,
    /// The largest `|P - P^T|` entry over all steps.
    pub max_asymmetry: f64,
}

/// How often [`CovarianceCheck`] computes P's eigenvalues (an eigen-decomposition costs about
/// ten filter steps; the Cholesky test at every step about a fifth of one).
pub const EIGEN_EVERY: usize = 1000;

impl CovarianceCheck {
    fn new() -> CovarianceCheck {
        CovarianceCheck {
            steps: 0,
            not_positive_definite: 0,
            eigen_steps: 0,
            min_eigenvalue: f64::INFINITY,
            min_relative: f64::INFINITY,
            max_asymmetry: 0.0,
        }
    }

    fn add(&mut self, core: &Core) {
        // NaN propagates (f64::min would drop it): a NaN covariance must fail the check.
        let worst = |a: f64, b: f64| if b.is_nan() || b < a { b } else { a };
        let (definite, _, asymmetry) = core.covariance_check(false);
        let eig = if !definite || self.steps.is_multiple_of(EIGEN_EVERY) {
            core.covariance_check(true).1
        } else {
            None
        };
        self.steps += 1;
        self.not_positive_definite += usize::from(!definite);
        if let Some((min, max)) = eig {
            self.eigen_steps += 1;
            self.min_eigenvalue = worst(self.min_eigenvalue, min);
            self.min_relative = worst(self.min_relative, min / max);
        }
        self.max_asymmetry = -worst(-self.max_asymmetry, -asymmetry);
    }
}

/// A recording's signal columns, read where they are: the Python bindings hand numpy's memory
/// over without a copy, and a fleet's recordings are large.
#[derive(Debug, Clone, Copy)]
pub struct Columns<'a> {
    /// Forward speed \[m/s\], one per step; every other column has its length.
    pub speed: &'a [f64],
    /// Wheelset lateral acceleration \[m/s2\].
    pub ws_acc_y: &'a [f64],
    /// Wheelset yaw rate \[rad/s\].
    pub ws_yaw_rate: &'a [f64],
    /// Bogie frame lateral acceleration \[m/s2\].
    pub frame_acc_y: &'a [f64],
    /// The roll-rate gyroscope, when the record has one (0 otherwise, as in [`Sample`]).
    pub ws_roll_rate: Option<&'a [f64]>,
    /// The design line's curvature and cant, when the record has them (0 otherwise).
    pub design: Option<(&'a [f64], &'a [f64])>,
}

impl Columns<'_> {
    /// Refuses columns of unequal length, naming the first that differs from `speed`.
    pub fn check(&self) -> Result<usize, Error> {
        let n = self.speed.len();
        let others = [
            ("ws_acc_y", Some(self.ws_acc_y)),
            ("ws_yaw_rate", Some(self.ws_yaw_rate)),
            ("frame_acc_y", Some(self.frame_acc_y)),
            ("ws_roll_rate", self.ws_roll_rate),
            ("design_curvature", self.design.map(|d| d.0)),
            ("design_cant", self.design.map(|d| d.1)),
        ];
        for (name, column) in others {
            if let Some(c) = column
                && c.len() != n
            {
                return Err(Error::ColumnLength {
                    column: name,
                    len: c.len(),
                    speed_len: n,
                });
            }
        }
        Ok(n)
    }

    fn sample(&self, k: usize) -> Sample {
        Sample {
            speed: self.speed[k],
            ws_acc_y: self.ws_acc_y[k],
            ws_yaw_rate: self.ws_yaw_rate[k],
            frame_acc_y: self.frame_acc_y[k],
            ws_roll_rate: self.ws_roll_rate.map_or(0.0, |r| r[k]),
            design: self.design.map_or([0.0; 2], |(c, h)| [c[k], h[k]]),
        }
    }
}

/// The FMU's parameter values with `overrides` (FMI name, value as text) applied, refusing
/// unknown names, non-parameters and unparsable values by name.
pub fn settings(overrides: &[(String, String)]) -> Result<Values, Error> {
    let mut v = Values::from_table(VARIABLES);
    for (name, text) in overrides {
        let spec = VARIABLES
            .iter()
            .find(|s| s.name == name)
            .ok_or_else(|| SettingError::UnknownVariable(name.clone()))?;
        if !spec.is_parameter() {
            return Err(SettingError::NotParameter(name.clone()).into());
        }
        let bad = |expected: &'static str| SettingError::Value {
            name: name.clone(),
            text: text.clone(),
            expected,
        };
        let i = spec.vr as usize;
        match spec.start {
            Start::Real(_) => {
                v.real[i] = text.trim().parse().map_err(|_| bad("not a number"))?;
            }
            Start::Integer(_) => {
                v.integer[i] = text.trim().parse().map_err(|_| bad("not an integer"))?;
            }
            Start::Boolean(_) => {
                v.boolean[i] = match text.trim() {
                    "true" | "1" => true,
                    "false" | "0" => false,
                    _ => return Err(bad("not a boolean (true/false)").into()),
                }
            }
            Start::String(_) => v.string[i] = text.clone(),
        }
    }
    Ok(v)
}

/// The configuration for `values`. The calibration file is the one named by `calibration`, or
/// by the `calibration_file` setting as the FMU resolves it (absolute, or relative to the working
/// directory: there are no resources here), or, if neither names one and
/// `use_calibration_file` is on, the file shipped in the FMU (built in). The setting is honoured
/// because a user who passes the FMU's parameters expects the FMU's result; both naming
/// different files is refused.
pub fn config(values: &Values, calibration: Option<&Path>) -> Result<(Config, Vec<Note>), Error> {
    let named = setting_calibration(values, calibration)?;
    let calibration = calibration.or(named.as_deref());
    let use_file = values.boolean[vr::USE_CALIBRATION_FILE as usize];
    let mut v = values.clone();
    v.boolean[vr::USE_CALIBRATION_FILE as usize] = false;
    let mut notes = vec![];
    let built_in = Path::new("calibration.toml (built in)");
    let c = if use_file {
        match calibration {
            Some(path) => calibration::load(path)?,
            None => calibration::parse(SHIPPED, built_in)?,
        }
    } else {
        None
    };
    if let Some(c) = &c {
        let what = calibration.unwrap_or(built_in).display().to_string();
        v = crate::config::with_file_parameters(&v, c, &what, &mut notes);
    }
    // The diagonal model's sigmas must be valid even when a calibration replaces them.
    let (mut config, more) = Config::from_values(&v, None)?;
    notes.extend(more);
    if let Some(c) = c {
        notes.push(Note::Info(format!(
            "Q and R from the calibration ({})",
            c.status
        )));
        config = config.with_calibration(c);
    }
    Ok((config, notes))
}

/// The calibration file the `calibration_file` setting names, when it is not the shipped one's
/// name: checked to exist, and to agree with the `calibration` argument if both are given.
fn setting_calibration(
    values: &Values,
    calibration: Option<&Path>,
) -> Result<Option<std::path::PathBuf>, Error> {
    let name = &values.string[vr::CALIBRATION_FILE as usize];
    if name == crate::config::DEFAULT_CALIBRATION_FILE
        || !values.boolean[vr::USE_CALIBRATION_FILE as usize]
    {
        return Ok(None);
    }
    let missing = |path: std::path::PathBuf| SettingError::CalibrationMissing {
        name: name.clone(),
        path,
    };
    let path = crate::config::calibration_path(values, None)
        .ok_or_else(|| missing(Path::new(name).to_path_buf()))?;
    // Not a regular file (a directory, a device) is the loader's error, as in the FMU.
    if !path.exists() {
        return Err(missing(path).into());
    }
    // One file named two ways (`..`, a link) is one file.
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    match calibration {
        Some(given) if !same(given, &path) => Err(SettingError::CalibrationTwice {
            argument: given.to_path_buf(),
            setting: name.clone(),
        }
        .into()),
        _ => Ok(Some(path)),
    }
}

/// The learned filter `values` ask for (`estimator` 2), as the FMU builds it, with the tap bank
/// built into the library unless `tap_file` is absolute, its contract checked against `config`
/// (the Kalman channel it will run with).
pub fn learned(values: &Values, config: &Config) -> Result<Option<Learned>, Error> {
    crate::fmu::learned_from_values(values, None, config, &fmi_abi::Logger::silent())
}

/// Refuses the design line given twice: by `line_file` (in `config`) and by the samples
/// (`design_given`: arrays or recording columns), which the FMU would not read.
pub fn one_design(config: &Config, design_given: bool) -> Result<(), Error> {
    if config.line.is_some() && design_given {
        return Err(Error::LineFile(
            "design_curvature and design_cant, and the setting line_file, both give the design line: give one".into(),
        ));
    }
    Ok(())
}

/// Runs the Kalman filter (and the smoother, if `smooth`) over `samples` taken every `h`
/// seconds; the learned filter is not run (see [`process_learned`]).
pub fn process(
    config: &Config,
    h: f64,
    samples: &[Sample],
    smooth: bool,
) -> Result<Processed, Error> {
    // The Kalman filter is the estimate here: `gain` 0 means its own (time-varying) gain, not
    // the one the learned filter's channel takes.
    let alone = Config {
        gain: config.gain_alone,
        ..config.clone()
    };
    process_learned(&alone, None, h, samples, smooth)
}

/// [`process`] with the learned filter `learned` (a fresh one, as the FMU builds at
/// initialization) stepping beside the Kalman filter, as the FMU does.
pub fn process_learned(
    config: &Config,
    learned: Option<Learned>,
    h: f64,
    samples: &[Sample],
    smooth: bool,
) -> Result<Processed, Error> {
    run(
        config,
        learned,
        h,
        samples.len(),
        |k| samples[k],
        smooth,
        false,
    )
}

/// [`process_learned`] over columns read in place; unequal lengths are refused.
pub fn process_columns(
    config: &Config,
    learned: Option<Learned>,
    h: f64,
    columns: &Columns,
    smooth: bool,
) -> Result<Processed, Error> {
    let n = columns.check()?;
    run(config, learned, h, n, |k| columns.sample(k), smooth, false)
}

/// [`process_columns`] that also checks the filter covariance after every step
/// ([`Processed::covariance`]); the estimates are the same.
pub fn process_columns_checked(
    config: &Config,
    learned: Option<Learned>,
    h: f64,
    columns: &Columns,
    smooth: bool,
) -> Result<Processed, Error> {
    let n = columns.check()?;
    run(config, learned, h, n, |k| columns.sample(k), smooth, true)
}

/// The FMU's stepping over `n` samples, the `k`-th given by `sample(k)`; with `check`, the
/// covariance is checked after every filter step.
fn run(
    config: &Config,
    learned: Option<Learned>,
    h: f64,
    n: usize,
    sample: impl Fn(usize) -> Sample,
    smooth: bool,
    check: bool,
) -> Result<Processed, Error> {
    let start = Resume::new(config, learned);
    Ok(run_from(config, start, h, n, sample, smooth, check)?.0)
}

/// Where a run stopped: the filter, the learned filter and the distance travelled. A run
/// continued from it ([`process_columns_from`]) gives the outputs one run over all the samples
/// would: a recording longer than memory, or a day-long soak, goes through in pieces.
#[derive(Debug, Clone)]
pub struct Resume {
    /// The Kalman filter as the last step left it.
    pub core: Core,
    /// The learned filter's windows and delay line (none with `estimator` 1).
    pub learned: Option<Learned>,
    /// Distance travelled \[m\], integrated from the speed as the FMU's `distance` output.
    pub distance: f64,
    /// The sensors' biases ([`crate::bias`]).
    pub bias: crate::bias::Bias,
    /// The design line's response and its history ([`crate::design`]).
    pub design: crate::design::Design,
}

impl Resume {
    /// The start of a run: the FMU at initialization.
    pub fn new(config: &Config, learned: Option<Learned>) -> Resume {
        Resume {
            core: config.core(),
            learned,
            distance: 0.0,
            bias: crate::bias::Bias::new(config.bias_sigma),
            design: crate::design::Design::new(config.design.clone())
                .with_line(config.line.clone()),
        }
    }
}

/// [`process_columns_checked`] (with `check`) continuing from `start`, without the smoother
/// (it needs every step from the first); also where the run stopped.
pub fn process_columns_from(
    config: &Config,
    start: Resume,
    h: f64,
    columns: &Columns,
    check: bool,
) -> Result<(Processed, Resume), Error> {
    let n = columns.check()?;
    run_from(config, start, h, n, |k| columns.sample(k), false, check)
}

/// [`process_learned`] continuing from `start`, without the smoother; also where the run
/// stopped (the learned filter as the run left it: the long-wave stage's fit reads its log).
pub fn process_learned_from(
    config: &Config,
    start: Resume,
    h: f64,
    samples: &[Sample],
) -> Result<(Processed, Resume), Error> {
    run_from(
        config,
        start,
        h,
        samples.len(),
        |k| samples[k],
        false,
        false,
    )
}

/// [`run`] from `start`; also where it stopped.
fn run_from(
    config: &Config,
    start: Resume,
    h: f64,
    n: usize,
    sample: impl Fn(usize) -> Sample,
    smooth: bool,
    check: bool,
) -> Result<(Processed, Resume), Error> {
    let Resume {
        mut core,
        mut learned,
        mut distance,
        mut bias,
        mut design,
    } = start;
    let mut estimates = learned.as_ref().map(|_| Vec::with_capacity(n));
    let mut contact = learned.as_ref().map(|_| Vec::with_capacity(n));
    let (mut conicity, mut novelty, mut outside) = (Vec::new(), Vec::new(), Vec::new());
    if !(h > 0.0 && h.is_finite()) {
        return Err(Error::SampleStep(h));
    }
    if smooth {
        core.record_history();
    }
    let mut out = Processed::default();
    // For each sample, the index of the last filter step at or before it (None before the first).
    let mut step_of: Vec<Option<usize>> = Vec::with_capacity(n);
    let initial = core.alignment();
    let mut checked_p = check.then(CovarianceCheck::new);
    let mut biases = bias.active().then(|| Vec::with_capacity(n));
    for k in 0..n {
        let s = &sample(k);
        let settings = step::Settings {
            min_speed: config.min_speed,
            design_speed: config.design_speed,
        };
        let input = step::Input {
            speed: s.speed,
            sensors: [s.ws_acc_y, s.ws_yaw_rate, s.frame_acc_y, s.ws_roll_rate],
            design: s.design,
        };
        let stepped = step::step(
            settings,
            &mut core,
            learned.as_mut(),
            &mut bias,
            &mut design,
            &mut distance,
            h,
            input,
        )
        .map_err(|source| Error::AtSample {
            index: k + 1,
            source,
        })?;
        if let step::Stepped::Filtered { update, .. } = stepped {
            if update.is_err_and(|skip| skip != crate::engine::Skip::Pending) {
                out.skipped += 1;
            }
            if let Some(c) = checked_p.as_mut() {
                c.add(&core);
            }
        }
        step_of.push(core.recorded_steps().checked_sub(1));
        out.distance.push(distance);
        if let Some(b) = biases.as_mut() {
            b.push(bias.estimate);
        }
        out.filtered.push(core.alignment());
        let changes = bias.integrals.outputs();
        outside.push(step::outside_training(learned.as_ref(), &design, &bias));
        out.changes.push(changes);
        if let (Some(l), Some(e), Some(c)) = (&learned, estimates.as_mut(), contact.as_mut()) {
            let grow = crate::integrals::growth(changes);
            let mut estimate = l.estimate(distance, core.alignment());
            estimate.std *= grow;
            estimate.lagged_std *= grow;
            e.push(estimate);
            c.push(l.contact_scale());
            conicity.push(l.conicity());
            novelty.push(l.novelty());
        }
    }
    out.learned = estimates;
    out.bias = biases;
    out.conicity = contact.is_some().then_some(conicity);
    out.novelty = contact.is_some().then_some(novelty);
    out.outside_training = outside;
    out.contact_scale = contact;
    out.covariance = checked_p;
    if smooth {
        let smoothed = core.smoothed_alignment();
        out.smoothed = Some(
            step_of
                .iter()
                .map(|k| k.map_or(initial, |k| smoothed[k]))
                .collect(),
        );
    }
    let end = Resume {
        core,
        learned,
        distance,
        bias,
        design,
    };
    Ok((out, end))
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmi_abi::instance::Instance;
    use fmi_abi::{InstantiateContext, Logger};

    fn samples(n: usize, speed: impl Fn(usize) -> f64) -> Vec<Sample> {
        (0..n)
            .map(|k| Sample {
                speed: speed(k),
                ws_acc_y: 0.3 * (k as f64 * 0.05).sin(),
                ws_yaw_rate: 0.01 * (k as f64 * 0.03).cos(),
                frame_acc_y: 0.05 * (k as f64 * 0.02).sin(),
                ws_roll_rate: 0.0,
                design: [0.0; 2],
            })
            .collect()
    }

    /// The offline filter is the FMU's filter: same outputs, bit for bit, for every prior and
    /// gain, under a speed that starts below min_speed and changes at every step.
    #[test]
    fn offline_filtering_equals_the_fmu() {
        for (model, gain) in [("1", "1"), ("2", "1"), ("3", "1"), ("3", "2")] {
            let overrides = vec![
                ("use_calibration_file".to_string(), "false".to_string()),
                ("alignment_model".to_string(), model.to_string()),
                ("gain".to_string(), gain.to_string()),
                ("estimator".to_string(), "1".to_string()),
            ];
            let values = settings(&overrides).unwrap();
            let (config, _) = config(&values, None).unwrap();
            let speed = |k: usize| if gain == "2" { 20.0 } else { 0.002 * k as f64 };
            let recorded = samples(1500, speed);
            let offline = process(&config, 1e-3, &recorded, false).unwrap();

            let ctx = InstantiateContext {
                instance_name: "t".into(),
                resources: None,
            };
            let mut inst = Instance::<crate::Estimator>::new(&ctx, Logger::silent())
                .map_err(|(_, e)| e)
                .unwrap();
            inst.set_boolean(&[vr::USE_CALIBRATION_FILE], &[false])
                .unwrap();
            inst.set_integer(
                &[vr::ALIGNMENT_MODEL, vr::GAIN, vr::ESTIMATOR],
                &[model.parse().unwrap(), gain.parse().unwrap(), 1],
            )
            .unwrap();
            inst.setup_experiment(0.0, None).unwrap();
            inst.enter_initialization_mode().unwrap();
            inst.exit_initialization_mode().unwrap();
            let mut t = 0.0;
            for (k, s) in recorded.iter().enumerate() {
                inst.set_real(
                    &[vr::SPEED, vr::WS_ACC_Y, vr::WS_YAW_RATE, vr::FRAME_ACC_Y],
                    &[s.speed, s.ws_acc_y, s.ws_yaw_rate, s.frame_acc_y],
                )
                .unwrap();
                inst.do_step(t, 1e-3).unwrap();
                t += 1e-3;
                let mut o = [0.0; 3];
                inst.get_real(&[vr::ALIGNMENT, vr::ALIGNMENT_STD, vr::DISTANCE], &mut o)
                    .unwrap();
                assert_eq!(
                    (o[0], o[1]),
                    offline.filtered[k],
                    "model {model} gain {gain} step {k}"
                );
                assert_eq!(o[2], offline.distance[k]);
            }
        }
    }

    /// With the learned filter (the default), the offline outputs are the FMU's too, bit for
    /// bit: alignment, its std, the lagged estimate and which estimator is active, under a
    /// speed that rises through the taps' lower bound.
    #[test]
    fn offline_learned_filtering_equals_the_fmu() {
        // Without resources the FMU has no calibration file: the diagonal noise model on both,
        // a Kalman channel other than the bank's (allowed: the two sides are compared here).
        let values = settings(&[
            ("use_calibration_file".into(), "false".into()),
            ("allow_other_kalman".into(), "true".into()),
        ])
        .unwrap();
        let (config, _) = config(&values, None).unwrap();
        let speed = |k: usize| 3.0 + 0.002 * k as f64;
        let recorded = samples(6000, speed);
        // A roll-rate column the three-sensor taps do not use, NaN or implausible in places:
        // it must change nothing (the FMU leaves that input unread).
        let with_roll: Vec<Sample> = recorded
            .iter()
            .enumerate()
            .map(|(k, s)| Sample {
                ws_roll_rate: [f64::NAN, 1e9, 0.01][k % 3],
                ..*s
            })
            .collect();
        let offline = process_learned(
            &config,
            learned(&values, &config).unwrap(),
            1e-3,
            &with_roll,
            false,
        )
        .unwrap();
        let est = offline.learned.unwrap();
        assert!(
            est.iter()
                .any(|e| e.active == crate::learned::ACTIVE_LEARNED)
        );
        assert!(est.iter().any(|e| e.active == crate::learned::ACTIVE_PAPER));
        let ctx = InstantiateContext {
            instance_name: "t".into(),
            resources: None,
        };
        let mut inst = Instance::<crate::Estimator>::new(&ctx, Logger::silent())
            .map_err(|(_, e)| e)
            .unwrap();
        inst.set_boolean(
            &[vr::USE_CALIBRATION_FILE, vr::ALLOW_OTHER_KALMAN],
            &[false, true],
        )
        .unwrap();
        inst.setup_experiment(0.0, None).unwrap();
        inst.enter_initialization_mode().unwrap();
        inst.exit_initialization_mode().unwrap();
        let mut t = 0.0;
        for (k, s) in recorded.iter().enumerate() {
            inst.set_real(
                &[vr::SPEED, vr::WS_ACC_Y, vr::WS_YAW_RATE, vr::FRAME_ACC_Y],
                &[s.speed, s.ws_acc_y, s.ws_yaw_rate, s.frame_acc_y],
            )
            .unwrap();
            inst.do_step(t, 1e-3).unwrap();
            t += 1e-3;
            let mut o = [0.0; 7];
            inst.get_real(
                &[
                    vr::ALIGNMENT,
                    vr::ALIGNMENT_STD,
                    vr::ALIGNMENT_LAGGED,
                    vr::ALIGNMENT_LAGGED_STD,
                    vr::CONTACT_SCALE,
                    vr::CONICITY_ESTIMATE,
                    vr::NOVELTY,
                ],
                &mut o,
            )
            .unwrap();
            let mut active = [0];
            inst.get_integer(&[vr::ACTIVE_ESTIMATOR], &mut active)
                .unwrap();
            let e = est[k];
            let c = offline.contact_scale.as_ref().unwrap()[k];
            let (a, n) = (
                offline.conicity.as_ref().unwrap()[k],
                offline.novelty.as_ref().unwrap()[k],
            );
            assert_eq!(
                o,
                [e.alignment, e.std, e.lagged, e.lagged_std, c, a, n],
                "step {k}"
            );
            assert_eq!(active[0], e.active, "step {k}");
        }
    }

    /// Columns read in place give the samples' results, bit for bit, with and without the
    /// roll-rate column; unequal columns are refused by name.
    #[test]
    fn columns_are_processed_as_samples() {
        let values = settings(&[("use_roll_rate".into(), "true".into())]).unwrap();
        let (config, _) = config(&values, None).unwrap();
        let recorded = samples(3000, |k| 10.0 + 0.005 * k as f64);
        let col = |f: fn(&Sample) -> f64| recorded.iter().map(f).collect::<Vec<f64>>();
        let (v, a, y, f) = (
            col(|s| s.speed),
            col(|s| s.ws_acc_y),
            col(|s| s.ws_yaw_rate),
            col(|s| s.frame_acc_y),
        );
        let roll: Vec<f64> = (0..v.len())
            .map(|k| 0.01 * (k as f64 * 0.1).sin())
            .collect();
        for with_roll in [false, true] {
            let columns = Columns {
                speed: &v,
                ws_acc_y: &a,
                ws_yaw_rate: &y,
                frame_acc_y: &f,
                ws_roll_rate: with_roll.then_some(roll.as_slice()),
                design: None,
            };
            let rows = if with_roll {
                Sample::with_roll_rate(recorded.clone(), &roll)
            } else {
                recorded.clone()
            };
            let want = process_learned(
                &config,
                learned(&values, &config).unwrap(),
                1e-3,
                &rows,
                true,
            );
            let got = process_columns(
                &config,
                learned(&values, &config).unwrap(),
                1e-3,
                &columns,
                true,
            );
            assert_eq!(got.unwrap(), want.unwrap());
        }
        let short = Columns {
            speed: &v,
            ws_acc_y: &a,
            ws_yaw_rate: &y[1..],
            frame_acc_y: &f,
            ws_roll_rate: None,
            design: None,
        };
        let err = process_columns(&config, None, 1e-3, &short, false).unwrap_err();
        assert!(
            err.to_string().contains("'ws_yaw_rate' has 2999 samples"),
            "{err}"
        );
    }

    /// Oracle: causality. Cutting the record at sample `k` (here: changing every sample from
    /// `k` on) leaves every output before `k` unchanged, the learned filter's causal estimate
    /// and its fixed-lag estimate alike, for both sensor sets.
    #[test]
    fn the_learned_outputs_read_no_later_sample() {
        for roll in ["false", "true"] {
            let values = settings(&[("use_roll_rate".into(), roll.into())]).unwrap();
            let (config, _) = config(&values, None).unwrap();
            let recorded: Vec<Sample> = samples(8000, |_| 20.0)
                .into_iter()
                .enumerate()
                .map(|(k, s)| Sample {
                    ws_roll_rate: 0.02 * (k as f64 * 0.07).sin(),
                    ..s
                })
                .collect();
            let run = |r: &[Sample]| {
                process_learned(&config, learned(&values, &config).unwrap(), 1e-3, r, false)
                    .unwrap()
                    .learned
                    .unwrap()
            };
            let before = run(&recorded);
            let k = 6000;
            let mut cut = recorded.clone();
            for s in &mut cut[k..] {
                s.ws_acc_y += 1.0;
                s.ws_roll_rate -= 0.1;
            }
            let after = run(&cut);
            assert_eq!(before[..k], after[..k], "roll rate {roll}");
            assert!(before[k..].iter().zip(&after[k..]).any(|(a, b)| a != b));
            assert!(before[k - 1].active == crate::learned::ACTIVE_LEARNED);
        }
    }

    #[test]
    fn bad_settings_are_named() {
        let e = settings(&[("nope".into(), "1".into())])
            .unwrap_err()
            .to_string();
        assert!(e.contains("'nope'"), "{e}");
        let e = settings(&[("prior_a".into(), "x".into())])
            .unwrap_err()
            .to_string();
        assert!(e.contains("prior_a") && e.contains("not a number"), "{e}");
        let e = settings(&[("alignment".into(), "1".into())])
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a parameter"), "{e}");
        let v = settings(&[("alignment_model".into(), "7".into())]).unwrap();
        assert!(
            config(&v, None)
                .unwrap_err()
                .to_string()
                .contains("alignment_model")
        );
    }

    /// The smoother's estimate is at least as good as the filter's on data from the model
    /// itself, and its variance is never larger than the filter's.
    #[test]
    fn smoothing_never_increases_the_variance() {
        let values = settings(&[("alignment_model".into(), "3".into())]).unwrap();
        let (config, _) = config(&values, None).unwrap();
        let recorded = samples(3000, |_| 20.0);
        let out = process(&config, 1e-3, &recorded, true).unwrap();
        let smoothed = out.smoothed.unwrap();
        assert_eq!(smoothed.len(), recorded.len());
        for (f, s) in out.filtered.iter().zip(&smoothed) {
            assert!(s.1 <= f.1 * (1.0 + 1e-9), "{} > {}", s.1, f.1);
        }
        // The last sample has seen everything in both.
        assert_eq!(smoothed.last(), out.filtered.last());
    }

    /// Measurement (run by hand): the covariance over a long run at varying speed with stops,
    /// per estimator and gain. `MEASURE_SECONDS` sets the simulated length.
    #[test]
    #[ignore]
    fn measure_covariance_over_a_long_run() {
        let seconds: f64 = std::env::var("MEASURE_SECONDS").map_or(600.0, |s| s.parse().unwrap());
        let n = (seconds * 1000.0) as usize;
        // 0 -> 40 m/s and back in 200 s cycles, with 20 s stops.
        let speed = |k: usize| {
            let t = (k as f64 * 1e-3) % 220.0;
            if t < 20.0 {
                0.0
            } else {
                40.0 * (std::f64::consts::PI * (t - 20.0) / 200.0).sin()
            }
        };
        let rows = samples(n, speed);
        for (estimator, gain) in [("1", "1"), ("1", "2"), ("2", "0"), ("2", "1")] {
            let overrides = vec![
                ("gain".to_string(), gain.to_string()),
                ("estimator".to_string(), estimator.to_string()),
            ];
            let values = settings(&overrides).unwrap();
            let (config, _) = config(&values, None).unwrap();
            let columns = Columns {
                speed: &rows.iter().map(|s| s.speed).collect::<Vec<_>>(),
                ws_acc_y: &rows.iter().map(|s| s.ws_acc_y).collect::<Vec<_>>(),
                ws_yaw_rate: &rows.iter().map(|s| s.ws_yaw_rate).collect::<Vec<_>>(),
                frame_acc_y: &rows.iter().map(|s| s.frame_acc_y).collect::<Vec<_>>(),
                ws_roll_rate: None,
                design: None,
            };
            let t = std::time::Instant::now();
            let out = process_columns_checked(
                &config,
                learned(&values, &config).unwrap(),
                1e-3,
                &columns,
                false,
            )
            .unwrap();
            println!(
                "estimator {estimator} gain {gain}: {:?} in {:.1} s",
                out.covariance.unwrap(),
                t.elapsed().as_secs_f64()
            );
        }
    }

    /// A run continued in pieces gives the outputs of one run over all the samples, bit for
    /// bit, for the learned filter (default) and the paper's time-varying filter, under a speed
    /// that stops and changes every step; the covariance check covers every step of both.
    #[test]
    fn a_run_continued_in_pieces_equals_one_run() {
        let speed = |k: usize| {
            if (k / 700).is_multiple_of(3) {
                0.0
            } else {
                5.0 + 0.01 * (k % 700) as f64
            }
        };
        let rows = samples(6000, speed);
        let col = |f: fn(&Sample) -> f64| rows.iter().map(f).collect::<Vec<_>>();
        let (v, a, y, f) = (
            col(|s| s.speed),
            col(|s| s.ws_acc_y),
            col(|s| s.ws_yaw_rate),
            col(|s| s.frame_acc_y),
        );
        let columns = |r: std::ops::Range<usize>| Columns {
            speed: &v[r.clone()],
            ws_acc_y: &a[r.clone()],
            ws_yaw_rate: &y[r.clone()],
            frame_acc_y: &f[r],
            ws_roll_rate: None,
            design: None,
        };
        for overrides in [vec![], vec![("estimator", "1")]] {
            let overrides: Vec<(String, String)> = overrides
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            let values = settings(&overrides).unwrap();
            let (config, _) = config(&values, None).unwrap();
            let whole = process_columns_checked(
                &config,
                learned(&values, &config).unwrap(),
                1e-3,
                &columns(0..6000),
                false,
            )
            .unwrap();
            let mut state = Resume::new(&config, learned(&values, &config).unwrap());
            let mut pieces = Processed::default();
            let mut steps = 0;
            for r in [0..1000, 1000..1001, 1001..4500, 4500..6000] {
                let (out, end) =
                    process_columns_from(&config, state, 1e-3, &columns(r), true).unwrap();
                state = end;
                pieces.distance.extend(out.distance);
                pieces.filtered.extend(out.filtered);
                pieces.learned = match (pieces.learned.take(), out.learned) {
                    (Some(mut a), Some(b)) => {
                        a.extend(b);
                        Some(a)
                    }
                    (None, b) => b,
                    (a, None) => a,
                };
                pieces.skipped += out.skipped;
                steps += out.covariance.unwrap().steps;
            }
            assert_eq!(pieces.distance, whole.distance, "{overrides:?}");
            assert_eq!(pieces.filtered, whole.filtered, "{overrides:?}");
            assert_eq!(pieces.learned, whole.learned, "{overrides:?}");
            let check = whole.covariance.unwrap();
            assert_eq!(steps, check.steps);
            // The samples that move (2100 of 6000 stand below min_speed).
            assert_eq!(check.steps, 3900);
            assert!(
                check.min_eigenvalue > 0.0 && check.max_asymmetry == 0.0,
                "{check:?}"
            );
            assert_eq!((check.not_positive_definite, check.eigen_steps), (0, 4));
        }
    }

    /// The `calibration_file` setting gives what the `calibration` argument gives (the FMU
    /// honours it; the offline path once ignored it and ran the shipped calibration), and
    /// naming two different files, or one that does not exist, is refused.
    #[test]
    fn the_calibration_file_setting_is_the_calibration_argument() {
        let dir = std::env::temp_dir().join(format!("offline-calibration-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // The shipped calibration with the yaw gyroscope's R four times larger.
        let text = calibration::SHIPPED.replacen(
            "[-2.5541701478697552e-5, 2.495913417533243e-7,",
            "[-2.5541701478697552e-5, 9.983653670132972e-7,",
            1,
        );
        assert_ne!(
            text,
            calibration::SHIPPED,
            "the shipped R row moved: update the test"
        );
        let file = dir.join("other.toml");
        std::fs::write(&file, text).unwrap();
        let run = |setting: Option<&Path>, argument: Option<&Path>| {
            let mut overrides = vec![("estimator".to_string(), "1".to_string())];
            if let Some(p) = setting {
                overrides.push(("calibration_file".into(), p.to_str().unwrap().into()));
            }
            let (config, _) = config(&settings(&overrides).unwrap(), argument)?;
            let recorded = samples(1500, |_| 20.0);
            Ok::<_, Error>(process(&config, 1e-3, &recorded, false).unwrap().filtered)
        };
        let by_setting = run(Some(&file), None).unwrap();
        assert_eq!(by_setting, run(None, Some(&file)).unwrap());
        assert_eq!(by_setting, run(Some(&file), Some(&file)).unwrap());
        let roundabout = dir
            .join("..")
            .join(dir.file_name().unwrap())
            .join("other.toml");
        assert_eq!(by_setting, run(Some(&file), Some(&roundabout)).unwrap());
        assert_ne!(by_setting, run(None, None).unwrap());
        let shipped = dir.join("shipped.toml");
        std::fs::write(&shipped, calibration::SHIPPED).unwrap();
        let twice = run(Some(&file), Some(&shipped)).unwrap_err().to_string();
        assert!(
            twice.contains("named twice") && twice.contains("other.toml"),
            "{twice}"
        );
        let missing = run(Some(&dir.join("none.toml")), None)
            .unwrap_err()
            .to_string();
        assert!(
            missing.contains("calibration_file") && missing.contains("none.toml"),
            "{missing}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
