//! The blend of the selected windows' estimates: linear in speed between the two bank speeds
//! around the current one, in contact condition between the two trained conditions around the
//! estimated one, and in conicity between the two trained conicities around the estimated or
//! given one (up to eight windows per estimate).

use super::weights;
use super::window::{History, Windows};

/// The interpolation weights of one estimate: (index, weight) pairs in speed and in condition.
pub(super) struct Blend {
    by_speed: Vec<(usize, f64)>,
    by_condition: Vec<(usize, f64)>,
}

impl Blend {
    /// The weights at `speed` among `speeds`, at `contact_scale` among `conditions` and at
    /// `conicity` among `conicities` (linear in the logarithm: equal ratios of conicity change
    /// a wheel's kinematic wavelength alike); one set of windows per speed when both are
    /// empty. The condition index is conicity-major ([`super::selection`]).
    pub(super) fn at(
        speeds: &[f64],
        speed: f64,
        conditions: &[f64],
        contact_scale: f64,
        conicities: &[f64],
        conicity: f64,
    ) -> Blend {
        let by_kalker = if conditions.is_empty() {
            vec![(0, 1.0)]
        } else {
            weights(conditions, contact_scale)
        };
        let by_condition = if conicities.is_empty() {
            by_kalker
        } else {
            let ln: Vec<f64> = conicities.iter().map(|c| c.ln()).collect();
            let nk = conditions.len().max(1);
            weights(&ln, conicity.ln())
                .into_iter()
                .flat_map(|(c, a)| by_kalker.iter().map(move |(k, b)| (c * nk + k, a * b)))
                .collect()
        };
        Blend {
            by_speed: weights(speeds, speed),
            by_condition,
        }
    }

    /// The (speed index, weight) pairs of the blend in speed.
    pub(super) fn by_speed(&self) -> &[(usize, f64)] {
        &self.by_speed
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
