#![allow(clippy::result_large_err)]
//! The `orchestrator` command line. See `orchestrator --help` and the README.
//!
//! Exit codes: 0 success; 1 an I/O failure (results cannot be written); 2 bad input (a file,
//! the system description, a connection, a parameter, the command line); 3 an FMU failed during
//! the run (results recorded until then are kept).

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
    about = "A fast, strict FMI 2.0 co-simulation master, and the alignment-estimation studies"
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
    /// Input signals: CSV with a `time` column and one column per input variable.
    #[arg(long)]
    input: Option<PathBuf>,
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
    let summary = cosim.run(&opts)?;
    report(&summary);
    if is_standard && let Some(results) = &summary.results {
        standard_case_metrics(results)?;
    }
    Ok(())
}

/// The standard case's accuracy: `metrics.json` beside results.csv, and the table on stdout.
fn standard_case_metrics(results: &Path) -> Result<(), RunError> {
    use orchestrator::study::standard;
    let cols = standard::Columns::read(results).map_err(RunError::Io)?;
    let m = match standard::evaluate_results(&cols) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("no accuracy metrics: {e}");
            return Ok(());
        }
    };
    let path = results.with_file_name("metrics.json");
    std::fs::write(&path, standard::metrics_json(&m))
        .map_err(|e| RunError::Io(format!("cannot write {}: {e}", path.display())))?;
    println!(
        "Alignment estimate against the truth (EN 13848 bands; {}):",
        path.display()
    );
    print!("{}", standard::table(&m));
    Ok(())
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
        progress: !args.common.quiet,
        log: log_config(&args.common),
    };
    let summary = orchestrator::simulate::simulate(&args.fmu, signals.as_ref(), &settings, &opts)?;
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

fn main() -> ExitCode {
    let cli = Cli::parse();
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
