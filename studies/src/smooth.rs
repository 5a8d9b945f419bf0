//! `alignment-studies smooth`: the estimator run offline over recorded sensor signals, filtered and
//! smoothed (Rauch-Tung-Striebel), from a CSV or Parquet file (by extension) such as the
//! `results.csv` of a run; the output is Parquet when its name ends in `.parquet` (units and the
//! command's provenance in its metadata, [`orchestrator::parquet`]), else CSV.
//!
//! Input: a table with a `time` column at a constant step and the columns `speed` (or
//! `forward_speed`), `ws_acc_y`, `ws_yaw_rate` and `frame_acc_y`, each optionally prefixed by a
//! component name (`vehicle.ws_acc_y`). Row `k` holds the samples at the end of the step that
//! ends at `time[k]`; a first row at the start time with the initial values (as `results.csv`
//! has) is used only for its time. Output columns: `time`, `distance`, `alignment_filtered`,
//! `alignment_filtered_std`, `alignment_smoothed`, `alignment_smoothed_std` (metres); with a
//! learned smoother (`--learned FILE`, from `alignment-studies learn`) also `alignment_learned`
//! and `alignment_hybrid`, computed on its 1 m grid and interpolated linearly to every row.

use crate::study::learned::LearnedSmoother;
use crate::study::metrics::resample;
use fmu_estimator::offline::{self, Processed, Sample};
use orchestrator::record::push_f64;
use std::path::Path;

/// Reads the samples and the step from a CSV file.
pub fn read_samples(path: &Path) -> Result<(Vec<f64>, f64, Vec<Sample>), String> {
    let cols = orchestrator::csv::Csv::read_any(path)?;
    let find = |names: &[&str]| {
        cols.column(names)
            .map_err(|e| format!("{}: {e}", path.display()))
    };
    let time = find(&["time"])?;
    if time.len() < 3 {
        return Err(format!("{}: fewer than 3 rows", path.display()));
    }
    let h = time[1] - time[0];
    if !(h > 0.0) {
        return Err(format!(
            "{}: time does not increase at line 3",
            path.display()
        ));
    }
    for (k, w) in time.windows(2).enumerate() {
        if ((w[1] - w[0]) - h).abs() > 1e-6 * h {
            return Err(format!(
                "{}: the time step changes at line {} ({} s instead of {h} s): the filter needs a constant step",
                path.display(),
                k + 3,
                w[1] - w[0]
            ));
        }
    }
    let speed = find(&["speed", "forward_speed"])?;
    let acc = find(&["ws_acc_y"])?;
    let yaw = find(&["ws_yaw_rate"])?;
    let frame = find(&["frame_acc_y"])?;
    // A first row at the start time holds initial values, not the end of a step.
    let samples = Sample::from_columns(&speed[1..], &acc[1..], &yaw[1..], &frame[1..]);
    Ok((time[1..].to_vec(), h, samples))
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
) -> Result<(Vec<f64>, Vec<f64>), String> {
    // A saved learned smoother is about a megabyte of JSON; the bound only stops a device or a
    // runaway file.
    let text = fmi_abi::resource::read_text(file, "learned smoother file", 1 << 30)?;
    let l = LearnedSmoother::from_json(&text, file)?;
    let kalman = l.kalman(samples, h)?;
    let (learned, hybrid) = l
        .apply(samples, h, &kalman)
        .map_err(|e| format!("{}: {e}", file.display()))?;
    // From its grid (every `decimation`-th sample) to every sample, linearly in distance.
    let grid: Vec<f64> = distance.iter().step_by(l.decimation).copied().collect();
    Ok((
        resample(&grid, &learned, distance),
        resample(&grid, &hybrid, distance),
    ))
}

/// Filters and smooths `input`, writing `output` (through a temporary file renamed at the end);
/// with `learned`, also the learned smoother saved in that file.
pub fn smooth_file(
    input: &Path,
    output: &Path,
    overrides: &[(String, String)],
    calibration: Option<&Path>,
    learned: Option<&Path>,
) -> Result<Processed, String> {
    // Refused before any work: a symlink, FIFO or device given as --out is never replaced.
    orchestrator::outdir::refuse_special(output).map_err(|e| e.to_string())?;
    let (time, h, samples) = read_samples(input)?;
    let provenance = serde_json::json!({
        "command": "alignment-studies smooth",
        "version": env!("CARGO_PKG_VERSION"),
        "input": input.display().to_string(),
        "settings": overrides,
        "calibration": calibration.map(|p| p.display().to_string()),
        "learned": learned.map(|p| p.display().to_string()),
    });
    let values = offline::settings(overrides)?;
    let (config, notes) = offline::config(&values, calibration)?;
    for n in notes {
        if let fmu_estimator::config::Note::Warning(m) = n {
            eprintln!("warning: {m}");
        }
    }
    let out = offline::process(&config, h, &samples, true)?;
    let learned = learned
        .map(|f| learned_columns(f, &samples, h, &out.distance))
        .transpose()?;
    // Per process: two commands writing the same output never share a temporary file.
    let parquet = orchestrator::parquet::is_parquet(output);
    let ext = if parquet { "parquet" } else { "csv" };
    let tmp = output.with_extension(format!("{ext}.{}.partial", std::process::id()));
    if parquet {
        let (names, columns) = output_columns(&time, &out, learned.as_ref());
        let units: Vec<String> = names
            .iter()
            .map(|n| if n == "time" { "s" } else { "m" }.to_string())
            .collect();
        let cols: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
        orchestrator::parquet::write(&tmp, &names, &units, &cols, &provenance.to_string())
            .inspect_err(|_| {
                let _ = std::fs::remove_file(&tmp);
            })?;
    } else {
        std::fs::write(&tmp, to_csv(&time, &out, learned.as_ref()))
            .map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    }
    std::fs::rename(&tmp, output).map_err(|e| {
        format!(
            "cannot rename {} to {}: {e}",
            tmp.display(),
            output.display()
        )
    })?;
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

    #[test]
    fn reads_prefixed_columns_and_drops_the_initial_row() {
        let p = write(
            "ok",
            "time,vehicle.forward_speed,vehicle.ws_acc_y,vehicle.ws_yaw_rate,vehicle.frame_acc_y\n0,0,0,0,0\n0.001,20,0.1,0.2,0.3\n0.002,20,0.4,0.5,0.6\n",
        );
        let (t, h, s) = read_samples(&p).unwrap();
        assert_eq!(t, vec![0.001, 0.002]);
        assert!((h - 0.001).abs() < 1e-15);
        assert_eq!(s[1].ws_yaw_rate, 0.5);
    }

    #[test]
    fn missing_columns_and_uneven_steps_are_named() {
        let p = write("missing", "time,speed,ws_acc_y\n0,1,2\n1,1,2\n2,1,2\n");
        let e = read_samples(&p).unwrap_err();
        assert!(e.contains("ws_yaw_rate") && e.contains("in.csv"), "{e}");
        let p = write(
            "uneven",
            "time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n0,1,0,0,0\n0.001,1,0,0,0\n0.003,1,0,0,0\n",
        );
        let e = read_samples(&p).unwrap_err();
        assert!(e.contains("line 4") && e.contains("constant step"), "{e}");
    }
}
