//! The standard curved case (the robustness study's curve table): the 2.1 km metro-like line
//! of the vehicle FMU's `metro-line.csv` at 18 m/s (what `studies/curved.ssd` runs), against
//! the same irregularities on straight track, for the paper's filter and the default.
//!
//! Each seed's vehicle run is recorded once on the line and once straight (the same track seed
//! lays the same irregularities at the same distances), and both estimators process them
//! offline as the FMU steps: on the line told the design (`design_curvature`, `design_cant`,
//! the mode an infrastructure manager runs), told the design fitted from the sensors
//! (`design_line::fit`, for a line whose design is not known), and the default once more told
//! nothing. The
//! curves of radius 500 m and more are also judged on their own stretches, against the same
//! stretches of the straight run.

use super::metrics::{BandMetrics, evaluate};
use super::records::{
    Flagged, Output, Record, estimate, estimate_learned, flagged_learned, record_table, share_of,
};
use super::runs::{Fmus, seeded};
use super::standard::{DS, TRIM};
use crate::Error;
use fmu_estimator::offline::{Sample, fitted};
use orchestrator::system::Value;
use rayon::prelude::*;
use serde::Serialize;

/// The line (in the vehicle FMU's resources), its speed \[m/s\] and the run's length \[s\].
pub const LINE: &str = "metro-line.csv";
const SPEED: f64 = 18.0;
const RUN: f64 = 114.0;
/// The stretches of `metro-line.csv` around its curves of radius 500 m and more (1200 m and
/// 1500 m, with their transitions and 30-40 m either side) \[m\].
pub const WIDE_CURVES: [(f64, f64); 2] = [(560.0, 970.0), (1460.0, 1840.0)];

/// The tight curve, reported apart: radius 300 m with 60 m transitions and 100 mm cant from
/// 100 m on, 200 m long, at the line's speed, flange contact on (the ML95's leading wheelset
/// needs more shift than the 9 mm clearance there); beyond the shipped design response's
/// envelope, so `outside_training` must set.
pub const TIGHT: [(&str, f64); 5] = [
    ("curve_radius", 300.0),
    ("curve_transition", 60.0),
    ("curve_cant", 0.1),
    ("curve_start", 100.0),
    ("curve_length", 200.0),
];
/// Its run \[s\] (to 600 m).
const TIGHT_RUN: f64 = 33.0;

/// One seed's figures.
#[derive(Debug, Clone, Serialize)]
pub struct CurveRun {
    /// Track seed.
    pub seed: u32,
    /// Straight track: the paper's filter, the default.
    pub straight: [BandMetrics; 2],
    /// The line, design known: the paper's filter, the default.
    pub known: [BandMetrics; 2],
    /// The line, the default told nothing.
    pub untold: BandMetrics,
    /// The line, the default told the design fitted from the sensors (`design_line::fit`,
    /// the mode for a line whose design is not known): the paper's filter, the default.
    pub fitted: [BandMetrics; 2],
    /// The wide curves' stretches, the default: straight, then design known (each the mean of
    /// the two stretches' Jrel, whole band).
    pub wide: [f64; 2],
    /// The tight curve ([`TIGHT`]), design known, the default: the run's figures, and the share
    /// of its samples in the circular part with `outside_training` set.
    pub tight: (BandMetrics, f64),
    /// The line with flange contact on, design known, the default: the run's figures, the
    /// share of its samples with `outside_training` set, and the wide curves' stretches' whole
    /// Jrel (mean of the two).
    pub flange: (BandMetrics, f64, f64),
    /// The line without flange contact, the default: the share of its samples with
    /// `outside_training` set, design known (a false alarm), then told nothing (where the
    /// estimate is useless, the flag should be set).
    pub line_flagged: [f64; 2],
}

/// How a run is laid: the line, straight, or the tight curve with flange contact.
#[derive(Clone, Copy, PartialEq)]
enum Lay {
    Line,
    Straight,
    Tight,
    LineWithFlanges,
}

fn record(fmus: &Fmus, seed: u32, lay: Lay) -> Result<Record, Error> {
    let mut settings = seeded(seed);
    match lay {
        Lay::Line => settings.push(("line_file".into(), Value::String(LINE.into()))),
        Lay::LineWithFlanges => {
            settings.push(("line_file".into(), Value::String(LINE.into())));
            settings.push(("flange_contact".into(), Value::Boolean(true)));
        }
        Lay::Straight => {}
        Lay::Tight => {
            for (n, v) in TIGHT {
                settings.push((n.into(), Value::Real(v)));
            }
            settings.push(("flange_contact".into(), Value::Boolean(true)));
        }
    }
    let stop = if lay == Lay::Tight { TIGHT_RUN } else { RUN };
    // The roll gyroscope (its own noise stream: no other signal changes) for the design fit.
    let roll = (lay == Lay::Line).then_some("ws_roll_rate");
    let (mut rec, table) = record_table(
        fmus,
        settings,
        stop,
        Some(&|_| SPEED),
        roll,
        &["design_curvature", "design_cant"],
    )?;
    let col = |n: &str| {
        table
            .column(&format!("vehicle.{n}"))
            .map(|x| x[1..].to_vec())
            .ok_or_else(|| Error::Input(format!("the vehicle FMU has no output '{n}'")))
    };
    let (k, c) = (col("design_curvature")?, col("design_cant")?);
    for (i, s) in rec.samples.iter_mut().enumerate() {
        s.design = [k[i], c[i]];
    }
    Ok(rec)
}

/// `rec` with the design fitted from its sensors in place of the line's.
fn with_fitted_design(rec: &Record) -> Result<Record, Error> {
    let model = fmu_estimator::design::DesignModel::shipped().map_err(Error::Input)?;
    let (samples, _) =
        fitted::with_fitted_design(&rec.samples, 1e-3, &model).map_err(Error::Input)?;
    Ok(Record {
        samples,
        distance: rec.distance.clone(),
        alignment: rec.alignment.clone(),
    })
}

/// The default's estimate (`paper`: the paper's filter's) over `rec` with the user's
/// estimator settings `user`, the design removed when `told`.
fn judged(
    user: &[(String, String)],
    rec: &Record,
    paper: bool,
    told: bool,
    window: Option<(f64, f64)>,
) -> Result<BandMetrics, Error> {
    let samples = samples_told(rec, told);
    let (distance, est) = if paper {
        let mut settings = user.to_vec();
        settings.push(("estimator".into(), "1".into()));
        estimate(&samples, 1e-3, &settings, None, false)?
    } else {
        estimate_learned(&samples, 1e-3, user, Output::Alignment)?
    };
    let (a, b) = window.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
    let keep = |d: &[f64], x: &[f64]| -> (Vec<f64>, Vec<f64>) {
        d.iter()
            .zip(x)
            .filter(|(d, _)| **d >= a && **d <= b)
            .map(|(d, x)| (*d, *x))
            .unzip()
    };
    let (ed, ex) = keep(&distance, &est);
    let (td, tx) = keep(&rec.distance, &rec.alignment);
    Ok(evaluate(&ed, &ex, &td, &tx, DS, TRIM)?)
}

/// The default told the design over `rec`.
fn flagged(user: &[(String, String)], rec: &Record) -> Result<Flagged, Error> {
    flagged_told(user, rec, true)
}

/// `rec`'s samples with the design inputs, or (`told` false) without them.
fn samples_told(rec: &Record, told: bool) -> Vec<Sample> {
    let mut samples = rec.samples.clone();
    if !told {
        for s in &mut samples {
            s.design = [0.0; 2];
        }
    }
    samples
}

/// The default over `rec`, told the design or not (`told`).
fn flagged_told(user: &[(String, String)], rec: &Record, told: bool) -> Result<Flagged, Error> {
    flagged_learned(&samples_told(rec, told), 1e-3, user)
}

/// The share of the default's samples over `rec` with `outside_training` set, told the design
/// or not.
fn share(user: &[(String, String)], rec: &Record, told: bool) -> Result<f64, Error> {
    let (_, _, flags) = flagged_told(user, rec, told)?;
    Ok(share_of(&flags))
}

/// The line with flange contact: the run's figures, the share flagged, the wide curves' whole.
fn with_flanges(fmus: &Fmus, seed: u32) -> Result<(BandMetrics, f64, f64), Error> {
    let rec = record(fmus, seed, Lay::LineWithFlanges)?;
    let user = &fmus.estimator_texts();
    let (distance, est, flags) = flagged(user, &rec)?;
    let share = share_of(&flags);
    let m = evaluate(&distance, &est, &rec.distance, &rec.alignment, DS, TRIM)?;
    let wide = WIDE_CURVES
        .iter()
        .map(|w| judged(user, &rec, false, true, Some(*w)).map(|m| m.whole.jrel))
        .sum::<Result<f64, Error>>()?
        / WIDE_CURVES.len() as f64;
    Ok((m, share, wide))
}

/// The default told the design over the tight curve: its figures and the share of the circular
/// part's samples with `outside_training` set.
fn tight(fmus: &Fmus, seed: u32) -> Result<(BandMetrics, f64), Error> {
    let rec = record(fmus, seed, Lay::Tight)?;
    let (distance, est, flags) = flagged(&fmus.estimator_texts(), &rec)?;
    let (a, b) = (
        TIGHT[3].1 + TIGHT[1].1,
        TIGHT[3].1 + TIGHT[1].1 + TIGHT[4].1,
    );
    let inside: Vec<bool> = rec
        .distance
        .iter()
        .zip(&flags)
        .filter(|(d, _)| **d >= a && **d <= b)
        .map(|(_, f)| *f)
        .collect();
    let share = share_of(&inside);
    let m = evaluate(&distance, &est, &rec.distance, &rec.alignment, DS, TRIM)?;
    Ok((m, share))
}

fn run_one(fmus: &Fmus, seed: u32) -> Result<CurveRun, Error> {
    let user = &fmus.estimator_texts();
    let (straight, line) = (
        record(fmus, seed, Lay::Straight)?,
        record(fmus, seed, Lay::Line)?,
    );
    let wide = |rec: &Record, told: bool| -> Result<f64, Error> {
        let mut sum = 0.0;
        for w in WIDE_CURVES {
            sum += judged(user, rec, false, told, Some(w))?.whole.jrel;
        }
        Ok(sum / WIDE_CURVES.len() as f64)
    };
    Ok(CurveRun {
        seed,
        straight: [
            judged(user, &straight, true, false, None)?,
            judged(user, &straight, false, false, None)?,
        ],
        known: [
            judged(user, &line, true, true, None)?,
            judged(user, &line, false, true, None)?,
        ],
        untold: judged(user, &line, false, false, None)?,
        fitted: {
            let fitted = with_fitted_design(&line)?;
            [
                judged(user, &fitted, true, true, None)?,
                judged(user, &fitted, false, true, None)?,
            ]
        },
        wide: [wide(&straight, false)?, wide(&line, true)?],
        tight: tight(fmus, seed)?,
        flange: with_flanges(fmus, seed)?,
        line_flagged: [share(user, &line, true)?, share(user, &line, false)?],
    })
}

/// Every seed, in parallel.
pub fn run(fmus: &Fmus, seeds: &[u32]) -> Result<Vec<CurveRun>, Error> {
    seeds.par_iter().map(|&s| run_one(fmus, s)).collect()
}

fn mean(x: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = x.collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn bands(runs: &[CurveRun], pick: impl Fn(&CurveRun) -> &BandMetrics) -> String {
    format!(
        "{:.3} / {:.3} / {:.3} / {:.3} (worst seed {:.3})",
        mean(runs.iter().map(|r| pick(r).whole.jrel)),
        mean(runs.iter().map(|r| pick(r).d1.jrel)),
        mean(runs.iter().map(|r| pick(r).d2.jrel)),
        mean(runs.iter().map(|r| pick(r).d3.jrel)),
        runs.iter()
            .map(|r| pick(r).whole.jrel)
            .fold(0.0f64, f64::max)
    )
}

/// The table (means over the seeds).
pub fn markdown(seeds: &[u32], runs: &[CurveRun]) -> String {
    let mut s = format!(
        "### Curves: the standard curved case\n\nThe vehicle FMU's `{LINE}` (2.1 km, four curves of radius 400-1500 m, transitions 40-100 m, cant 30-120 mm) at {SPEED} m/s, {RUN} s, against the same irregularities on straight track. Jrel whole / D1 / D2 / D3, mean over seeds {seeds:?}.\n\n| run | paper's filter | default (learned) |\n|---|---|---|\n"
    );
    s.push_str(&format!(
        "| straight track | {} | {} |\n",
        bands(runs, |r| &r.straight[0]),
        bands(runs, |r| &r.straight[1])
    ));
    s.push_str(&format!(
        "| the line, design known | {} | {} |\n",
        bands(runs, |r| &r.known[0]),
        bands(runs, |r| &r.known[1])
    ));
    s.push_str(&format!(
        "| the line, design fitted from the sensors | {} | {} |\n",
        bands(runs, |r| &r.fitted[0]),
        bands(runs, |r| &r.fitted[1])
    ));
    s.push_str(&format!(
        "| the line, told nothing | | {} |\n",
        bands(runs, |r| &r.untold)
    ));
    s.push_str(&format!(
        "\n`outside_training` (default) on the line: design known {:.1} % of the samples, told nothing {:.1} %.\n",
        100.0 * mean(runs.iter().map(|r| r.line_flagged[0])),
        100.0 * mean(runs.iter().map(|r| r.line_flagged[1]))
    ));
    s.push_str(&format!(
        "\nCurves of radius 500 m and more (stretches {WIDE_CURVES:?} m), default, whole: straight {:.3}, design known {:.3}.\n",
        mean(runs.iter().map(|r| r.wide[0])),
        mean(runs.iter().map(|r| r.wide[1]))
    ));
    s.push_str(&format!(
        "\nWith flange contact on (the physical vehicle: the ML95's stiff bogie presses its leading wheelset against the flange in most of these curves), default told the design: {}; `outside_training` set on {:.0} % of the samples; the wide curves' stretches {:.3}.\n",
        bands(runs, |r| &r.flange.0),
        100.0 * mean(runs.iter().map(|r| r.flange.1)),
        mean(runs.iter().map(|r| r.flange.2))
    ));
    let tight = bands(runs, |r| &r.tight.0);
    s.push_str(&format!(
        "\nThe tight curve, apart (radius 300 m, transitions 60 m, cant 100 mm, flange contact on; 600 m at {SPEED} m/s), default told the design: {tight}; `outside_training` set on {:.0} % of the circular part's samples.\n",
        100.0 * mean(runs.iter().map(|r| r.tight.1))
    ));
    s
}
