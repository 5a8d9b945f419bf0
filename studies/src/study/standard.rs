//! The standard case's evaluation: from the results of a run of the standard system
//! (vehicle -> estimator), the accuracy in each band, written as `metrics.json` and printed
//! beside the paper's Table (docs/references.md section 1).

use super::metrics::{BANDS, BandMetrics, evaluate};
use crate::Error;
use orchestrator::master::Table;

/// The paper's standard case, J \[mm\] / Jrel per band (its Tables 3 and 4).
pub const PAPER_STANDARD: [(&str, f64, f64); 4] = [
    ("whole", 0.36, 0.25),
    ("D1", 0.21, 0.48),
    ("D2", 0.22, 0.26),
    ("D3", 0.18, 0.15),
];

/// Grid step and trim of the evaluation (see `metrics`).
pub const DS: f64 = 0.05;
/// Metres dropped at each end after the band-pass \[m\] (see `metrics`).
pub const TRIM: f64 = 10.0;

/// The band metrics of a standard-case run: the estimator's alignment (against its own
/// distance) and the vehicle's true alignment (against the vehicle's distance). The first row
/// (t = start, before any step) is left out.
pub fn evaluate_results(cols: &Table) -> Result<BandMetrics, Error> {
    let skip = |x: &[f64]| x[1.min(x.len())..].to_vec();
    let require = |name: &str| cols.require(name).map_err(Error::Input);
    Ok(evaluate(
        &skip(require("estimator.distance")?),
        &skip(require("estimator.alignment")?),
        &skip(require("vehicle.distance")?),
        &skip(require("vehicle.alignment")?),
        DS,
        TRIM,
    )?)
}

/// The band metrics of the estimator's fixed-lag output (`alignment_lagged` against
/// `distance_lagged`), when the results hold it and the estimator made one (`lag` > 0).
pub fn evaluate_lagged(cols: &Table) -> Option<Result<BandMetrics, Error>> {
    let skip = |x: &[f64]| x[1.min(x.len())..].to_vec();
    let (d, a) = (
        cols.column("estimator.distance_lagged")?,
        cols.column("estimator.alignment_lagged")?,
    );
    let dist = cols.column("estimator.distance")?;
    // distance_lagged == distance: no lagged output (lag 0 or estimator 1).
    if d.iter().zip(dist).all(|(a, b)| a == b) {
        return None;
    }
    let require = |name: &str| cols.require(name).map_err(Error::Input);
    Some((|| {
        Ok(evaluate(
            &skip(d),
            &skip(a),
            &skip(require("vehicle.distance")?),
            &skip(require("vehicle.alignment")?),
            DS,
            TRIM,
        )?)
    })())
}

/// `{"bands": {"whole": {"J_mm": .., "Jrel": .., "truth_rms_mm": ..}, "D1": .., ...},
/// "lagged": {"bands": ..} (when present)}`.
pub fn metrics_json(m: &BandMetrics, lagged: Option<&BandMetrics>) -> String {
    let mut value = serde_json::json!({ "bands": m, "method": {
        "grid_step_m": DS, "trim_m": TRIM, "filter": "Butterworth band-pass, order 4 per edge, zero phase (sosfiltfilt)",
    }});
    if let Some(l) = lagged {
        value["lagged"] =
            serde_json::json!({ "bands": l, "output": "alignment_lagged at distance_lagged" });
    }
    serde_json::to_string_pretty(&value).unwrap_or_default()
}

/// Our figures beside the paper's, one band per line.
pub fn table(m: &BandMetrics) -> String {
    let mut s = format!(
        "  {:<7} {:>22}   {:>16}\n",
        "band", "ours J [mm] / Jrel", "paper J / Jrel"
    );
    for (b, (name, pj, pr)) in BANDS.iter().zip(PAPER_STANDARD) {
        debug_assert_eq!(b.name, name);
        let a = m.get(name).expect("all four bands");
        s.push_str(&format!(
            "  {:<7} {:>12.3} / {:>6.3}   {:>9.2} / {:>4.2}\n",
            name, a.j_mm, a.jrel, pj, pr
        ));
    }
    s
}
