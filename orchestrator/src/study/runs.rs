//! Running the FMUs for the studies: the vehicle alone (identification, calibration) or the
//! standard system (evaluation), in-process through the master, with the variables the
//! analysis needs kept in memory.

use crate::master::{Algorithm, Cosimulation, RunOptions, Table};
use crate::system::{Component, Endpoint, Experiment, System, Value};
use fmi_import::LogConfig;
use std::path::PathBuf;

/// The two FMUs of the studies.
#[derive(Debug, Clone)]
pub struct Fmus {
    pub vehicle: PathBuf,
    pub estimator: PathBuf,
}

/// Settings applied to one component, as `(variable, value)` in the FMU's own terms.
pub type Settings = Vec<(String, Value)>;

/// The run length and step of the paper's standard case: 20 s at 1 ms, 20 m/s.
pub const STOP: f64 = 20.0;
pub const STEP: f64 = 1e-3;

fn options(stop: f64, record: Vec<Endpoint>) -> RunOptions {
    RunOptions {
        start: 0.0,
        stop,
        step: STEP,
        algorithm: Algorithm::GaussSeidel,
        out_dir: None,
        record: Some(record),
        interval: None,
        progress: false,
        log: LogConfig {
            min_status: fmi_import::fmi2Status::Error,
            ..LogConfig::default()
        },
        collect: true,
    }
}

fn run(system: System, stop: f64, record: Vec<Endpoint>) -> Result<Table, String> {
    let cosim = Cosimulation::load(system).map_err(|e| e.to_string())?;
    let summary = cosim
        .run(&options(stop, record))
        .map_err(|e| e.to_string())?;
    summary.table.ok_or_else(|| "no table was collected".into())
}

/// The vehicle alone with `settings`, recording `variables` (vehicle variable names).
pub fn vehicle_run(
    fmus: &Fmus,
    settings: Settings,
    variables: &[&str],
    stop: f64,
) -> Result<Table, String> {
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
) -> Result<Table, String> {
    let system = System {
        name: "vehicle".into(),
        components: vec![Component {
            name: "vehicle".into(),
            source: fmus.vehicle.clone(),
            parameters: settings,
        }],
        connections: vec![],
        experiment: Experiment::default(),
    };
    let record = variables
        .iter()
        .map(|v| Endpoint::new("vehicle", v))
        .collect();
    let Some(speed) = speed else {
        return run(system, stop, record);
    };
    let cosim = Cosimulation::load(system).map_err(|e| e.to_string())?;
    let speed_vr = cosim.model_descriptions()[0]
        .variable("speed")
        .map(|v| v.value_reference)
        .ok_or("the vehicle FMU has no 'speed' input")?;
    let summary = cosim
        .run_with_inputs(&options(stop, record), &|t, out: &mut Vec<(u32, f64)>| {
            out.clear();
            out.push((speed_vr, speed(t)));
        })
        .map_err(|e| e.to_string())?;
    summary.table.ok_or_else(|| "no table was collected".into())
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
) -> Result<Table, String> {
    let mut system = System::standard_case(&fmus.vehicle, &fmus.estimator);
    system.components[0].parameters = vehicle;
    system.components[1].parameters = estimator;
    let record = EVALUATED
        .iter()
        .map(|e| Endpoint::parse(e).expect("constant names"))
        .collect();
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
