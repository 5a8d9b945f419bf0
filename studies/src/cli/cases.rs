//! `alignment-studies standard | robustness | resonance | all`: the paper's cases on held-out
//! seeds ([`crate::report::cases`]).

use super::{Report, StudyArgs, progress_bar};
use crate::Error;
pub use crate::report::cases::Group;

/// Runs the groups' cases with a progress bar; `log` gets the lines worth seeing at once.
pub fn execute(a: &StudyArgs, groups: &[Group], log: &dyn Fn(&str)) -> Result<Report, Error> {
    crate::report::cases::cases(
        &a.fmus.fmus()?,
        &a.evaluation(),
        groups,
        &a.out,
        log,
        &progress_bar(a.quiet),
    )
}
