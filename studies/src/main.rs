#![allow(clippy::result_large_err)]
//! The `alignment-studies` command line: the estimation studies on top of the orchestrator.
//! See `alignment-studies --help` and `docs/studies.md`.
//!
//! Exit codes as `orchestrator`'s: 0 success; 1 results cannot be written; 2 bad input; 3 an FMU
//! failed during a run.

use clap::{Args, Parser, Subcommand};
use orchestrator::master::RunError;
use orchestrator::system::Endpoint;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "alignment-studies",
    version,
    about = "The alignment-estimation studies: calibration, the paper's cases, variants, learned filters"
)]
struct Cli {
    #[command(subcommand)]
    command: StudyCommand,
}

/// The track seed the shipped estimator is identified and calibrated on.
const CALIBRATION_SEED: u32 = 101;

#[derive(Subcommand)]
enum StudyCommand {
    /// Identify the simplified model's (kx, cx, ky, cy) and calibrate Q and R on one track seed,
    /// and write the estimator's calibration file (rebuild the FMU afterwards: cargo xtask fmu).
    Calibrate {
        #[command(flatten)]
        fmus: StudyFmus,
        /// The calibration file to write (default: the shipped one,
        /// fmu-estimator/resources/calibration.toml; required with --set, which makes a
        /// calibration for another vehicle).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Track seed of the identification and calibration runs (not the vehicle's default
        /// track, seed 1, so that a plain `run` of the standard case is a held-out track).
        #[arg(long, default_value_t = CALIBRATION_SEED)]
        seed: u32,
        /// Directory for the figure of the identification (model_adjustment.svg).
        #[arg(long, default_value = "out/study")]
        plots: PathBuf,
    },
    /// The standard case on held-out seeds.
    Standard(StudyArgs),
    /// The robustness cases (noise, vertical irregularity, conicity, Kalker coefficients).
    Robustness(StudyArgs),
    /// The resonance cases at the vehicle's first lateral mode.
    Resonance(StudyArgs),
    /// Every case, in parallel.
    All(StudyArgs),
    /// Beyond the paper: the estimator's options (alignment prior, steady-state gain, RTS
    /// smoother, speed following) against the paper's filter, at constant and variable speed.
    Variants(StudyArgs),
    /// Fit the learned FIR smoother on one track seed and save it (JSON) for `orchestrator
    /// smooth --learned`: taps from the run after its first 20 s, the split chosen on those.
    Learn(LearnArgs),
    /// Fit the estimator FMU's learned filter (the tap bank, resources/learned.taps) in the
    /// metric's bands: every speed, with and without the roll-rate gyroscope, causal and with
    /// the fixed lags; ridge chosen on validation seeds (rebuild the FMU afterwards: cargo
    /// xtask fmu).
    Taps(TapsArgs),
    /// Filter and smooth recorded sensor signals offline with the estimator (RTS smoother): a
    /// CSV with time, speed, ws_acc_y, ws_yaw_rate, frame_acc_y (e.g. a run's results.csv).
    Smooth {
        /// The CSV of recorded signals.
        input: PathBuf,
        /// The CSV to write (time, distance, alignment_filtered[_std], alignment_smoothed[_std]).
        #[arg(long, default_value = "out/smoothed.csv")]
        out: PathBuf,
        /// Set an estimator parameter: name=value (repeatable), e.g. alignment_model=3.
        #[arg(long = "set", value_name = "PARAMETER=VALUE")]
        set: Vec<String>,
        /// A calibration file instead of the one built into the estimator.
        #[arg(long)]
        calibration: Option<PathBuf>,
        /// A learned smoother (from `study learn`): adds the columns alignment_learned and
        /// alignment_hybrid.
        #[arg(long)]
        learned: Option<PathBuf>,
    },
}

/// `study taps`' options.
#[derive(Args, Clone)]
struct TapsArgs {
    #[command(flatten)]
    fmus: StandardFmus,
    /// Speeds of the bank [m/s].
    #[arg(long, value_delimiter = ',', default_value = "5,10,15,20,25,30")]
    speeds: Vec<f64>,
    /// Kalker-coefficient scales of the training runs (one run each): each condition gets its
    /// own taps, blended at run time by the contact model fitted with them.
    #[arg(long, value_delimiter = ',', default_value = "1,0.75,0.5")]
    kalker_scales: Vec<f64>,
    /// One set of taps fitted on every condition's runs at once, no contact model.
    #[arg(long)]
    pooled: bool,
    /// Lags of the fixed-lag entries [m].
    #[arg(long, value_delimiter = ',', default_value = "10")]
    lags: Vec<f64>,
    /// Fit only the three-sensor taps (the vehicle has no ws_roll_rate).
    #[arg(long)]
    no_roll_rate: bool,
    /// Track seed of the training runs.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    seed: u32,
    /// Track seeds the ridge is chosen on (neither the training seed nor an evaluation seed).
    #[arg(long, value_delimiter = ',', default_value = "102,103,104,105,106")]
    validation_seeds: Vec<u32>,
    /// The file to write.
    #[arg(long, default_value = "fmu-estimator/resources/learned.taps")]
    out: PathBuf,
}

/// `study learn`'s options.
#[derive(Args, Clone)]
struct LearnArgs {
    #[command(flatten)]
    fmus: StandardFmus,
    /// Track seed of the training run.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    seed: u32,
    /// Length of the training run [s], more than 40.
    #[arg(long, default_value_t = 1000.0)]
    stop: f64,
    /// Look-ahead [m] (rounded to grid points) for an on-board filter combined with the
    /// paper's causal filter, 0 for a causal one; absent: the offline smoother (60 m each
    /// way) with the shaping filter's RTS smoother.
    #[arg(long)]
    lag: Option<f64>,
    /// Grid step along the track [m] the sensors are decimated to (finer costs more: the
    /// window is 60 m whatever the step).
    #[arg(long, default_value_t = alignment_studies::study::learned::GRID)]
    grid: f64,
    /// Kalker-coefficient scales of the vehicle to train on, one run each (e.g. 1,0.5 for a
    /// filter robust to the wheel-rail contact; 1: the vehicle as it is).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    kalker_scales: Vec<f64>,
    /// Constant speed of the training runs [m/s] (default: the vehicle's, 20); the filter
    /// applies to records at this speed only.
    #[arg(long)]
    speed: Option<f64>,
    /// The file to write.
    #[arg(long, default_value = "out/learned.json")]
    out: PathBuf,
}

/// The studies' FMUs and the user's settings for them.
#[derive(Args, Clone)]
struct StudyFmus {
    #[command(flatten)]
    fmus: StandardFmus,
    /// Set a parameter of the vehicle or the estimator in every run of the study:
    /// vehicle.NAME=VALUE or estimator.NAME=VALUE (repeatable), e.g. vehicle.vehicle=manchester.toml
    /// with estimator.calibration_file=/abs/path/cal.toml from `study calibrate`. The seeds and
    /// the cases' conditions stay the study's.
    #[arg(long = "set", value_name = "COMPONENT.VARIABLE=VALUE")]
    set: Vec<String>,
}

#[derive(Args, Clone)]
struct StudyArgs {
    #[command(flatten)]
    fmus: StudyFmus,
    /// Held-out track seeds (never the calibration seed).
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5")]
    seeds: Vec<u32>,
    /// The seed the estimator was calibrated on, refused among the evaluation seeds.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    calibration_seed: u32,
    /// Output directory for the JSON results and report.md.
    #[arg(long, default_value = "out/study")]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
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

fn split_assignment(s: &str) -> Result<(&str, &str), RunError> {
    s.split_once('=')
        .ok_or_else(|| RunError::Config(format!("--set {s}: expected NAME=VALUE")))
}

fn study_fmus(f: &StandardFmus) -> alignment_studies::study::runs::Fmus {
    alignment_studies::study::runs::Fmus::new(f.vehicle.clone(), f.estimator.clone())
}

/// The study's FMUs with the user's `--set` settings.
fn study_fmus_with(f: &StudyFmus) -> Result<alignment_studies::study::runs::Fmus, RunError> {
    let mut fmus = study_fmus(&f.fmus);
    for s in &f.set {
        let (name, value) = split_assignment(s)?;
        let e = Endpoint::parse(name).map_err(|e| RunError::Config(format!("--set {s}: {e}")))?;
        fmus.set(&e.component, &e.variable, value)
            .map_err(|e| RunError::Config(format!("--set {s}: {e}")))?;
    }
    Ok(fmus)
}

const STANDARD: &str = "Standard case";
const ROBUSTNESS: &str = "Robustness";
const RESONANCE: &str = "Resonance";

fn study(what: StudyCommand) -> Result<(), RunError> {
    use alignment_studies::study::{calibrate, cases, identify, plot, runs};
    let args = match what {
        StudyCommand::Calibrate {
            fmus,
            out,
            seed,
            plots,
        } => {
            if let Some(s) = fmus.set.iter().find(|s| s.starts_with("estimator.")) {
                return Err(RunError::Config(format!(
                    "--set {s}: study calibrate builds the estimator's parameters and noise itself; --set takes vehicle settings here"
                )));
            }
            let out = match (out, fmus.set.is_empty()) {
                (Some(out), _) => out,
                (None, true) => PathBuf::from("fmu-estimator/resources/calibration.toml"),
                (None, false) => {
                    return Err(RunError::Config(
                        "--out is required with --set: a calibration for another vehicle must not replace the shipped one".into(),
                    ));
                }
            };
            let fmus = study_fmus_with(&fmus)?;
            let vehicle = fmus.vehicle_params().map_err(RunError::Config)?;
            let id = identify::identify(&fmus, &vehicle, seed, runs::STOP, runs::STEP)
                .map_err(RunError::Config)?;
            let p = &id.params;
            println!(
                "identified on seed {seed} ({} evaluations): kx {:.4e} N/m, cx {:.4e} N s/m, ky {:.4e} N/m, cy {:.4e} N s/m (Table 2: 7.95e5, 1.47e4, 4.12e6, 1.41e5)",
                id.evaluations, p.kx, p.cx, p.ky, p.cy
            );
            println!(
                "misfit J_ls {:.4} (with Table 2's values {:.4})",
                id.cost, id.cost_table_2
            );
            std::fs::create_dir_all(&plots)
                .map_err(|e| RunError::Io(format!("cannot create {}: {e}", plots.display())))?;
            let figure = plots.join("model_adjustment.svg");
            plot::model_adjustment(&figure, &id).map_err(RunError::Io)?;
            println!("wrote {}", figure.display());
            let cal = calibrate::calibrate(&fmus, &id.params, seed, runs::STOP, runs::STEP)
                .map_err(RunError::Config)?;
            let r = cal.r.diagonal().map(f64::sqrt);
            println!(
                "calibrated on seed {seed}: sqrt(diag R) = [{:.3e}, {:.3e}, {:.3e}, {:.3e}]",
                r[0], r[1], r[2], r[3]
            );
            let cal = calibrate::tune(&fmus, &cal, runs::STOP).map_err(RunError::Config)?;
            println!(
                "tuned on seed {seed}: virtual measurement variance x {:e}, alignment process noise x {:e}: whole-band Jrel there {:.4}",
                cal.virtual_scale,
                cal.xi_scale,
                cal.tuned_jrel.unwrap_or(f64::NAN)
            );
            let cal = calibrate::tune_prior(&fmus, &cal).map_err(RunError::Config)?;
            println!(
                "8-state prior (integrated random walk) on seed {seed}: prior_sigma_xi {} m (whole-band Jrel there {:.4})",
                cal.prior_sigma_xi.unwrap_or(f64::NAN),
                cal.prior_jrel.unwrap_or(f64::NAN)
            );
            let text = calibrate::to_toml(&cal, seed, calibrate::PROVENANCE);
            std::fs::write(&out, text)
                .map_err(|e| RunError::Io(format!("cannot write {}: {e}", out.display())))?;
            println!(
                "wrote {} (rebuild the estimator FMU: cargo xtask fmu)",
                out.display()
            );
            return Ok(());
        }
        StudyCommand::Standard(a) => (a, vec!["standard"]),
        StudyCommand::Robustness(a) => (a, vec!["robustness"]),
        StudyCommand::Resonance(a) => (a, vec!["resonance"]),
        StudyCommand::All(a) => (a, vec!["standard", "robustness", "resonance"]),
        StudyCommand::Variants(a) => return study_variants(&a),
        StudyCommand::Learn(a) => return study_learn(&a),
        StudyCommand::Taps(a) => return study_taps(&a),
        StudyCommand::Smooth { .. } => unreachable!("main runs smooth"),
    };
    let (a, groups) = args;
    if a.seeds.contains(&a.calibration_seed) {
        return Err(RunError::Config(format!(
            "seed {} is the calibration seed: accuracy must be measured on other tracks",
            a.calibration_seed
        )));
    }
    let fmus = study_fmus_with(&a.fmus)?;
    let estimator = fmi_import::Fmu::open(&fmus.estimator)?;
    // The filter's conicity, which the robustness case lowers by 10 %: the user's (or their
    // calibration file's) if set, else the FMU's default.
    let alpha = match estimator
        .model_description()
        .variable("alpha")
        .map(|v| &v.kind)
    {
        Some(model_description::VariableKind::Real(r)) => r.start.unwrap_or(0.1),
        _ => 0.1,
    };
    let alpha = fmus.estimator_number("alpha").unwrap_or(alpha);
    drop(estimator);
    let params = fmus.vehicle_params().map_err(RunError::Config)?;
    let conicity = params.wheelset.conicity;
    let vehicle = fmu_vehicle::dynamics::Vehicle::new(
        params,
        conicity,
        fmu_vehicle::dynamics::ContactOptions::default(),
    );
    let mut plan: Vec<(&str, Vec<cases::Case>)> = vec![];
    for g in groups {
        match g {
            "standard" => plan.push((STANDARD, vec![cases::standard()])),
            "robustness" => plan.push((ROBUSTNESS, cases::robustness(alpha))),
            _ => {
                let mode = fmu_vehicle::modal::modes(&vehicle, 20.0)
                    .first_lateral()
                    .ok_or_else(|| {
                        RunError::Config(
                            "the vehicle has no lightly damped lateral mode at 20 m/s".into(),
                        )
                    })?;
                println!(
                    "first lateral mode of the vehicle at 20 m/s: {:.3} Hz (damping {:.3}): wavelength {:.2} m",
                    mode.frequency,
                    mode.damping,
                    20.0 / mode.frequency
                );
                plan.push((RESONANCE, cases::resonance(mode.frequency, 20.0)));
            }
        }
    }
    let total: usize = plan.iter().map(|(_, c)| c.len()).sum::<usize>() * a.seeds.len();
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(total as u64)
    };
    let started = std::time::Instant::now();
    let all: Vec<cases::Case> = plan.iter().flat_map(|(_, c)| c.iter().cloned()).collect();
    let results =
        cases::run_cases(&fmus, &all, &a.seeds, &|| bar.inc(1)).map_err(RunError::Config)?;
    bar.finish_and_clear();
    std::fs::create_dir_all(&a.out)
        .map_err(|e| RunError::Io(format!("cannot create {}: {e}", a.out.display())))?;
    let mut report = String::from("# Alignment estimation study\n\n");
    let mut offset = 0;
    for (title, group) in &plan {
        let slice = &results[offset..offset + group.len()];
        offset += group.len();
        let md = cases::markdown(title, slice);
        println!("{md}");
        report.push_str(&md);
        report.push('\n');
        let file = a
            .out
            .join(format!("{}.json", title.to_lowercase().replace(' ', "_")));
        let json = serde_json::to_string_pretty(slice).unwrap_or_default();
        std::fs::write(&file, json)
            .map_err(|e| RunError::Io(format!("cannot write {}: {e}", file.display())))?;
        match *title {
            STANDARD => {
                // The time series and figures of the first held-out seed (run once more: the
                // parallel runs keep only the metrics).
                let seed = a.seeds[0];
                let table = cases::run_seed_table(&fmus, &group[0], seed, runs::STOP)
                    .map_err(RunError::Config)?;
                let ts = plot::TimeSeries::from_table(&table).map_err(RunError::Config)?;
                let csv = format!("standard_seed{seed}.csv");
                ts.write_csv(&a.out.join(&csv)).map_err(RunError::Io)?;
                let heading = format!("standard case, seed {seed}");
                plot::estimate_vs_truth(
                    &a.out.join("standard_alignment.svg"),
                    &ts.distance,
                    &ts.estimate,
                    &ts.truth,
                    &format!("estimated vs true alignment, {heading}"),
                )
                .map_err(RunError::Io)?;
                plot::spectra(
                    &a.out.join("standard_spectra.svg"),
                    &ts.distance,
                    &ts.estimate,
                    &ts.truth,
                    &format!("amplitude spectra, {heading}"),
                )
                .map_err(RunError::Io)?;
                report.push_str(&format!(
                    "Seed {seed}: time series [{csv}]({csv}).\n\n![estimated vs true alignment](standard_alignment.svg)\n\n![amplitude spectra](standard_spectra.svg)\n\n"
                ));
            }
            ROBUSTNESS | RESONANCE => {
                let svg = format!("{}.svg", title.to_lowercase());
                plot::case_bars(&a.out.join(&svg), slice, &format!("{title}: Jrel per band"))
                    .map_err(RunError::Io)?;
                report.push_str(&format!("![{title}: Jrel per band]({svg})\n\n"));
            }
            _ => {}
        }
    }
    let report_path = a.out.join("report.md");
    std::fs::write(&report_path, report)
        .map_err(|e| RunError::Io(format!("cannot write {}: {e}", report_path.display())))?;
    eprintln!(
        "{total} runs in {:.1} s; report in {}",
        started.elapsed().as_secs_f64(),
        report_path.display()
    );
    Ok(())
}

fn study_variants(a: &StudyArgs) -> Result<(), RunError> {
    use alignment_studies::study::variants;
    if a.seeds.contains(&a.calibration_seed) {
        return Err(RunError::Config(format!(
            "seed {} is the calibration seed: accuracy must be measured on other tracks",
            a.calibration_seed
        )));
    }
    if let Some(s) = a.fmus.set.first() {
        return Err(RunError::Config(format!(
            "--set {s}: study variants runs the estimator offline with its shipped calibration and the ML95 vehicle; --set is for calibrate, standard, robustness, resonance and all"
        )));
    }
    let fmus = study_fmus(&a.fmus.fmus);
    let started = std::time::Instant::now();
    let cfg = |e: String| RunError::Config(e);
    use variants::Conditions;
    let calibration =
        variants::record_seeds(&fmus, &[a.calibration_seed], Conditions::Standard).map_err(cfg)?;
    let (irw, irw_j) = variants::tune_prior_sigma(&calibration[0], 2, &[], None).map_err(cfg)?;
    let (shaping, shaping_j) =
        variants::tune_prior_sigma(&calibration[0], 3, &[], None).map_err(cfg)?;
    println!(
        "prior_sigma_xi chosen on the calibration seed {}: integrated random walk {irw} m (whole Jrel there {irw_j:.3}), shaping filter {shaping} m ({shaping_j:.3})",
        a.calibration_seed
    );
    let tuned = variants::Tuned {
        irw_sigma_xi: irw,
        shaping_sigma_xi: shaping,
    };
    use alignment_studies::study::learned::{
        GRID, Lookahead, default_partner, kalker_label, learn, provenance, training_runs,
    };
    let compared = variants::variants(&tuned);
    // The learned filters, each with its Kalman partner (the shaping filter's RTS smoother
    // offline, the paper's causal filter on board), fitted on the calibration seed: on the
    // vehicle as it is, and on it and the same with its Kalker coefficients halved (robust).
    let (runs, _) = training_runs(
        &fmus,
        a.calibration_seed,
        variants::LEARNING_STOP,
        &[1.0, 0.5],
        None,
    )
    .map_err(cfg)?;
    let mut learned = vec![];
    for scales in [&[1.0][..], &[1.0, 0.5][..]] {
        let from = provenance(&fmus, a.calibration_seed, variants::LEARNING_STOP, scales);
        let trained = format!(
            "fitted on the calibration seed, Kalker {} %",
            kalker_label(scales)
        );
        let forms = [
            (Lookahead::Smoother, GRID),
            (Lookahead::FixedLag(variants::LAG), GRID),
        ];
        // On the nominal vehicle only, the causal form and the shortest look-ahead, on a finer
        // grid (their anti-alias filter's delay is a fraction of a metre): what a causal linear
        // estimator of the three sensors reaches (docs/cross-level.md section 6).
        let near_causal =
            variants::NEAR_CAUSAL.map(|lag| (Lookahead::FixedLag(lag), variants::FINE_GRID));
        let extra = if scales.len() == 1 {
            &near_causal[..]
        } else {
            &[]
        };
        for &(lookahead, grid) in forms.iter().chain(extra) {
            let partner = default_partner(lookahead, shaping);
            let (l, j) =
                learn(&runs[..scales.len()], &from, lookahead, grid, partner).map_err(cfg)?;
            println!(
                "learned FIR ({lookahead:?}) from {from}: split {} m (mean whole Jrel there {j:.3}) with {}",
                l.split, l.partner.name
            );
            learned.push((l, trained.clone()));
        }
    }
    let with_learned =
        |records: &[variants::Record]| -> Result<Vec<variants::VariantResult>, RunError> {
            let mut out = variants::compare(records, &compared).map_err(cfg)?;
            for (l, trained) in &learned {
                out.extend(variants::compare_learned(records, l, trained).map_err(cfg)?);
            }
            Ok(out)
        };
    let constant = variants::record_seeds(&fmus, &a.seeds, Conditions::Standard).map_err(cfg)?;
    let at_constant = with_learned(&constant)?;
    let flat = variants::record_seeds(&fmus, &a.seeds, Conditions::NoVertical).map_err(cfg)?;
    let at_flat = with_learned(&flat)?;
    let kalker = variants::record_seeds(&fmus, &a.seeds, Conditions::KalkerHalf).map_err(cfg)?;
    let at_kalker = with_learned(&kalker)?;
    let variable =
        variants::record_seeds(&fmus, &a.seeds, Conditions::VariableSpeed).map_err(cfg)?;
    let at_variable =
        variants::compare(&variable, &variants::speed_variants(&tuned)).map_err(cfg)?;
    // The estimator FMU's learned filter (its default) against the paper's filter, as the FMU
    // computes them (the built-in tap bank), under the conditions the taps must hold in.
    let three_quarters =
        variants::record_seeds(&fmus, &a.seeds, Conditions::KalkerThreeQuarters).map_err(cfg)?;
    let fmu_rows = variants::learned_variants();
    let fmu_tables: Vec<(&str, &str, Vec<variants::VariantResult>)> = vec![
        (
            "standard",
            "Standard case (20 m/s, 20 s)",
            variants::compare(&constant, &fmu_rows).map_err(cfg)?,
        ),
        (
            "kalker_75",
            "Kalker coefficients at 75 % in the vehicle (between the taps' training conditions)",
            variants::compare(&three_quarters, &fmu_rows).map_err(cfg)?,
        ),
        (
            "kalker_50",
            "Kalker coefficients at 50 % in the vehicle",
            variants::compare(&kalker, &fmu_rows).map_err(cfg)?,
        ),
        (
            "variable_speed",
            "Variable speed (0 -> 20 -> 10 m/s, 50 s; the learned filter blends its taps by speed, below 5 m/s the paper's filter)",
            variants::compare(&variable, &fmu_rows).map_err(cfg)?,
        ),
    ];
    let mut md = String::from(
        "# Beyond the paper: estimator variants\n\n## The estimator FMU: learned filter (default) and the paper's filter\n\n",
    );
    for (_, title, rows) in &fmu_tables {
        md.push_str(&variants::markdown(title, &a.seeds, rows));
        md.push('\n');
    }
    md.push_str("## Options of the Kalman filter and the earlier learned FIR\n\n");
    md.push_str(&variants::markdown(
        "Standard case (20 m/s, 20 s)",
        &a.seeds,
        &at_constant,
    ));
    md.push('\n');
    md.push_str(&variants::markdown(
        "Standard case without vertical irregularities (vertical profile and cross-level off)",
        &a.seeds,
        &at_flat,
    ));
    md.push('\n');
    md.push_str(&variants::markdown(
        "Kalker coefficients -50 % in the vehicle (robustness: calibration and taps unchanged)",
        &a.seeds,
        &at_kalker,
    ));
    md.push('\n');
    md.push_str(&variants::markdown(
        "Variable speed (0 -> 20 -> 10 m/s, 50 s)",
        &a.seeds,
        &at_variable,
    ));
    println!("{md}");
    std::fs::create_dir_all(&a.out)
        .map_err(|e| RunError::Io(format!("cannot create {}: {e}", a.out.display())))?;
    let json = serde_json::json!({
        "calibration_seed": a.calibration_seed,
        "seeds": a.seeds,
        "tuned": tuned,
        "constant_speed": at_constant,
        "no_vertical_irregularity": at_flat,
        "kalker_half": at_kalker,
        "variable_speed": at_variable,
        "estimator_fmu": fmu_tables.iter().map(|(k, _, r)| (k.to_string(), serde_json::to_value(r).unwrap_or_default())).collect::<serde_json::Map<_, _>>(),
    });
    for (name, text) in [
        ("variants.md", md),
        (
            "variants.json",
            serde_json::to_string_pretty(&json).unwrap_or_default(),
        ),
    ] {
        let path = a.out.join(name);
        std::fs::write(&path, text)
            .map_err(|e| RunError::Io(format!("cannot write {}: {e}", path.display())))?;
    }
    eprintln!(
        "variants in {:.1} s; written to {}",
        started.elapsed().as_secs_f64(),
        a.out.join("variants.md").display()
    );
    Ok(())
}

fn study_learn(a: &LearnArgs) -> Result<(), RunError> {
    use alignment_studies::study::learned::{
        Lookahead, WINDOW, decimation, default_partner, learn, training_runs, validation,
    };
    use alignment_studies::study::runs::{STEP, STOP};
    use alignment_studies::study::variants;
    let cfg = |e: String| RunError::Config(e);
    let (grid, out) = (a.grid, &a.out);
    // The grid the filter will have (a whole number of samples), checked before the runs.
    let speed = a.speed.unwrap_or(20.0);
    let grid =
        STEP * speed * decimation(speed, grid).map_err(|e| cfg(format!("--grid: {e}")))? as f64;
    let lookahead = match a.lag {
        None => Lookahead::Smoother,
        Some(m) if (0.0..=WINDOW).contains(&m) => Lookahead::FixedLag((m / grid).round() as usize),
        Some(m) => {
            return Err(cfg(format!(
                "--lag must be between 0 and {WINDOW} m (the window), not {m}"
            )));
        }
    };
    let (runs, provenance) = training_runs(
        &study_fmus(&a.fmus),
        a.seed,
        a.stop,
        &a.kalker_scales,
        a.speed,
    )
    .map_err(cfg)?;
    // The shaping filter's virtual-measurement sigma, chosen as the study does, on the first
    // 20 s of the (first) training run.
    let (sigma, _) =
        variants::tune_prior_sigma(&validation(&runs[0]), 3, &[], None).map_err(cfg)?;
    let (l, j) = learn(
        &runs,
        &provenance,
        lookahead,
        grid,
        default_partner(lookahead, sigma),
    )
    .map_err(cfg)?;
    create_parent(out)?;
    std::fs::write(out, l.to_json())
        .map_err(|e| RunError::Io(format!("cannot write {}: {e}", out.display())))?;
    let ahead = match l.lookahead {
        Lookahead::Smoother => format!("smoother, {WINDOW} m each way"),
        Lookahead::FixedLag(n) => format!("look-ahead {} m", n as f64 * l.grid()),
    };
    println!(
        "learned FIR ({ahead}, grid {} m) at {} m/s: {}; split {} m with {} (whole Jrel on the first {} s: {j:.3}); wrote {}",
        l.grid(),
        l.speed,
        l.provenance,
        l.split,
        l.partner.name,
        STOP,
        out.display()
    );
    Ok(())
}

fn study_taps(a: &TapsArgs) -> Result<(), RunError> {
    use alignment_studies::study::learned::taps::{Options, fit};
    let mut o = Options::shipped();
    o.speeds = a.speeds.clone();
    o.kalker_scales = a.kalker_scales.clone();
    o.per_condition = !a.pooled;
    o.lags = a.lags.clone();
    o.roll_rate = !a.no_roll_rate;
    o.training_seed = a.seed;
    o.validation_seeds = a.validation_seeds.clone();
    let defaults = Options::shipped();
    if (
        o.speeds.clone(),
        o.kalker_scales.clone(),
        o.per_condition,
        o.lags.clone(),
        o.roll_rate,
        o.training_seed,
        o.validation_seeds.clone(),
    ) != (
        defaults.speeds,
        defaults.kalker_scales,
        defaults.per_condition,
        defaults.lags,
        defaults.roll_rate,
        defaults.training_seed,
        defaults.validation_seeds,
    ) {
        o.command = std::env::args().collect::<Vec<_>>().join(" ");
    }
    let started = std::time::Instant::now();
    let bank = fit(&study_fmus(&a.fmus), &o, &|m| eprintln!("{m}")).map_err(RunError::Config)?;
    create_parent(&a.out)?;
    std::fs::write(&a.out, bank.to_bytes())
        .map_err(|e| RunError::Io(format!("cannot write {}: {e}", a.out.display())))?;
    for m in bank.contact.iter().flat_map(|c| &c.speeds) {
        println!(
            "{:>5} m/s contact model: rms error of the Kalker scale on the validation runs {:.3}",
            m.speed, m.rms_error
        );
    }
    for e in &bank.entries {
        let w = e.windows.last().expect("full window");
        let condition = e
            .condition
            .map(|c| format!("Kalker {:>3} %", c * 100.0))
            .unwrap_or_default();
        println!(
            "{:>5} m/s {condition} {:<48} lag {:>4} m: ridge {:.0e}, validation objective {:.4}, rms error {:.3} mm",
            e.speed,
            e.channels.join(","),
            e.lag as f64 * bank.grid,
            e.ridge,
            e.validation_objective,
            w.rms_error * 1e3
        );
    }
    eprintln!(
        "tap bank in {:.1} s; wrote {}",
        started.elapsed().as_secs_f64(),
        a.out.display()
    );
    Ok(())
}

/// Creates the directory a file is to be written in, if it names one.
fn create_parent(file: &Path) -> Result<(), RunError> {
    match file.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => std::fs::create_dir_all(dir)
            .map_err(|e| RunError::Io(format!("cannot create {}: {e}", dir.display()))),
        None => Ok(()),
    }
}

fn smooth(
    input: &Path,
    out: &Path,
    set: &[String],
    calibration: Option<&Path>,
    learned: Option<&Path>,
) -> Result<(), RunError> {
    let overrides = set
        .iter()
        .map(|s| split_assignment(s).map(|(k, v)| (k.trim().to_string(), v.trim().to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    create_parent(out)?;
    let processed = alignment_studies::smooth::smooth_file(input, out, &overrides, calibration, learned)
        .map_err(RunError::Config)?;
    eprintln!(
        "{} samples filtered and smoothed ({} updates skipped); wrote {}",
        processed.filtered.len(),
        processed.skipped,
        out.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        StudyCommand::Smooth {
            input,
            out,
            set,
            calibration,
            learned,
        } => smooth(
            &input,
            &out,
            &set,
            calibration.as_deref(),
            learned.as_deref(),
        ),
        what => study(what),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
