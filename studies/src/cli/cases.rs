//! `alignment-studies standard | robustness | resonance | all`: the paper's cases on held-out
//! seeds ([`crate::report::cases`]).

use super::{Report, StudyArgs, progress_bar};
use crate::Error;
pub use crate::report::cases::Group;
use crate::report::written::StudyDir;

/// How every document `--doc` writes begins ([`crate::report::cases::as_document`]).
const DOC_MARK: &[u8] =
    b"<!-- Generated: do not edit. Regenerate with `alignment-studies all --doc";

/// Runs the groups' cases with a progress bar; `log` gets the lines worth seeing at once.
pub fn execute(a: &StudyArgs, groups: &[Group], log: &dyn Fn(&str)) -> Result<Report, Error> {
    let doc = a
        .doc
        .as_deref()
        .map(|d| {
            let inputs = [
                a.fmus.fmus.vehicle.as_path(),
                a.fmus.fmus.estimator.as_path(),
            ];
            super::guard(d, &inputs, a.force, Some(DOC_MARK))
        })
        .transpose()?;
    let names = crate::report::cases::outputs(groups, a.seeds.first().copied().unwrap_or(0));
    let dir = StudyDir::check(&a.out, &names, a.force)?;
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
    report.guarded.extend(doc);
    report.study_dir = Some(dir);
    Ok(report)
}
