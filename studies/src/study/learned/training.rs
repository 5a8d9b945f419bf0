//! Training runs of the vehicle FMU and the fit of a learned smoother on them, as the study does
//! (module docs of [`super`], step 6).

use super::{LearnedSmoother, Lookahead, Partner};
use crate::Error;
use crate::study::records::{Record, record};
use crate::study::runs::{Fmus, STEP, STOP, seeded};

/// The training runs of [`learn`]: `stop` s of the vehicle on track `seed` at `speed` (its
/// default, 20 m/s, if `None`), once per Kalker-coefficient scale in `kalker_scales` (1: the vehicle as it is; training on
/// several makes the taps robust to the wheel-rail contact, at some cost in accuracy on the
/// nominal vehicle), and a description of them.
pub fn training_runs(
    fmus: &Fmus,
    seed: u32,
    stop: f64,
    kalker_scales: &[f64],
    speed: Option<f64>,
) -> Result<(Vec<Record>, String), crate::Error> {
    if let Some(v) = speed
        && !(v.is_finite() && v > 0.0)
    {
        return Err(Error::input(format!(
            "the training speed must be a positive number of m/s; got {v}"
        )));
    }
    if !(stop > 2.0 * STOP) {
        return Err(Error::input(format!(
            "the training run must be longer than {} s (the first {STOP} s choose the split); got {stop} s",
            2.0 * STOP
        )));
    }
    if kalker_scales.is_empty() || kalker_scales.iter().any(|k| !(k.is_finite() && *k > 0.0)) {
        return Err(Error::input(format!(
            "the Kalker scales must be positive numbers; got {kalker_scales:?}"
        )));
    }
    let runs = kalker_scales
        .iter()
        .map(|&k| {
            let mut settings = seeded(seed);
            settings.push(("kalker_scale".into(), orchestrator::system::Value::Real(k)));
            match speed {
                Some(v) => record(fmus, settings, stop, Some(&move |_| v)),
                None => record(fmus, settings, stop, None),
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((runs, provenance(fmus, seed, stop, kalker_scales)))
}

/// How [`training_runs`] were made, for the saved file and the study's report.
pub fn provenance(fmus: &Fmus, seed: u32, stop: f64, kalker_scales: &[f64]) -> String {
    format!(
        "{} on track seed {seed}, {stop} s, Kalker coefficients at {} %; taps fitted after the first {STOP} s, split chosen on those",
        fmus.vehicle.display(),
        kalker_label(kalker_scales)
    )
}

/// `[1.0, 0.5]` as "100 and 50".
pub fn kalker_label(kalker_scales: &[f64]) -> String {
    let scales: Vec<String> = kalker_scales
        .iter()
        .map(|k| format!("{}", k * 100.0))
        .collect();
    scales.join(" and ")
}

/// Fits a learned smoother as the study does, on [`training_runs`]: the taps from everything
/// after the first [`STOP`] s of each run, the split chosen on those first seconds (stretches the
/// taps have not seen; the mean whole-band Jrel over the runs). Returns it and that mean Jrel.
pub fn learn(
    runs: &[Record],
    provenance: &str,
    lookahead: Lookahead,
    grid: f64,
    partner: Partner,
) -> Result<(LearnedSmoother, f64), Error> {
    let head = validation_len();
    let mut fit = runs
        .first()
        .ok_or_else(|| Error::input("no training run"))?
        .tail(head);
    for r in &runs[1..] {
        // The joints are a handful of samples in hundreds of thousands: left as they are.
        let t = r.tail(head);
        let d0 = fit.distance.last().copied().unwrap_or(0.0)
            - t.distance.first().copied().unwrap_or(0.0);
        fit.samples.extend_from_slice(&t.samples);
        fit.distance.extend(t.distance.iter().map(|d| d + d0));
        fit.alignment.extend_from_slice(&t.alignment);
    }
    let mut l = LearnedSmoother::train(&fit, lookahead, grid, partner, provenance)?;
    let heads: Vec<Record> = runs.iter().map(validation).collect();
    let j = l.tune_split(&heads)?;
    Ok((l, j))
}

/// Samples in the first [`STOP`] s of a training run.
fn validation_len() -> usize {
    (STOP / STEP).round() as usize
}

/// The first [`STOP`] s of a training run, which the taps are not fitted on: where [`learn`]
/// chooses the split (and `alignment-studies learn` the shaping filter's virtual measurement).
pub fn validation(run: &Record) -> Record {
    run.head(validation_len())
}
