//! The learned filters' fits: the FIR smoother for `smooth --learned` (`alignment-studies
//! learn`) and the estimator FMU's tap bank (`alignment-studies taps`); each report's file is
//! what was fitted.

use super::Report;
use crate::Error;
use crate::study::learned::taps::{Options, fit};
use crate::study::runs::Fmus;
use std::path::Path;

/// What `learn` fits: the training runs and the filter's form.
#[derive(Debug, Clone)]
pub struct LearnOptions {
    /// Track seed of the training run.
    pub seed: u32,
    /// Length of the training run \[s\], more than 40.
    pub stop: f64,
    /// Look-ahead \[m\] of an on-board filter combined with the paper's causal filter (0:
    /// causal); `None`: the offline smoother with the shaping filter's RTS smoother.
    pub lag: Option<f64>,
    /// Grid step along the track \[m\] the sensors are decimated to.
    pub grid: f64,
    /// Kalker-coefficient scales of the vehicle to train on, one run each.
    pub kalker_scales: Vec<f64>,
    /// Constant speed of the training runs [m/s] (`None`: the vehicle's, 20).
    pub speed: Option<f64>,
}

/// Fits the learned FIR estimator on runs of the vehicle FMU; the report's file is the filter
/// (JSON) for `smooth --learned`, written to `out`.
pub fn learn(fmus: &Fmus, a: &LearnOptions, out: &Path) -> Result<Report, Error> {
    use crate::study::learned::{
        Lookahead, SMOOTHER_WINDOW, decimation, default_partner, learn, training_runs, validation,
    };
    use crate::study::runs::{STEP, STOP};
    use crate::study::variants;
    let grid = a.grid;
    // The grid the filter will have (a whole number of samples), checked before the runs.
    let speed = a.speed.unwrap_or(20.0);
    let grid = STEP
        * speed
        * decimation(speed, grid).map_err(|e| Error::Input(format!("--grid: {e}")))? as f64;
    let lookahead = match a.lag {
        None => Lookahead::Smoother,
        Some(m) if (0.0..=SMOOTHER_WINDOW).contains(&m) => {
            Lookahead::FixedLag((m / grid).round() as usize)
        }
        Some(m) => {
            return Err(Error::Input(format!(
                "--lag must be between 0 and {SMOOTHER_WINDOW} m (the window), not {m}"
            )));
        }
    };
    let (runs, provenance) = training_runs(fmus, a.seed, a.stop, &a.kalker_scales, a.speed)?;
    // The shaping filter's virtual-measurement sigma, chosen as the study does, on the first
    // 20 s of the (first) training run.
    let (sigma, _) = variants::tune_prior_sigma(&validation(&runs[0]), 3, &[], None)?;
    let (l, j) = learn(
        &runs,
        &provenance,
        lookahead,
        grid,
        default_partner(lookahead, sigma),
    )?;
    let ahead = match l.lookahead {
        Lookahead::Smoother => format!("smoother, {SMOOTHER_WINDOW} m each way"),
        Lookahead::FixedLag(n) => format!("look-ahead {} m", n as f64 * l.grid()),
    };
    let markdown = format!(
        "learned FIR ({ahead}, grid {} m) at {} m/s: {}; split {} m with {} (whole Jrel on the first {} s: {j:.3}); wrote {}",
        l.grid(),
        l.speed,
        l.provenance,
        l.split,
        l.partner.name,
        STOP,
        out.display()
    );
    let mut report = Report {
        markdown,
        ..Report::default()
    };
    report.file(out.to_path_buf(), l.to_json());
    Ok(report)
}

/// Fits the estimator FMU's tap bank with options `o` (method: [`crate::study::learned::taps`]);
/// the report's file is the bank, for `out`, its Markdown the contact model's error per speed
/// and each entry's ridge and validation figures. `log` gets the fit's progress.
pub fn taps(fmus: &Fmus, o: &Options, out: &Path, log: &dyn Fn(&str)) -> Result<Report, Error> {
    let started = std::time::Instant::now();
    let bank = fit(fmus, o, log)?;
    let mut lines = vec![];
    for m in bank.contact.iter().flat_map(|c| &c.speeds) {
        lines.push(format!(
            "{:>5} m/s contact model: rms error of the Kalker scale on its validation runs {:.3}",
            m.speed, m.rms_error
        ));
        if let Some(c) = &m.conicity {
            lines.push(format!(
                "{:>5} m/s conicity model: rms error of ln(conicity) on its validation runs {:.3}; novelty level (squared distance) {:.1}",
                m.speed, c.rms_error, c.level
            ));
        }
    }
    for e in &bank.entries {
        let w = e.windows.last().expect("full window");
        let condition = e
            .condition
            .map(|c| format!("Kalker {:>3} %", c * 100.0))
            .unwrap_or_default();
        lines.push(format!(
            "{:>5} m/s {condition} {:<48} lag {:>4} m: ridge {:.0e}, band weights {:?}, validation objective {:.4}, rms error {:.3} mm",
            e.speed,
            e.channels.join(","),
            e.lag as f64 * bank.grid,
            e.ridge,
            e.band_weights.unwrap_or([1.0; 4]),
            e.validation_objective,
            w.rms_error * 1e3
        ));
    }
    let mut report = Report {
        markdown: lines.join("\n"),
        note: format!(
            "tap bank in {:.1} s; wrote {}",
            started.elapsed().as_secs_f64(),
            out.display()
        ),
        ..Report::default()
    };
    report.file(out.to_path_buf(), bank.to_bytes());
    Ok(report)
}
