//! `alignment-studies fit`: everything the estimator FMU needs for one vehicle, fitted from its
//! FMU into one directory: the simplified model's identification and Q/R calibration
//! (`fitted-calibration.toml`, with the identification's figure), the tap bank fitted with that
//! calibration's Kalman channel (`fitted.taps`), and `report.md` with the validation figures
//! per condition, the bank's envelope and the standard case on held-out seeds.
//!
//! The files are written into `dir` as they are made; the caller stages `dir` and moves it into
//! place only when everything is there ([`crate::cli::fit`]).

use super::calibration::{FIGURE, calibration};
use crate::Error;
use crate::study::cases::{self, Case};
use crate::study::learned::taps::{Options, fit_each};
use crate::study::runs::Fmus;
use fmu_estimator::learned::bank::Bank;
use orchestrator::system::Value;
use std::path::Path;

/// The calibration file in the directory.
pub const CALIBRATION: &str = "fitted-calibration.toml";
/// The tap bank in the directory.
pub const TAPS: &str = "fitted.taps";
/// The report in the directory.
pub const REPORT: &str = "report.md";
/// Every file a fit writes.
pub const FILES: [&str; 4] = [CALIBRATION, TAPS, REPORT, FIGURE];

/// What a fit needs beyond the FMUs.
#[derive(Debug, Clone)]
pub struct FitOptions {
    /// The tap bank's options; its `calibration` is set by the fit.
    pub taps: Options,
    /// Held-out track seeds of the standard case in the report (neither the training seed
    /// nor a validation seed).
    pub evaluation_seeds: Vec<u32>,
    /// Where the directory will be, for the commands the report shows.
    pub final_dir: std::path::PathBuf,
}

/// Fits the vehicle of `fmus` into `dir` (which exists and is empty); `log` gets the stages'
/// lines, `done` the share of the work finished (0-1) as it grows. Returns the report's text.
pub fn fit(
    fmus: &Fmus,
    o: &FitOptions,
    dir: &Path,
    log: &dyn Fn(&str),
    done: &(dyn Fn(f64) + Sync),
) -> Result<String, Error> {
    let started = std::time::Instant::now();
    let seeds = &o.evaluation_seeds;
    if let Some(s) = seeds
        .iter()
        .find(|s| **s == o.taps.training_seed || o.taps.validation_seeds.contains(s))
    {
        return Err(Error::Input(format!(
            "evaluation seed {s} is the training seed or a validation seed: the report's figures must be on held-out tracks"
        )));
    }
    // Shares of the work: the calibration (about 1 %), each speed by its simulated time, the
    // evaluation (four estimators on the standard case).
    let costs: Vec<f64> = o
        .taps
        .speeds
        .iter()
        .map(|v| {
            crate::study::learned::taps::speed_cost(&o.taps, *v)
                * (o.taps.kalker_scales.len() * o.taps.conicities.len().max(1)) as f64
        })
        .collect();
    let evaluation = 4.0 * seeds.len() as f64 * 20.0;
    let total = costs.iter().sum::<f64>() * 1.01 + evaluation;
    // 1. The simplified model and its noise.
    let calibration_file = dir.join(CALIBRATION);
    let cal_lines = std::cell::RefCell::new(vec![]);
    let cal = calibration(
        fmus,
        o.taps.training_seed,
        calibration_file.clone(),
        dir,
        &|l| {
            log(l);
            cal_lines.borrow_mut().push(l.to_string());
        },
    )?;
    for (path, bytes) in &cal.files {
        write(path, bytes)?;
    }
    let mut done_cost = costs.iter().sum::<f64>() * 0.01;
    done(done_cost / total);

    // 2. The tap bank on that calibration's Kalman channel.
    let mut taps = o.taps.clone();
    taps.calibration = Some(calibration_file.clone());
    let so_far = std::cell::Cell::new(done_cost);
    let bank = fit_each(fmus, &taps, log, &|v| {
        let i = taps.speeds.iter().position(|s| *s == v).unwrap_or(0);
        so_far.set(so_far.get() + costs[i]);
        done(so_far.get() / total);
    })?;
    done_cost = so_far.get();
    let taps_file = dir.join(TAPS);
    write(&taps_file, &bank.to_bytes())?;

    // 3. The standard case on held-out seeds, four ways.
    let results = evaluate(fmus, &calibration_file, &taps_file, seeds, &|| {})?;
    done((done_cost + evaluation) / total);

    let name = fmus
        .vehicle_params()
        .map(|p| p.name)
        .unwrap_or_else(|_| "the vehicle FMU's".into());
    let final_dir = &o.final_dir;
    let mut md = format!(
        "# Estimator fit for {name}\n\nMade by `{}` in {:.0} s: the vehicle FMU {}{}.\n",
        o.taps.command,
        started.elapsed().as_secs_f64(),
        fmus.vehicle.display(),
        settings_text(&fmus.vehicle_settings)
    );
    md.push_str(&format!(
        "\n## Use\n\n```\norchestrator run standard.ssd --set estimator.tap_file={0}/{TAPS} --set estimator.calibration_file={0}/{CALIBRATION}\n```\n\nThe estimator takes the model parameters from `{CALIBRATION}` where they are left at their defaults. In fmpy, the same two start values.\n",
        final_dir.display()
    ));
    md.push_str(&format!(
        "\n## Calibration (track seed {})\n\n",
        o.taps.training_seed
    ));
    for l in cal_lines.borrow().iter() {
        if !l.starts_with("wrote") {
            md.push_str(&format!("- {l}\n"));
        }
    }
    md.push_str(&format!("\n![the identification's fit]({FIGURE})\n"));
    md.push_str(&bank_text(&bank, &taps));
    md.push_str(&format!(
        "\n## The standard case on held-out seeds\n\n{}",
        cases::markdown("Standard case (20 s at 20 m/s)", &results)
    ));
    write(&dir.join(REPORT), md.as_bytes())?;
    Ok(md)
}

/// The standard case on `seeds` with the shipped default, the paper's filter with the fitted
/// calibration, and the learned filter with the fitted bank and calibration, told nothing (the
/// contact read from the sensors as the record goes) and told the nominal contact
/// (`kalker_scale` 1: the 400 m record's first 200 m are then not spent reading it).
pub fn evaluate(
    fmus: &Fmus,
    calibration: &Path,
    taps: &Path,
    seeds: &[u32],
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<cases::CaseResult>, Error> {
    let path = |p: &Path| -> Result<Value, Error> {
        Ok(Value::String(
            std::path::absolute(p)
                .map_err(|e| Error::Io(format!("{}: {e}", p.display())))?
                .to_string_lossy()
                .into_owned(),
        ))
    };
    let case = |name: &str, estimator: Vec<(String, Value)>| Case {
        name: name.into(),
        vehicle: vec![],
        estimator,
        paper: None,
    };
    let fitted_calibration = ("calibration_file".to_string(), path(calibration)?);
    let fitted = vec![
        ("estimator".into(), Value::Integer(2)),
        fitted_calibration.clone(),
        ("tap_file".into(), path(taps)?),
    ];
    let mut told = fitted.clone();
    told.push(("kalker_scale".into(), Value::Real(1.0)));
    let all = [
        case(
            "shipped default (learned.taps, built-in calibration)",
            vec![("estimator".into(), Value::Integer(2))],
        ),
        case(
            "paper's filter, fitted calibration",
            vec![("estimator".into(), Value::Integer(1)), fitted_calibration],
        ),
        case(
            "learned filter, fitted bank and calibration, told nothing",
            fitted,
        ),
        case(
            "learned filter, fitted bank and calibration, told kalker_scale = 1",
            told,
        ),
    ];
    cases::run_cases(fmus, &all, seeds, progress)
}

/// The user's vehicle settings, for the report's first line.
fn settings_text(settings: &[(String, Value)]) -> String {
    if settings.is_empty() {
        return String::new();
    }
    let s: Vec<String> = settings.iter().map(|(n, v)| format!("{n} = {v}")).collect();
    format!(" with {}", s.join(", "))
}

/// The bank's part of the report: conditions and envelope, the contact model's errors, and
/// each entry's validation figures.
fn bank_text(bank: &Bank, o: &Options) -> String {
    let mut md = String::from("\n## Tap bank\n\n");
    let conicities = if o.conicities.is_empty() {
        "the vehicle's own".to_string()
    } else {
        format!("{:?}", o.conicities)
    };
    md.push_str(&format!(
        "Speeds {:?} m/s; Kalker scales {:?}; conicities {conicities}; training seed {}, validation seeds {:?}.\n\n",
        o.speeds, o.kalker_scales, o.training_seed, o.validation_seeds
    ));
    // The envelope: the conditions trained at each speed (the others were unstable there).
    md.push_str("| speed (m/s) | conditions trained | left out (unstable) |\n|---|---|---|\n");
    for v in &o.speeds {
        let mut trained: Vec<(Option<f64>, Option<f64>)> = bank
            .entries
            .iter()
            .filter(|e| {
                e.speed == *v && e.lag == 0 && !e.channels.iter().any(|c| c == "ws_roll_rate")
            })
            .map(|e| (e.conicity, e.condition))
            .collect();
        trained.dedup();
        let label = |(c, k): &(Option<f64>, Option<f64>)| {
            let mut s = k
                .map(|k| format!("Kalker {} %", k * 100.0))
                .unwrap_or_else(|| "pooled".into());
            if let Some(c) = c {
                s.push_str(&format!(" at {c}"));
            }
            s
        };
        let wanted: Vec<(Option<f64>, Option<f64>)> = if o.conicities.is_empty() {
            o.kalker_scales.iter().map(|k| (None, Some(*k))).collect()
        } else {
            o.conicities
                .iter()
                .flat_map(|c| o.kalker_scales.iter().map(move |k| (Some(*c), Some(*k))))
                .collect()
        };
        let single = o.kalker_scales.len() == 1 && o.conicities.len() <= 1;
        let left: Vec<String> = if single && trained.is_empty() {
            vec!["all".into()]
        } else if single {
            vec![]
        } else {
            wanted
                .iter()
                .filter(|w| !trained.contains(w))
                .map(label)
                .collect()
        };
        md.push_str(&format!(
            "| {v} | {} | {} |\n",
            trained.len(),
            if left.is_empty() {
                "none".into()
            } else {
                left.join(", ")
            }
        ));
    }
    if let Some(c) = &bank.contact {
        md.push_str("\nContact model, rms error on the validation runs:\n\n| speed (m/s) | Kalker scale | ln(conicity) |\n|---|---|---|\n");
        for m in &c.speeds {
            md.push_str(&format!(
                "| {} | {:.3} | {} |\n",
                m.speed,
                m.rms_error,
                m.conicity
                    .as_ref()
                    .map(|c| format!("{:.3}", c.rms_error))
                    .unwrap_or_else(|| "-".into())
            ));
        }
    }
    md.push_str("\nEntries (validation objective: the plain sum of Jrel^2 over whole, D1, D2, D3 on the validation runs, estimated from their start; rms error of the full window):\n\n| speed (m/s) | condition | sensors | lag (m) | ridge | band weights | validation objective | rms error (mm) |\n|---|---|---|---|---|---|---|---|\n");
    for e in &bank.entries {
        let w = e.windows.last().expect("full window");
        let mut condition = e
            .condition
            .map(|c| format!("Kalker {} %", c * 100.0))
            .unwrap_or_else(|| "pooled".into());
        if let Some(c) = e.conicity {
            condition.push_str(&format!(", conicity {c}"));
        }
        md.push_str(&format!(
            "| {} | {condition} | {} | {} | {:.0e} | {:?} | {:.4} | {:.3} |\n",
            e.speed,
            e.channels.len() - 1,
            e.lag as f64 * bank.grid,
            e.ridge,
            e.band_weights.unwrap_or([1.0; 4]),
            e.validation_objective,
            w.rms_error * 1e3
        ));
    }
    md
}

/// Writes a file of the staged directory.
fn write(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    std::fs::write(path, bytes)
        .map_err(|e| Error::Io(format!("cannot write {}: {e}", path.display())))
}

/// Fits a bank from recorded passes into `dir` ([`crate::study::learned::recorded`]): the bank
/// and `report.md` (the passes' placements, the speeds covered, the entries' validation
/// figures). Returns the report's text.
pub fn from_recordings(
    fmus: &Fmus,
    o: &Options,
    passes: &[crate::study::learned::recorded::Pass],
    reference: &crate::study::learned::recorded::Reference,
    validation_share: f64,
    (dir, final_dir): (&Path, &Path),
    log: &dyn Fn(&str),
) -> Result<String, Error> {
    let started = std::time::Instant::now();
    let fitted =
        crate::study::learned::recorded::fit(fmus, o, passes, reference, validation_share, log)?;
    write(&dir.join(TAPS), &fitted.bank.to_bytes())?;
    let mut md = format!(
        "# Estimator fit from recordings\n\nMade by `{}` in {:.0} s: {} passes against a reference of {:.0}-{:.0} m; validation from {:.0} m on.\n",
        o.command,
        started.elapsed().as_secs_f64(),
        passes.len(),
        reference.distance[0],
        reference.distance[reference.distance.len() - 1],
        fitted.cut
    );
    md.push_str(&format!(
        "\n## Use\n\n```\norchestrator run standard.ssd --set estimator.tap_file={}/{TAPS}{}\n```\n",
        final_dir.display(),
        o.calibration
            .as_ref()
            .map(|c| format!(" --set estimator.calibration_file={}", c.display()))
            .unwrap_or_default()
    ));
    md.push_str("\n## Passes\n\nReference position = the pass's first `distance` + offset + scale x odometry (the pass's integrated speed from its first sample), found by correlating the shipped default's estimate with the reference (3-200 m).\n\n| pass | offset (m) | scale - 1 (%) | correlation | mean speed (m/s) | trains (m/s) |\n|---|---|---|---|---|---|\n");
    for (file, at, v, bank) in &fitted.passes {
        md.push_str(&format!(
            "| {} | {:+.2} | {:+.3} | {:.3} | {v:.1} | {bank} |\n",
            file.display(),
            at.offset,
            (at.scale - 1.0) * 100.0,
            at.correlation
        ));
    }
    let mut speeds: Vec<f64> = fitted.bank.entries.iter().map(|e| e.speed).collect();
    speeds.dedup();
    md.push_str(&format!(
        "\nBank speeds {speeds:?} m/s, the recordings' own contact and wheels, three sensors. Outside {:?}-{:?} m/s the estimator falls back to the paper's filter; between them it blends.\n",
        speeds.first().copied().unwrap_or(0.0),
        speeds.last().copied().unwrap_or(0.0)
    ));
    md.push_str("\n| speed (m/s) | lag (m) | ridge | band weights | validation objective | rms error (mm) |\n|---|---|---|---|---|---|\n");
    for e in &fitted.bank.entries {
        let w = e.windows.last().expect("full window");
        md.push_str(&format!(
            "| {} | {} | {:.0e} | {:?} | {:.4} | {:.3} |\n",
            e.speed,
            e.lag as f64 * fitted.bank.grid,
            e.ridge,
            e.band_weights.unwrap_or([1.0; 4]),
            e.validation_objective,
            w.rms_error * 1e3
        ));
    }
    write(&dir.join(REPORT), md.as_bytes())?;
    Ok(md)
}
