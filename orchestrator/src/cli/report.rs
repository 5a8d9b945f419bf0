//! What the command line shows of a run on stderr: the progress bar and the closing summary.

use crate::master::{End, Progress, RunSummary};

/// The command line's progress bar, drawn on stderr from the master's [`Progress`] reports for a
/// run of 10 000 steps or more (the master itself draws nothing).
pub fn progress_bar() -> impl FnMut(Progress) {
    let mut bar: Option<indicatif::ProgressBar> = None;
    move |p| match p {
        Progress::Start { total } if total >= 10_000 => {
            let b = indicatif::ProgressBar::new(total);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:40}] {percent:>3}% {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar = Some(b);
        }
        Progress::Start { .. } => {}
        Progress::Step { done } => {
            if let Some(b) = &bar {
                b.set_position(done);
            }
        }
        Progress::End { .. } => {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
        }
    }
}

/// What a finished run prints on stderr: steps, time, cost per step and where the rows are.
pub fn summary_text(summary: &RunSummary) -> String {
    let mut text = String::new();
    match &summary.end {
        End::Instance(who) => text.push_str(&format!(
            "'{who}' ended the simulation at t = {} s (fmi2DoStep returned fmi2Discard with fmi2Terminated): the run stops there\n",
            summary.final_time
        )),
        End::Observer => text.push_str(&format!(
            "an observer stopped the run at t = {} s\n",
            summary.final_time
        )),
        End::StopTime | End::Interrupted | End::Failed => {}
    }
    let per_step = summary.wall.as_secs_f64() / summary.steps.max(1) as f64 * 1e6;
    text.push_str(&format!(
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
    ));
    text
}
