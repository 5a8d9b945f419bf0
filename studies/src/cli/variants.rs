//! `alignment-studies variants`: the estimator FMU's estimators and the filter's options
//! against the paper's filter ([`crate::report::variants`]).

use super::{Report, StudyArgs};
use crate::Error;
use crate::report::written::StudyDir;

/// Refuses `--set` (the comparison runs the estimator offline with its shipped calibration and
/// the ML95 vehicle), then runs it; `log` gets the choices made on the calibration seed.
pub fn execute(a: &StudyArgs, log: &dyn Fn(&str)) -> Result<Report, Error> {
    if let Some(doc) = &a.doc {
        return Err(Error::Input(format!(
            "--doc {}: variants writes its report in --out only; --doc is for standard, robustness, resonance and all",
            doc.display()
        )));
    }
    if let Some(s) = a.fmus.set.first() {
        return Err(Error::Input(format!(
            "--set {s}: variants runs the estimator offline with its shipped calibration and the ML95 vehicle; --set is for calibrate, standard, robustness, resonance and all"
        )));
    }
    let names = crate::report::variants::OUTPUTS.map(String::from);
    let dir = StudyDir::check(&a.out, &names, a.force)?;
    let mut report =
        crate::report::variants::variants(&a.fmus.fmus.fmus(), &a.evaluation(), &a.out, log)?;
    report.study_dir = Some(dir);
    Ok(report)
}
