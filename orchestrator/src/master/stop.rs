//! A per-run stop: a token the caller creates and hands to one run (or to several it means to
//! stop together), set from anywhere (the command line's Ctrl-C handler, another thread, an
//! observer) and read by the stepping loop once per step.
//!
//! A token, not a process-wide flag: two runs in one process (a study's threads, a Python
//! session) stop independently, and a token once set stays set for its own run only; the next
//! run gets a new one.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Asks the runs it is given to ([`super::Runner::stop_on`]) to stop at their next step
/// boundary; such a run keeps its results and returns [`super::RunError::Interrupted`]. Clones
/// share the request. A fresh token (the default) is not set.
#[derive(Debug, Clone, Default)]
pub struct StopToken(Arc<AtomicBool>);

impl StopToken {
    /// A token not set, to hand to the runs it is to stop (the same as `default()`).
    pub fn new() -> StopToken {
        StopToken::default()
    }

    /// Requests the stop; returns whether this is the first request (the command line quits
    /// at once on the second).
    pub fn stop(&self) -> bool {
        !self.0.swap(true, Ordering::SeqCst)
    }

    /// Whether the stop was requested.
    #[inline]
    pub fn is_stopped(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_a_request_and_other_tokens_do_not_see_it() {
        let a = StopToken::new();
        let shared = a.clone();
        let other = StopToken::new();
        assert!(!a.is_stopped());
        assert!(shared.stop(), "the first request");
        assert!(!a.stop(), "a second request on a clone");
        assert!(a.is_stopped() && shared.is_stopped());
        assert!(!other.is_stopped());
    }
}
