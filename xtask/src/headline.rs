//! The demo's headline: four rows from `alignment-studies variants`' JSON (the estimator FMU's
//! table for the standard case) under a line saying for which vehicle and wheel state they
//! hold, and one sentence on the nominal-only taps.
//!
//! Rows are picked by their stable keys, the FMU settings and the output judged
//! (`output: "Lagged"` for `alignment_lagged`, absent for `alignment`), not by position or
//! name: the studies' table has more rows and its names are prose.

use anyhow::{Context, Result, bail};
use serde_json::Value;

/// The paper's Jrel for the standard case, whole / D1 / D2 / D3 (its results table).
const PAPER: [f64; 4] = [0.25, 0.48, 0.26, 0.15];

/// The bands, in the table's order, as the JSON names them.
pub(crate) const BANDS: [&str; 4] = ["whole", "D1", "D2", "D3"];

/// One row of the estimator FMU's tables: its label here, its settings and whether it is
/// judged on `alignment_lagged`.
struct Key {
    label: &'static str,
    settings: &'static [(&'static str, &'static str)],
    lagged: bool,
}

const DEFAULT: Key = Key {
    label: "learned filter, causal, contact-blended (default)",
    settings: &[("estimator", "2"), ("use_roll_rate", "false")],
    lagged: false,
};
const LAGGED: Key = Key {
    label: "learned, fixed lag 10 m (`alignment_lagged`)",
    settings: &[("estimator", "2"), ("use_roll_rate", "false")],
    lagged: true,
};
const PAPERS_FILTER: Key = Key {
    label: "paper's filter on our vehicle (`estimator = 1`)",
    settings: &[("estimator", "1")],
    lagged: false,
};
const NOMINAL: Key = Key {
    label: "nominal-only taps",
    settings: &[("estimator", "2"), ("tap_file", "learned-nominal.taps")],
    lagged: false,
};

/// The headline from the parsed `variants.json`: the facts the figures hold for, the table,
/// the sentence on the nominal-only taps.
pub fn headline(v: &Value) -> Result<String> {
    let seeds: Vec<u64> = v["seeds"]
        .as_array()
        .context("no \"seeds\"")?
        .iter()
        .map(|s| s.as_u64().context("a seed is not a number"))
        .collect::<Result<_>>()?;
    let table = |condition: &str| {
        v["estimator_fmu"][condition]
            .as_array()
            .with_context(|| format!("no estimator_fmu.{condition} table"))
    };
    let standard = table("standard")?;
    let mut text = format!(
        "\nAlignment accuracy on our vehicle FMU: an ML95-type metro car with coned \
         treads of conicity 0.10 (the paper's), nominal Kalker creep coefficients, straight track, \
         sensors with white noise only (0.01 m/s2, 0.0005 rad/s), 20 m/s for 20 s.\nJrel (rms error / rms truth; lower is \
         better), mean over the held-out track seeds {}:\n\n",
        seed_list(&seeds)
    );
    text += TABLE_HEAD;
    for key in [&DEFAULT, &LAGGED, &PAPERS_FILTER] {
        let jrel = bands(find(standard, key)?)?;
        text += &row(key.label, &jrel.map(|j| format!("{j:.3}")));
    }
    text += &row(
        "the paper (its own vehicle)",
        &PAPER.map(|j| format!("{j:.2}")),
    );
    text += "\n";
    text += &nominal_note(standard, table("kalker_50").ok());
    Ok(text)
}

/// The head of a table of Jrel per band.
pub(crate) const TABLE_HEAD: &str =
    "| estimator | whole 3-200 m | D1 3-25 m | D2 25-70 m | D3 70-200 m |\n|---|---|---|---|---|\n";

/// A table row: `label`, then the four bands' cells.
pub(crate) fn row(label: &str, cells: &[String; 4]) -> String {
    format!("| {label} | {} |\n", cells.join(" | "))
}

/// Why the nominal-only taps look better here, with their figures and the default's on the
/// worn contact (Kalker 50 %) when the tables have them.
fn nominal_note(standard: &[Value], kalker_50: Option<&Vec<Value>>) -> String {
    let whole = |rows: &[Value], key: &Key| Some(bands(find(rows, key).ok()?).ok()?[0]);
    let here = whole(standard, &NOMINAL).map_or(String::new(), |j| format!(", whole {j:.3}"));
    let worn = kalker_50
        .and_then(|rows| Some((whole(rows, &DEFAULT)?, whole(rows, &NOMINAL)?)))
        .map_or(String::new(), |(d, n)| {
            format!(
                " (Kalker 50 %, as with worn wheels and rails: default {d:.3}, nominal-only {n:.3})"
            )
        });
    format!(
        "Nominal-only taps (`tap_file = learned-nominal.taps`{here}) look better on this vehicle \
         because they were fitted for exactly it and its wheel state; the default blends tap banks \
         fitted for other wheel/rail contact conditions too, to stay usable when the contact \
         differs{worn}, and pays for that on the nominal case. Its taps hold for wheels near \
         the ML95's conicity only: on others, and on vehicles they were not fitted for, the \
         estimator sets `outside_training` (docs/accuracy.md).\n"
    )
}

/// The row with exactly `key`'s settings (in any order) and output, and not smoothed.
fn find<'a>(rows: &'a [Value], key: &Key) -> Result<&'a Value> {
    let matches = |r: &Value| {
        let Some(settings) = r["settings"].as_array() else {
            return false;
        };
        let mut have: Vec<(&str, &str)> = settings
            .iter()
            .filter_map(|s| Some((s[0].as_str()?, s[1].as_str()?)))
            .collect();
        let mut want = key.settings.to_vec();
        have.sort();
        want.sort();
        have.len() == settings.len()
            && have == want
            && (r["output"] == "Lagged") == key.lagged
            && r["smooth"] != true
    };
    let mut found = rows.iter().filter(|r| matches(r));
    match (found.next(), found.next()) {
        (Some(r), None) => Ok(r),
        (None, _) => bail!("no row for \"{}\" (settings {:?})", key.label, key.settings),
        (Some(_), Some(_)) => bail!("two rows for \"{}\"", key.label),
    }
}

/// A row's mean Jrel per band, in [`BANDS`]' order.
fn bands(row: &Value) -> Result<[f64; 4]> {
    let list = row["bands"].as_array().context("a row without bands")?;
    let mut out = [0.0; 4];
    for (slot, name) in out.iter_mut().zip(BANDS) {
        *slot = list
            .iter()
            .find(|b| b[0] == name)
            .and_then(|b| b[1].as_f64())
            .with_context(|| format!("a row without band {name}"))?;
    }
    Ok(out)
}

/// `1-5` for consecutive seeds, else `1, 3, 8`.
pub(crate) fn seed_list(seeds: &[u64]) -> String {
    match seeds {
        [first, .., last] if seeds.windows(2).all(|w| w[1] == w[0] + 1) => {
            format!("{first}-{last}")
        }
        _ => seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", "),
    }
}

#[cfg(test)]
#[path = "headline_tests.rs"]
mod tests;
