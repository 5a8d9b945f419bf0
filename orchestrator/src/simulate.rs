//! `orchestrator simulate FMU --input signals.csv`: one FMU driven by recorded input signals,
//! like `fmpy simulate`. The input file is a CSV whose first column is `time` and whose other
//! columns are named after input variables of the FMU; at each communication point `t` the
//! inputs are set to the signals linearly interpolated at `t` (held beyond the last row), then
//! the FMU steps to `t + h`. Every output is recorded. Times must be finite and must not go
//! backwards; signal values are any number `f64` parses (`nan` and `inf` included, so that an
//! FMU's handling of bad samples can be driven). Errors name the file, the line and the column.

use crate::master::{Cosimulation, RunError, RunOptions, RunSummary};
use crate::system::{Component, Experiment, System};
use std::path::Path;

/// Input signals: a time column and one column per input.
#[derive(Debug, Clone, PartialEq)]
pub struct Signals {
    pub time: Vec<f64>,
    pub names: Vec<String>,
    pub columns: Vec<Vec<f64>>,
}

impl Signals {
    /// Reads a CSV file; errors name the file, the line and the column.
    pub fn read(path: &Path) -> Result<Signals, String> {
        let text = crate::input::read_text(path, crate::input::CSV_LIMIT)
            .map_err(|e| format!("cannot read input file {}: {e}", path.display()))?;
        Self::parse(&text).map_err(|e| format!("input file {}: {e}", path.display()))
    }

    pub fn parse(text: &str) -> Result<Signals, String> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
        let (header_index, header) = lines.next().ok_or("the file is empty")?;
        let names: Vec<String> = header
            .split(',')
            .map(|s| s.trim().trim_matches('"').to_string())
            .collect();
        if names.first().map(String::as_str) != Some("time") {
            return Err(format!(
                "line {}: the first column must be 'time', found '{}'",
                header_index + 1,
                names.first().map(String::as_str).unwrap_or("")
            ));
        }
        let mut time = vec![];
        let mut columns = vec![vec![]; names.len() - 1];
        for (i, line) in lines {
            let fields: Vec<&str> = line.split(',').collect();
            if fields.len() != names.len() {
                return Err(format!(
                    "line {}: {} fields, the header has {}",
                    i + 1,
                    fields.len(),
                    names.len()
                ));
            }
            let mut values = Vec::with_capacity(fields.len());
            for (j, f) in fields.iter().enumerate() {
                values.push(f.trim().parse::<f64>().map_err(|_| {
                    format!(
                        "line {}, column '{}': '{}' is not a number",
                        i + 1,
                        names[j],
                        f.trim()
                    )
                })?);
            }
            // A NaN or infinite time would break the interpolation's ordering (and a NaN
            // slips through every comparison); the signal values themselves may be anything,
            // NaN included, to drive an FMU's handling of bad samples.
            if !values[0].is_finite() {
                return Err(format!(
                    "line {}, column 'time': '{}' is not a finite time",
                    i + 1,
                    fields[0].trim()
                ));
            }
            if let Some(&last) = time.last()
                && values[0] < last
            {
                return Err(format!(
                    "line {}: time {} goes backwards (previous {last})",
                    i + 1,
                    values[0]
                ));
            }
            time.push(values[0]);
            for (c, v) in columns.iter_mut().zip(&values[1..]) {
                c.push(*v);
            }
        }
        if time.is_empty() {
            return Err("no data rows".into());
        }
        Ok(Signals {
            time,
            names: names[1..].to_vec(),
            columns,
        })
    }

    /// Column `c` linearly interpolated at `t`, held constant outside the time range.
    pub fn at(&self, c: usize, t: f64) -> f64 {
        let (ts, xs) = (&self.time, &self.columns[c]);
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

/// Runs one FMU with `signals` on its inputs. Implemented as a one-component system whose
/// inputs are set before every step, so it shares the master's recording and error handling.
pub fn simulate(
    fmu: &Path,
    signals: Option<&Signals>,
    settings: &[(String, String)],
    opts: &RunOptions,
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
    match signals {
        None => cosim.run(opts),
        Some(s) => {
            let md = cosim.model_descriptions()[0].clone();
            let mut vrs = vec![];
            for n in &s.names {
                let v = md.variable(n).ok_or_else(|| {
                    RunError::Config(format!(
                        "input column '{n}': {} has no variable of that name",
                        fmu.display()
                    ))
                })?;
                if v.causality != model_description::Causality::Input
                    || v.kind.base_type() != model_description::BaseType::Real
                {
                    return Err(RunError::Config(format!(
                        "input column '{n}': the variable is not a Real input of {}",
                        fmu.display()
                    )));
                }
                vrs.push(v.value_reference);
            }
            cosim.run_with_inputs(opts, &|t: f64, out: &mut Vec<(u32, f64)>| {
                out.clear();
                for (c, vr) in vrs.iter().enumerate() {
                    out.push((*vr, s.at(c, t)));
                }
            })
        }
    }
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
