//! `orchestrator simulate FMU --input signals.csv`: one FMU driven by recorded input signals,
//! like `fmpy simulate`. The input file is a CSV ([`crate::csv`]: quoted names, a BOM, comments
//! and `component.`-prefixed names accepted, duplicated names refused) whose first column is
//! `time` and whose other columns are named after input variables of the FMU; a Parquet file
//! (by extension, any codec pyarrow writes) likewise. The recording format's `distance`
//! column ([`RECORDING_ONLY`]) is ignored with a note when the FMU has no such input.
//!
//! | input variable | value at a communication point `t` |
//! |---|---|
//! | Real, continuous | the signal linearly interpolated at `t` (held beyond the last row) |
//! | Real, discrete (or fixed/tunable) | the last row at or before `t`, held (as fmpy) |
//! | Integer, Enumeration | the last row at or before `t`, held; must be a whole number |
//! | Boolean | the last row at or before `t`, held; `0`/`1` or `false`/`true` |
//!
//! Then the FMU steps to `t + h`. Every output is recorded. Times must be finite and must not go
//! backwards; Real values are any number `f64` parses (`nan` and `inf` included, so that an
//! FMU's handling of bad samples can be driven). Errors name the file, the line and the column.
//!
//! Timing: the value set at `t` is what the FMU reads for the step from `t` to `t + h`. A
//! recorded `results.csv` of a Gauss-Seidel run holds in row `t + h` the producer's output that
//! the consumer read for that step; replayed as it is, it reaches the consumer one step late.
//! `--replay` reads the signals one step ahead (`t` takes the row of `t + h`), so that a record
//! replays exactly. A time within 1e-9 (relative) of a row's time takes that row's value.

use crate::master::{Cosimulation, ProgressFn, RunError, RunOptions, RunSummary, StopToken};
use crate::system::{Component, Experiment, System};
use model_description::{BaseType, Variability};
use std::path::Path;

/// Input signals: a time column and one column per input.
#[derive(Debug, Clone, PartialEq)]
pub struct Signals {
    /// Sample times \[s\], at least one: finite, never decreasing (at equal times the last
    /// row wins).
    pub time: Vec<f64>,
    /// The input columns' names, `time` left out (a `component.` prefix is kept as written).
    pub names: Vec<String>,
    /// One vector per name, one value per time; any `f64`, NaN and infinities included.
    pub columns: Vec<Vec<f64>>,
}

impl Signals {
    /// Reads a CSV file, or a Parquet file by its `.parquet` extension ([`crate::parquet`]);
    /// errors name the file, the line (a Parquet file: the row) and the column.
    pub fn read(path: &Path) -> Result<Signals, String> {
        if crate::parquet::is_parquet(path) {
            let csv = crate::csv::Csv::read_any(path).map_err(|e| format!("input file {e}"))?;
            if let Some(k) = csv
                .columns
                .first()
                .and_then(|t| t.iter().position(|x| !x.is_finite()))
            {
                return Err(format!(
                    "input file {}: row {}: time is not a finite number",
                    path.display(),
                    k + 1
                ));
            }
            return Self::from_csv(csv).map_err(|e| format!("input file {}: {e}", path.display()));
        }
        let text = crate::input::read_text(path, crate::input::CSV_LIMIT)
            .map_err(|e| format!("cannot read input file {}: {e}", path.display()))?;
        Self::parse(&text).map_err(|e| format!("input file {}: {e}", path.display()))
    }

    /// The row whose time is `t` to within a master clock's rounding (1e-9 relative), if any:
    /// a time computed as `start + k h` or `t + h` must meet the row recorded for it.
    fn row_at(&self, t: f64) -> Option<usize> {
        let tol = 1e-9 * t.abs().max(1.0);
        let i = self.time.partition_point(|&x| x < t - tol);
        (i < self.time.len() && (self.time[i] - t).abs() <= tol).then_some(i)
    }

    /// Column `c` held: the value of the last row at or before `t` (the first row before it).
    pub fn held(&self, c: usize, t: f64) -> f64 {
        if let Some(i) = self.row_at(t) {
            // The last of several rows at the same time, as `at` takes.
            let last = self.time.partition_point(|&x| x <= self.time[i]) - 1;
            return self.columns[c][last];
        }
        let i = self.time.partition_point(|&x| x <= t);
        self.columns[c][i.saturating_sub(1)]
    }

    /// Parses CSV text (the rules of [`crate::csv`], `time` first and finite); an error names
    /// the line and column, not the file.
    pub fn parse(text: &str) -> Result<Signals, String> {
        Self::from_csv(crate::csv::Csv::parse_finite(text, &["time"])?)
    }

    /// The signals of a table whose first column is `time` (finite, checked by the reader).
    fn from_csv(csv: crate::csv::Csv) -> Result<Signals, String> {
        if csv.names.first().map(String::as_str) != Some("time") {
            return Err(format!(
                "line {}: the first column must be 'time', found '{}'",
                csv.header_line,
                csv.names.first().map(String::as_str).unwrap_or("")
            ));
        }
        let time = csv.columns[0].clone();
        // A NaN or infinite time (refused by the reader) would break the interpolation's
        // ordering; the signal values themselves may be anything, NaN included, to drive an
        // FMU's handling of bad samples.
        for (k, t) in time.iter().enumerate() {
            if k > 0 && *t < time[k - 1] {
                return Err(format!(
                    "line {}: time {t} goes backwards (previous {})",
                    csv.lines[k],
                    time[k - 1]
                ));
            }
        }
        if time.is_empty() {
            return Err("no data rows".into());
        }
        Ok(Signals {
            time,
            names: csv.names[1..].to_vec(),
            columns: csv.columns[1..].to_vec(),
        })
    }

    /// Column `c` linearly interpolated at `t`, held constant outside the time range; a row's
    /// own value at its time (to within a clock's rounding).
    pub fn at(&self, c: usize, t: f64) -> f64 {
        let (ts, xs) = (&self.time, &self.columns[c]);
        if let Some(i) = self.row_at(t) {
            let last = ts.partition_point(|&x| x <= ts[i]) - 1;
            return xs[last];
        }
        if t <= ts[0] {
            return xs[0];
        }
        if t >= ts[ts.len() - 1] {
            return xs[xs.len() - 1];
        }
        let i = ts.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (ts[i], ts[i + 1]);
        if t1 == t0 {
            return xs[i + 1];
        }
        xs[i] + (xs[i + 1] - xs[i]) * (t - t0) / (t1 - t0)
    }
}

/// Columns of the recording format (docs/recordings.md) that no estimator input takes: a
/// recording written by `track_alignment` carries them, and refusing them would make users
/// strip a documented column by hand. Ignored, with a note, when the FMU has no input of
/// that name; any other unknown column is still refused (a typo would leave an input at its
/// start value).
pub const RECORDING_ONLY: &[&str] = &["distance"];

/// Runs one FMU with `signals` on its inputs. Implemented as a one-component system whose
/// inputs are set before every step, so it shares the master's recording and error handling.
/// The component is named after the FMU's file stem (`Feedthrough.fmu`: `Feedthrough`), which
/// is also the prefix of its results' columns. Progress goes to `progress` when
/// [`RunOptions::progress`] asks for it; setting `stop` stops the run at the next step.
pub fn simulate(
    fmu: &Path,
    signals: Option<&Signals>,
    settings: &[(String, String)],
    opts: &RunOptions,
    replay: bool,
    progress: &mut ProgressFn<'_>,
    stop: &StopToken,
) -> Result<RunSummary, RunError> {
    let name = fmu
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("fmu")
        .to_string();
    let system = System {
        name: name.clone(),
        components: vec![Component {
            name: name.clone(),
            source: fmu.to_path_buf(),
            parameters: vec![],
        }],
        connections: vec![],
        experiment: Experiment::default(),
    };
    let mut cosim = Cosimulation::load(system)?;
    for (variable, value) in settings {
        cosim.set(&crate::system::Endpoint::new(&name, variable), value)?;
    }
    let runner = cosim.runner(opts).progress(progress).stop_on(stop);
    match signals {
        None => runner.run(),
        Some(s) => {
            let md = cosim.model_descriptions()[0].clone();
            // The inputs by name, and per input its column and whether it is held.
            let (mut names, mut columns) = (vec![], vec![]);
            for (c, n) in s.names.iter().enumerate() {
                // `component.variable` as a results.csv names it: the part after the prefix.
                let found = md
                    .variable(n)
                    .or_else(|| n.rsplit_once('.').and_then(|(_, bare)| md.variable(bare)));
                let bare = n.rsplit_once('.').map_or(n.as_str(), |(_, b)| b);
                let is_input =
                    found.is_some_and(|v| v.causality == model_description::Causality::Input);
                if !is_input && RECORDING_ONLY.contains(&bare) {
                    eprintln!(
                        "note: input column '{n}' is not an input of {}: ignored (a recording's position along the line)",
                        fmu.display()
                    );
                    continue;
                }
                let v = found.ok_or_else(|| {
                    RunError::Config(format!(
                        "input column '{n}': {} has no variable of that name",
                        fmu.display()
                    ))
                })?;
                if v.causality != model_description::Causality::Input {
                    return Err(RunError::Config(format!(
                        "input column '{n}': '{}' is not an input of {}",
                        v.name,
                        fmu.display()
                    )));
                }
                let base = v.kind.base_type();
                let hold = match base {
                    BaseType::Real => v.variability != Variability::Continuous,
                    BaseType::Integer | BaseType::Enumeration | BaseType::Boolean => {
                        check_discrete(s, c, base)?;
                        true
                    }
                    BaseType::String => {
                        return Err(RunError::Config(format!(
                            "input column '{n}': '{}' is a String input, which a CSV of numbers cannot drive",
                            v.name
                        )));
                    }
                };
                names.push(crate::system::Endpoint::new(&name, &v.name));
                columns.push((c, hold));
            }
            // Replaying a record: the value set at t is the row of t + h.
            let lead = if replay { opts.step } else { 0.0 };
            let fill = |t: f64, out: &mut [f64]| {
                let t = t + lead;
                for (x, &(c, hold)) in out.iter_mut().zip(&columns) {
                    *x = if hold { s.held(c, t) } else { s.at(c, t) };
                }
            };
            runner.inputs(&names, &fill).run()
        }
    }
}

/// An Integer, Enumeration or Boolean column holds whole numbers (0 or 1 for a Boolean) within
/// the 32-bit range FMI 2.0 gives them.
fn check_discrete(s: &Signals, c: usize, base: BaseType) -> Result<(), RunError> {
    let ok = |x: f64| match base {
        BaseType::Boolean => x == 0.0 || x == 1.0,
        _ => x.fract() == 0.0 && x >= i32::MIN as f64 && x <= i32::MAX as f64,
    };
    if let Some(k) = s.columns[c].iter().position(|x| !ok(*x)) {
        return Err(RunError::Config(format!(
            "input column '{}', row {} (t = {}): {} is not a valid {} value{}",
            s.names[c],
            k + 1,
            s.time[k],
            s.columns[c][k],
            base.as_str(),
            if base == BaseType::Boolean {
                " (0, 1, false or true)"
            } else {
                " (a whole number)"
            }
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signals_parse_and_interpolate() {
        let s = Signals::parse("time,u,v\n0,0,1\n1,10,1\n# comment\n2,20,3\n").unwrap();
        assert_eq!(s.names, vec!["u", "v"]);
        assert_eq!(s.at(0, 0.5), 5.0);
        assert_eq!(s.at(0, -1.0), 0.0);
        assert_eq!(s.at(1, 1.5), 2.0);
        assert_eq!(s.at(1, 9.0), 3.0);
    }

    #[test]
    fn bad_files_name_line_and_column() {
        assert!(
            Signals::parse("t,u\n0,1\n")
                .unwrap_err()
                .contains("first column must be 'time'")
        );
        let e = Signals::parse("time,u\n0,1\n1,x\n").unwrap_err();
        assert!(
            e.contains("line 3") && e.contains("'u'") && e.contains("'x'"),
            "{e}"
        );
        assert!(
            Signals::parse("time,u\n1,1\n0,1\n")
                .unwrap_err()
                .contains("backwards")
        );
        assert!(
            Signals::parse("time,u\n0,1,2\n")
                .unwrap_err()
                .contains("line 2")
        );
    }
}
