//! Beyond the paper: the estimator FMU's estimators and the filter's options (priors,
//! steady-state gain, RTS smoother, speed following, learned FIR) against the paper's filter,
//! each seed recorded once through the vehicle FMU and processed offline
//! (`alignment-studies variants`): `variants.md` and `variants.json`.

use super::{Evaluation, Report};
use crate::Error;
use crate::study::runs::Fmus;
use crate::study::variants;
use std::path::Path;

/// The files [`variants()`] writes into its directory: what the output policy checks before the
/// work ([`super::written`]).
pub const OUTPUTS: [&str; 2] = ["variants.md", "variants.json"];

/// Runs the comparison on the evaluation's seeds, the choices made on its calibration seed, and
/// builds the report for the directory `out`; `log` gets those choices as they are made. The
/// estimator runs offline with its shipped calibration, so `fmus` carries no settings.
pub fn variants(
    fmus: &Fmus,
    evaluation: &Evaluation,
    out: &Path,
    log: &dyn Fn(&str),
) -> Result<Report, Error> {
    evaluation.held_out()?;
    let a = evaluation;
    let started = std::time::Instant::now();
    use variants::Conditions;
    let calibration = variants::record_seeds(fmus, &[a.calibration_seed], Conditions::Standard)?;
    let (irw, irw_j) = variants::tune_prior_sigma(&calibration[0], 2, &[], None)?;
    let (shaping, shaping_j) = variants::tune_prior_sigma(&calibration[0], 3, &[], None)?;
    log(&format!(
        "prior_sigma_xi chosen on the calibration seed {}: integrated random walk {irw} m (whole Jrel there {irw_j:.3}), shaping filter {shaping} m ({shaping_j:.3})",
        a.calibration_seed
    ));
    let tuned = variants::Tuned {
        irw_sigma_xi: irw,
        shaping_sigma_xi: shaping,
    };
    use crate::study::learned::{
        Lookahead, SMOOTHER_GRID, default_partner, kalker_label, learn, provenance, training_runs,
    };
    let compared = variants::variants(&tuned);
    // The learned filters, each with its Kalman partner (the shaping filter's RTS smoother
    // offline, the paper's causal filter on board), fitted on the calibration seed: on the
    // vehicle as it is, and on it and the same with its Kalker coefficients halved (robust).
    let (runs, _) = training_runs(
        fmus,
        a.calibration_seed,
        variants::LEARNING_STOP,
        &[1.0, 0.5],
        None,
    )?;
    let mut learned = vec![];
    for scales in [&[1.0][..], &[1.0, 0.5][..]] {
        let from = provenance(fmus, a.calibration_seed, variants::LEARNING_STOP, scales);
        let trained = format!(
            "fitted on the calibration seed, Kalker {} %",
            kalker_label(scales)
        );
        let forms = [
            (Lookahead::Smoother, SMOOTHER_GRID),
            (Lookahead::FixedLag(variants::LAG), SMOOTHER_GRID),
        ];
        // On the nominal vehicle only, the causal form and the shortest look-ahead, on a finer
        // grid (their anti-alias filter's delay is a fraction of a metre): what a causal linear
        // estimator of the three sensors reaches (docs/learned-filter.md).
        let near_causal =
            variants::NEAR_CAUSAL.map(|lag| (Lookahead::FixedLag(lag), variants::FINE_GRID));
        let extra = if scales.len() == 1 {
            &near_causal[..]
        } else {
            &[]
        };
        for &(lookahead, grid) in forms.iter().chain(extra) {
            let partner = default_partner(lookahead, shaping);
            let (l, j) = learn(&runs[..scales.len()], &from, lookahead, grid, partner)?;
            log(&format!(
                "learned FIR ({lookahead:?}) from {from}: split {} m (mean whole Jrel there {j:.3}) with {}",
                l.split, l.partner.name
            ));
            learned.push((l, trained.clone()));
        }
    }
    let with_learned =
        |records: &[variants::Record]| -> Result<Vec<variants::VariantResult>, Error> {
            let mut out = variants::compare(records, &compared)?;
            for (l, trained) in &learned {
                out.extend(variants::compare_learned(records, l, trained)?);
            }
            Ok(out)
        };
    let constant = variants::record_seeds(fmus, &a.seeds, Conditions::Standard)?;
    let at_constant = with_learned(&constant)?;
    let flat = variants::record_seeds(fmus, &a.seeds, Conditions::NoVertical)?;
    let at_flat = with_learned(&flat)?;
    let kalker = variants::record_seeds(fmus, &a.seeds, Conditions::KalkerHalf)?;
    let at_kalker = with_learned(&kalker)?;
    let variable = variants::record_seeds(fmus, &a.seeds, Conditions::VariableSpeed)?;
    let at_variable = variants::compare(&variable, &variants::speed_variants(&tuned))?;
    // The estimator FMU's learned filter (its default) against the paper's filter, as the FMU
    // computes them (the built-in tap bank), under the conditions the taps must hold in.
    let three_quarters = variants::record_seeds(fmus, &a.seeds, Conditions::KalkerThreeQuarters)?;
    let fmu_rows = variants::learned_variants();
    // The variable-speed profile's references: constant speeds over its distance (the sensors
    // see less of the track at lower speed, so the profile's figure lies among these).
    let mut at_speeds = vec![];
    for v in [10, 15, 20] {
        let records = variants::record_seeds(fmus, &a.seeds, Conditions::ConstantSpeed(v))?;
        for mut r in variants::compare(&records, &fmu_rows[..3])? {
            r.name = format!("{}, {v} m/s", r.name);
            at_speeds.push(r);
        }
    }
    let fmu_tables: Vec<(&str, &str, Vec<variants::VariantResult>)> = vec![
        (
            "standard",
            "Standard case (20 m/s, 20 s)",
            variants::compare(&constant, &fmu_rows)?,
        ),
        (
            "kalker_75",
            "Kalker coefficients at 75 % in the vehicle (between the taps' training conditions)",
            variants::compare(&three_quarters, &fmu_rows)?,
        ),
        (
            "kalker_50",
            "Kalker coefficients at 50 % in the vehicle",
            variants::compare(&kalker, &fmu_rows)?,
        ),
        (
            "variable_speed",
            "Variable speed (0 -> 20 -> 10 m/s, 50 s; the learned filter blends its taps by speed, below 5 m/s the paper's filter)",
            variants::compare(&variable, &fmu_rows)?,
        ),
        (
            "constant_speed_640m",
            "Constant speeds over the variable-speed profile's 640 m (its references)",
            at_speeds,
        ),
    ];
    let mut md = String::from(
        "# Beyond the paper: estimator variants\n\n## The estimator FMU: learned filter (default) and the paper's filter\n\n",
    );
    for (_, title, rows) in &fmu_tables {
        md.push_str(&variants::markdown(title, &a.seeds, rows));
        md.push('\n');
    }
    md.push_str("## Options of the Kalman filter and the earlier learned FIR\n\n");
    for (title, rows) in [
        ("Standard case (20 m/s, 20 s)", &at_constant),
        (
            "Standard case without vertical irregularities (vertical profile and cross-level off)",
            &at_flat,
        ),
        (
            "Kalker coefficients -50 % in the vehicle (robustness: calibration and taps unchanged)",
            &at_kalker,
        ),
        ("Variable speed (0 -> 20 -> 10 m/s, 50 s)", &at_variable),
    ] {
        md.push_str(&variants::markdown(title, &a.seeds, rows));
        md.push('\n');
    }
    md.pop();
    let json = serde_json::json!({
        "calibration_seed": a.calibration_seed,
        "seeds": a.seeds,
        "tuned": tuned,
        "constant_speed": at_constant,
        "no_vertical_irregularity": at_flat,
        "kalker_half": at_kalker,
        "variable_speed": at_variable,
        "estimator_fmu": fmu_tables.iter().map(|(k, _, r)| (k.to_string(), serde_json::to_value(r).unwrap_or_default())).collect::<serde_json::Map<_, _>>(),
    });
    let mut report = Report {
        markdown: md.clone(),
        note: format!(
            "variants in {:.1} s; written to {}",
            started.elapsed().as_secs_f64(),
            out.join("variants.md").display()
        ),
        ..Report::default()
    };
    report.file(out.join(OUTPUTS[0]), md);
    let json = serde_json::to_string_pretty(&json).unwrap_or_default();
    report.file(out.join(OUTPUTS[1]), json);
    Ok(report)
}
