//! Communication step sizes as masters compute them.
//!
//! A master that keeps time on an integer clock (libcosim counts nanoseconds) passes
//! `h = t(k+1) - t(k)` converted to seconds, so a constant 1 ms step arrives as
//! 0.0009999999999999992 and 0.0010000000000000009 by turns, and the rounding grows with `t`
//! (at t = 1000 s an ulp of `t` is 1.1e-13 s). A model that compares step sizes exactly then
//! rebuilds what depends on `h` on every other step, or takes an extra internal substep. These
//! helpers compare with a relative tolerance of [`RELATIVE`]: far above any clock's rounding,
//! far below any step change a model could tell apart.

/// Relative difference under which two step sizes are the same step.
pub const RELATIVE: f64 = 1e-9;

/// Whether `a` and `b` are the same step size (within [`RELATIVE`]).
pub fn same(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= RELATIVE * a.abs().max(b.abs())
}

/// The number of equal substeps of at most `max` that cover `h`: `ceil(h / max)`, except that
/// a ratio within [`RELATIVE`] above a whole number counts as that number (a step of
/// 1.0000000000000009 ms with a 1 ms internal step is one substep, not two).
pub fn substeps(h: f64, max: f64) -> usize {
    let ratio = h / max;
    let whole = ratio.round();
    let n = if whole >= 1.0 && (ratio - whole).abs() <= RELATIVE * whole {
        whole
    } else {
        ratio.ceil()
    };
    if n.is_finite() && n >= 1.0 {
        n as usize
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The step sizes libcosim passes for a 1 ms step: differences of a nanosecond clock.
    fn libcosim_steps(n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| ((k + 1) as f64 * 1e6) * 1e-9 - (k as f64 * 1e6) * 1e-9)
            .collect()
    }

    #[test]
    fn a_nanosecond_clocks_steps_are_the_same_step() {
        let steps = libcosim_steps(20_000);
        assert!(steps.iter().any(|h| *h != 1e-3), "the clock does round");
        for h in &steps {
            assert!(same(*h, 1e-3), "{h}");
            assert_eq!(substeps(*h, 1e-3), 1, "{h}");
            assert_eq!(substeps(*h, 2.5e-4), 4, "{h}");
        }
    }

    #[test]
    fn real_differences_are_kept() {
        assert!(!same(1e-3, 1.001e-3));
        assert!(!same(1e-3, 2e-3));
        assert_eq!(substeps(1.001e-3, 1e-3), 2);
        assert_eq!(substeps(0.5e-3, 1e-3), 1);
        assert_eq!(substeps(2.5e-3, 1e-3), 3);
        assert_eq!(substeps(3e-3, 1e-3), 3);
        assert_eq!(substeps(f64::NAN, 1e-3), 1);
    }
}
