//! Real sensors (the robustness study's sensor table): each sensor error of the vehicle FMU
//! alone, at the sizes issue 29 measured, other sample steps at the paper's noise density, and
//! the two presets, for the paper's filter and the default learned filter.
//!
//! Every run stands still for [`STANDSTILL`] s, then runs the standard case (20 s at 20 m/s):
//! a train's run starts at a stop, where the estimator reads the biases
//! (`fmu-estimator/src/bias.rs`). Both estimators are told the bias priors [`PRIORS`] (a user
//! states the sensor's class), and the default once more told nothing. The vehicle's run is
//! recorded once per condition and seed and both estimators process it offline, as the FMU
//! steps. The metric is the standard case's, over the moving part. With odometry 2 % high the
//! estimate is compared at the true positions (the recorded distance), not at the estimator's.

use super::metrics::{BandMetrics, evaluate};
use super::records::{
    Output, Record, estimate, estimate_learned, flagged_learned, record_stepped, share_of,
};
use super::runs::{Fmus, STEP, seeded};
use super::standard::{DS, TRIM};
use crate::Error;
use orchestrator::system::Value;
use rayon::prelude::*;
use serde::Serialize;

/// The standstill before the run \[s\].
pub const STANDSTILL: f64 = 5.0;
/// The run's speed after it \[m/s\] and its duration \[s\]: the standard case's.
const SPEED: f64 = 20.0;
const RUN: f64 = 20.0;

/// The bias priors both estimators are told: generous for a MEMS part (`sensor_grade` 2 has
/// 9.8e-3 m/s2 and 1.75e-3 rad/s; the accelerometers' prior also covers a 0.6 deg tilt).
pub const PRIORS: [(&str, &str); 3] = [
    ("bias_sigma_ws_acc_y", "0.1"),
    ("bias_sigma_ws_yaw_rate", "2e-3"),
    ("bias_sigma_frame_acc_y", "0.1"),
];

/// One sensor condition: vehicle settings, the sample step, and whether odometry reads high.
#[derive(Debug, Clone, Serialize)]
pub struct Condition {
    /// The row's name.
    pub name: String,
    /// The vehicle FMU's parameters (FMI name, value).
    pub vehicle: Vec<(String, f64)>,
    /// The communication step, the sensors' sample step \[s\].
    pub step: f64,
    /// The estimator's speed input over the true one (1.02: odometry 2 % high).
    pub odometry: f64,
    /// The learned filter with the roll-rate gyroscope too (`use_roll_rate`).
    pub roll_rate: bool,
}

fn condition(name: &str, vehicle: &[(&str, f64)]) -> Condition {
    Condition {
        name: name.into(),
        vehicle: vehicle.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
        step: STEP,
        odometry: 1.0,
        roll_rate: false,
    }
}

/// At step `step` with the paper's noise as a density: 0.01 m/s2 and 5e-4 rad/s per sample at
/// 1 kHz, so `psd = sigma^2 / 500 Hz`.
fn at_rate(name: &str, step: f64) -> Condition {
    Condition {
        step,
        ..condition(
            name,
            &[
                ("ws_acc_y_noise_psd", 1e-4 / 500.0),
                ("frame_acc_y_noise_psd", 1e-4 / 500.0),
                ("ws_yaw_rate_noise_psd", 2.5e-7 / 500.0),
            ],
        )
    }
}

/// The table's rows: the ideal sensors first.
pub fn conditions() -> Vec<Condition> {
    let tilt = (0.05f64 / 9.81).asin();
    vec![
        condition("ideal (the paper's white noise)", &[]),
        condition("yaw gyro bias 1e-4 rad/s", &[("ws_yaw_rate_bias", 1e-4)]),
        condition("yaw gyro bias 3e-4 rad/s", &[("ws_yaw_rate_bias", 3e-4)]),
        condition("yaw gyro bias 1e-3 rad/s", &[("ws_yaw_rate_bias", 1e-3)]),
        condition(
            "wheelset accelerometer bias 0.05 m/s2",
            &[("ws_acc_y_bias", 0.05)],
        ),
        condition(
            "both accelerometers tilted 0.29 deg (0.05 m/s2 of gravity)",
            &[
                ("ws_acc_y_misalignment", tilt),
                ("frame_acc_y_misalignment", tilt),
            ],
        ),
        condition(
            "both accelerometers +5 % scale",
            &[
                ("ws_acc_y_scale_error", 0.05),
                ("frame_acc_y_scale_error", 0.05),
            ],
        ),
        condition(
            "yaw gyro drift 10 deg/h, 100 s (Gauss-Markov)",
            &[
                (
                    "ws_yaw_rate_bias_instability",
                    10.0f64.to_radians() / 3600.0,
                ),
                ("ws_yaw_rate_bias_tau", 100.0),
            ],
        ),
        Condition {
            odometry: 1.02,
            ..condition("speed 2 % high (odometry), at true positions", &[])
        },
        at_rate("2 kHz (0.5 ms), paper's noise density", 5e-4),
        at_rate("1 kHz, paper's noise density", 1e-3),
        at_rate("500 Hz (2 ms), paper's noise density", 2e-3),
        at_rate("200 Hz (5 ms), paper's noise density", 5e-3),
        condition("tactical preset (sensor_grade 1)", &[("sensor_grade", 1.0)]),
        condition("MEMS preset (sensor_grade 2)", &[("sensor_grade", 2.0)]),
        Condition {
            roll_rate: true,
            ..condition(
                "tactical preset, with the roll-rate gyroscope (use_roll_rate)",
                &[("sensor_grade", 1.0)],
            )
        },
        Condition {
            roll_rate: true,
            ..condition(
                "MEMS preset, with the roll-rate gyroscope (use_roll_rate)",
                &[("sensor_grade", 2.0)],
            )
        },
    ]
}

/// One condition's figures: per estimator, the metrics per seed.
#[derive(Debug, Clone, Serialize)]
pub struct SensorResult {
    /// The condition.
    pub condition: Condition,
    /// The paper's filter, told the priors.
    pub paper: Vec<BandMetrics>,
    /// The default (learned), told the priors.
    pub learned: Vec<BandMetrics>,
    /// The default told nothing.
    pub learned_untold: Vec<BandMetrics>,
    /// The share of its moving samples with `outside_training` set, per seed.
    pub untold_flagged: Vec<f64>,
}

fn profile(t: f64) -> f64 {
    if t < STANDSTILL { 0.0 } else { SPEED }
}

fn run_one(fmus: &Fmus, c: &Condition, seed: u32) -> Result<([BandMetrics; 3], f64), Error> {
    let mut settings = seeded(seed);
    for (name, value) in &c.vehicle {
        let value = if name == "sensor_grade" {
            Value::Integer(*value as i32)
        } else {
            Value::Real(*value)
        };
        settings.push((name.clone(), value));
    }
    let roll = c.roll_rate.then_some("ws_roll_rate");
    let mut rec: Record = record_stepped(
        fmus,
        settings,
        STANDSTILL + RUN,
        Some(&profile),
        roll,
        c.step,
    )?;
    for s in &mut rec.samples {
        s.speed *= c.odometry;
    }
    // The moving part only is judged: from the last standing sample on.
    let from = rec
        .samples
        .iter()
        .rposition(|s| s.speed == 0.0)
        .unwrap_or(0);
    // The user's settings first, the study's after them.
    let user = fmus.estimator_texts();
    let mut told: Vec<(String, String)> = user
        .iter()
        .cloned()
        .chain(PRIORS.iter().map(|(n, v)| (n.to_string(), v.to_string())))
        .collect();
    let mut paper = told.clone();
    paper.push(("estimator".into(), "1".into()));
    let mut untold = user;
    if c.roll_rate {
        // The roll gyroscope told like the yaw gyroscope; the paper's filter does not read it.
        told.push(("bias_sigma_ws_roll_rate".into(), PRIORS[1].1.into()));
        told.push(("use_roll_rate".into(), "true".into()));
        untold.push(("use_roll_rate".into(), "true".into()));
    }
    let judge = |(distance, est): (Vec<f64>, Vec<f64>)| -> Result<BandMetrics, Error> {
        // At the true positions when odometry is off, else where the estimator puts them.
        let at = if c.odometry != 1.0 {
            &rec.distance
        } else {
            &distance
        };
        Ok(evaluate(
            &at[from..],
            &est[from..],
            &rec.distance[from..],
            &rec.alignment[from..],
            DS,
            TRIM,
        )?)
    };
    let (distance, untold_est, flags) = flagged_learned(&rec.samples, c.step, &untold)?;
    Ok((
        [
            judge(estimate(&rec.samples, c.step, &paper, None, false)?)?,
            judge(estimate_learned(
                &rec.samples,
                c.step,
                &told,
                Output::Alignment,
            )?)?,
            judge((distance, untold_est))?,
        ],
        share_of(&flags[from..]),
    ))
}

/// Every condition on every seed, in parallel.
pub fn run(fmus: &Fmus, seeds: &[u32]) -> Result<Vec<SensorResult>, Error> {
    conditions()
        .into_par_iter()
        .map(|c| {
            let runs: Vec<([BandMetrics; 3], f64)> = seeds
                .par_iter()
                .map(|&s| run_one(fmus, &c, s))
                .collect::<Result<_, Error>>()?;
            Ok(SensorResult {
                paper: runs.iter().map(|r| r.0[0].clone()).collect(),
                learned: runs.iter().map(|r| r.0[1].clone()).collect(),
                learned_untold: runs.iter().map(|r| r.0[2].clone()).collect(),
                untold_flagged: runs.iter().map(|r| r.1).collect(),
                condition: c,
            })
        })
        .collect()
}

fn mean(ms: &[BandMetrics], band: fn(&BandMetrics) -> f64) -> f64 {
    ms.iter().map(band).sum::<f64>() / ms.len().max(1) as f64
}

fn bands(ms: &[BandMetrics]) -> String {
    format!(
        "{:.3} / {:.3} / {:.3} / {:.3}",
        mean(ms, |m| m.whole.jrel),
        mean(ms, |m| m.d1.jrel),
        mean(ms, |m| m.d2.jrel),
        mean(ms, |m| m.d3.jrel)
    )
}

/// The table (means over the seeds).
pub fn markdown(seeds: &[u32], results: &[SensorResult]) -> String {
    let mut s = format!(
        "### Robustness: sensors\n\nEach sensor error of the vehicle FMU alone, other sample steps, and the presets; a {STANDSTILL} s standstill, then the standard case. Jrel whole / D1 / D2 / D3, mean over seeds {seeds:?}. Both estimators told the bias priors ({}); \"told nothing\": the default without them, and the share of the moving distance over which it sets `outside_training`.\n\n| sensors | paper's filter | default (learned) | default told nothing, whole | told nothing, flagged |\n|---|---|---|---|---|\n",
        PRIORS
            .iter()
            .map(|(n, v)| format!("`{n} = {v}`"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for r in results {
        s.push_str(&format!(
            "| {} | {} | {} | {:.3} | {:.0} % |\n",
            r.condition.name,
            bands(&r.paper),
            bands(&r.learned),
            mean(&r.learned_untold, |m| m.whole.jrel),
            100.0 * r.untold_flagged.iter().sum::<f64>() / r.untold_flagged.len().max(1) as f64
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rate_rows_share_the_paper_density() {
        // psd x Nyquist is the paper's per-sample variance at 1 kHz.
        let c = at_rate("x", 1e-3);
        let acc = c
            .vehicle
            .iter()
            .find(|(n, _)| n == "ws_acc_y_noise_psd")
            .unwrap()
            .1;
        assert!(((acc * 500.0).sqrt() - 0.01).abs() < 1e-15);
        assert_eq!(conditions()[0].vehicle, vec![]);
    }
}
