//! `alignment-studies standard | robustness | resonance | all`: the paper's cases on held-out
//! seeds ([`crate::report::cases`]).

use super::{Report, StudyArgs, progress_bar};
use crate::Error;
pub use crate::report::cases::Group;

/// Runs the groups' cases with a progress bar; `log` gets the lines worth seeing at once.
pub fn execute(a: &StudyArgs, groups: &[Group], log: &dyn Fn(&str)) -> Result<Report, Error> {
    let mut report = crate::report::cases::cases(
        &a.fmus.fmus()?,
        &a.evaluation(),
        groups,
        &a.out,
        log,
        &progress_bar(a.quiet),
    )?;
    if let Some(doc) = &a.doc {
        let command: Vec<String> = std::env::args().collect();
        let text = crate::report::cases::as_document(&report.markdown, &command.join(" "), &a.out);
        report.file(doc.clone(), text);
    }
    Ok(report)
}
