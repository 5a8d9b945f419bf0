//! The demo's second table: the standard curved case from `alignment-studies all`'s
//! `curves.json` (one object per held-out seed, `studies/src/study/curves.rs` `CurveRun`):
//! the default and the paper's filter told the design, the default on the same irregularities
//! on straight track (the oracle of what it should reach), told the design fitted from the
//! sensors, and told nothing.

use crate::headline::{BANDS, TABLE_HEAD, row};
use anyhow::{Context, Result};
use serde_json::Value;

/// The rows: label, the run's field, the index in its `[paper's filter, default]` pair (`None`:
/// the field is one run's metrics).
const ROWS: [(&str, &str, Option<usize>); 5] = [
    (
        "learned filter (default), told the design",
        "known",
        Some(1),
    ),
    ("paper's filter, told the design", "known", Some(0)),
    (
        "learned filter, the same irregularities on straight track",
        "straight",
        Some(1),
    ),
    (
        "learned filter, told the design fitted from the sensors",
        "fitted",
        Some(1),
    ),
    ("learned filter, told nothing", "untold", None),
];

/// The table from the parsed `curves.json`.
pub fn curves(v: &Value) -> Result<String> {
    let runs = v.as_array().context("not a list of runs")?;
    anyhow::ensure!(!runs.is_empty(), "no runs");
    let seeds: Vec<u64> = runs
        .iter()
        .map(|r| r["seed"].as_u64())
        .collect::<Option<_>>()
        .context("a run without a seed")?;
    let mut text = format!(
        "\nOn the standard curved case (studies/curved.ssd: 2.1 km of line with curves of radius \
         400-1500 m, transitions of 40-100 m and cant up to 120 mm, at 18 m/s), design known \
         from design_curvature and design_cant (or line_file), mean Jrel over the held-out track \
         seeds {}:\n\n",
        crate::headline::seed_list(&seeds)
    );
    text += TABLE_HEAD;
    for (label, field, index) in ROWS {
        let mut sum = [0.0; 4];
        for run in runs {
            let metrics = match index {
                Some(i) => &run[field][i],
                None => &run[field],
            };
            for (slot, band) in sum.iter_mut().zip(BANDS) {
                *slot += metrics[band]["Jrel"]
                    .as_f64()
                    .with_context(|| format!("no {field} {band} Jrel for seed {}", run["seed"]))?;
            }
        }
        let cells = sum.map(|s| format!("{:.3}", s / runs.len() as f64));
        text += &row(label, &cells);
    }
    text += "\nDesign not known: fitted from the whole record (track_alignment.fit_design, \
             offline); D3 is lost to its transitions' ends. Told nothing, the curves swamp \
             the estimate; where the vehicle runs against its \
             flanges the estimate is not usable either, and outside_training says so \
             (docs/accuracy.md, \"Curves\").\n";
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// One band set whose figures start with `x` (whole `x`, D1 `x + 0.001`, ...).
    fn metrics(x: f64) -> Value {
        json!({
            "whole": {"Jrel": x, "J_mm": 0.0, "truth_rms_mm": 1.0},
            "D1": {"Jrel": x + 0.001, "J_mm": 0.0, "truth_rms_mm": 1.0},
            "D2": {"Jrel": x + 0.002, "J_mm": 0.0, "truth_rms_mm": 1.0},
            "D3": {"Jrel": x + 0.003, "J_mm": 0.0, "truth_rms_mm": 1.0},
        })
    }

    fn run(seed: u64, shift: f64) -> Value {
        json!({
            "seed": seed,
            "straight": [metrics(0.5 + shift), metrics(0.1 + shift)],
            "known": [metrics(0.6 + shift), metrics(0.2 + shift)],
            "untold": metrics(50.0 + shift),
            "fitted": [metrics(1.1 + shift), metrics(1.2 + shift)],
            "wide": [0.1, 0.1],
        })
    }

    #[test]
    fn rows_are_the_means_over_the_seeds_of_the_right_fields() {
        let text = curves(&json!([run(1, 0.0), run(2, 0.02)])).unwrap();
        assert!(text.contains("seeds 1-2"), "{text}");
        for line in [
            "| learned filter (default), told the design | 0.210 | 0.211 | 0.212 | 0.213 |",
            "| paper's filter, told the design | 0.610 | 0.611 | 0.612 | 0.613 |",
            "| learned filter, the same irregularities on straight track | 0.110 | 0.111 | 0.112 | 0.113 |",
            "| learned filter, told the design fitted from the sensors | 1.210 | 1.211 | 1.212 | 1.213 |",
            "| learned filter, told nothing | 50.010 | 50.011 | 50.012 | 50.013 |",
        ] {
            assert!(text.contains(line), "{line} not in\n{text}");
        }
    }

    #[test]
    fn a_missing_figure_is_named() {
        let mut bad = run(3, 0.0);
        bad["known"][1]["D2"] = json!({});
        let e = curves(&json!([bad])).unwrap_err().to_string();
        assert!(e.contains("known D2") && e.contains('3'), "{e}");
        assert!(curves(&json!([])).is_err());
    }
}
