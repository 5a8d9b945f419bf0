//! Running the FMUs for the studies: the vehicle alone (identification, calibration) or the
//! standard system (evaluation), in-process through the master, with the variables the
//! analysis needs kept in memory.

use crate::Error;
use fmi_import::LogConfig;
use fmu_vehicle::params::VehicleParams;
use orchestrator::master::{Cosimulation, RunOptions, Table};
use orchestrator::system::{Component, Endpoint, Experiment, System, Value};
use std::path::PathBuf;

/// The two FMUs of the studies, and the user's settings for each, applied to every run before
/// the study's own (so a study's seeds and conditions hold; [`STUDY_CONTROLLED`] are refused).
#[derive(Debug, Clone, Default)]
pub struct Fmus {
    /// The vehicle FMU (RailVehicle.fmu).
    pub vehicle: PathBuf,
    /// The estimator FMU (AlignmentEstimator.fmu).
    pub estimator: PathBuf,
    /// The user's vehicle settings, checked against [`STUDY_CONTROLLED`].
    pub vehicle_settings: Settings,
    /// The user's estimator settings (a `calibration_file` brings its file's `[parameters]`
    /// along).
    pub estimator_settings: Settings,
    /// The two FMUs opened once, held for the study's runs: each run's co-simulation then
    /// shares them ([`fmi_import::Fmu::open_shared`]) instead of loading the libraries again.
    _held: Held,
}

/// FMUs kept open (see [`Fmus`]).
#[derive(Clone, Default)]
struct Held(Vec<fmi_import::Fmu>);

impl std::fmt::Debug for Held {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} FMUs held open", self.0.len())
    }
}

/// The vehicle variables the studies set themselves (seeds and the cases' conditions), and
/// those that would undo them: a track file replaces the seeded tracks and their conditions.
pub const STUDY_CONTROLLED: [&str; 9] = [
    "track_seed",
    "noise_seed",
    "vertical_irregularity",
    "lateral_irregularity",
    "sensor_noise",
    "kalker_scale",
    "harmonic_amplitude",
    "harmonic_wavelength",
    "track_file",
];

/// The vehicle's forward speed: the studies' cases and the resonance wavelength are at the
/// vehicle's default, 20 m/s.
const FIXED_SPEED: &str = "speed";

impl Fmus {
    /// The FMUs at `vehicle` and `estimator` with no settings of the user's.
    pub fn new(vehicle: PathBuf, estimator: PathBuf) -> Fmus {
        // One that cannot be opened is not held: the first run that loads it says why.
        let held = Held(
            [&vehicle, &estimator]
                .iter()
                .filter_map(|p| fmi_import::Fmu::open_shared(p).ok())
                .collect(),
        );
        Fmus {
            vehicle,
            estimator,
            _held: held,
            ..Fmus::default()
        }
    }

    /// Adds the user's setting `component.variable = text` (component `vehicle` or
    /// `estimator`); the value is typed against the FMU's model description when a run loads
    /// it.
    ///
    /// `estimator.calibration_file` also sets the simplified model's parameters the file holds
    /// (the FMU reads only Q and R from it at run time), and a relative path is made absolute
    /// (the FMU would look for it in its resources).
    pub fn set(&mut self, component: &str, variable: &str, text: &str) -> Result<(), Error> {
        let setting = (variable.to_string(), Value::String(text.to_string()));
        if (component, variable) == ("estimator", "calibration_file") {
            let path = std::path::absolute(text)
                .map_err(|e| Error::Input(format!("calibration file {text}: {e}")))?;
            for (name, value) in fmu_estimator::calibration::file_parameters(&path)
                .map_err(fmu_estimator::error::Error::from)?
            {
                self.estimator_settings.push((name, Value::Real(value)));
            }
            let path = path
                .to_str()
                .ok_or_else(|| Error::input("the calibration file's path is not UTF-8"))?;
            self.estimator_settings
                .push((variable.into(), Value::String(path.into())));
            return Ok(());
        }
        match component {
            "vehicle" if STUDY_CONTROLLED.contains(&variable) => Err(Error::Input(format!(
                "vehicle.{variable} is set by the studies themselves (seeds: --seeds, --seed, --calibration-seed; tracks and conditions: the cases)"
            ))),
            "vehicle" if variable == FIXED_SPEED => Err(Error::input(
                "vehicle.speed: the studies run at the vehicle's default speed, 20 m/s (their cases and the resonance wavelength assume it)",
            )),
            "vehicle" => {
                self.vehicle_settings.push(setting);
                Ok(())
            }
            "estimator" => {
                self.estimator_settings.push(setting);
                Ok(())
            }
            other => Err(Error::Input(format!(
                "no component '{other}' in the studies (vehicle or estimator)"
            ))),
        }
    }

    /// The user's estimator settings as text, for the studies that run the estimator's
    /// library over recorded samples rather than its FMU (the sensor and curve tables): all
    /// but `estimator`, since there each row names the estimator it measures.
    pub fn estimator_texts(&self) -> Vec<(String, String)> {
        self.estimator_settings
            .iter()
            .filter(|(n, _)| n != "estimator")
            .map(|(n, v)| (n.clone(), v.to_string()))
            .collect()
    }

    /// The number the user set for `variable` of the estimator, if any (the last one).
    pub fn estimator_number(&self, variable: &str) -> Option<f64> {
        number(last(&self.estimator_settings, variable)?)
    }

    /// The vehicle's parameter set, as the vehicle FMU will read it: the file named by the
    /// user's `vehicle.vehicle` (`ml95.toml`, `manchester.toml` or an absolute path), else ML95,
    /// with the user's `vehicle.conicity` when positive (the FMU's override of the file's).
    /// The identification takes the simplified model's fixed parameters from it, and the
    /// resonance study its modes.
    pub fn vehicle_params(&self) -> Result<VehicleParams, Error> {
        let mut params = match last(&self.vehicle_settings, "vehicle") {
            Some(Value::String(name)) => {
                VehicleParams::named(name.trim(), None).map_err(Error::Input)?
            }
            _ => VehicleParams::ml95(),
        };
        if let Some(c) = last(&self.vehicle_settings, "conicity")
            .and_then(number)
            .filter(|c| *c > 0.0)
        {
            params.wheelset.conicity = c;
        }
        Ok(params)
    }
}

/// The last value `settings` give `variable`, the one a run applies.
fn last<'a>(settings: &'a Settings, variable: &str) -> Option<&'a Value> {
    settings
        .iter()
        .rev()
        .find(|(n, _)| n == variable)
        .map(|(_, v)| v)
}

/// A setting's value as a number, if it is one (the user's are text until a run types them).
fn number(v: &Value) -> Option<f64> {
    match v {
        Value::String(s) => s.trim().parse().ok(),
        Value::Real(x) => Some(*x),
        _ => None,
    }
}

/// Settings applied to one component, as `(variable, value)` in the FMU's own terms.
pub type Settings = Vec<(String, Value)>;

/// The run length and step of the paper's standard case: 20 s at 1 ms, 20 m/s.
pub const STOP: f64 = 20.0;
/// The communication step \[s\] of every study run (1 kHz, the sensors' rate).
pub const STEP: f64 = 1e-3;

fn options(stop: f64, record: Vec<Endpoint>, step: f64) -> RunOptions {
    RunOptions {
        record: Some(record),
        log: LogConfig {
            min_status: fmi_import::fmi2Status::Error,
            ..LogConfig::default()
        },
        collect: true,
        ..RunOptions::new(0.0, stop, step)
    }
}

fn run(system: System, stop: f64, record: Vec<Endpoint>) -> Result<Table, Error> {
    run_at(system, stop, record, STEP)
}

fn run_at(system: System, stop: f64, record: Vec<Endpoint>, step: f64) -> Result<Table, Error> {
    let cosim = Cosimulation::load(system)?;
    let summary = cosim.run(&options(stop, record, step))?;
    summary
        .table
        .ok_or_else(|| Error::Input("no table was collected".into()))
}

/// The vehicle alone with `settings`, recording `variables` (vehicle variable names).
pub fn vehicle_run(
    fmus: &Fmus,
    settings: Settings,
    variables: &[&str],
    stop: f64,
) -> Result<Table, Error> {
    vehicle_run_driven(fmus, settings, variables, stop, None)
}

/// A speed input as a function of time [s -> m/s].
pub type SpeedProfile<'a> = &'a (dyn Fn(f64) -> f64 + Sync);

/// [`vehicle_run`] with the vehicle's `speed` input set from `speed` before every step (its
/// default, 20 m/s, when `None`).
pub fn vehicle_run_driven(
    fmus: &Fmus,
    settings: Settings,
    variables: &[&str],
    stop: f64,
    speed: Option<SpeedProfile<'_>>,
) -> Result<Table, Error> {
    vehicle_run_stepped(fmus, settings, variables, stop, speed, STEP)
}

/// [`vehicle_run_driven`] with the communication step `step` (the sensors' sample step).
pub fn vehicle_run_stepped(
    fmus: &Fmus,
    settings: Settings,
    variables: &[&str],
    stop: f64,
    speed: Option<SpeedProfile<'_>>,
    step: f64,
) -> Result<Table, Error> {
    let system = System {
        name: "vehicle".into(),
        components: vec![Component {
            name: "vehicle".into(),
            source: fmus.vehicle.clone(),
            parameters: fmus
                .vehicle_settings
                .iter()
                .cloned()
                .chain(settings)
                .collect(),
        }],
        connections: vec![],
        experiment: Experiment::default(),
    };
    let record = variables
        .iter()
        .map(|v| Endpoint::new("vehicle", v))
        .collect();
    let Some(speed) = speed else {
        return run_at(system, stop, record, step);
    };
    let cosim = Cosimulation::load(system)?;
    let inputs = [Endpoint::new("vehicle", "speed")];
    let fill = |t: f64, out: &mut [f64]| out[0] = speed(t);
    let opts = options(stop, record, step);
    let summary = cosim.runner(&opts).inputs(&inputs, &fill).run()?;
    summary
        .table
        .ok_or_else(|| Error::Input("no table was collected".into()))
}

/// The columns the evaluation reads from a standard-system run.
pub const EVALUATED: [&str; 4] = [
    "vehicle.distance",
    "vehicle.alignment",
    "estimator.distance",
    "estimator.alignment",
];

/// The standard system (vehicle -> estimator) with settings for each component.
pub fn standard_run(
    fmus: &Fmus,
    vehicle: Settings,
    estimator: Settings,
    stop: f64,
) -> Result<Table, Error> {
    standard_run_recording(fmus, vehicle, estimator, stop, &[])
}

/// [`standard_run`] recording `extra` (`component.variable`) beside [`EVALUATED`].
pub fn standard_run_recording(
    fmus: &Fmus,
    vehicle: Settings,
    estimator: Settings,
    stop: f64,
    extra: &[&str],
) -> Result<Table, Error> {
    let mut system = super::standard_case::system(&fmus.vehicle, &fmus.estimator)?;
    system.components[0].parameters = fmus
        .vehicle_settings
        .iter()
        .cloned()
        .chain(vehicle)
        .collect();
    // The paper's cases measure the paper's filter (estimator 1) unless the case or the user
    // (--set estimator.estimator=2) sets another: the study's cases come last, so
    // `cases::with_learned`'s twins run the learned filter; `alignment-studies variants`
    // compares its outputs and options.
    system.components[1].parameters = std::iter::once(("estimator".to_string(), Value::Integer(1)))
        .chain(fmus.estimator_settings.iter().cloned())
        .chain(estimator)
        .collect();
    let record = EVALUATED
        .iter()
        .chain(extra)
        .map(|e| Endpoint::parse(e).map_err(Error::Input))
        .collect::<Result<_, _>>()?;
    run(system, stop, record)
}

/// The vehicle settings that select a track and noise realization: `track_seed = seed`,
/// `noise_seed = seed + 1000` (so the noise never repeats a track's random stream).
pub fn seeded(seed: u32) -> Settings {
    vec![
        ("track_seed".into(), Value::Integer(seed as i32)),
        ("noise_seed".into(), Value::Integer(seed as i32 + 1000)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The user's estimator settings reach the studies that run the estimator's library as
    /// text it parses, all but the estimator's choice, which each of their rows makes.
    #[test]
    fn the_users_estimator_settings_are_given_to_the_library_as_text() {
        let mut fmus = Fmus::default();
        for (n, v) in [
            ("tap_file", "learned-nominal.taps"),
            ("estimator", "2"),
            ("lag", "5"),
        ] {
            fmus.set("estimator", n, v).unwrap();
        }
        fmus.estimator_settings
            .push(("bias_sigma_ws_acc_y".into(), Value::Real(0.1)));
        fmus.estimator_settings
            .push(("use_roll_rate".into(), Value::Boolean(true)));
        let texts = fmus.estimator_texts();
        assert_eq!(
            texts,
            [
                ("tap_file", "learned-nominal.taps"),
                ("lag", "5"),
                ("bias_sigma_ws_acc_y", "0.1"),
                ("use_roll_rate", "true"),
            ]
            .map(|(n, v)| (n.to_string(), v.to_string()))
        );
        // As the library reads them.
        assert!(fmu_estimator::offline::settings(&texts).is_ok());
    }
}
