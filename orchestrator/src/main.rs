#![allow(clippy::result_large_err)]
//! The `orchestrator` command line. See `orchestrator --help` and `docs/orchestrator.md`.
//!
//! Exit codes: 0 success; 1 an I/O failure (results cannot be written); 2 bad input (a file,
//! the system description, a connection, a parameter, the command line); 3 an FMU failed during
//! the run (results recorded until then are kept); 130 `run` or `simulate` interrupted by
//! Ctrl-C (SIGINT), SIGTERM or SIGHUP: the run stops at the next step boundary and keeps the
//! results recorded until then (a second signal quits at once, leaving `results.csv.partial`).

use clap::{Args, Parser, Subcommand, ValueEnum};
use fmi_abi::types::fmi2Status;
use fmi_import::LogConfig;
use orchestrator::master::{Algorithm, Cosimulation, RunError, RunOptions};
use orchestrator::system::{Endpoint, System};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "orchestrator",
    version,
    about = "A fast, strict FMI 2.0 co-simulation master"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a system: an SSP file (.ssd or .ssp), or the built-in standard case
    /// (vehicle -> estimator) when no file is given.
    Run(RunArgs),
    /// Run one FMU, optionally with input signals from a CSV file (like `fmpy simulate`).
    Simulate(SimulateArgs),
    /// Describe an FMU: identity, capabilities, default experiment and variables (like `fmpy info`).
    Info {
        /// The .fmu file.
        fmu: PathBuf,
    },
    /// Write a system (by default the standard case) as an .ssp archive that other masters
    /// (libcosim, OMSimulator, fmpy) can run.
    ExportSsp {
        /// The .ssp file to write.
        out: PathBuf,
        /// An SSP system to re-export instead of the standard case.
        #[arg(long)]
        system: Option<PathBuf>,
        #[command(flatten)]
        fmus: StandardFmus,
    },
}

#[derive(Args, Clone)]
struct StandardFmus {
    /// The vehicle FMU of the standard case.
    #[arg(long, default_value = "target/fmu/RailVehicle.fmu")]
    vehicle: PathBuf,
    /// The estimator FMU of the standard case.
    #[arg(long, default_value = "target/fmu/AlignmentEstimator.fmu")]
    estimator: PathBuf,
}

#[derive(Args, Clone)]
struct Common {
    /// Stop time [s] (default: the system's, else 20 s for the standard case).
    #[arg(long)]
    stop: Option<f64>,
    /// Communication step [s] (default: the system's, else the first FMU's default step).
    #[arg(long)]
    step: Option<f64>,
    /// Start time [s].
    #[arg(long, default_value_t = 0.0)]
    start: f64,
    /// Output directory for results.csv and results.units.csv.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Record only these variables (component.variable, repeatable or comma-separated); default: every output.
    #[arg(long, value_delimiter = ',')]
    record: Vec<String>,
    /// Recording interval [s], a whole number of steps (default: every step).
    #[arg(long)]
    interval: Option<f64>,
    /// Do not write results.
    #[arg(long)]
    no_record: bool,
    /// Lowest FMU log status shown.
    #[arg(long, value_enum, default_value_t = LogLevel::Warning)]
    log_level: LogLevel,
    /// FMU log categories to switch on (with --log-level info), comma-separated.
    #[arg(long, value_delimiter = ',')]
    log_categories: Vec<String>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

#[derive(Args)]
struct RunArgs {
    /// An SSP system (.ssd or .ssp); the built-in standard case if absent.
    system: Option<PathBuf>,
    #[command(flatten)]
    fmus: StandardFmus,
    #[command(flatten)]
    common: Common,
    /// Set a parameter before initialization: component.variable=value (repeatable).
    #[arg(long = "set", value_name = "COMPONENT.VARIABLE=VALUE")]
    set: Vec<String>,
    /// Jacobi instead of Gauss-Seidel.
    #[arg(long)]
    jacobi: bool,
}

#[derive(Args)]
struct SimulateArgs {
    /// The .fmu file.
    fmu: PathBuf,
    /// Input signals: CSV with a `time` column and one column per input variable (Real
    /// continuous inputs interpolated; discrete, Integer, Enumeration and Boolean ones held).
    #[arg(long)]
    input: Option<PathBuf>,
    /// Replay a recorded results.csv exactly: the value set at t is the row of t + h (a
    /// recorded row t + h holds what the consumer read for the step from t). Without it the
    /// inputs are the rows at t, one step later than in the recorded run.
    #[arg(long, requires = "input")]
    replay: bool,
    #[command(flatten)]
    common: Common,
    /// Set a parameter before initialization: variable=value (repeatable).
    #[arg(long = "set", value_name = "VARIABLE=VALUE")]
    set: Vec<String>,
}

#[derive(Clone, Copy, ValueEnum)]
enum LogLevel {
    Info,
    Warning,
    Error,
}

fn log_config(c: &Common) -> LogConfig {
    let min_status = match c.log_level {
        LogLevel::Info => fmi2Status::OK,
        LogLevel::Warning => fmi2Status::Warning,
        LogLevel::Error => fmi2Status::Error,
    };
    LogConfig {
        min_status,
        debug_logging: matches!(c.log_level, LogLevel::Info),
        categories: (!c.log_categories.is_empty()).then(|| c.log_categories.clone()),
        ..LogConfig::default()
    }
}

fn split_assignment(s: &str) -> Result<(&str, &str), RunError> {
    s.split_once('=')
        .ok_or_else(|| RunError::Config(format!("--set {s}: expected NAME=VALUE")))
}

fn options(
    c: &Common,
    system: &System,
    cosim: &Cosimulation,
    default_stop: Option<f64>,
) -> Result<RunOptions, RunError> {
    let stop = c
        .stop
        .or(system.experiment.stop)
        .or(default_stop)
        .or_else(|| {
            cosim
                .model_descriptions()
                .first()
                .and_then(|m| m.default_experiment.as_ref())
                .and_then(|d| d.stop_time)
        })
        .ok_or_else(|| RunError::Config("no stop time: give --stop".into()))?;
    let step = c
        .step
        .or(system.experiment.step)
        .or_else(|| {
            cosim
                .model_descriptions()
                .first()
                .and_then(|m| m.default_experiment.as_ref())
                .and_then(|d| d.step_size)
        })
        .ok_or_else(|| RunError::Config("no communication step: give --step".into()))?;
    let record = if c.record.is_empty() {
        None
    } else {
        Some(
            c.record
                .iter()
                .map(|r| Endpoint::parse(r).map_err(RunError::Config))
                .collect::<Result<Vec<_>, _>>()?,
        )
    };
    Ok(RunOptions {
        start: c.start,
        stop,
        step,
        algorithm: Algorithm::GaussSeidel,
        out_dir: (!c.no_record).then(|| c.out.clone()),
        record,
        interval: c.interval,
        collect: false,
        progress: !c.quiet,
        log: log_config(c),
    })
}

fn load_system(
    path: Option<&Path>,
    fmus: &StandardFmus,
) -> Result<(System, Option<orchestrator::ssp::LoadedSystem>), RunError> {
    match path {
        None => Ok((System::standard_case(&fmus.vehicle, &fmus.estimator), None)),
        Some(p) => {
            let loaded = orchestrator::ssp::read(p).map_err(|e| RunError::Config(e.to_string()))?;
            Ok((loaded.system.clone(), Some(loaded)))
        }
    }
}

fn report(summary: &orchestrator::master::RunSummary) {
    if let Some(who) = &summary.ended_by {
        eprintln!(
            "'{who}' ended the simulation at t = {} s (fmi2DoStep returned fmi2Discard with fmi2Terminated): the run stops there",
            summary.final_time
        );
    }
    let per_step = summary.wall.as_secs_f64() / summary.steps.max(1) as f64 * 1e6;
    eprintln!(
        "{} steps to t = {} s in {:.3} s ({:.3} us per step){}",
        summary.steps,
        summary.final_time,
        summary.wall.as_secs_f64(),
        per_step,
        summary
            .results
            .as_ref()
            .map(|p| format!("; {} rows in {}", summary.rows, p.display()))
            .unwrap_or_default()
    );
}

fn run(args: RunArgs) -> Result<(), RunError> {
    let (system, _keep) = load_system(args.system.as_deref(), &args.fmus)?;
    let is_standard = args.system.is_none();
    let mut cosim = Cosimulation::load(system.clone())?;
    for s in &args.set {
        let (name, value) = split_assignment(s)?;
        let e = Endpoint::parse(name).map_err(|e| RunError::Config(format!("--set {s}: {e}")))?;
        cosim.set(&e, value)?;
    }
    let mut opts = options(&args.common, &system, &cosim, is_standard.then_some(20.0))?;
    if args.jacobi {
        opts.algorithm = Algorithm::Jacobi;
    }
    // The standard case is evaluated from the recorded table in memory, not read back.
    opts.collect = is_standard;
    let fmus: Vec<(&str, &Path)> = system
        .components
        .iter()
        .map(|c| (c.name.as_str(), c.source.as_path()))
        .collect();
    let files: &[&str] = if is_standard {
        &["results.csv", "results.units.csv"]
    } else {
        &["results.csv", "results.units.csv"]
    };
    let _out = hold_output(&args.common, files, &fmus, &args.set)?;
    let summary = cosim.run(&opts)?;
    report(&summary);
    Ok(())
}

/// The output directory of `run` or `simulate` (none with --no-record): locked for this
/// process, cleared of the previous run's outputs, its output files checked (no symlink, FIFO or
/// device is replaced) and the manifest written before the run, so that even a failed run's
/// partial results can be traced (`orchestrator::outdir`).
fn hold_output(
    common: &Common,
    files: &[&str],
    fmus: &[(&str, &Path)],
    settings: &[String],
) -> Result<Option<orchestrator::outdir::OutputDir>, RunError> {
    use orchestrator::outdir::{Manifest, OutputDir, fmu_record, refuse_special, rfc3339};
    if common.no_record {
        return Ok(None);
    }
    let io = |e: std::io::Error| {
        RunError::Io(format!(
            "cannot write results in {} (nothing was run): {e}",
            common.out.display()
        ))
    };
    let out = OutputDir::open(&common.out).map_err(io)?;
    for f in files {
        refuse_special(&out.path().join(f)).map_err(io)?;
    }
    let manifest = Manifest {
        program: concat!("orchestrator ", env!("CARGO_PKG_VERSION")).into(),
        command: std::env::args().collect(),
        settings: settings.to_vec(),
        fmus: fmus
            .iter()
            .map(|(c, p)| fmu_record(c, p))
            .collect::<Result<_, _>>()
            .map_err(io)?,
        time_utc: rfc3339(std::time::SystemTime::now()),
        files: files.iter().map(|f| f.to_string()).collect(),
    };
    out.write_manifest(&manifest).map_err(io)?;
    Ok(Some(out))
}


fn simulate(args: SimulateArgs) -> Result<(), RunError> {
    let signals = match &args.input {
        Some(p) => Some(orchestrator::simulate::Signals::read(p).map_err(RunError::Config)?),
        None => None,
    };
    let settings: Vec<(String, String)> = args
        .set
        .iter()
        .map(|s| split_assignment(s).map(|(a, b)| (a.to_string(), b.to_string())))
        .collect::<Result<_, _>>()?;
    let fmu = fmi_import::Fmu::open(&args.fmu)?;
    let de = fmu
        .model_description()
        .default_experiment
        .clone()
        .unwrap_or_default();
    drop(fmu);
    let stop = args
        .common
        .stop
        .or(signals.as_ref().and_then(|s| s.time.last().copied()))
        .or(de.stop_time);
    let step = args.common.step.or(de.step_size);
    let (Some(stop), Some(step)) = (stop, step) else {
        return Err(RunError::Config(
            "give --stop and --step (the FMU has no default experiment for them)".into(),
        ));
    };
    let record = if args.common.record.is_empty() {
        None
    } else {
        let name = args
            .fmu
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("fmu")
            .to_string();
        Some(
            args.common
                .record
                .iter()
                .map(|r| Endpoint::new(&name, r))
                .collect(),
        )
    };
    let opts = RunOptions {
        start: args.common.start,
        stop,
        step,
        algorithm: Algorithm::GaussSeidel,
        out_dir: (!args.common.no_record).then(|| args.common.out.clone()),
        record,
        interval: args.common.interval,
        collect: false,
        progress: !args.common.quiet,
        log: log_config(&args.common),
    };
    let _out = hold_output(
        &args.common,
        &["results.csv", "results.units.csv"],
        &[("fmu", args.fmu.as_path())],
        &args.set,
    )?;
    let summary = orchestrator::simulate::simulate(
        &args.fmu,
        signals.as_ref(),
        &settings,
        &opts,
        args.replay,
    )?;
    report(&summary);
    Ok(())
}

fn info(path: &Path) -> Result<(), RunError> {
    let archive = orchestrator::info::read_archive(path).map_err(RunError::Config)?;
    print!("{}", orchestrator::info::describe(path, &archive));
    Ok(())
}

fn export_ssp(out: &Path, system: Option<&Path>, fmus: &StandardFmus) -> Result<(), RunError> {
    let (system, _keep) = load_system(system, fmus)?;
    orchestrator::ssp::write_ssp(&system, out).map_err(|e| RunError::Config(e.to_string()))?;
    eprintln!("wrote {}", out.display());
    Ok(())
}


/// Ctrl-C (and SIGTERM, SIGHUP) during `run` or `simulate`: the first asks the master to stop
/// at the next step boundary and keep the results; a second one quits at once. The handler runs
/// on ctrlc's own thread, not in signal context, so printing and exiting there are safe.
fn stop_on_interrupt() {
    let installed = ctrlc::set_handler(|| {
        if orchestrator::master::request_stop() {
            eprintln!(
                "interrupted: stopping at the next step boundary and keeping the results (interrupt again to quit at once)"
            );
        } else {
            eprintln!("interrupted again: quitting at once");
            std::process::exit(130);
        }
    });
    if let Err(e) = installed {
        eprintln!("warning: cannot handle Ctrl-C ({e}); an interrupt will lose the results");
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if matches!(cli.command, Command::Run(_) | Command::Simulate(_)) {
        stop_on_interrupt();
    }
    let result = match cli.command {
        Command::Run(a) => run(a),
        Command::Simulate(a) => simulate(a),
        Command::Info { fmu } => info(&fmu),
        Command::ExportSsp { out, system, fmus } => export_ssp(&out, system.as_deref(), &fmus),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
