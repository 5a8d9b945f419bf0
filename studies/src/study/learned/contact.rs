//! The contact model of a tap bank: the Kalker-coefficient scale (and, in a bank fitted over
//! conicities, `ln(conicity)`) as linear functions of the contact features
//! ([`fmu_estimator::learned::contact`]), fitted by least squares on the training runs of every
//! trained condition at one speed, their errors measured on the validation runs; and the
//! forward model of the features in the condition, with the residual covariance and the level
//! the novelty is measured in.
//!
//! The features come from the estimator's own [`Moments`] over each run's grid cells, so the fit
//! sees exactly what the FMU computes. The first [`WARM_UP`] of a run (the moments' memory
//! filling, and the start transient) is left out of the fits, the errors and the level.

#[cfg(doc)]
use super::taps::CONTACT_BAND;
use super::taps::{BANK_GRID, CONTACT_MEMORY, Condition, GridRun, KALKER_BANDS};
use crate::Error;
use fmu_estimator::learned::contact::{
    ConicityModel, FEATURES, LEVEL_SHARE, Moments, NodeModel, SpeedModel, forward_terms, linear,
};
use nalgebra::{DMatrix, DVector};

/// Start of each run left out \[m\].
pub const WARM_UP: f64 = CONTACT_MEMORY;

/// The features of every cell of a run at `speed` past the warm-up, in `bands`.
fn features(run: &GridRun, speed: f64, bands: &[[f64; 2]]) -> Vec<Vec<f64>> {
    let mut m = Moments::new(BANK_GRID, bands, CONTACT_MEMORY, &[speed]);
    let skip = (WARM_UP / BANK_GRID).round() as usize;
    let mut out = vec![];
    for (i, cell) in run.cells.cells.iter().enumerate() {
        m.push(cell, speed);
        if i >= skip
            && let Some(f) = m.features(0)
        {
            out.push(f.to_vec());
        }
    }
    out
}

/// Least squares of `y` on the rows `a`; `what` names the quantity in the error.
fn least_squares(rows: &[Vec<f64>], y: &[f64], speed: f64, what: &str) -> Result<Vec<f64>, Error> {
    let n = rows[0].len();
    let (mut ata, mut aty) = (DMatrix::<f64>::zeros(n, n), DVector::<f64>::zeros(n));
    for (r, y) in rows.iter().zip(y) {
        let a = DVector::from_column_slice(r);
        ata += &a * a.transpose();
        aty += &a * *y;
    }
    Ok(ata
        .cholesky()
        .ok_or_else(|| {
            Error::input(format!(
                "at {speed} m/s the contact features do not tell the {what} apart"
            ))
        })?
        .solve(&aty)
        .iter()
        .copied()
        .collect())
}

/// The root-mean-square of `model(features) - truth(condition)` over `cells` (0 without any):
/// a model's error on the validation cells.
fn rms_error<'a>(
    cells: impl Iterator<Item = &'a (Condition, Vec<f64>)>,
    model: impl Fn(&[f64]) -> f64,
    truth: impl Fn(&Condition) -> f64,
) -> f64 {
    let (mut sq, mut n) = (0.0, 0usize);
    for (c, f) in cells {
        sq += (model(f) - truth(c)).powi(2);
        n += 1;
    }
    (sq / n.max(1) as f64).sqrt()
}

/// The features of every run past its warm-up, each with its run's condition.
fn labelled(
    runs: &[(Condition, GridRun)],
    speed: f64,
    bands: &[[f64; 2]],
) -> Vec<(Condition, Vec<f64>)> {
    runs.iter()
        .flat_map(|(c, r)| features(r, speed, bands).into_iter().map(move |f| (*c, f)))
        .collect()
}

/// The model at `speed` from runs labelled by their condition, on the features in `bands`
/// ([`CONTACT_BAND`] first).
pub(super) fn fit(
    speed: f64,
    training: &[(Condition, GridRun)],
    validation: &[(Condition, GridRun)],
    bands: &[[f64; 2]],
) -> Result<SpeedModel, Error> {
    let train = labelled(training, speed, bands);
    let valid = labelled(validation, speed, bands);
    let rows: Vec<Vec<f64>> = train
        .iter()
        .map(|(_, f)| f.iter().copied().chain([1.0]).collect())
        .collect();
    let k: Vec<f64> = train.iter().map(|(c, _)| c.kalker).collect();
    let coefficients = least_squares(&rows, &k, speed, "conditions")?;
    let rms_error = rms_error(valid.iter(), |f| linear(&coefficients, f), |c| c.kalker);
    let coned = train.iter().all(|(c, _)| c.conicity.is_some());
    let conicity = if coned {
        Some(conicity_model(speed, &train, &valid, &rows, &coefficients)?)
    } else {
        None
    };
    let kalker_by_conicity = if coned {
        by_conicity(speed, &train, &valid, bands)?
    } else {
        vec![]
    };
    Ok(SpeedModel {
        speed,
        coefficients,
        rms_error,
        conicity,
        kalker_by_conicity,
    })
}

/// Per conicity of the runs, the Kalker scale from the features of D1 and its octaves (the first
/// four bands), fitted on that conicity's training runs and judged on its validation runs
/// ([`SpeedModel::kalker_by_conicity`]). Conicity bank at 20 m/s, validation seeds 102-106,
/// conicities 0.05-0.4 at Kalker 100 and 50 %: whole Jrel told nothing 0.192 from D1's five
/// features, 0.165 from the 20; told the conicity 0.111 and 0.101.
fn by_conicity(
    speed: f64,
    train: &[(Condition, Vec<f64>)],
    valid: &[(Condition, Vec<f64>)],
    bands: &[[f64; 2]],
) -> Result<Vec<NodeModel>, Error> {
    let mut nodes: Vec<f64> = train.iter().filter_map(|(c, _)| c.conicity).collect();
    nodes.sort_by(f64::total_cmp);
    nodes.dedup();
    // The runtime reads a prefix of the bands: D1's octaves must follow D1.
    let kalker = 1 + KALKER_BANDS.len();
    if bands.get(1..kalker) != Some(&KALKER_BANDS[..]) {
        return Err(Error::input(format!(
            "the contact bands {bands:?} do not start with D1 and its octaves {KALKER_BANDS:?}"
        )));
    }
    let read = FEATURES * kalker;
    let first = |f: &[f64]| -> Vec<f64> { f[..read].iter().copied().chain([1.0]).collect() };
    nodes
        .into_iter()
        .map(|n| {
            let at = |(c, _): &&(Condition, Vec<f64>)| c.conicity == Some(n);
            let rows: Vec<Vec<f64>> = train.iter().filter(at).map(|(_, f)| first(f)).collect();
            let k: Vec<f64> = train.iter().filter(at).map(|(c, _)| c.kalker).collect();
            let coefficients = least_squares(&rows, &k, speed, "Kalker scales")?;
            let rms_error = rms_error(
                valid.iter().filter(at),
                |f| linear(&coefficients, &f[..read]),
                |c| c.kalker,
            );
            Ok(NodeModel {
                conicity: n,
                coefficients,
                rms_error,
            })
        })
        .collect()
}

/// The conicity's estimator, the features' forward model and the novelty's level at `speed`.
fn conicity_model(
    speed: f64,
    train: &[(Condition, Vec<f64>)],
    valid: &[(Condition, Vec<f64>)],
    rows: &[Vec<f64>],
    kalker: &[f64],
) -> Result<ConicityModel, Error> {
    let ln = |c: &Condition| c.conicity.expect("a bank over conicities").ln();
    let x: Vec<f64> = train.iter().map(|(c, _)| ln(c)).collect();
    let coefficients = least_squares(rows, &x, speed, "conicities")?;
    let rms_error = rms_error(valid.iter(), |f| linear(&coefficients, f), ln);
    // The forward model at the runs' own conditions, one feature at a time.
    let terms: Vec<Vec<f64>> = train
        .iter()
        .map(|(c, _)| forward_terms(ln(c), c.kalker).to_vec())
        .collect();
    let n = train[0].1.len();
    let forward: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            let y: Vec<f64> = train.iter().map(|(_, f)| f[i]).collect();
            least_squares(&terms, &y, speed, "conditions' features")
        })
        .collect::<Result<_, _>>()?;
    let predict = |x: f64, y: f64| -> Vec<f64> {
        let t = forward_terms(x, y);
        forward
            .iter()
            .map(|row| row.iter().zip(&t).map(|(a, b)| a * b).sum())
            .collect()
    };
    let mut cov = DMatrix::<f64>::zeros(n, n);
    for (c, f) in train {
        let p = predict(ln(c), c.kalker);
        let r = DVector::from_iterator(n, f.iter().zip(&p).map(|(a, b)| a - b));
        cov += &r * r.transpose();
    }
    cov /= train.len() as f64;
    let precision = cov.clone().try_inverse().ok_or_else(|| {
        Error::input(format!(
            "at {speed} m/s the contact features' residuals are degenerate"
        ))
    })?;
    let precision: Vec<f64> = (0..n * n).map(|i| precision[(i / n, i % n)]).collect();
    let model = ConicityModel {
        coefficients,
        rms_error,
        forward: forward.clone(),
        precision,
        level: 1.0,
    };
    // The level: the squared distance exceeded on LEVEL_SHARE of the validation cells, each
    // judged at the condition the runtime estimates from it (clamped as there).
    let range = conditions_range(train);
    let mut d2: Vec<f64> = valid
        .iter()
        .map(|(_, f)| {
            let x = linear(&model.coefficients, f).clamp(range.0, range.1);
            let y = linear(kalker, f).clamp(range.2, range.3);
            // The FMU's own code, at level 1: the squared distance itself.
            model.novelty(f, x, y)
        })
        .collect();
    d2.sort_by(f64::total_cmp);
    let at = ((1.0 - LEVEL_SHARE) * d2.len() as f64) as usize;
    let level = d2
        .get(at.min(d2.len().saturating_sub(1)))
        .copied()
        .filter(|l| l.is_finite() && *l > 0.0)
        .ok_or_else(|| Error::input(format!("at {speed} m/s no validation features")))?;
    Ok(ConicityModel { level, ..model })
}

/// The trained ranges: ln conicity low and high, Kalker scale low and high.
fn conditions_range(train: &[(Condition, Vec<f64>)]) -> (f64, f64, f64, f64) {
    train.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), (k, _)| {
            let x = k.conicity.expect("a bank over conicities").ln();
            (a.min(x), b.max(x), c.min(k.kalker), d.max(k.kalker))
        },
    )
}
