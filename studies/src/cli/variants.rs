//! `alignment-studies variants` and `envelope`: studies that write their report into `--out`
//! only and run the shipped FMUs with the settings they name themselves
//! ([`crate::report::variants`], [`crate::report::envelope`]).

use super::{Report, StudyArgs};
use crate::Error;
use crate::report::written::StudyDir;
use crate::report::{Evaluation, envelope, variants};
use crate::study::runs::Fmus;
use std::path::Path;

/// A study run on the FMUs and seeds into a directory, its log given.
type Run = dyn Fn(&Fmus, &Evaluation, &Path, &dyn Fn(&str)) -> Result<Report, Error>;

/// A study of this kind: its command name, what `--set` would undo, its output names and the
/// study itself.
struct DirStudy<'a> {
    name: &'static str,
    why_no_set: &'static str,
    outputs: &'a [&'a str],
    run: &'a Run,
}

/// Refuses `--doc` and `--set`, checks the output directory before the work, then runs.
fn execute_in_dir(a: &StudyArgs, s: DirStudy, log: &dyn Fn(&str)) -> Result<Report, Error> {
    if let Some(doc) = &a.doc {
        return Err(Error::Input(format!(
            "--doc {}: {} writes its report in --out only; --doc is for standard, robustness, resonance and all",
            doc.display(),
            s.name
        )));
    }
    if let Some(set) = a.fmus.set.first() {
        return Err(Error::Input(format!(
            "--set {set}: {} {}; --set is for calibrate, standard, robustness, resonance and all",
            s.name, s.why_no_set
        )));
    }
    let names: Vec<String> = s.outputs.iter().map(|n| n.to_string()).collect();
    let dir = StudyDir::check(&a.out, &names, a.force)?;
    let mut report = (s.run)(&a.fmus.fmus.fmus(), &a.evaluation(), &a.out, log)?;
    report.study_dir = Some(dir);
    Ok(report)
}

/// `variants`: refuses `--set` (the comparison runs the estimator offline with its shipped
/// calibration and the ML95 vehicle), then runs it; `log` gets the choices made on the
/// calibration seed.
pub fn execute(a: &StudyArgs, log: &dyn Fn(&str)) -> Result<Report, Error> {
    let study = DirStudy {
        name: "variants",
        why_no_set: "runs the estimator offline with its shipped calibration and the ML95 vehicle",
        outputs: &variants::OUTPUTS,
        run: &variants::variants,
    };
    execute_in_dir(a, study, log)
}

/// `envelope`: the outside_training flag over 10 km runs.
pub fn envelope(a: &StudyArgs, log: &dyn Fn(&str)) -> Result<Report, Error> {
    let study = DirStudy {
        name: "envelope",
        why_no_set: "runs the shipped vehicle and estimator with the conditions it names",
        outputs: &envelope::OUTPUTS,
        run: &envelope::envelope,
    };
    execute_in_dir(a, study, log)
}
