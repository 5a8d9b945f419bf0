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
    CHANNELS, CONTACT_SPEED_POWER, ConicityModel, FEATURES, LEVEL_SHARE, Moments, NodeModel,
    SpeedModel, YoungModel, forward_terms, linear,
};
use fmu_estimator::learned::spectral::{self, Spectra};
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

/// The track a young memory holds when its conicity models are fitted \[m\]
/// ([`YoungModel`]): close at the start, where the features change fastest, and up to three
/// quarters of the memory (the full memory's model takes over at [`CONTACT_MEMORY`]).
pub const YOUNG_FILLS: [f64; 8] = [5.0, 10.0, 20.0, 35.0, 50.0, 75.0, 100.0, 150.0];

/// How far apart along a run the young memories start \[m\]: each one a fresh [`Moments`]
/// (its filters started anew, as at a run's start), so a 10 km run gives 200 of them.
const YOUNG_STRIDE: f64 = 50.0;

/// Per fill of [`YOUNG_FILLS`], the features of the young memories started every
/// [`YOUNG_STRIDE`] along a run at `speed`, at that fill.
fn young_features(run: &GridRun, speed: f64, bands: &[[f64; 2]]) -> Vec<Vec<Vec<f64>>> {
    let cells = &run.cells.cells;
    let at: Vec<usize> = YOUNG_FILLS
        .iter()
        .map(|f| (f / BANK_GRID).round() as usize)
        .collect();
    let last = at[at.len() - 1];
    let stride = (YOUNG_STRIDE / BANK_GRID).round() as usize;
    let mut out = vec![vec![]; at.len()];
    for start in (0..cells.len().saturating_sub(last - 1)).step_by(stride) {
        let mut m = Moments::new(BANK_GRID, bands, CONTACT_MEMORY, &[speed]);
        let mut next = 0;
        for (i, cell) in cells[start..start + last].iter().enumerate() {
            m.push(cell, speed);
            if at.get(next) == Some(&(i + 1)) {
                if let Some(f) = m.features(0) {
                    out[next].push(f.to_vec());
                }
                next += 1;
            }
        }
    }
    out
}

/// Cells' features, each with its run's condition.
type Labelled = Vec<(Condition, Vec<f64>)>;

/// [`young_features`] of every run, each with its run's condition: per fill, the cells.
fn young_labelled(runs: &[(Condition, GridRun)], speed: f64, bands: &[[f64; 2]]) -> Vec<Labelled> {
    let mut out = vec![vec![]; YOUNG_FILLS.len()];
    for (c, r) in runs {
        for (all, fill) in out.iter_mut().zip(young_features(r, speed, bands)) {
            all.extend(fill.into_iter().map(|f| (*c, f)));
        }
    }
    out
}

/// A least-squares row: the features, then 1 for the constant (the models' layout,
/// [`linear`]).
fn row(f: &[f64]) -> Vec<f64> {
    f.iter().copied().chain([1.0]).collect()
}

/// `ln(conicity)` of a run's condition, in a bank over conicities.
fn ln_conicity(c: &Condition) -> f64 {
    c.conicity.expect("a bank over conicities").ln()
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
    let rows: Vec<Vec<f64>> = train.iter().map(|(_, f)| row(f)).collect();
    let k: Vec<f64> = train.iter().map(|(c, _)| c.kalker).collect();
    let coefficients = least_squares(&rows, &k, speed, "conditions")?;
    let rms_error = rms_error(valid.iter(), |f| linear(&coefficients, f), |c| c.kalker);
    let coned = train.iter().all(|(c, _)| c.conicity.is_some());
    let conicity = if coned {
        let young = [
            young_labelled(training, speed, bands),
            young_labelled(validation, speed, bands),
        ];
        Some(conicity_model(
            speed,
            [&train, &valid],
            &young,
            &rows,
            &coefficients,
        )?)
    } else {
        None
    };
    let kalker_by_conicity = if coned {
        by_conicity(speed, &train, &valid, bands)?
    } else {
        vec![]
    };
    let spectra = if coned {
        Some(spectra(speed, training)?)
    } else {
        None
    };
    Ok(SpeedModel {
        speed,
        coefficients,
        rms_error,
        conicity,
        kalker_by_conicity,
        spectra,
    })
}

/// The model cross-spectra of the training runs at `speed` ([`spectral`]): per condition, Welch's
/// estimate over the run past its [`WARM_UP`] (the start transient), of the channels divided by
/// the speed's powers as the runtime divides them; a condition with several runs (a vehicle
/// family) the mean of theirs.
fn spectra(speed: f64, training: &[(Condition, GridRun)]) -> Result<Spectra, Error> {
    let bins = spectral::stored_bins(BANK_GRID);
    let skip = (WARM_UP / BANK_GRID).round() as usize;
    let mut conditions: Vec<[f64; 2]> = vec![];
    let mut sums: Vec<(Vec<[f64; spectral::PACKED]>, f64)> = vec![];
    for (c, run) in training {
        let Some(conicity) = c.conicity else {
            continue;
        };
        let x: Vec<[f64; 3]> = run
            .cells
            .cells
            .iter()
            .skip(skip)
            .map(|cell| {
                std::array::from_fn(|i| cell[CHANNELS[i]] / speed.powi(CONTACT_SPEED_POWER[i]))
            })
            .collect();
        let w = spectral::welch(&x, spectral::WINDOW, BANK_GRID, bins).ok_or_else(|| {
            Error::input(format!(
                "at {speed} m/s, {c}: the training run is shorter than the spectra's window"
            ))
        })?;
        let key = [conicity, c.kalker];
        match conditions.iter().position(|k| *k == key) {
            Some(i) => {
                for (a, b) in sums[i].0.iter_mut().zip(&w) {
                    for (a, b) in a.iter_mut().zip(b) {
                        *a += b;
                    }
                }
                sums[i].1 += 1.0;
            }
            None => {
                conditions.push(key);
                sums.push((w, 1.0));
            }
        }
    }
    let values = sums
        .iter()
        .flat_map(|(w, n)| w.iter().flatten().map(move |v| (v / n) as f32))
        .collect();
    let s = Spectra {
        window: spectral::WINDOW,
        first_bin: bins[0],
        conditions,
        values,
    };
    s.check(BANK_GRID)
        .map_err(|e| Error::input(format!("at {speed} m/s, the model spectra: {e}")))?;
    Ok(s)
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
    let first = |f: &[f64]| row(&f[..read]);
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

/// The share of a young model's own least-squares coefficients in the ones it ships with, the
/// rest the full memory's model's: chosen on the validation seeds (20 m/s, seeds 102-106, 400 m,
/// conicity 0.05-0.3 x Kalker 100 / 75 / 50 %, told nothing; whole Jrel mean, worst, and at
/// 0.1 with Kalker 100 / 75 / 50 %):
///
/// | share | mean | worst | conditions above 0.2 | at 0.1 |
/// |---|---|---|---|---|
/// | 0 (the full model from the first cell) | 0.160 | 0.269 | 5 of 30 | 0.127 / 0.143 / 0.165 |
/// | 0.3 | 0.155 | 0.262 | 3 | 0.126 / 0.142 / 0.161 |
/// | 0.5 | 0.154 | 0.258 | 2 | 0.128 / 0.143 / 0.159 |
/// | 0.7 | 0.155 | 0.253 | 2 | 0.134 / 0.146 / 0.159 |
/// | 1 (the young fit alone) | 0.159 | 0.246 | 2 | 0.151 / 0.156 / 0.164 |
///
/// Why not the young fit alone, whose `ln(conicity)` error is the least (validation, 20 m/s,
/// at 20 / 50 / 100 m: 0.35 / 0.21 / 0.14 against the full model's 0.63 / 0.26 / 0.15): the
/// taps' error is steep and lopsided in the conicity's (told 15 % low, whole 0.19, D1 0.54; 18 %
/// high 0.15, D1 0.39; at 0.1, Kalker 100 %), and the young fit reads the nominal wheels 0.1-0.17
/// low over 20-100 m where the full model reads them high. Half of each cancels that.
pub const YOUNG_SHARE: f64 = 0.5;

/// The young memories' conicity models at `speed`, from the training and validation cells
/// per fill ([`young_labelled`]), each mixed with the full memory's model `full`
/// ([`YOUNG_SHARE`]).
fn young_models(
    speed: f64,
    full: &[f64],
    train: &[Labelled],
    valid: &[Labelled],
) -> Result<Vec<YoungModel>, Error> {
    YOUNG_FILLS
        .iter()
        .zip(train.iter().zip(valid))
        .map(|(fill, (train, valid))| {
            if train.is_empty() {
                return Err(Error::input(format!(
                    "at {speed} m/s no training run is {fill} m long"
                )));
            }
            let rows: Vec<Vec<f64>> = train.iter().map(|(_, f)| row(f)).collect();
            let x: Vec<f64> = train.iter().map(|(c, _)| ln_conicity(c)).collect();
            let own = least_squares(&rows, &x, speed, "conicities")?;
            let coefficients: Vec<f64> = own
                .iter()
                .zip(full)
                .map(|(y, f)| YOUNG_SHARE * y + (1.0 - YOUNG_SHARE) * f)
                .collect();
            let rms_error = rms_error(valid.iter(), |f| linear(&coefficients, f), ln_conicity);
            Ok(YoungModel {
                fill: *fill,
                coefficients,
                rms_error,
            })
        })
        .collect()
}

/// The conicity's estimator, the features' forward model and the novelty's level at `speed`.
/// `[train, valid]`: the cells of full memories; `young`: the young memories' cells, training
/// and validation, per fill ([`young_labelled`]).
fn conicity_model(
    speed: f64,
    [train, valid]: [&[(Condition, Vec<f64>)]; 2],
    young: &[Vec<Labelled>; 2],
    rows: &[Vec<f64>],
    kalker: &[f64],
) -> Result<ConicityModel, Error> {
    let x: Vec<f64> = train.iter().map(|(c, _)| ln_conicity(c)).collect();
    let coefficients = least_squares(rows, &x, speed, "conicities")?;
    let rms_error = rms_error(valid.iter(), |f| linear(&coefficients, f), ln_conicity);
    let young = young_models(speed, &coefficients, &young[0], &young[1])?;
    // The forward model at the runs' own conditions, one feature at a time.
    let terms: Vec<Vec<f64>> = train
        .iter()
        .map(|(c, _)| forward_terms(ln_conicity(c), c.kalker).to_vec())
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
        let p = predict(ln_conicity(c), c.kalker);
        let r = DVector::from_iterator(n, f.iter().zip(&p).map(|(a, b)| a - b));
        cov += &r * r.transpose();
    }
    cov /= train.len() as f64;
    let precision = cov.clone().try_inverse().ok_or_else(|| {
        Error::input(format!(
            "at {speed} m/s the contact features' residuals are degenerate"
        ))
    })?;
    // The upper triangle mirrored: the inverse is symmetric to rounding, and a bank keeps the
    // triangle alone, so the level below is measured with the matrix the runtime reads.
    let precision: Vec<f64> = (0..n * n)
        .map(|i| {
            let (r, c) = (i / n, i % n);
            precision[(r.min(c), r.max(c))]
        })
        .collect();
    let model = ConicityModel {
        coefficients,
        rms_error,
        forward: forward.clone(),
        precision,
        level: 1.0,
        young,
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
            let x = ln_conicity(k);
            (a.min(x), b.max(x), c.min(k.kalker), d.max(k.kalker))
        },
    )
}
