//! `alignment-studies design-response`: fits the vehicle's response to the design line for the
//! estimator's design correction and writes it (`fmu-estimator/resources/design-response.toml`
//! for the ML95).

use super::{Report, StudyFmus};
use crate::Error;
use crate::study::design::{self, DesignFitOptions};
use clap::Args;
use std::path::PathBuf;

/// `design-response`'s options.
#[derive(Args, Clone, Debug)]
pub struct DesignArgs {
    /// The vehicle FMU (its `--set vehicle.NAME=VALUE` settings apply to every run).
    #[command(flatten)]
    pub fmus: StudyFmus,
    /// Bank speeds in m/s, ascending.
    #[arg(long, value_delimiter = ',', default_value = "5,7.5,10,12.5,15,17.5,20,22.5,25,27.5,30", allow_negative_numbers = true, value_parser = super::speed)]
    pub speeds: Vec<f64>,
    /// Random training lines per speed.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub lines: u32,
    /// Cells of history (the FIR's memory is this times 0.2 m).
    #[arg(long, default_value_t = 250, value_parser = clap::value_parser!(u32).range(1..=2000))]
    pub taps: u32,
    /// The file to write.
    #[arg(long, default_value = "out/design-response.toml")]
    pub out: PathBuf,
    /// Replace an existing file at --out that this command did not write.
    #[arg(long)]
    pub force: bool,
    /// No progress lines.
    #[arg(long)]
    pub quiet: bool,
}

/// How every file this command writes begins.
const MARK: &[u8] = b"# The vehicle's response to the design line";

/// Fits and reports ([`design::fit`]).
pub fn execute(a: &DesignArgs) -> Result<Report, Error> {
    if a.speeds.windows(2).any(|w| w[1] <= w[0]) {
        return Err(Error::input(format!(
            "--speeds {:?}: the bank speeds must be ascending",
            a.speeds
        )));
    }
    let inputs = [a.fmus.fmus.vehicle.as_path()];
    let guard = super::guard(&a.out, &inputs, a.force, Some(MARK))?;
    let fmus = a.fmus.fmus()?;
    let options = DesignFitOptions {
        speeds: a.speeds.clone(),
        lines: a.lines as usize,
        taps: a.taps as usize,
        ..DesignFitOptions::default()
    };
    let work = tempfile::tempdir().map_err(|e| Error::Io(format!("a work directory: {e}")))?;
    let quiet = a.quiet;
    let say = move |m: &str| {
        if !quiet {
            eprintln!("{m}");
        }
    };
    let started = std::time::Instant::now();
    let (model, quality) = design::fit(&fmus, &options, work.path(), &say)?;
    let header = format!(
        "The vehicle's response to the design line (alignment-studies design-response):\n\
         vehicle '{}', {} random lines of {} m per speed (seeds {}..; ridge chosen on two more), {} taps of {} m.\n\
         Read by the estimator FMU's design_response_file; format: fmu-estimator/src/design.rs.",
        model.vehicle, options.lines, options.length, options.seed, options.taps, options.cell
    );
    let mut md = String::from(
        "# Design response\n\nValidation residual rms against the rms of what was to fit (after the rigid part), and the ridge chosen, per bank speed:\n\n| speed m/s | ws_acc_y m/s2 | ws_yaw_rate rad/s | frame_acc_y m/s2 | ws_roll_rate rad/s | ws_y m (the shift, for the flange check) |\n|---|---|---|---|---|---|\n",
    );
    for q in &quality {
        md.push_str(&format!("| {} |", q.speed));
        for (ridge, f) in q.rms {
            md.push_str(&format!(" {:.2e} of {:.2e} ({ridge:.0e}) |", f[2], f[3]));
        }
        md.push('\n');
    }
    md.push_str(&format!(
        "\nEnvelope: curvature up to {:.2e} 1/m, uncompensated lateral acceleration up to {:.2} m/s2, predicted shift up to the flange clearance {} m.\n",
        model.max_curvature, model.max_uncompensated, model.flange_clearance
    ));
    let mut report = Report {
        markdown: md,
        note: format!(
            "design response fitted in {:.0} s, written to {}",
            started.elapsed().as_secs_f64(),
            a.out.display()
        ),
        ..Report::default()
    };
    report.file(a.out.clone(), design::to_toml(&model, &header));
    report.guarded.push(guard);
    Ok(report)
}
