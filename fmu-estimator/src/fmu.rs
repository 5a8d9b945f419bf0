//! The estimator as an FMI model: its variable table and what each FMI phase does.
//!
//! Timing: `fmi2DoStep(t, h)` predicts from `t` to `t + h` and then updates with the inputs
//! present at that call, taken as the sensor samples at `t + h`. That is what a Gauss-Seidel
//! master with the vehicle stepped first delivers; with a Jacobi master the samples are one
//! step old, a latency the study accounts for. Outputs are the estimate at `t + h`.

use crate::config::{Config, Note};
use crate::core::Core;
use crate::engine::Skip;
use crate::error::{Error, SettingError};
use crate::learned::{Bank, Choice, Learned};
use crate::step;
use fmi_abi::{InstantiateContext, Logger, Model, ModelInfo, StepOutcome, Values, VarSpec};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

pub use crate::variables::{VARIABLES, vr};

/// How far (relative) the communication step may be from the learned filter's sample step
/// before the log says so once: rounding of a step written in decimal
/// is far below it, a real other rate (500 Hz against 1 kHz) far above.
const STEP_TOLERANCE: f64 = 0.01;

/// The estimator's FMI model state. Everything here is part of a saved FMU state.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Estimator {
    resources: Option<PathBuf>,
    /// The filter, built at the end of initialization.
    core: Option<Core>,
    min_speed: f64,
    /// `> 0`: the speed the filter's matrices are built for, whatever the input says.
    design_speed: f64,
    holding: bool,
    /// The learned filter (estimator 2).
    learned: Option<Learned>,
    /// The sensors' biases.
    bias: crate::bias::Bias,
    /// The design line's response ([`crate::design`]).
    design: crate::design::Design,
    /// Whether the design line went beyond the design model's envelope (warned once).
    design_warned: bool,
    /// Whether design inputs were seen set while `line_file` gives the design (warned once).
    inputs_ignored_warned: bool,
    /// Whether the last step's speed was outside the taps' range (for the warning on entry).
    outside: bool,
    /// Whether `outside_training` has set in this run (warned once).
    novelty_warned: bool,
    /// Whether a yaw-rate bias was suspected in this run (warned once).
    bias_warned: bool,
    /// Whether the integrals' check has set `outside_training` in this run (warned once).
    integrals_warned: bool,
    /// The step size warned about, if any (once).
    step_warned: bool,
    /// Warnings that recur per step, logged once and counted.
    repeats: fmi_abi::logger::Repeats,
    /// This instance's share of the parsed files ([`crate::parsed`]): when the last instance
    /// (or saved state) goes, they are let go, so that an importer may unload the library.
    #[serde(skip)]
    _files: FilesInUse,
}

/// The FMU's instances and saved states, as users of the parsed tap banks and design responses.
static FILES: crate::parsed::Group = crate::parsed::Group::new(|| {
    crate::learned::bank::BANKS.clear();
    crate::design::MODELS.clear();
});

/// A member of [`FILES`] (a new one for every instance, copy and restored state).
#[derive(Debug, Clone)]
struct FilesInUse(#[allow(dead_code, reason = "held for its drop")] crate::parsed::Member);

impl Default for FilesInUse {
    fn default() -> Self {
        FilesInUse(FILES.join())
    }
}

impl Estimator {
    fn write_outputs(&self, v: &mut Values) {
        let Some(core) = &self.core else { return };
        let (xi, std) = core.alignment();
        let (body, xi_rate) = core.states();
        let distance = v.real[vr::DISTANCE as usize];
        let changes = self.bias.integrals.outputs();
        // A curve or a bias not told: the estimate's error grows with what it did not explain
        // ([`crate::integrals`]), whichever estimator gives it.
        let grow = crate::integrals::growth(changes);
        v.boolean[vr::OUTSIDE_TRAINING as usize] =
            crate::step::outside_training(self.learned.as_ref(), &self.design, &self.bias);
        let [heading, velocity, level] = changes;
        v.real[vr::HEADING_CHANGE as usize] = heading;
        v.real[vr::RELATIVE_VELOCITY_CHANGE as usize] = velocity;
        v.real[vr::HEADING_LEVEL as usize] = level;
        let o = &mut v.real;
        o[vr::ALIGNMENT_KALMAN as usize] = xi;
        match &self.learned {
            Some(l) => {
                let e = l.estimate(distance, (xi, std));
                o[vr::ALIGNMENT as usize] = e.alignment;
                o[vr::ALIGNMENT_STD as usize] = e.std * grow;
                o[vr::ALIGNMENT_LAGGED as usize] = e.lagged;
                o[vr::ALIGNMENT_LAGGED_STD as usize] = e.lagged_std * grow;
                o[vr::DISTANCE_LAGGED as usize] = distance - l.lag();
                v.integer[vr::ACTIVE_ESTIMATOR as usize] = e.active;
                v.real[vr::CONTACT_SCALE as usize] = l.contact_scale();
                v.real[vr::CONICITY_ESTIMATE as usize] = l.conicity();
                v.real[vr::NOVELTY as usize] = l.novelty();
            }
            None => {
                o[vr::ALIGNMENT as usize] = xi;
                o[vr::ALIGNMENT_STD as usize] = std * grow;
                o[vr::ALIGNMENT_LAGGED as usize] = xi;
                o[vr::ALIGNMENT_LAGGED_STD as usize] = std * grow;
                o[vr::DISTANCE_LAGGED as usize] = distance;
                v.integer[vr::ACTIVE_ESTIMATOR as usize] = crate::learned::ACTIVE_PAPER;
                v.real[vr::CONTACT_SCALE as usize] = 0.0;
                v.real[vr::CONICITY_ESTIMATE as usize] = 0.0;
                v.real[vr::NOVELTY as usize] = 0.0;
            }
        }
        let o = &mut v.real;
        for (r, b) in [
            vr::WS_ACC_Y_BIAS,
            vr::WS_YAW_RATE_BIAS,
            vr::FRAME_ACC_Y_BIAS,
            vr::WS_ROLL_RATE_BIAS,
        ]
        .into_iter()
        .zip(self.bias.estimate)
        {
            o[r as usize] = b;
        }
        for (k, r) in [
            vr::EST_Y,
            vr::EST_PSI,
            vr::EST_Y_F,
            vr::EST_VY,
            vr::EST_PSI_RATE,
            vr::EST_VY_F,
        ]
        .into_iter()
        .enumerate()
        {
            o[r as usize] = body[k];
        }
        o[vr::EST_XI_RATE as usize] = xi_rate;
        v.integer[vr::SKIPPED_UPDATES as usize] = core.skipped();
        v.integer[vr::REBUILDS as usize] = core.rebuilds();
    }
}

impl Model for Estimator {
    const INFO: ModelInfo = ModelInfo {
        model_name: "AlignmentEstimator",
        model_identifier: "AlignmentEstimator",
        // By build.rs from the sources and what shapes the modelDescription: new when they change.
        guid: env!("ESTIMATOR_GUID"),
        description: "Estimate of the lateral alignment of a railway track (from its design line where design_curvature and design_cant or line_file give it) from a wheelset accelerometer, a wheelset yaw gyroscope and a bogie-frame accelerometer: by default the learned filter (estimator = 2, with the Kalman filter as one of its channels); estimator = 1 is the paper's Kalman filter (Munoz, Ros, Escalona).",
        author: "railway track-geometry toolkit",
        version: env!("CARGO_PKG_VERSION"),
        default_start: 0.0,
        default_stop: 20.0,
        default_step: 0.001,
    };
    /// The sources' and tap banks' fingerprint (build.rs): a state saved by another build is
    /// refused.
    const STATE_LAYOUT: &'static str = env!("ESTIMATOR_STATE_LAYOUT");

    fn variables() -> &'static [VarSpec] {
        VARIABLES
    }

    fn instantiate(ctx: &InstantiateContext, _log: &Logger) -> Result<Self, String> {
        Ok(Estimator {
            resources: ctx.resources.clone(),
            core: None,
            min_speed: crate::variables::MIN_SPEED_DEFAULT,
            design_speed: 0.0,
            holding: false,
            learned: None,
            bias: crate::bias::Bias::new([0.0; 4]),
            design: crate::design::Design::new(None),
            design_warned: false,
            inputs_ignored_warned: false,
            outside: false,
            novelty_warned: false,
            bias_warned: false,
            integrals_warned: false,
            step_warned: false,
            repeats: Default::default(),
            _files: FilesInUse::default(),
        })
    }

    fn calculate_initial(&mut self, v: &mut Values) {
        v.real[vr::ALIGNMENT_STD as usize] = v.real[vr::P0_XI as usize];
        v.real[vr::ALIGNMENT_LAGGED_STD as usize] = v.real[vr::P0_XI as usize];
        let lag = v.real[vr::LAG as usize];
        let learned = v.integer[vr::ESTIMATOR as usize] == 2 && lag.is_finite() && lag > 0.0;
        v.real[vr::DISTANCE_LAGGED as usize] = if learned { -lag } else { 0.0 };
    }

    fn exit_initialization(&mut self, v: &mut Values, log: &Logger) -> Result<(), String> {
        // fmi-abi's Model takes messages: the layer logs them with fmi2Error.
        let (config, notes) =
            Config::from_values(v, self.resources.as_deref()).map_err(|e| e.to_string())?;
        for note in notes {
            match note {
                Note::Info(m) => log.info(&m),
                Note::Warning(m) => log.warning(&m),
            }
        }
        let core = config.core();
        let speed = v.real[vr::SPEED as usize];
        if speed.is_finite() && speed >= config.min_speed {
            let (rank, n, lambda) = core.observability(speed);
            if rank < n {
                log.warning(&format!(
                    "the model is not observable at {speed} m/s (PBH rank {rank} < {n} at eigenvalue {lambda}): some states cannot be estimated from the sensors"
                ));
            }
        }
        self.min_speed = config.min_speed;
        self.design_speed = config.design_speed;
        self.learned = learned_from_values(v, self.resources.as_deref(), &config, log)
            .map_err(|e| e.to_string())?;
        self.core = Some(core);
        self.bias = crate::bias::Bias::new(config.bias_sigma);
        self.design =
            crate::design::Design::new(config.design.clone()).with_line(config.line.clone());
        self.design_warned = false;
        self.inputs_ignored_warned = false;
        self.holding = false;
        self.outside = false;
        self.novelty_warned = false;
        self.bias_warned = false;
        self.integrals_warned = false;
        self.step_warned = false;
        self.repeats.clear();
        self.write_outputs(v);
        Ok(())
    }

    fn terminate(&mut self, _: &mut Values, log: &Logger) {
        self.repeats.report(log);
    }

    fn do_step(
        &mut self,
        v: &mut Values,
        _t: f64,
        h: f64,
        log: &Logger,
    ) -> Result<StepOutcome, String> {
        let input = step::Input {
            speed: v.real[vr::SPEED as usize],
            sensors: [
                v.real[vr::WS_ACC_Y as usize],
                v.real[vr::WS_YAW_RATE as usize],
                v.real[vr::FRAME_ACC_Y as usize],
                v.real[vr::WS_ROLL_RATE as usize],
            ],
            design: [
                v.real[vr::DESIGN_CURVATURE as usize],
                v.real[vr::DESIGN_CANT as usize],
            ],
        };
        let settings = step::Settings {
            min_speed: self.min_speed,
            design_speed: self.design_speed,
        };
        let core = self.core.as_mut().ok_or("the filter was not initialized")?;
        let stepped = step::step(
            settings,
            core,
            self.learned.as_mut(),
            &mut self.bias,
            &mut self.design,
            &mut v.real[vr::DISTANCE as usize],
            h,
            input,
        )
        .map_err(|e| e.to_string())?;
        match stepped {
            step::Stepped::Held { finite_speed } => {
                v.boolean[vr::UPDATED as usize] = false;
                Ok(self.held(input.speed, finite_speed, log))
            }
            step::Stepped::Filtered {
                update,
                implausible,
            } => {
                self.holding = false;
                let mut outcome = self.note_implausible(&implausible, log);
                self.note_step(h, log);
                if let Some(note) = self.core.as_mut().and_then(|c| c.take_start_note()) {
                    log.warning(&note);
                }
                let updated = match update {
                    Ok(nis) => {
                        v.real[vr::NIS as usize] = nis;
                        true
                    }
                    // A sample step shorter than the filter's: no update yet, nothing wrong.
                    Err(Skip::Pending) => false,
                    Err(skip) => {
                        self.note_skip(skip, implausible.is_empty(), input.sensors, log);
                        outcome = StepOutcome::Warning;
                        false
                    }
                };
                v.boolean[vr::UPDATED as usize] = updated;
                self.note_speed_range(input.speed, log);
                self.note_novelty(v.real[vr::DISTANCE as usize], log);
                self.note_bias(v.real[vr::DISTANCE as usize], log);
                self.note_integrals(v.real[vr::DISTANCE as usize], log);
                self.note_design(v.real[vr::DISTANCE as usize], input.design, log);
                self.write_outputs(v);
                Ok(outcome)
            }
        }
    }
}

/// What a step logs, once or by [`Repeats`], so that a long run's log says each thing once and
/// counts the rest. Apart from [`Model::do_step`] so the step reads as the filter's sequence.
impl Estimator {
    /// The filter held (speed below `min_speed`, or not finite): said once per hold.
    fn held(&mut self, speed: f64, finite_speed: bool, log: &Logger) -> StepOutcome {
        if !self.holding {
            log.info(&format!(
                "speed {speed} m/s is below min_speed {} m/s: holding the estimate",
                self.min_speed
            ));
            self.holding = true;
        }
        if finite_speed {
            return StepOutcome::Ok;
        }
        self.repeats.warn(log, "non-finite speed", || {
            format!("non-finite speed {speed}: estimate held")
        });
        StepOutcome::Warning
    }

    /// Sensors replaced as implausible this step.
    fn note_implausible(&mut self, implausible: &[String], log: &Logger) -> StepOutcome {
        if implausible.is_empty() {
            return StepOutcome::Ok;
        }
        self.repeats.warn(log, "implausible sensor sample", || {
            format!(
                "implausible sensor sample ({}): skipped like a non-finite one",
                implausible.join(", ")
            )
        });
        StepOutcome::Warning
    }

    /// A communication step other than the taps' sample step: said once.
    fn note_step(&mut self, h: f64, log: &Logger) {
        if let Some(l) = self.learned.as_ref()
            && !self.step_warned
            && (h - l.sample_step()).abs() > STEP_TOLERANCE * l.sample_step()
        {
            log.info(&format!(
                "step {h} s: the learned filter's taps were fitted on samples every {} s; its grid is by distance and its Kalman channel runs on its own clock, so the estimate holds at this step to the figures of docs/estimator-fmu.md (\"Sample step\")",
                l.sample_step()
            ));
            self.step_warned = true;
        }
    }

    /// A skipped measurement update; a non-finite sample already reported as implausible is
    /// not reported twice.
    fn note_skip(&mut self, skip: Skip, unreported: bool, sensors: [f64; 4], log: &Logger) {
        match skip {
            Skip::NonFinite if unreported => {
                self.repeats.warn(log, "non-finite sensor sample", || {
                    format!(
                        "non-finite sensor sample (ws_acc_y={}, ws_yaw_rate={}, frame_acc_y={}): measurement update skipped, prediction kept",
                        sensors[0], sensors[1], sensors[2]
                    )
                });
            }
            Skip::NonFinite | Skip::Pending => {}
            Skip::NotPositiveDefinite => {
                self.repeats
                    .warn(log, "innovation covariance not positive definite", || {
                        "innovation covariance not positive definite: measurement update skipped"
                            .into()
                    });
            }
        }
    }

    /// The design line beyond the design model's envelope ([`crate::design`]), and design inputs
    /// set while `line_file` gives the design (they are not read): each said once.
    fn note_design(&mut self, distance: f64, inputs: [f64; 2], log: &Logger) {
        if self.design.from_line() && inputs != [0.0; 2] && !self.inputs_ignored_warned {
            log.warning(&format!(
                "at {distance:.1} m design_curvature and design_cant are set ({:.2e} 1/m, {:.3} m) but line_file gives the design: the inputs are not read (said once)",
                inputs[0], inputs[1]
            ));
            self.inputs_ignored_warned = true;
        }
        // What the correction used: the line's value, or the input as given (an invalid one,
        // replaced by the last valid, is what the warning is about).
        let design = if self.design.from_line() {
            self.design.last()
        } else {
            inputs
        };
        if self.design.outside() && !self.design_warned {
            log.warning(&format!(
                "at {distance:.1} m the design line (curvature {:.2e} 1/m, cant {:.3} m) is beyond what design_response_file was fitted on: the vehicle may be in flange contact or beyond its linear range, and the estimate is less trustworthy (outside_training set; said once)",
                design[0], design[1]
            ));
            self.design_warned = true;
        }
    }

    /// A yaw-rate mean that straight track does not give ([`crate::bias`]): said once.
    fn note_bias(&mut self, distance: f64, log: &Logger) {
        if let Some((mean, over)) = self.bias.integrals.suspected_bias()
            && !self.bias_warned
        {
            log.warning(&format!(
                "at {distance:.1} m the yaw rate's mean over the last {over:.0} m is {mean:.2e} rad/s, beyond the 1e-4 rad/s of straight track: a gyroscope bias is likely, and the estimate may be several times less accurate; set bias_sigma_ws_yaw_rate and start the run standing still (said once)"
            ));
            self.bias_warned = true;
        }
    }

    /// The integrals' check setting `outside_training` ([`crate::integrals`]): said once.
    fn note_integrals(&mut self, distance: f64, log: &Logger) {
        use crate::integrals::{VELOCITY_LEVEL, WINDOW};
        let integrals = &self.bias.integrals;
        if !integrals.outside() || self.integrals_warned {
            return;
        }
        let [heading, velocity, level] = integrals.outputs();
        let why = if heading.abs() > level {
            format!(
                "the yaw gyroscope's heading changed by {heading:.4} rad over the last {WINDOW:.0} m, beyond the {level:.4} rad that straight track's irregularities give (heading_level): a curve whose design is not connected (design_curvature and design_cant, or line_file) or a gyroscope bias not removed (bias_sigma_ws_yaw_rate and a standstill)"
            )
        } else {
            format!(
                "ws_acc_y - frame_acc_y integrates to {velocity:.3} m/s over the last {WINDOW:.0} m, beyond the {VELOCITY_LEVEL} m/s that the primary suspension allows: one accelerometer carries a bias the other does not (bias_sigma_ws_acc_y, bias_sigma_frame_acc_y and a standstill), or a curve's design is not connected"
            )
        };
        log.warning(&format!(
            "at {distance:.1} m {why}; outside_training is set, and the estimate may be many times less accurate (said once)"
        ));
        self.integrals_warned = true;
    }

    /// `outside_training` setting for the first time in the run: said once.
    fn note_novelty(&mut self, distance: f64, log: &Logger) {
        if let Some(l) = self.learned.as_ref()
            && !self.novelty_warned
            && l.outside_training()
        {
            let why = if l.beyond_conicities() {
                let c = l.selected_conicities();
                let fitted = if c[0] == c[c.len() - 1] {
                    format!("{}", c[0])
                } else {
                    format!("{}-{}", c[0], c[c.len() - 1])
                };
                format!(
                    "the wheels' conicity ({:.3}: the one told, or conicity_estimate's running mean) lies more than {:.0} % beyond the conicity the selected taps were fitted at ({fitted}): the wheels are not the ones they know",
                    l.judged_conicity().unwrap_or(l.conicity()),
                    (crate::learned::stream::CONICITY_MARGIN - 1.0) * 100.0,
                )
            } else {
                format!(
                    "the sensors are unlike what the learned taps were fitted on (novelty {:.2} > 1, conicity_estimate {:.3}, contact_scale {:.2})",
                    l.novelty(),
                    l.conicity(),
                    l.contact_scale()
                )
            };
            log.warning(&format!(
                "at {distance:.1} m {why}: outside_training is set; the estimate may be several times less accurate (said once)"
            ));
            self.novelty_warned = true;
        }
    }

    /// The speed leaving the learned taps' range: said each time it leaves.
    fn note_speed_range(&mut self, speed: f64, log: &Logger) {
        if let Some(l) = self.learned.as_ref() {
            let (lo, hi) = l.speed_range();
            let outside = !(speed >= lo && speed <= hi);
            if outside && !self.outside {
                log.warning(&format!(
                    "speed {speed} m/s is outside the learned taps' range ({lo}-{hi} m/s): 'alignment' is the Kalman filter's (active_estimator = 1) until it is back inside"
                ));
            }
            self.outside = outside;
        }
    }
}

/// The learned filter the parameters ask for (`estimator` 2), from `tap_file` (in the resources
/// directory unless absolute; when there is no resources directory, as offline, the bank built
/// into the library with the `builtin-banks` feature), its contract checked against this
/// runtime and the Kalman channel `config` builds ([`crate::learned::contract`]).
pub fn learned_from_values(
    v: &Values,
    resources: Option<&std::path::Path>,
    config: &Config,
    log: &Logger,
) -> Result<Option<Learned>, Error> {
    match v.integer[vr::ESTIMATOR as usize] {
        1 => return Ok(None),
        2 => {}
        e => return Err(SettingError::Estimator(e).into()),
    }
    let lag = v.real[vr::LAG as usize];
    if !(lag >= 0.0 && lag.is_finite()) {
        return Err(SettingError::Lag(lag).into());
    }
    let name = v.string[vr::TAP_FILE as usize].trim().to_string();
    // Without resources (the offline path) a shipped name is the bank built into the library.
    let builtin = resources
        .is_none()
        .then(|| crate::learned::shared_named(&name))
        .flatten();
    let bank = match (builtin, crate::config::user_file(&name, resources)) {
        (Some(bank), _) => bank.map_err(Error::Bank)?,
        (None, Some(path)) if !path.exists() => {
            return Err(SettingError::TapFileMissing { name, path }.into());
        }
        (None, Some(path)) => Bank::load_shared(&path).map_err(Error::Bank)?,
        (None, None) => return Err(SettingError::TapFileRelative { name }.into()),
    };
    check_contract(v, &bank, config, &name, log)?;
    let conicity = v.real[vr::CONICITY as usize];
    if !(conicity >= 0.0 && conicity.is_finite()) {
        return Err(SettingError::TapConicity(conicity).into());
    }
    let kalker = v.real[vr::KALKER_SCALE as usize];
    if !(kalker >= 0.0 && kalker.is_finite()) {
        return Err(SettingError::TapKalker(kalker).into());
    }
    let choice = Choice {
        roll_rate: v.boolean[vr::USE_ROLL_RATE as usize],
        lag,
        conicity: (conicity > 0.0).then_some(conicity),
        kalker: (kalker > 0.0).then_some(kalker),
    };
    let learned = Learned::new(&bank, choice).map_err(|source| Error::TapFile {
        tap_file: name.clone(),
        source,
    })?;
    let (lo, hi) = learned.speed_range();
    log.info(&format!(
        "learned filter from {name}: {} sensors, {lo}-{hi} m/s, lag {} m",
        if choice.roll_rate { 4 } else { 3 },
        learned.lag()
    ));
    Ok(Some(learned))
}

/// The parameters outside the Kalman channel's part of the contract: the learned filter's own,
/// the gain (the fit's time-varying channel equals the steady-state one after the start-up) and
/// the initial covariance (a start-up transient the steady-state gain does not have). Any other
/// parameter not at its default can make the channel differ from the bank's.
const OUTSIDE_THE_CONTRACT: [&str; 10] = [
    "estimator",
    "lag",
    "conicity",
    "kalker_scale",
    "use_roll_rate",
    "tap_file",
    "allow_other_kalman",
    "gain",
    "p0_xi",
    "p0_stationary",
];

/// The bank's contract against this runtime: a runtime constant or design that differs is an
/// error; a Kalman channel that differs is one too, unless `allow_other_kalman` makes it a
/// warning. The message lists the parameters not at their defaults that feed the Kalman
/// channel (the bank was fitted with the defaults, `alignment-studies taps`): where the
/// difference comes from, as far as the FMU can tell.
fn check_contract(
    v: &Values,
    bank: &Bank,
    config: &Config,
    name: &str,
    log: &Logger,
) -> Result<(), Error> {
    let here = crate::learned::contract::Contract::expected(
        config,
        bank.grid,
        bank.kalman_highpass,
        bank.kalman_shelf,
        bank.contact.as_ref().map(|c| c.band),
        bank.provenance.sample_step,
    );
    let (runtime, kalman) = bank.contract.differences(&here);
    if !runtime.is_empty() {
        return Err(Error::OtherBuild {
            tap_file: name.to_string(),
            differences: runtime.join("; "),
        });
    }
    if kalman.is_empty() {
        return Ok(());
    }
    let changed: Vec<String> = VARIABLES
        .iter()
        .filter(|s| s.is_parameter() && !OUTSIDE_THE_CONTRACT.contains(&s.name))
        .filter_map(|s| {
            let i = s.vr as usize;
            let (now, start) = match s.start {
                fmi_abi::variables::Start::Real(x) => (v.real[i].to_string(), x.to_string()),
                fmi_abi::variables::Start::Integer(x) => (v.integer[i].to_string(), x.to_string()),
                fmi_abi::variables::Start::Boolean(x) => (v.boolean[i].to_string(), x.to_string()),
                fmi_abi::variables::Start::String(x) => {
                    (format!("'{}'", v.string[i]), format!("'{x}'"))
                }
            };
            (now != start).then(|| format!("{} = {now} (default {start})", s.name))
        })
        .collect();
    let message = format!(
        "tap_file '{name}' was fitted with another Kalman channel than this one ({}): {}; parameters not at their defaults: {}",
        bank.provenance.partner,
        kalman.join("; "),
        if changed.is_empty() {
            "none".to_string()
        } else {
            changed.join(", ")
        }
    );
    if v.boolean[vr::ALLOW_OTHER_KALMAN as usize] {
        log.warning(&format!(
            "{message}. allow_other_kalman is true: the learned filter runs on this channel, approximately"
        ));
        Ok(())
    } else {
        Err(Error::OtherKalman { mismatch: message })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_variable_table_is_dense_and_the_model_description_valid() {
        fmi_abi::variables::VarIndex::new(super::VARIABLES).unwrap();
        let md = crate::model_description();
        assert_eq!(md.validate(), vec![]);
        assert_eq!(
            model_description::ModelDescription::from_xml(&md.to_xml()).unwrap(),
            md
        );
    }
}
