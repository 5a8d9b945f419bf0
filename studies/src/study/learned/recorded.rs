//! A tap bank fitted from recordings of an instrumented train against a reference alignment of
//! the same line (a track recording car's), the deployment path of `alignment-studies fit
//! --recordings`.
//!
//! | step | how |
//! |---|---|
//! | odometry | each pass's distance is the rectangle rule of its `speed` (as the estimator integrates it), from its first `distance` value when it has that column |
//! | placement | the reference position of a sample `d` metres of odometry after the pass's start `s0` is `s0 + offset + scale * d`: found by the correlation of the shipped default's estimate with the reference in the whole band (3-200 m, zero phase), over offsets within [`SEARCH_OFFSET`] and scales within [`SEARCH_SCALE`], then refined (parabola through the best offset's neighbours; scales in steps of [`FINE_SCALE_STEP`]) |
//! | split | by reference position: the last `validation_share` of the line validates (ridge, band weights, the report's figures), the rest trains; each pass is cut there |
//! | speeds | each pass trains the bank speed (a multiple of 2.5 m/s) nearest its mean speed; its cells are rescaled from their own speed (at least the bank's lowest) to it as the runtime rescales its history; a speed's taps hold over +-1.25 m/s where no neighbouring speed is fitted |
//! | taps | [`super::taps::fit_recorded`]: one condition (the recordings' own), three sensors, causal and fixed-lag, on the Kalman channel of the given calibration |

use super::taps::{GridRun, Options, channel, fit_recorded, recorded_run};
use crate::Error;
use crate::smooth::read_samples;
use crate::study::metrics::{BANDS, bandpass, resample};
use crate::study::records::Record;
use crate::study::runs::{Fmus, STEP};
use fmu_estimator::learned::bank::Bank;
use fmu_estimator::offline::{self, Sample};
use std::path::{Path, PathBuf};

/// How far a pass's start may be from where its odometry says \[m\].
pub const SEARCH_OFFSET: f64 = 30.0;
/// How far a pass's distance scale may be from 1.
pub const SEARCH_SCALE: f64 = 0.01;
/// The coarse scale step of the search.
const COARSE_SCALE_STEP: f64 = 0.001;
/// The fine scale step of the search.
pub const FINE_SCALE_STEP: f64 = 0.0001;
/// Rounds of the placement's refinement between the search's grid points.
const REFINEMENTS: usize = 4;
/// The grid the placement correlates on \[m\].
const PLACE_GRID: f64 = 0.25;
/// A pass's first metres, left out of the placement (the estimator's start).
const PLACE_SKIP: f64 = 100.0;
/// A reference step this many times its median is a gap.
pub const GAP_FACTOR: f64 = 5.0;
/// The fewest samples a training or validation part of a pass has (20 s at 1 ms, the standard
/// case's length; a shorter piece is left out).
const MIN_PART: usize = 20_000;
/// The bank speeds a pass is assigned to are multiples of this \[m/s\].
pub const SPEED_GRID: f64 = 2.5;

/// A reference alignment of the line.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Position along the line \[m\], increasing.
    pub distance: Vec<f64>,
    /// Lateral alignment \[m\].
    pub alignment: Vec<f64>,
}

/// Reads a reference (CSV or Parquet with columns `distance` and `alignment`): increasing
/// distance, no gaps (a step over [`GAP_FACTOR`] times the median), finite values; errors name
/// the file and the line.
pub fn read_reference(path: &Path) -> Result<Reference, Error> {
    let cols = orchestrator::csv::Csv::read_any(path)
        .map_err(|e| Error::Input(format!("reference {e}")))?;
    let col = |name: &str| {
        cols.column(&[name])
            .map(|c| c.to_vec())
            .map_err(|m| Error::Input(format!("reference {}: {m}", path.display())))
    };
    let (distance, alignment) = (col("distance")?, col("alignment")?);
    let place = |k: usize| cols.place(k);
    if distance.len() < 2 {
        return Err(Error::Input(format!(
            "reference {}: fewer than 2 rows",
            path.display()
        )));
    }
    for k in 0..distance.len() {
        if !(distance[k].is_finite() && alignment[k].is_finite()) {
            return Err(Error::Input(format!(
                "reference {}: a value at {} is not a finite number",
                path.display(),
                place(k)
            )));
        }
    }
    let mut steps: Vec<f64> = distance.windows(2).map(|w| w[1] - w[0]).collect();
    if let Some(k) = steps.iter().position(|d| !(*d > 0.0)) {
        return Err(Error::Input(format!(
            "reference {}: distance does not increase at {}",
            path.display(),
            place(k + 1)
        )));
    }
    let raw = steps.clone();
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    if let Some(k) = raw.iter().position(|d| *d > GAP_FACTOR * median) {
        return Err(Error::Input(format!(
            "reference {}: a gap of {:.3} m before {} (the steps are {median} m): the reference must cover the line without gaps",
            path.display(),
            raw[k],
            place(k + 1)
        )));
    }
    Ok(Reference {
        distance,
        alignment,
    })
}

/// One recorded pass.
#[derive(Debug, Clone)]
pub struct Pass {
    /// The file.
    pub file: PathBuf,
    /// The samples, one per millisecond.
    pub samples: Vec<Sample>,
    /// Where the odometry starts \[m\] (the first `distance`, else 0).
    pub start: f64,
}

/// Reads a pass (the recording format of docs/python.md); its step must be the estimator's
/// 1 ms, which the tap bank's grid and contract are made for.
pub fn read_pass(path: &Path) -> Result<Pass, Error> {
    let (_, h, samples) = read_samples(path).map_err(|e| Error::Input(e.to_string()))?;
    if (h - STEP).abs() > 1e-9 {
        return Err(Error::Input(format!(
            "{}: the step is {h} s; a tap bank is fitted from recordings at the estimator's {STEP} s",
            path.display()
        )));
    }
    // The fit's regressors are the raw sensors: a curved line's design response would be
    // fitted into the taps, while the estimator removes it before them. Refused until the fit
    // removes it too.
    if let Some(k) = samples.iter().position(|s| s.design != [0.0; 2]) {
        return Err(Error::Input(format!(
            "{}: the design line is not straight at sample {} (design_curvature {}, design_cant {}): a tap bank is fitted from recordings on straight, level track only",
            path.display(),
            k + 1,
            samples[k].design[0],
            samples[k].design[1]
        )));
    }
    let cols = orchestrator::csv::Csv::read_any(path).map_err(Error::Input)?;
    let start = cols
        .column(&["distance"])
        .ok()
        .and_then(|d| d.first().copied())
        .unwrap_or(0.0);
    Ok(Pass {
        file: path.to_path_buf(),
        samples,
        start,
    })
}

/// Where a pass lies on the reference: the reference position of a sample `d` metres of
/// odometry after the pass's recorded start `s0` is `s0 + offset + scale * d`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// \[m\].
    pub offset: f64,
    /// The odometry's scale (1: exact).
    pub scale: f64,
    /// The correlation of the estimate with the reference there.
    pub correlation: f64,
}

/// The correlation of `e` (band-passed estimate at odometry `s`) with the band-passed
/// reference `r` (on the grid from `r0` every [`PLACE_GRID`]) at `offset`, `scale`.
fn correlation(s: &[f64], e: &[f64], r0: f64, r: &[f64], offset: f64, scale: f64) -> f64 {
    let (mut se, mut sr, mut ser, mut see, mut srr, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (si, ei) in s.iter().zip(e) {
        let x = (offset + scale * si - r0) / PLACE_GRID;
        if x < 0.0 || x >= (r.len() - 1) as f64 {
            continue;
        }
        let j = x.floor() as usize;
        let f = x - j as f64;
        let ri = r[j] * (1.0 - f) + r[j + 1] * f;
        se += ei;
        sr += ri;
        ser += ei * ri;
        see += ei * ei;
        srr += ri * ri;
        n += 1.0;
    }
    if n < 100.0 {
        return f64::NEG_INFINITY;
    }
    let cov = ser / n - se / n * sr / n;
    let ve = see / n - (se / n).powi(2);
    let vr = srr / n - (sr / n).powi(2);
    cov / (ve * vr).sqrt()
}

/// Places a pass whose estimate is `estimate` at odometry `odometry` (metres from its first
/// sample) and whose recorded start is `start` on the reference.
pub fn place(
    start: f64,
    odometry: &[f64],
    estimate: &[f64],
    reference: &Reference,
    file: &Path,
) -> Result<Placement, Error> {
    let band = &BANDS[0];
    let last = odometry[odometry.len() - 1];
    if last < PLACE_SKIP + 200.0 {
        return Err(Error::Input(format!(
            "{}: {last:.0} m long; a pass must be over {} m to be placed on the reference",
            file.display(),
            PLACE_SKIP + 200.0
        )));
    }
    let n = ((last - PLACE_SKIP) / PLACE_GRID).floor() as usize;
    let s: Vec<f64> = (0..n).map(|i| PLACE_SKIP + i as f64 * PLACE_GRID).collect();
    let e = bandpass(&resample(odometry, estimate, &s), PLACE_GRID, band)
        .map_err(|m| Error::Input(format!("{}: {m}", file.display())))?;
    // The reference in the pass's own coordinates: position minus the recorded start.
    let r0 = reference.distance[0] - start;
    let rn = ((reference.distance[reference.distance.len() - 1] - reference.distance[0])
        / PLACE_GRID)
        .floor() as usize;
    let grid: Vec<f64> = (0..rn)
        .map(|i| reference.distance[0] + i as f64 * PLACE_GRID)
        .collect();
    let r = bandpass(
        &resample(&reference.distance, &reference.alignment, &grid),
        PLACE_GRID,
        band,
    )
    .map_err(|m| Error::Input(format!("reference: {m}")))?;
    let best = |scales: &[f64], offsets: &[f64]| {
        let mut b = (f64::NEG_INFINITY, 0.0, 1.0);
        for &k in scales {
            for &a in offsets {
                let c = correlation(&s, &e, r0, &r, a, k);
                if c > b.0 {
                    b = (c, a, k);
                }
            }
        }
        b
    };
    let steps = |lo: f64, hi: f64, step: f64| -> Vec<f64> {
        let n = ((hi - lo) / step).round() as usize;
        (0..=n).map(|i| lo + i as f64 * step).collect()
    };
    let coarse = best(
        &steps(1.0 - SEARCH_SCALE, 1.0 + SEARCH_SCALE, COARSE_SCALE_STEP),
        &steps(-SEARCH_OFFSET, SEARCH_OFFSET, PLACE_GRID),
    );
    let fine = best(
        &steps(
            coarse.2 - COARSE_SCALE_STEP,
            coarse.2 + COARSE_SCALE_STEP,
            FINE_SCALE_STEP,
        ),
        &steps(coarse.1 - 2.0, coarse.1 + 2.0, PLACE_GRID / 5.0),
    );
    // The peak between the grid's points: offset and scale in turn, each by a parabola through
    // the best and its neighbours (the two trade against each other over a pass's length).
    let c = |a: f64, k: f64| correlation(&s, &e, r0, &r, a, k);
    let vertex = |x: f64, h: f64, f: &dyn Fn(f64) -> f64| -> f64 {
        let (m, z, p) = (f(x - h), f(x), f(x + h));
        let curvature = m - 2.0 * z + p;
        // A neighbour off the reference (no correlation there) leaves the point as it is.
        if curvature.is_finite() && curvature < 0.0 {
            x + (0.5 * (m - p) / curvature).clamp(-1.0, 1.0) * h
        } else {
            x
        }
    };
    let (mut a, mut k) = (fine.1, fine.2);
    for _ in 0..REFINEMENTS {
        a = vertex(a, PLACE_GRID / 5.0, &|x| c(x, k));
        k = vertex(k, FINE_SCALE_STEP, &|x| c(a, x));
    }
    let shift = a - fine.1;
    let fine = (c(a, k), fine.1, k);
    if !(fine.0 > 0.3) {
        return Err(Error::Input(format!(
            "{}: no overlap with the reference found (best correlation {:.2} within {SEARCH_OFFSET} m and {} % of the odometry)",
            file.display(),
            fine.0,
            SEARCH_SCALE * 100.0
        )));
    }
    Ok(Placement {
        offset: fine.1 + shift,
        scale: fine.2,
        correlation: fine.0,
    })
}

/// What a fit from recordings found and made.
pub struct Fitted {
    /// The bank.
    pub bank: Bank,
    /// Each pass: its file, placement (offset relative to its recorded start), mean speed and
    /// the bank speed it trained.
    pub passes: Vec<(PathBuf, Placement, f64, f64)>,
    /// The reference position where validation begins \[m\].
    pub cut: f64,
}

/// Fits a bank from `passes` against `reference` (see the module's table); the last
/// `validation_share` of the reference validates. `o` gives the lags, seeds for the
/// provenance, encoding and calibration.
pub fn fit(
    fmus: &Fmus,
    o: &Options,
    passes: &[Pass],
    reference: &Reference,
    validation_share: f64,
    progress: &dyn Fn(&str),
) -> Result<Fitted, Error> {
    let config = channel(o)?;
    let defaults = offline::settings(&[])?;
    let (default_config, _) = offline::config(&defaults, None)?;
    let r_end = reference.distance[reference.distance.len() - 1];
    let r0 = reference.distance[0];
    let cut = r_end - validation_share * (r_end - r0);
    let mut placed = vec![];
    // Per bank speed, the training and validation parts.
    let mut parts: Vec<(f64, Vec<Record>, Vec<Record>)> = vec![];
    // The shipped default, whose estimate places each pass.
    let learned = offline::learned(&defaults, &default_config)?;
    for p in passes {
        let out =
            offline::process_learned(&default_config, learned.clone(), STEP, &p.samples, false)?;
        let estimate: Vec<f64> = match &out.learned {
            Some(l) => l.iter().map(|e| e.alignment).collect(),
            None => out.filtered.iter().map(|k| k.0).collect(),
        };
        let odometry = &out.distance;
        let at = place(p.start, odometry, &estimate, reference, &p.file)?;
        let mean_speed = out.distance[out.distance.len() - 1] / (p.samples.len() as f64 * STEP);
        let speed = (mean_speed / SPEED_GRID).round().max(1.0) * SPEED_GRID;
        progress(&format!(
            "{}: offset {:+.2} m, distance scale {:+.3} %, correlation {:.2}; mean speed {mean_speed:.1} m/s, trains {speed} m/s",
            p.file.display(),
            at.offset,
            (at.scale - 1.0) * 100.0,
            at.correlation
        ));
        // The pass cut at the validation's start, each part a record with the reference as
        // its target.
        let position = |k: usize| p.start + at.offset + at.scale * odometry[k];
        let split = (0..p.samples.len())
            .find(|k| position(*k) >= cut)
            .unwrap_or(p.samples.len());
        // Each part keeps the samples the reference covers.
        let part = |from: usize, to: usize| -> Option<Record> {
            let from = (from..to).find(|k| position(*k) >= r0)?;
            let to = (from..to).rev().find(|k| position(*k) <= r_end)? + 1;
            if to < from + MIN_PART {
                return None;
            }
            let base = if from == 0 {
                0.0
            } else {
                out.distance[from - 1]
            };
            let positions: Vec<f64> = (from..to).map(position).collect();
            Some(Record {
                samples: p.samples[from..to].to_vec(),
                distance: out.distance[from..to].iter().map(|d| d - base).collect(),
                alignment: resample(&reference.distance, &reference.alignment, &positions),
            })
        };
        let slot = match parts.iter().position(|r| r.0 == speed) {
            Some(i) => i,
            None => {
                parts.push((speed, vec![], vec![]));
                parts.len() - 1
            }
        };
        parts[slot].1.extend(part(0, split));
        parts[slot].2.extend(part(split, p.samples.len()));
        placed.push((p.file.clone(), at, mean_speed, speed));
    }
    // The runtime takes a cell's speed as at least the bank's lowest: so does the fit.
    let floor = parts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let grid = |records: &[Record], speed: f64| -> Result<Vec<GridRun>, Error> {
        records
            .iter()
            .map(|r| recorded_run(r, &config, speed, floor))
            .collect()
    };
    let mut runs: Vec<(f64, Vec<GridRun>, Vec<GridRun>)> = parts
        .iter()
        .map(|(v, t, w)| Ok((*v, grid(t, *v)?, grid(w, *v)?)))
        .collect::<Result<_, Error>>()?;
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (speed, train, valid) in &runs {
        if train.is_empty() || valid.is_empty() {
            return Err(Error::Input(format!(
                "the passes at {speed} m/s cover only the {} stretch of the line (training before {cut:.0} m, validation after): give passes over both",
                if train.is_empty() {
                    "validation"
                } else {
                    "training"
                }
            )));
        }
    }
    let files: Vec<String> = passes
        .iter()
        .map(|p| p.file.display().to_string())
        .collect();
    let source = format!(
        "recordings of an instrumented train ({}), against a reference alignment; training before {cut:.0} m, validation after",
        files.join(", ")
    );
    let bank = fit_recorded(fmus, o, &runs, (SPEED_GRID / 2.0, &source), progress)?;
    Ok(Fitted {
        bank,
        passes: placed,
        cut,
    })
}

/// Recordings made from runs of the vehicle FMU, for testing and demonstrating a fit from
/// recordings: a pass with the odometry errors of a real train, and a reference.
pub mod synthetic {
    use crate::study::records::Record;
    use std::fmt::Write;
    use std::path::Path;

    /// Writes `r` as an instrumented train records it (the recording format): its speed
    /// `scale` times the true one, its `distance` column starting at `offset` and growing
    /// `scale` times the true distance. The true position of odometry `s` is then
    /// `(s - offset) / scale`.
    pub fn write_pass(r: &Record, offset: f64, scale: f64, path: &Path) -> std::io::Result<()> {
        let mut t = String::from("time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y,distance\n");
        for (k, (s, d)) in r.samples.iter().zip(&r.distance).enumerate() {
            let _ = writeln!(
                t,
                "{},{},{},{},{},{}",
                (k + 1) as f64 * 1e-3,
                s.speed * scale,
                s.ws_acc_y,
                s.ws_yaw_rate,
                s.frame_acc_y,
                offset + scale * d
            );
        }
        std::fs::write(path, t)
    }

    /// Writes the true alignment of `r` every 0.25 m as a reference (`distance,alignment`),
    /// without the rows inside `gap` (to test the check).
    pub fn write_reference(
        r: &Record,
        gap: Option<(f64, f64)>,
        path: &Path,
    ) -> std::io::Result<()> {
        let mut t = String::from("distance,alignment\n");
        let mut next = 0.0;
        for (d, a) in r.distance.iter().zip(&r.alignment) {
            if *d >= next {
                if !gap.is_some_and(|(lo, hi)| *d > lo && *d < hi) {
                    let _ = writeln!(t, "{d},{a}");
                }
                next += 0.25;
            }
        }
        std::fs::write(path, t)
    }
}

#[cfg(test)]
mod tests {
    /// A pass on a curved line is refused by name, one on straight track (zero design
    /// columns) read.
    #[test]
    fn a_curved_pass_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let head = "time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y,design_curvature,design_cant\n";
        let straight = dir.path().join("straight.csv");
        std::fs::write(
            &straight,
            format!("{head}0.001,20,0,0,0,0,0\n0.002,20,0,0,0,0,0\n"),
        )
        .unwrap();
        assert_eq!(super::read_pass(&straight).unwrap().samples.len(), 2);
        let curved = dir.path().join("curved.csv");
        std::fs::write(
            &curved,
            format!("{head}0.001,20,0,0,0,0,0\n0.002,20,0,0,0,0.001,0.05\n"),
        )
        .unwrap();
        let e = super::read_pass(&curved).unwrap_err().to_string();
        assert!(e.contains("curved.csv") && e.contains("sample 2"), "{e}");
    }
}
