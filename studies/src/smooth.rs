//! `alignment-studies smooth`: the estimator run offline over recorded sensor signals, filtered and
//! smoothed (Rauch-Tung-Striebel), from a CSV or Parquet file (by extension) such as the
//! `results.csv` of a run; the output is Parquet when its name ends in `.parquet` (units and the
//! command's provenance in its metadata, [`orchestrator::parquet`]), else CSV.
//!
//! Input: a table with a `time` column at a constant step and the columns `speed` (or
//! `forward_speed`), `ws_acc_y`, `ws_yaw_rate` and `frame_acc_y`, optionally `ws_roll_rate` and
//! the design line (`design_curvature` with `design_cant`; a curved line's recording without
//! them is estimated as if straight, which the curves swamp), each optionally prefixed by a
//! component name (`vehicle.ws_acc_y`). Every row is a sample, the first one too (the recording
//! format, docs/recordings.md: a row per sample; a run's `results.csv` starts with the sensors'
//! initial values, also a sample); the output has a row per input row. Output columns: `time`, `distance`, `alignment_filtered`,
//! `alignment_filtered_std`, `alignment_smoothed`, `alignment_smoothed_std` (metres); with a
//! learned smoother (`--learned FILE`, from `alignment-studies learn`) also `alignment_learned`
//! and `alignment_hybrid`, computed on its 1 m grid and interpolated linearly to every row.

use crate::study::learned::LearnedSmoother;
use crate::study::metrics::resample;
use fmu_estimator::offline::{self, Processed, Sample};
use orchestrator::outfile::{self, Replace};
use orchestrator::record::push_f64;

/// How every CSV this command writes begins: an existing file that starts so was written by
/// it, and is replaced without `--force` ([`orchestrator::outfile`]).
pub const CSV_MARK: &[u8] = b"time,distance,alignment_filtered,alignment_filtered_std,";
use std::path::{Path, PathBuf};

/// A recording the estimator cannot read; every variant names the file (and the line where
/// one applies). Bad input (exit 2).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RecordingError {
    /// The file cannot be read as CSV or Parquet, in the reader's words (they name the file).
    #[error("{0}")]
    Read(String),
    /// A column the estimator needs is missing or unreadable.
    #[error("{}: {message}", file.display())]
    Column {
        /// The recording.
        file: PathBuf,
        /// The column look-up's message, naming the column.
        message: String,
    },
    /// Fewer than two rows: the step cannot be read from the time column.
    #[error("{}: fewer than 2 rows (the step is read from the time column)", file.display())]
    FewRows {
        /// The recording.
        file: PathBuf,
    },
    /// The first two times do not increase (the step would be zero or negative).
    #[error("{}: time does not increase at {place}", file.display())]
    TimeNotIncreasing {
        /// The recording.
        file: PathBuf,
        /// The second row: `line N` of a CSV file (the file's own line), `row N` of Parquet.
        place: String,
    },
    /// A time that is not a finite number: the steps around it cannot be checked.
    #[error("{}: time {time} at {place} is not a finite number", file.display())]
    TimeNotFinite {
        /// The recording.
        file: PathBuf,
        /// Where: `line N` of a CSV file, `row N` of Parquet.
        place: String,
        /// The value read.
        time: f64,
    },
    /// A time step differs from the first by more than 1e-6 of it: the filter needs one step.
    #[error(
        "{}: the time step changes at {place} ({step} s instead of {expected} s): the filter needs a constant step",
        file.display()
    )]
    StepChanges {
        /// The recording.
        file: PathBuf,
        /// The later row: `line N` of a CSV file (blank and comment lines counted, as an
        /// editor shows them), `row N` of Parquet.
        place: String,
        /// That row's step \[s\].
        step: f64,
        /// The first step \[s\].
        expected: f64,
    },
}

/// A recording read: its times, step and samples, and which optional columns it had.
#[derive(Debug, Clone)]
pub struct Recorded {
    /// The time column \[s\].
    pub time: Vec<f64>,
    /// Its constant step \[s\].
    pub step: f64,
    /// A sample per row.
    pub samples: Vec<Sample>,
    /// Whether it had `ws_roll_rate`.
    pub roll_rate: bool,
    /// Whether it had `design_curvature` and `design_cant`.
    pub design: bool,
}

/// Reads the samples and the step from a CSV file.
pub fn read_samples(path: &Path) -> Result<(Vec<f64>, f64, Vec<Sample>), RecordingError> {
    read_recording(path).map(|r| (r.time, r.step, r.samples))
}

/// Reads a recording (CSV, or Parquet by the extension).
pub fn read_recording(path: &Path) -> Result<Recorded, RecordingError> {
    let cols = orchestrator::csv::Csv::read_any(path).map_err(RecordingError::Read)?;
    let file = || path.to_path_buf();
    let find = |names: &[&str]| {
        cols.column(names)
            .map_err(|message| RecordingError::Column {
                file: file(),
                message,
            })
    };
    let time = find(&["time"])?;
    if time.len() < 2 {
        return Err(RecordingError::FewRows { file: file() });
    }
    let place = |k: usize| cols.place(k);
    if let Some(k) = time.iter().position(|t| !t.is_finite()) {
        return Err(RecordingError::TimeNotFinite {
            file: file(),
            place: place(k),
            time: time[k],
        });
    }
    let h = time[1] - time[0];
    if !(h > 0.0) {
        return Err(RecordingError::TimeNotIncreasing {
            file: file(),
            place: place(1),
        });
    }
    for (k, w) in time.windows(2).enumerate() {
        if ((w[1] - w[0]) - h).abs() > 1e-6 * h {
            return Err(RecordingError::StepChanges {
                file: file(),
                place: place(k + 1),
                step: w[1] - w[0],
                expected: h,
            });
        }
    }
    let speed = find(&["speed", "forward_speed"])?;
    let acc = find(&["ws_acc_y"])?;
    let yaw = find(&["ws_yaw_rate"])?;
    let frame = find(&["frame_acc_y"])?;
    let mut samples = Sample::from_columns(speed, acc, yaw, frame);
    // Optional columns: absent, they are 0 (no roll-rate gyroscope; straight, level track).
    let optional = |name: &str| -> Result<Option<&[f64]>, RecordingError> {
        match cols.find(name) {
            Ok(None) => Ok(None),
            Ok(Some(_)) => find(&[name]).map(Some),
            Err(message) => Err(RecordingError::Column {
                file: file(),
                message,
            }),
        }
    };
    let roll_rate = optional("ws_roll_rate")?;
    if let Some(roll) = roll_rate {
        samples = Sample::with_roll_rate(samples, roll);
    }
    let design = match (optional("design_curvature")?, optional("design_cant")?) {
        (None, None) => false,
        (Some(k), Some(c)) => {
            for (s, (k, c)) in samples.iter_mut().zip(k.iter().zip(c)) {
                s.design = [*k, *c];
            }
            true
        }
        (k, _) => {
            return Err(RecordingError::Column {
                file: file(),
                message: format!(
                    "design_curvature and design_cant come together (the design line): it has only {}",
                    if k.is_some() {
                        "design_curvature"
                    } else {
                        "design_cant"
                    }
                ),
            });
        }
    };
    Ok(Recorded {
        time: time.to_vec(),
        step: h,
        samples,
        roll_rate: roll_rate.is_some(),
        design,
    })
}

/// The output CSV text, numbers written as in `results.csv` ([`orchestrator::record`]); `learned`, if
/// given, adds the learned and hybrid estimates per sample.
pub fn to_csv(time: &[f64], out: &Processed, learned: Option<&(Vec<f64>, Vec<f64>)>) -> String {
    let (names, columns) = output_columns(time, out, learned);
    let mut s: Vec<u8> = names.join(",").into_bytes();
    s.push(b'\n');
    let mut buf = ryu::Buffer::new();
    for k in 0..time.len() {
        for (j, c) in columns.iter().enumerate() {
            if j > 0 {
                s.push(b',');
            }
            push_f64(&mut s, c[k], &mut buf);
        }
        s.push(b'\n');
    }
    String::from_utf8(s).expect("digits, signs and letters only")
}

/// The output's column names and values: what [`to_csv`] and the Parquet output write.
fn output_columns(
    time: &[f64],
    out: &Processed,
    learned: Option<&(Vec<f64>, Vec<f64>)>,
) -> (Vec<String>, Vec<Vec<f64>>) {
    let smoothed = |i: usize| -> Vec<f64> {
        out.smoothed
            .as_deref()
            .map_or(vec![f64::NAN; time.len()], |v| {
                v.iter().map(|e| if i == 0 { e.0 } else { e.1 }).collect()
            })
    };
    let mut names = vec![
        "time",
        "distance",
        "alignment_filtered",
        "alignment_filtered_std",
        "alignment_smoothed",
        "alignment_smoothed_std",
    ];
    let mut cols = vec![
        time.to_vec(),
        out.distance.clone(),
        out.filtered.iter().map(|e| e.0).collect(),
        out.filtered.iter().map(|e| e.1).collect(),
        smoothed(0),
        smoothed(1),
    ];
    if let Some((a, b)) = learned {
        names.extend(["alignment_learned", "alignment_hybrid"]);
        cols.extend([a.clone(), b.clone()]);
    }
    (names.into_iter().map(String::from).collect(), cols)
}

/// The learned smoother saved in `file` applied to `samples` (step `h`): its learned and hybrid
/// estimates per sample.
fn learned_columns(
    file: &Path,
    samples: &[Sample],
    h: f64,
    distance: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), crate::Error> {
    // A saved learned smoother is about a megabyte of JSON; the bound only stops a device or a
    // runaway file.
    let text = fmi_abi::resource::read_text(file, "learned smoother file", 1 << 30)
        .map_err(crate::Error::Input)?;
    let l = LearnedSmoother::from_json(&text, file)?;
    // A standing start (a run's results.csv begins with the vehicle's outputs before its first
    // step, at speed 0) gets no learned estimate (NaN): the taps hold the dynamics at the one
    // speed they were fitted at. A stop later in the record is refused by the speed check.
    let first = samples
        .iter()
        .position(|s| s.speed > 0.0)
        .unwrap_or(samples.len());
    let (samples, moving) = (&samples[first..], &distance[first..]);
    let kalman = l.kalman(samples, h)?;
    let (learned, hybrid) = l
        .apply(samples, h, &kalman)
        .map_err(|e| e.context(file.display()))?;
    // From its grid (every `decimation`-th sample) to every sample, linearly in distance.
    let grid: Vec<f64> = moving.iter().step_by(l.decimation).copied().collect();
    let standing = vec![f64::NAN; first];
    Ok((
        [standing.clone(), resample(&grid, &learned, moving)].concat(),
        [standing, resample(&grid, &hybrid, moving)].concat(),
    ))
}

/// The fitted design as a line file (docs/vehicle-fmu.md: `distance,curvature,cant`), numbers
/// written so that they read back exactly; its first line is [`LINE_MARK`].
pub fn line_csv(input: &Path, rows: &[(f64, f64, f64)]) -> String {
    let mut text = format!(
        "{} from {} (design_line::fit; rows linear between, rounded 10 m as the line's default)\ndistance,curvature,cant\n",
        String::from_utf8_lossy(LINE_MARK),
        input.display()
    );
    for (d, k, c) in rows {
        text += &format!("{d:?},{k:?},{c:?}\n");
    }
    text
}

/// How every line file `--design-out` writes begins: an existing file that starts so was
/// written by it, and is replaced without `--force`.
pub const LINE_MARK: &[u8] = b"# The design line alignment-studies smooth --fit-design fitted";

/// `--fit-design`, and where `--design-out` writes the fitted line (a line file) with its output
/// policy.
#[derive(Debug, Clone, Copy)]
pub struct FitDesign<'a> {
    /// The line file to write, if any, and how an existing one may be replaced.
    pub line_out: Option<(&'a Path, Replace<'a>)>,
}

/// Filters and smooths `input`, writing `output` by the output policy ([`outfile`]: checked
/// before the recording is read, written through a temporary file renamed into place); with
/// `learned`, also the learned smoother saved in that file; with `fit_design`, the design line
/// fitted from the recording's sensors ([`offline::fitted`]) removed, and written as a line
/// file where it says. A refused or failed write is [`crate::Error::Io`] (exit 1), bad input
/// [`crate::Error::Input`] (exit 2).
pub fn smooth_file(
    input: &Path,
    output: &Path,
    overrides: &[(String, String)],
    calibration: Option<&Path>,
    learned: Option<&Path>,
    fit_design: Option<FitDesign>,
    replace: Replace,
) -> Result<Processed, crate::Error> {
    let mut inputs = vec![input];
    inputs.extend(calibration);
    inputs.extend(learned);
    // Refused before any work: an input, a symlink, FIFO or device, someone else's file.
    let refused = |e: std::io::Error| crate::Error::Io(e.to_string());
    outfile::check(output, &inputs, replace).map_err(refused)?;
    let line_out = fit_design.and_then(|f| f.line_out);
    let mut line_inputs = inputs.clone();
    line_inputs.push(output);
    if let Some((path, policy)) = line_out {
        outfile::check(path, &line_inputs, policy).map_err(refused)?;
    }
    let Recorded {
        time,
        step: h,
        samples,
        roll_rate,
        design: design_given,
    } = read_recording(input)?;
    let provenance = serde_json::json!({
        "command": "alignment-studies smooth",
        "version": env!("CARGO_PKG_VERSION"),
        "input": input.display().to_string(),
        "settings": overrides,
        "calibration": calibration.map(|p| p.display().to_string()),
        "learned": learned.map(|p| p.display().to_string()),
        "fit_design": fit_design.is_some(),
    });
    let values = offline::settings(overrides)?;
    let (config, notes) = offline::config(&values, calibration)?;
    let bad = |e: String| crate::Error::Input(format!("{}: {e}", input.display()));
    offline::one_design(&config, design_given).map_err(|e| bad(e.to_string()))?;
    let samples = if fit_design.is_some() {
        if config.line.is_some() {
            return Err(bad(
                "the setting line_file gives the design and --fit-design asks to fit it: give one"
                    .into(),
            ));
        }
        if design_given {
            return Err(bad("it has the design (design_curvature, design_cant) and --fit-design asks to fit it: give one".into()));
        }
        if !roll_rate {
            return Err(bad("--fit-design needs the column ws_roll_rate: the cant ramps the roll gyroscope sees place the transitions".into()));
        }
        let model = config.design.as_deref().ok_or_else(|| {
            bad("--fit-design needs design_response_file (the vehicle's gauge and response), which is set empty".into())
        })?;
        let (samples, fitted) =
            offline::fitted::with_fitted_design(&samples, h, model).map_err(bad)?;
        if let Some((path, policy)) = line_out {
            let text = line_csv(input, &fitted.rows());
            outfile::write_bytes(path, &line_inputs, policy, text.as_bytes()).map_err(refused)?;
        }
        samples
    } else {
        samples
    };
    for n in notes {
        if let fmu_estimator::config::Note::Warning(m) = n {
            eprintln!("warning: {m}");
        }
    }
    // Below min_speed the estimate is held at its start: a recording with no sample above it
    // (a standing train, a speed column in km/h divided wrongly) would give all zeros.
    if !samples
        .iter()
        .any(|s| s.speed.is_finite() && s.speed >= config.min_speed)
    {
        return Err(crate::Error::Input(format!(
            "{}: no row at a speed of at least {} m/s (min_speed), where the estimator works: the estimate would be all zeros; nothing written",
            input.display(),
            config.min_speed
        )));
    }
    let out = offline::process(&config, h, &samples, true)?;
    let learned = learned
        .map(|f| learned_columns(f, &samples, h, &out.distance))
        .transpose()?;
    // Through a temporary file in the output's directory, renamed into place.
    let written = if orchestrator::parquet::is_parquet(output) {
        let (names, columns) = output_columns(&time, &out, learned.as_ref());
        let units: Vec<String> = names
            .iter()
            .map(|n| if n == "time" { "s" } else { "m" }.to_string())
            .collect();
        let cols: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
        outfile::write(output, &inputs, replace, |tmp| {
            orchestrator::parquet::write(tmp, &names, &units, &cols, &provenance.to_string())
                .map_err(std::io::Error::other)
        })
    } else {
        let text = to_csv(&time, &out, learned.as_ref());
        outfile::write_bytes(output, &inputs, replace, text.as_bytes())
    };
    written.map_err(refused)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("orch-smooth-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("in.csv");
        std::fs::write(&p, text).unwrap();
        p
    }

    /// The design line and the roll-rate gyroscope are read where the recording has them (the
    /// format `track_alignment` writes), and the design's two columns come together.
    #[test]
    fn reads_the_optional_columns() {
        let head = "time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y";
        let p = write(
            "design",
            &format!(
                "{head},v.ws_roll_rate,design_curvature,design_cant\n0,20,0,0,0,0.01,0.002,0.1\n0.001,20,0,0,0,0.02,0.003,0.12\n"
            ),
        );
        let (_, _, s) = read_samples(&p).unwrap();
        assert_eq!(s[1].design, [0.003, 0.12]);
        assert_eq!(s[1].ws_roll_rate, 0.02);
        let p = write("plain", &format!("{head}\n0,20,0,0,0\n0.001,20,0,0,0\n"));
        let (_, _, s) = read_samples(&p).unwrap();
        assert_eq!((s[1].design, s[1].ws_roll_rate), ([0.0; 2], 0.0));
        let p = write(
            "half",
            &format!("{head},design_cant\n0,20,0,0,0,0.1\n0.001,20,0,0,0,0.1\n"),
        );
        let e = read_samples(&p).unwrap_err().to_string();
        assert!(
            e.contains("in.csv") && e.contains("only design_cant"),
            "{e}"
        );
    }

    #[test]
    fn reads_prefixed_columns_and_every_row() {
        let p = write(
            "ok",
            "time,vehicle.forward_speed,vehicle.ws_acc_y,vehicle.ws_yaw_rate,vehicle.frame_acc_y\n0,0,0,0,0\n0.001,20,0.1,0.2,0.3\n0.002,20,0.4,0.5,0.6\n",
        );
        let (t, h, s) = read_samples(&p).unwrap();
        assert_eq!(t, vec![0.0, 0.001, 0.002], "the first row is a sample too");
        assert_eq!(s.len(), 3);
        assert!((h - 0.001).abs() < 1e-15);
        assert_eq!(s[0].speed, 0.0);
        assert_eq!(s[2].ws_yaw_rate, 0.5);
    }

    #[test]
    fn missing_columns_and_uneven_steps_are_named() {
        let p = write("missing", "time,speed,ws_acc_y\n0,1,2\n1,1,2\n2,1,2\n");
        let e = read_samples(&p).unwrap_err().to_string();
        assert!(e.contains("ws_yaw_rate") && e.contains("in.csv"), "{e}");
        let p = write(
            "uneven",
            "time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n0,1,0,0,0\n0.001,1,0,0,0\n0.003,1,0,0,0\n",
        );
        let e = read_samples(&p).unwrap_err().to_string();
        assert!(
            e.contains("at line 4 (") && e.contains("constant step"),
            "{e}"
        );
        // The file's own line numbers, with a comment and a blank line before the rows.
        let p = write(
            "commented",
            "# logger v2\ntime,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n\n0,1,0,0,0\n0.001,1,0,0,0\n0.003,1,0,0,0\n",
        );
        let e = read_samples(&p).unwrap_err().to_string();
        assert!(e.contains("at line 6 ("), "{e}");
        let p = write(
            "backwards",
            "# logger v2\ntime,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n0,1,0,0,0\n\n0,1,0,0,0\n",
        );
        let e = read_samples(&p).unwrap_err().to_string();
        assert!(e.contains("does not increase at line 5"), "{e}");
    }

    #[test]
    fn a_time_that_is_not_a_number_is_named() {
        // NaN compares false with everything, so the step check alone would let it through.
        let p = write(
            "nan-time",
            "time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n0,1,0,0,0\n0.001,1,0,0,0\nnan,1,0,0,0\n0.003,1,0,0,0\n",
        );
        let e = read_samples(&p).unwrap_err().to_string();
        assert!(
            e.contains("time NaN at line 4 is not a finite number"),
            "{e}"
        );
    }
}
