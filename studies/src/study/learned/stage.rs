//! The long-wave stage's fit (`alignment-studies stage`): taps over 600 m of the band-passed
//! sensors and the taps' own estimate, added to a bank's causal output
//! ([`fmu_estimator::learned::stage`], which says what the stage computes and why).
//!
//! # Method
//! For every speed of the bank and sensor set (three sensors, and with the roll-rate
//! gyroscope where the bank has those taps):
//! 1. Training runs: the vehicle FMU at that constant speed on each training seed, once per
//!    Kalker scale of the bank's entries, the seeds sharing [`TRAINING_DISTANCE`] per scale
//!    (at most [`super::taps::MAX_STOP`] s a run). The estimator library runs the bank over
//!    each as the FMU does (told nothing: contact estimated, the Kalman channel's scheduled
//!    gain) with the stage's log on ([`fmu_estimator::learned::Learned::log_stage`]): per
//!    grid cell the stage's band-passed inputs and the taps' estimate before it. Why five
//!    seeds: fitted on seed 101 alone, 244 taps learnt that track's irregularities (the
//!    validation runs gained, the held-out ones did not; docs/accuracy.md).
//! 2. Least squares with the taps' plain objective, `sum_b w_b Jrel_b^2` over the metric's
//!    bands ([`BAND_WEIGHTS`]): per band, the residual (truth at the cell minus the taps'
//!    estimate) and every input band-passed alike (zero phase, as the metric does), the
//!    inputs then delayed by each of the stage's lags (zeros before the run's start), the
//!    rows weighed by the band's truth power; rows every [`ROW_EVERY`] cells from [`SKIP`] m
//!    on (the memory full, the band-pass settled). A causal FIR fitted so minimises what the
//!    metric measures.
//! 3. Ridge: from [`RIDGES`] (times the normal equations' mean diagonal), the one of least
//!    objective on the validation runs (the validation seeds at every trained Kalker scale,
//!    [`VALIDATION_DISTANCE`] from their start, the estimate and the stage made as the FMU
//!    makes them with the stage's share over the start, the first 10 m trimmed as the
//!    standard case's metric is). Where no ridge improves on the taps alone the stage's taps
//!    at that speed are zeros (no correction).

use super::taps::{Condition, stable_record};
use crate::Error;
use crate::study::metrics::{BANDS, accuracy, bandpass, resample};
use crate::study::records::Record;
use crate::study::runs::{Fmus, STEP};
use fmu_estimator::config::Config;
use fmu_estimator::learned::bank::Bank;
use fmu_estimator::learned::grid::CHANNELS;
use fmu_estimator::learned::stage::{
    ESTIMATE, ESTIMATE_HIGHPASS_ORDER, HIGHPASS, LAGS, LOWPASS, SPACING, StageBank, StageEntry,
    StageRow, every, start_share,
};
use fmu_estimator::learned::{Choice, Learned};
use fmu_estimator::offline;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Training distance per Kalker scale and speed, shared by the training seeds \[m\].
pub const TRAINING_DISTANCE: f64 = 30_000.0;
/// Length of each validation run \[m\].
pub const VALIDATION_DISTANCE: f64 = 2_000.0;
/// Where the training rows begin \[m\]: the 600 m memory full and the band-pass settled.
/// (Fitted instead on 2 km pieces of the runs each from a cold start, rows from the start,
/// the stage helped no validation run at 17.5-27.5 m/s: a start and a full memory want other
/// taps. The runtime fades it in over the start instead: [`fmu_estimator::learned::stage::START_RAMP`].)
pub const SKIP: f64 = 800.0;
/// Cells between training rows (2 m on the 0.2 m grid): the residual's shortest waves in the
/// whole band are 3 m, and neighbouring rows add little.
pub const ROW_EVERY: usize = 10;
/// The ridges tried, relative to the normal equations' mean diagonal.
pub const RIDGES: [f64; 7] = [1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2];
/// The metric's trim at each end of a validation run \[m\] (the standard case's).
const TRIM: f64 = 10.0;

/// What the stage is fitted on.
#[derive(Debug, Clone)]
pub struct StageOptions {
    /// Track seeds of the training runs (they share [`TRAINING_DISTANCE`]).
    pub training_seeds: Vec<u32>,
    /// Track seeds of the validation runs (the ridge's choice).
    pub validation_seeds: Vec<u32>,
    /// Fit these of the bank's speeds only (empty: all). A stage lacking a speed of the taps
    /// is not applied ([`fmu_estimator::learned::stage`]): for tests of the fit.
    pub speeds: Vec<f64>,
}

impl StageOptions {
    /// The shipped default bank's stage: trained on the calibration seed and four seeds no
    /// fit of the default bank used (107-110), the ridge chosen on two of the taps'
    /// validation seeds.
    pub fn shipped() -> StageOptions {
        StageOptions {
            training_seeds: vec![101, 107, 108, 109, 110],
            validation_seeds: vec![102, 103],
            speeds: vec![],
        }
    }
}

/// One run's stage log, for one sensor set: rows per cell and the truth there.
struct Logged {
    /// Per input, the band-passed series (as the stage keeps them).
    inputs: Vec<Vec<f64>>,
    /// The taps' estimate before the stage (0 where they made none).
    estimate: Vec<f64>,
    /// The true alignment at each cell.
    truth: Vec<f64>,
}

/// `bank` (without a stage) over `rec` as the FMU runs it with the Kalman channel `config`,
/// for the sensor set with the roll rate or not: the stage's log.
fn logged(bank: &Bank, config: &Config, rec: &Record, roll_rate: bool) -> Result<Logged, Error> {
    let choice = Choice {
        roll_rate,
        lag: 0.0,
        conicity: None,
        kalker: None,
    };
    let mut learned =
        Learned::new(bank, choice).map_err(|e| Error::input(format!("the bank: {e}")))?;
    learned.log_stage();
    let (_, end) = offline::process_learned_from(
        config,
        offline::Resume::new(config, Some(learned)),
        STEP,
        &rec.samples,
    )?;
    let rows: Vec<StageRow> = end.learned.expect("a learned filter").take_stage_log();
    let n = if roll_rate { 5 } else { 4 };
    let distance: Vec<f64> = rows.iter().map(|r| r.distance).collect();
    Ok(Logged {
        inputs: (0..n)
            .map(|c| rows.iter().map(|r| r.inputs[c]).collect())
            .collect(),
        estimate: rows
            .iter()
            .map(|r| {
                if r.estimate.is_finite() {
                    r.estimate
                } else {
                    0.0
                }
            })
            .collect(),
        // The estimator's distance starts at the record's first sample (a piece of a run
        // starts where the run had gone).
        truth: {
            let offset = rec.distance.first().copied().unwrap_or(0.0)
                - rec.samples.first().map_or(0.0, |s| s.speed * STEP);
            let own: Vec<f64> = rec.distance.iter().map(|d| d - offset).collect();
            resample(&own, &rec.alignment, &distance)
        },
    })
}

/// The regressors of row `k`: each input `j` spacings back (`m` cells apart), 0 before the start.
fn regressors(inputs: &[Vec<f64>], k: usize, m: usize, out: &mut [f64]) {
    for (i, x) in inputs.iter().enumerate() {
        for j in 0..LAGS {
            out[i * LAGS + j] = k.checked_sub(j * m).map_or(0.0, |at| x[at]);
        }
    }
}

/// The stage's correction over a whole log with `taps` on a grid of `ds`, as the runtime makes
/// it at constant speed (its share over the run's start included).
fn corrected(l: &Logged, taps: &[f64], m: usize, ds: f64) -> Vec<f64> {
    let mut row = vec![0.0; taps.len()];
    (0..l.estimate.len())
        .map(|k| {
            regressors(&l.inputs, k, m, &mut row);
            let c = row.iter().zip(taps).map(|(a, b)| a * b).sum::<f64>();
            l.estimate[k] + start_share((k + 1) as f64 * ds) * c
        })
        .collect()
}

/// The ridge solution of the normal equations `gram`, `rhs` of `nc` inputs, the ridge `ridge`
/// times their mean diagonal.
fn solve(gram: &DMatrix<f64>, rhs: &DVector<f64>, nc: usize, ridge: f64) -> Option<Vec<f64>> {
    let p = nc * LAGS;
    let mut a = gram.clone();
    let scale = a.trace() / p as f64;
    for i in 0..p {
        a[(i, i)] += ridge * scale;
    }
    Some(a.cholesky()?.solve(rhs).iter().copied().collect())
}

/// The objective's weight of each band's `Jrel^2` ([`BANDS`]: whole, D1, D2, D3): the taps'
/// plain objective, so that the stage cannot buy the long waves with the short ones. (The
/// whole band alone, whose error the 70-200 m waves dominate, took D3 down 5 % on 2 km runs of
/// the held-out seeds but D1 and D2 up 6-7 %.)
pub const BAND_WEIGHTS: [f64; 4] = [1.0, 1.0, 1.0, 1.0];

/// `sum_b w_b Jrel_b^2` of `estimate` against the log's truth ([`BAND_WEIGHTS`]).
fn objective(estimate: &[f64], truth: &[f64], ds: f64) -> Result<f64, Error> {
    let mut s = 0.0;
    for (b, w) in BANDS.iter().zip(BAND_WEIGHTS) {
        if w > 0.0 {
            s += w * accuracy(estimate, truth, ds, b, TRIM)?.jrel.powi(2);
        }
    }
    Ok(s)
}

/// The stage at one speed for one sensor set from its training and validation logs.
fn fit_one(
    speed: f64,
    channels: Vec<String>,
    training: &[Logged],
    validation: &[Logged],
    ds: f64,
    m: usize,
) -> Result<StageEntry, Error> {
    let p = channels.len() * LAGS;
    let mut gram = DMatrix::<f64>::zeros(p, p);
    let mut rhs = DVector::<f64>::zeros(p);
    let skip = (SKIP / ds).round() as usize;
    let mut row = vec![0.0; p];
    for l in training {
        let residual: Vec<f64> = l
            .truth
            .iter()
            .zip(&l.estimate)
            .map(|(t, e)| t - e)
            .collect();
        for (band, w) in BANDS.iter().zip(BAND_WEIGHTS) {
            if w <= 0.0 {
                continue;
            }
            let pass = |x: &[f64]| bandpass(x, ds, band);
            let inputs: Vec<Vec<f64>> =
                l.inputs.iter().map(|x| pass(x)).collect::<Result<_, _>>()?;
            let target = pass(&residual)?;
            // Each band's squared error relative to its truth's power, as Jrel^2 weighs it.
            let truth = pass(&l.truth)?;
            let power = truth[skip.min(truth.len())..]
                .iter()
                .map(|t| t * t)
                .sum::<f64>()
                / truth.len().saturating_sub(skip).max(1) as f64;
            if !(power > 0.0) {
                continue;
            }
            let weight = w / power;
            for k in (skip..target.len()).step_by(ROW_EVERY) {
                regressors(&inputs, k, m, &mut row);
                let r = DVector::from_column_slice(&row);
                gram.syger(weight, &r, &r, 1.0);
                rhs.axpy(weight * target[k], &r, 1.0);
            }
        }
    }
    if rhs.iter().all(|v| *v == 0.0) {
        return Err(Error::input(format!(
            "at {speed} m/s no training run is longer than {SKIP} m"
        )));
    }
    gram.fill_upper_triangle_with_lower_triangle();
    let nc = channels.len();
    let score = |taps: &[f64]| -> Result<f64, Error> {
        let mut s = 0.0;
        for l in validation {
            s += objective(&corrected(l, taps, m, ds), &l.truth, ds)?;
        }
        Ok(s / validation.len() as f64)
    };
    let before = score(&vec![0.0; p])?;
    let mut best = (before, 0.0, vec![0.0; p]);
    for ridge in RIDGES {
        let Some(taps) = solve(&gram, &rhs, nc, ridge) else {
            continue;
        };
        let s = score(&taps)?;
        if s < best.0 {
            best = (s, ridge, taps);
        }
    }
    Ok(StageEntry {
        speed,
        channels,
        ridge: best.1,
        validation: [before, best.0],
        taps: best.2,
    })
}

/// `bank` with its long-wave stage fitted ([`StageOptions`]); `progress` hears each speed.
pub fn fit(
    fmus: &Fmus,
    o: &StageOptions,
    bank: &Bank,
    progress: &dyn Fn(&str),
) -> Result<Bank, Error> {
    let ds = bank.grid;
    let m = every(ds).ok_or_else(|| {
        Error::input(format!(
            "the bank's grid of {ds} m does not divide the stage's {SPACING} m"
        ))
    })?;
    // The taps alone, as the fit's runs estimate with them (a stage the bank has is fitted
    // anew), and the Kalman channel the FMU runs them with by default.
    let plain = Bank {
        stage: None,
        ..bank.clone()
    };
    let config = offline::config(&offline::settings(&[])?, None)?.0;
    let causal: Vec<_> = bank.entries.iter().filter(|e| e.lag == 0).collect();
    let mut speeds: Vec<f64> = causal.iter().map(|e| e.speed).collect();
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    if !o.speeds.is_empty() {
        speeds.retain(|v| o.speeds.contains(v));
    }
    let mut scales: Vec<f64> = causal.iter().filter_map(|e| e.condition).collect();
    scales.sort_by(f64::total_cmp);
    scales.dedup();
    if scales.is_empty() {
        scales.push(1.0);
    }
    let roll = causal
        .iter()
        .any(|e| e.channels.iter().any(|c| c == CHANNELS[3]));
    let sets: Vec<bool> = if roll { vec![false, true] } else { vec![false] };
    let mut entries = vec![];
    for speed in speeds {
        let share = TRAINING_DISTANCE / o.training_seeds.len().max(1) as f64;
        let jobs: Vec<(u32, f64, f64)> = o
            .training_seeds
            .iter()
            .map(|s| (*s, share))
            .chain(o.validation_seeds.iter().map(|s| (*s, VALIDATION_DISTANCE)))
            .flat_map(|(s, d)| scales.iter().map(move |k| (s, *k, d)))
            .collect();
        let runs: Vec<Option<Record>> = jobs
            .par_iter()
            .map(|(s, k, d)| {
                let condition = Condition {
                    kalker: *k,
                    conicity: None,
                };
                stable_record(fmus, *s, condition, None, speed, *d, true)
            })
            .collect::<Result<_, _>>()?;
        for roll_rate in &sets {
            let logs: Vec<(u32, Logged)> = jobs
                .par_iter()
                .zip(&runs)
                .filter_map(|((s, _, _), r)| r.as_ref().map(|r| (*s, r)))
                .map(|(s, r)| Ok((s, logged(&plain, &config, r, *roll_rate)?)))
                .collect::<Result<_, Error>>()?;
            let (training, validation): (Vec<_>, Vec<_>) = logs
                .into_iter()
                .partition(|(s, _)| o.training_seeds.contains(s));
            let training: Vec<Logged> = training.into_iter().map(|(_, l)| l).collect();
            let validation: Vec<Logged> = validation.into_iter().map(|(_, l)| l).collect();
            if training.is_empty() || validation.is_empty() {
                return Err(Error::input(format!(
                    "at {speed} m/s the vehicle is unstable in every training or validation run"
                )));
            }
            let mut channels: Vec<String> = CHANNELS[..if *roll_rate { 4 } else { 3 }]
                .iter()
                .map(|c| c.to_string())
                .collect();
            channels.push(ESTIMATE.into());
            let e = fit_one(speed, channels, &training, &validation, ds, m)?;
            progress(&format!(
                "{speed:>5} m/s, {} sensors: ridge {:.0e}, validation objective {:.4} -> {:.4}",
                if *roll_rate { 4 } else { 3 },
                e.ridge,
                e.validation[0],
                e.validation[1]
            ));
            entries.push(e);
        }
    }
    let mut out = bank.clone();
    out.stage = Some(StageBank {
        highpass: HIGHPASS,
        lowpass: LOWPASS,
        spacing: SPACING,
        lags: LAGS,
        estimate_highpass_order: ESTIMATE_HIGHPASS_ORDER,
        entries,
    });
    Ok(out)
}
