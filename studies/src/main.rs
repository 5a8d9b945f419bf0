#![allow(clippy::result_large_err)]
//! The `alignment-studies` command line: the estimation studies on top of the orchestrator.
//! See `alignment-studies --help` and `docs/studies.md`; each command is a module of
//! [`alignment_studies::cli`].
//!
//! Exit codes as `orchestrator`'s (docs/orchestrator.md): 0 success; 1 results cannot be
//! written or the output is refused (`orchestrator::outfile`); 2 bad input; 3 an FMU failed
//! during a run (a derailment of the vehicle is one); 130 `run` interrupted (Ctrl-C, SIGTERM,
//! SIGHUP: it stops at the next step boundary and keeps the results).

use alignment_studies::Error;
use alignment_studies::cli::cases::Group;
use alignment_studies::cli::{
    StudyArgs, calibrate, cases, design, fit, learn, orchestrator_summary, run, smooth, stage,
    taps, variants,
};
use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "alignment-studies",
    version,
    about = "The alignment-estimation studies on top of the orchestrator: the standard case with its accuracy, calibration, the paper's cases, variants, learned filters"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the standard case (standard.ssd: vehicle -> estimator, 20 s at 1 ms) through the
    /// master and write its accuracy, metrics.json, beside results.csv.
    Run(run::RunArgs),
    /// Identify the simplified model's (kx, cx, ky, cy) and calibrate Q and R on one track seed,
    /// and write the estimator's calibration file (rebuild the FMU afterwards: cargo xtask fmu).
    Calibrate(calibrate::CalibrateArgs),
    /// The standard case on held-out seeds.
    Standard(StudyArgs),
    /// The robustness cases (noise, vertical irregularity, conicity, Kalker coefficients) and
    /// the conicity sweep (0.05-0.4).
    Robustness(StudyArgs),
    /// The resonance cases at the vehicle's first lateral mode.
    Resonance(StudyArgs),
    /// Every case, in parallel. Each case runs with the paper's filter and with the FMU's
    /// default, the learned filter.
    All(StudyArgs),
    /// Beyond the paper: the estimator's options (alignment prior, steady-state gain, RTS
    /// smoother, speed following) against the paper's filter, at constant and variable speed.
    Variants(StudyArgs),
    /// The outside_training flag over 10 km runs: false alarms on the conditions the shipped
    /// taps were fitted for, detection on other vehicles and conditions.
    Envelope(StudyArgs),
    /// Fit the learned FIR smoother on one track seed and save it (JSON) for `smooth
    /// --learned`: taps from the run after its first 20 s, the split chosen on those.
    Learn(learn::LearnArgs),
    /// Fit the estimator FMU's learned filter (the tap bank, resources/learned.taps) in the
    /// metric's bands: every speed, with and without the roll-rate gyroscope, causal and with
    /// the fixed lags; ridge chosen on validation seeds (rebuild the FMU afterwards: cargo
    /// xtask fmu).
    Taps(taps::TapsArgs),
    /// Fit the long-wave stage of a tap bank: taps over 600 m of the band-passed sensors and
    /// the bank's own causal estimate, added to its causal output; writes the bank with it
    /// (rebuild the FMU afterwards: cargo xtask fmu).
    Stage(stage::StageArgs),
    /// Fit the estimator to a vehicle FMU in one directory: the simplified model's
    /// identification and Q/R calibration, the tap bank over speeds and contact conditions
    /// with that calibration, and report.md with the validation figures, the bank's envelope
    /// and the standard case on held-out seeds (use them with estimator.tap_file and
    /// estimator.calibration_file).
    Fit(fit::FitArgs),
    /// Fit the vehicle's response to the design line (curves and cant) for the estimator's
    /// design correction: the vehicle without irregularities on random curved lines at every
    /// bank speed, causal FIRs from the design's history to each sensor; writes the
    /// design_response_file (fmu-estimator/resources/design-response.toml for the ML95).
    DesignResponse(design::DesignArgs),
    /// Filter and smooth recorded sensor signals offline with the estimator (RTS smoother): a
    /// CSV with time, speed, ws_acc_y, ws_yaw_rate, frame_acc_y (e.g. a run's results.csv).
    Smooth(smooth::SmoothArgs),
}

/// Runs the command and writes what it produced.
fn execute(command: Command) -> Result<(), Error> {
    let say = |line: &str| println!("{line}");
    let report = match command {
        Command::Run(a) => {
            orchestrator::cli::run::stop_on_interrupt(&a.settings.common.interrupt);
            // The output directory stays locked until metrics.json is written.
            let done = run::execute(&a)?;
            eprintln!("{}", orchestrator_summary(&done.summary));
            return done.report.write();
        }
        Command::Smooth(a) => smooth::execute(&a)?,
        Command::Calibrate(a) => calibrate::execute(&a, &say)?,
        Command::Standard(a) => cases::execute(&a, &[Group::Standard], &say)?,
        Command::Robustness(a) => cases::execute(
            &a,
            &[Group::Robustness, Group::Conicity, Group::Vehicles],
            &say,
        )?,
        Command::Resonance(a) => cases::execute(&a, &[Group::Resonance], &say)?,
        Command::All(a) => cases::execute(&a, &Group::ALL, &say)?,
        Command::Envelope(a) => variants::envelope(&a, &say)?,
        Command::Variants(a) => variants::execute(&a, &say)?,
        Command::Learn(a) => learn::execute(&a)?,
        Command::DesignResponse(a) => design::execute(&a)?,
        Command::Taps(a) => taps::execute(&a, &|m| eprintln!("{m}"))?,
        Command::Stage(a) => stage::execute(&a, &|m| eprintln!("{m}"))?,
        Command::Fit(a) => {
            let md = fit::execute(&a, &|m| eprintln!("{m}"))?;
            println!("{md}");
            return Ok(());
        }
    };
    report.write()
}

fn main() -> ExitCode {
    match execute(Cli::parse().command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
