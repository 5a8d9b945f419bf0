//! `orchestrator run SYSTEM`: a system described in SSP, through the master.

use super::{Common, fmu_sources, progress_bar, split_assignment};
use crate::master::{Algorithm, Cosimulation, RunError, RunSummary, StopToken};
use crate::outdir::OutputDir;
use crate::system::{Endpoint, System};
use clap::Args;
use std::path::{Path, PathBuf};

/// `run`'s options.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// An SSP system (.ssd or .ssp), e.g. studies/standard.ssd (the vehicle -> estimator case).
    pub system: PathBuf,
    /// Run a component with this FMU instead of the system's source: COMPONENT=PATH (repeatable).
    #[arg(long = "fmu", value_name = "COMPONENT=PATH")]
    pub fmus: Vec<String>,
    /// What the run takes besides the system.
    #[command(flatten)]
    pub settings: Settings,
}

/// What a run of a given system takes from the command line.
#[derive(Args, Clone, Debug)]
pub struct Settings {
    /// The options every run shares.
    #[command(flatten)]
    pub common: Common,
    /// Set a parameter before initialization: component.variable=value (repeatable).
    #[arg(long = "set", value_name = "COMPONENT.VARIABLE=VALUE")]
    pub set: Vec<String>,
    /// Jacobi instead of Gauss-Seidel.
    #[arg(long)]
    pub jacobi: bool,
}

/// A finished run and its output directory, still locked (a caller may add files the
/// manifest lists, as `alignment-studies run` adds metrics.json).
pub struct Finished {
    /// What the run did.
    pub summary: RunSummary,
    /// The output directory, locked until this is dropped; none with `--no-record`.
    pub out: Option<OutputDir>,
}

/// Reads the system (with the `--fmu` replacements) and runs it.
pub fn run(args: &RunArgs) -> Result<Finished, RunError> {
    let sources = fmu_sources(&args.fmus)?;
    let loaded = crate::ssp::read_with(&args.system, &sources)
        .map_err(|e| RunError::Config(e.to_string()))?;
    let program = concat!("orchestrator ", env!("CARGO_PKG_VERSION"));
    run_system(&loaded.system, &args.settings, program, &[], false)
}

/// Runs `system` with the command line's settings; `extra` names the files besides the results
/// the caller will write into the output directory (listed in the manifest, so the next run
/// there removes them), `collect` keeps the rows in memory ([`RunSummary::table`]).
pub fn run_system(
    system: &System,
    s: &Settings,
    program: &str,
    extra: &[&str],
    collect: bool,
) -> Result<Finished, RunError> {
    let mut cosim = Cosimulation::load(system.clone())?;
    for a in &s.set {
        let (name, value) = split_assignment(a)?;
        let e = Endpoint::parse(name).map_err(|e| RunError::Config(format!("--set {a}: {e}")))?;
        cosim.set(&e, value)?;
    }
    let mut opts = s.common.options(system, &cosim)?;
    if s.jacobi {
        opts.algorithm = Algorithm::Jacobi;
    }
    opts.collect = collect;
    let fmus: Vec<(&str, &Path)> = system
        .components
        .iter()
        .map(|c| (c.name.as_str(), c.source.as_path()))
        .collect();
    let out = s
        .common
        .hold_output(&mut opts, program, extra, &fmus, &s.set)?;
    let summary = cosim
        .runner(&opts)
        .progress(&mut progress_bar())
        .stop_on(&s.common.interrupt)
        .run()?;
    Ok(Finished { summary, out })
}

/// Ctrl-C (and SIGTERM, SIGHUP) during a run (`run`, `simulate`, `alignment-studies run`): the
/// first sets `stop`, the token of the command's run ([`super::Common::interrupt`]), so that
/// it stops at the next step boundary and keeps the results; a second one quits at once. The
/// handler runs on ctrlc's own thread, not in signal context, so printing and exiting there
/// are safe. A process installs it once.
pub fn stop_on_interrupt(stop: &StopToken) {
    let stop = stop.clone();
    let installed = ctrlc::set_handler(move || {
        if stop.stop() {
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
