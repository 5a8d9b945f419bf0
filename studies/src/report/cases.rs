//! The paper's cases (standard, robustness, resonance) on held-out seeds, run in parallel: a
//! report with a table per group, its JSON, the first seed's time series and the figures
//! (`alignment-studies standard | robustness | resonance | all`).

use super::{Evaluation, Report, create_dir};
use crate::Error;
use crate::study::runs::{self, Fmus};
use crate::study::{cases, plot};
use std::path::Path;

/// How far the runs are, for a progress bar.
#[derive(Clone, Copy, Debug)]
pub enum Progress {
    /// This many runs are about to start.
    Runs(usize),
    /// One more run is done.
    Done,
    /// All runs are done (or one failed).
    Finished,
}

/// The groups of cases a command runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Group {
    /// The standard case (20 s at 20 m/s), with the paper's figures beside ours.
    Standard,
    /// The paper's Table 5: the filter's model parameters off the vehicle's.
    Robustness,
    /// The paper's Table 6: speeds around the vehicle's first lateral mode.
    Resonance,
    /// The wheels' conicity 0.05-0.4 (worn wheels), for each estimator told it or not.
    Conicity,
    /// Other vehicles: the Manchester Benchmark vehicle and ML95 variants.
    Vehicles,
}

impl Group {
    /// Every group, in the order `all` runs and reports them.
    pub const ALL: [Group; 5] = [
        Group::Standard,
        Group::Robustness,
        Group::Conicity,
        Group::Vehicles,
        Group::Resonance,
    ];

    fn title(self) -> &'static str {
        match self {
            Group::Standard => "Standard case",
            Group::Robustness => "Robustness",
            Group::Resonance => "Resonance",
            Group::Conicity => "Conicity",
            Group::Vehicles => "Vehicles",
        }
    }
}

/// The names [`cases()`] writes into its directory for `groups`, the first held-out seed being
/// `first_seed`: what the output policy checks before the work ([`super::written`]).
pub fn outputs(groups: &[Group], first_seed: u32) -> Vec<String> {
    let mut names = vec!["report.md".to_string()];
    for g in groups {
        let title = g.title().to_lowercase();
        names.push(format!("{}.json", title.replace(' ', "_")));
        match g {
            Group::Standard => names.extend([
                format!("standard_seed{first_seed}.csv"),
                "standard_alignment.svg".into(),
                "standard_spectra.svg".into(),
            ]),
            Group::Robustness | Group::Resonance | Group::Conicity | Group::Vehicles => {
                names.push(format!("{title}.svg"))
            }
        }
        if *g == Group::Robustness {
            names.push("sensors.json".into());
        }
    }
    names
}

/// Runs the groups' cases on the evaluation's seeds and builds the report for the directory
/// `out` (`report.md`, one JSON per group, the figures). `log` gets the lines worth seeing at
/// once; `progress` is told the number of runs, then called after each.
pub fn cases(
    fmus: &Fmus,
    evaluation: &Evaluation,
    groups: &[Group],
    out: &Path,
    log: &dyn Fn(&str),
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Report, Error> {
    evaluation.held_out()?;
    let seeds = &evaluation.seeds;
    // The vehicle variants' files, for the runs' duration.
    let variants =
        tempfile::tempdir().map_err(|e| Error::input(format!("a temporary directory: {e}")))?;
    let mut plan: Vec<(Group, Vec<cases::Case>)> = vec![];
    for &g in groups {
        let group = match g {
            Group::Standard => vec![cases::standard()],
            Group::Robustness => cases::robustness(filter_conicity(fmus)?),
            Group::Resonance => {
                let mode = first_lateral_mode(fmus)?;
                log(&format!(
                    "first lateral mode of the vehicle at 20 m/s: {:.3} Hz (damping {:.3}): wavelength {:.2} m",
                    mode.frequency,
                    mode.damping,
                    20.0 / mode.frequency
                ));
                cases::resonance(mode.frequency, 20.0)
            }
            Group::Conicity => {
                let bank = cases::conicity_bank()?;
                for (c, k) in cases::left_out(&bank) {
                    log(&format!(
                        "conicity sweep: conicity {c} at Kalker {} % is outside the shipped taps' envelope up to {} m/s (the vehicle is unstable there), left out",
                        k * 100.0,
                        cases::SWEEP_SPEED
                    ));
                }
                cases::conicity_sweep(&bank)
            }
            Group::Vehicles => crate::study::vehicles::cases(variants.path())?,
        };
        // A user who chose the estimator (--set estimator.estimator=N) gets that one only; the
        // conicity sweep names its estimators itself.
        let names_its_estimators = matches!(g, Group::Conicity | Group::Vehicles);
        let group = if names_its_estimators || fmus.estimator_number("estimator").is_some() {
            group
        } else {
            cases::with_learned(group)
        };
        plan.push((g, group));
    }
    let total: usize = plan.iter().map(|(_, c)| c.len()).sum::<usize>() * seeds.len();
    progress(Progress::Runs(total));
    let started = std::time::Instant::now();
    let all: Vec<cases::Case> = plan.iter().flat_map(|(_, c)| c.iter().cloned()).collect();
    let results = cases::run_cases(fmus, &all, seeds, &|| progress(Progress::Done));
    progress(Progress::Finished);
    let results = results?;
    // The robustness study's tables of what our vehicle FMU models and another may not: run
    // when the FMU has `parameter`, else said why not.
    let table = |parameter: &str, what: &str| {
        let wanted = groups.contains(&Group::Robustness);
        let possible = crate::study::interface::has_parameter(&fmus.vehicle, parameter);
        if wanted && !possible {
            log(&format!(
                "robustness: the {what} (parameter {parameter}); {} has none",
                fmus.vehicle.display()
            ));
        }
        wanted && possible
    };
    let sensors = table(
        "sensor_grade",
        "sensor table needs a vehicle FMU with sensor errors",
    )
    .then(|| crate::study::sensors::run(fmus, seeds))
    .transpose()?;
    let curves = table(
        "line_file",
        "curve table needs a vehicle FMU with a design line",
    )
    .then(|| crate::study::curves::run(fmus, seeds))
    .transpose()?;
    // The figures are drawn into the directory.
    create_dir(out)?;
    let mut report = Report::default();
    let mut md = String::from("# Alignment estimation study\n\n");
    let mut offset = 0;
    for (group, cases) in &plan {
        let title = group.title();
        let slice = &results[offset..offset + cases.len()];
        offset += cases.len();
        md.push_str(&cases::markdown(title, slice));
        md.push('\n');
        let json = serde_json::to_string_pretty(slice).unwrap_or_default();
        let file = format!("{}.json", title.to_lowercase().replace(' ', "_"));
        report.file(out.join(file), json);
        match group {
            Group::Standard => {
                md.push_str(&first_seed(seeds[0], out, fmus, &cases[0], &mut report)?)
            }
            Group::Robustness | Group::Resonance | Group::Conicity | Group::Vehicles => {
                let svg = format!("{}.svg", title.to_lowercase());
                let path = out.join(&svg);
                plot::case_bars(&path, slice, &format!("{title}: Jrel per band"))?;
                report.figures.push(path);
                md.push_str(&format!("![{title}: Jrel per band]({svg})\n\n"));
            }
        }
        if let (Group::Robustness, Some(sensors)) = (group, &sensors) {
            md.push_str(&crate::study::sensors::markdown(seeds, sensors));
            md.push('\n');
            let json = serde_json::to_string_pretty(sensors).unwrap_or_default();
            report.file(out.join("sensors.json"), json);
        }
        if let (Group::Robustness, Some(curves)) = (group, &curves) {
            md.push_str(&crate::study::curves::markdown(seeds, curves));
            md.push('\n');
            let json = serde_json::to_string_pretty(curves).unwrap_or_default();
            report.file(out.join("curves.json"), json);
        }
    }
    let report_path = out.join("report.md");
    report.note = format!(
        "{total} runs in {:.1} s; report in {}",
        started.elapsed().as_secs_f64(),
        report_path.display()
    );
    report.file(report_path, md.clone());
    report.markdown = md;
    Ok(report)
}

/// The report as a document of the repository (docs/results.md): headed by the command and the
/// time that made it, the figures left in the study's directory `out` (not committed), so the
/// dated figures live in one generated file instead of module docs.
pub fn as_document(markdown: &str, command: &str, out: &Path) -> String {
    let mut text = format!(
        "<!-- Generated: do not edit. Regenerate with `alignment-studies all --doc docs/results.md`. -->\n\n\
         # Results\n\n\
         Made by `{command}` ({} {}) on {}. The figures and per-case JSON are in `{}` of that run.\n\n\
         These are the paper's cases, each measured with the paper's filter (`estimator` 1), as the \
         paper did, and with the estimator FMU's default, the learned filter (`estimator` 2, causal \
         output `alignment`; rows \"learned filter\"). Its other outputs and options (fixed lag, \
         roll-rate gyroscope, contact conditions, variable speed) are compared by \
         `alignment-studies variants` (docs/learned-filter.md).\n\n",
        env!("CARGO_PKG_NAME"),
        env!("CARGO_PKG_VERSION"),
        orchestrator::outdir::rfc3339(std::time::SystemTime::now()),
        out.display()
    );
    let body = markdown
        .strip_prefix("# Alignment estimation study\n\n")
        .unwrap_or(markdown);
    for line in body.lines() {
        // Figures stay in the run's directory; no two blank lines where they were.
        if line.starts_with("![") || (line.is_empty() && text.ends_with("\n\n")) {
            continue;
        }
        // The report's sections under the document's own title.
        let line = line
            .strip_prefix("###")
            .map_or(line.to_string(), |l| format!("##{l}"));
        text.push_str(&unlinked(&line));
        text.push('\n');
    }
    text
}

/// `[text](file)` links to the run's files as plain `` `file` ``: they are not beside the
/// document.
fn unlinked(line: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(mid) = rest.find("](") {
        let (Some(open), Some(close)) = (rest[..mid].rfind('['), rest[mid..].find(')')) else {
            break;
        };
        out.push_str(&rest[..open]);
        out.push_str(&format!("`{}`", &rest[mid + 2..mid + close]));
        rest = &rest[mid + close + 1..];
    }
    out.push_str(rest);
    out
}

/// The time series and figures of the first held-out seed (run once more: the parallel runs
/// keep only the metrics); the report's paragraph linking them.
fn first_seed(
    seed: u32,
    out: &Path,
    fmus: &Fmus,
    case: &cases::Case,
    report: &mut Report,
) -> Result<String, Error> {
    let table = cases::run_seed_table(fmus, case, seed, runs::STOP)?;
    let ts = plot::TimeSeries::from_table(&table)?;
    let csv = format!("standard_seed{seed}.csv");
    report.file(out.join(&csv), ts.to_csv());
    let heading = format!("standard case, seed {seed}");
    let (alignment, spectra) = (
        out.join("standard_alignment.svg"),
        out.join("standard_spectra.svg"),
    );
    let title = format!("estimated vs true alignment, {heading}");
    plot::estimate_vs_truth(&alignment, &ts.distance, &ts.estimate, &ts.truth, &title)?;
    let title = format!("amplitude spectra, {heading}");
    plot::spectra(&spectra, &ts.distance, &ts.estimate, &ts.truth, &title)?;
    report.figures.extend([alignment, spectra]);
    Ok(format!(
        "Seed {seed}: time series [{csv}]({csv}).\n\n![estimated vs true alignment](standard_alignment.svg)\n\n![amplitude spectra](standard_spectra.svg)\n\n"
    ))
}

/// The filter's conicity, which the robustness case lowers by 10 %: the user's (or their
/// calibration file's) if set, else the FMU's default.
fn filter_conicity(fmus: &Fmus) -> Result<f64, Error> {
    let estimator = fmi_import::Fmu::open(&fmus.estimator).map_err(|e| Error::Run(e.into()))?;
    let alpha = match estimator
        .model_description()
        .variable("alpha")
        .map(|v| &v.kind)
    {
        Some(model_description::VariableKind::Real(r)) => r.start.unwrap_or(0.1),
        _ => 0.1,
    };
    Ok(fmus.estimator_number("alpha").unwrap_or(alpha))
}

/// The vehicle's first lightly damped lateral mode at 20 m/s.
fn first_lateral_mode(fmus: &Fmus) -> Result<fmu_vehicle::modal::Mode, Error> {
    let params = fmus.vehicle_params()?;
    let conicity = params.wheelset.conicity;
    let vehicle = fmu_vehicle::dynamics::Vehicle::new(
        params,
        conicity,
        fmu_vehicle::dynamics::ContactOptions::default(),
    );
    fmu_vehicle::modal::modes(&vehicle, 20.0)
        .first_lateral()
        .ok_or_else(|| Error::input("the vehicle has no lightly damped lateral mode at 20 m/s"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_document_has_its_provenance_and_no_links_into_the_run() {
        let md = "# Alignment estimation study\n\n### Standard case\n\n| a | b |\n|---|---|\n\nSeed 1: time series [s1.csv](s1.csv).\n\n![fig](standard_alignment.svg)\n";
        let doc = as_document(
            md,
            "alignment-studies all --doc d.md",
            Path::new("out/study"),
        );
        assert!(doc.starts_with("<!-- Generated: do not edit."), "{doc}");
        assert!(doc.contains("Made by `alignment-studies all --doc d.md`"));
        assert!(doc.contains("`out/study`"));
        assert!(doc.contains("\n## Standard case\n") && doc.contains("| a | b |"));
        assert!(!doc.contains("\n\n\n"), "{doc}");
        assert!(doc.contains("Seed 1: time series `s1.csv`."), "{doc}");
        assert!(!doc.contains("](") && !doc.contains("Alignment estimation study"));
    }
}
