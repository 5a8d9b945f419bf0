//! The blend of the selected windows' estimates: linear in speed between the two bank speeds
//! around the current one, and in contact condition between the two trained conditions around
//! the estimated one (up to four windows per estimate).

use super::weights;
use super::window::{History, Windows};

/// The interpolation weights of one estimate: (index, weight) pairs in speed and in condition.
pub(super) struct Blend {
    by_speed: Vec<(usize, f64)>,
    by_condition: Vec<(usize, f64)>,
}

impl Blend {
    /// The weights at `speed` among `speeds` and at `contact_scale` among `conditions` (one
    /// set of windows per speed when `conditions` is empty).
    pub(super) fn at(speeds: &[f64], speed: f64, conditions: &[f64], contact_scale: f64) -> Blend {
        Blend {
            by_speed: weights(speeds, speed),
            by_condition: if conditions.is_empty() {
                vec![(0, 1.0)]
            } else {
                weights(conditions, contact_scale)
            },
        }
    }

    /// The blended estimate and rms error of `set` (windows by speed, then by condition) on
    /// `hist`, each window's channels times `gain`; `None` while a window needed has no
    /// history covering it.
    pub(super) fn apply(
        &self,
        set: &[Vec<Windows>],
        hist: &impl History,
        gain: &[f64; 5],
    ) -> Option<(f64, f64)> {
        let (mut e, mut r) = (0.0, 0.0);
        for (s, a) in &self.by_speed {
            for (c, b) in &self.by_condition {
                let (ei, ri) = set[*s][*c].apply(hist, gain)?;
                e += a * b * ei;
                r += a * b * ri;
            }
        }
        Some((e, r))
    }
}
