//! The wheel-rail contact condition, estimated from the sensors: which taps to trust.
//!
//! # Why
//! The learned filter's short-wave (D1) accuracy depends on the creep coefficients: taps fitted
//! at the nominal Kalker coefficients give D1 Jrel about 0.11 on the nominal vehicle but about
//! 1.0 with the coefficients halved (worn wheels and rails), and taps fitted on both conditions
//! at once settle for 0.3 on each. The creep coefficients are not known on board, but they shape
//! how the wheelset answers the track: with less creep stiffness the wheelset follows the track
//! less tightly, its yaw rate grows against its lateral acceleration, and the two move more in
//! step. So the bank holds taps per contact condition, and this module estimates the condition
//! from the sensors to blend them.
//!
//! # Features
//! On the learned filter's distance grid, the three always-present sensors (`ws_acc_y`,
//! `ws_yaw_rate`, `frame_acc_y`) pass a band-pass (second-order Butterworth high-pass at the
//! band's long wavelength, then low-pass at its short one: the D1 band, 3-25 m, where the
//! conditions differ most). Running second moments `M_ij` of the band-passed channels are
//! exponentially weighted with a memory of `memory` metres (weight `1 / min(n, memory / ds)` for
//! the `n`-th cell, so the first cells are a plain mean). The features are scale-free, so the
//! track's roughness cancels:
//!
//! | feature | meaning |
//! |---|---|
//! | `ln(M_11 / M_00)` | yaw rate against wheelset acceleration |
//! | `ln(M_22 / M_00)` | frame against wheelset acceleration |
//! | `M_01 / sqrt(M_00 M_11)` | correlation of wheelset acceleration and yaw rate |
//! | `M_02 / sqrt(M_00 M_22)` | correlation of wheelset and frame accelerations |
//! | `M_12 / sqrt(M_11 M_22)` | correlation of yaw rate and frame acceleration |
//!
//! # Estimate
//! The Kalker-coefficient scale is a linear function of the features, fitted by least squares on
//! the training runs of every trained condition at each bank speed (`alignment-studies taps`),
//! blended linearly in speed like the taps, and clamped to the trained range. On the validation
//! seeds at 20 m/s it reaches about +-0.1 after 200 m of track (a scale of 1.0, 0.75 or 0.5).

use super::grid::Biquad;
use serde::{Deserialize, Serialize};

/// The channels the features read ([`super::grid::CHANNELS`] indices).
pub const CHANNELS: [usize; 3] = [0, 1, 2];
/// Number of features.
pub const FEATURES: usize = 5;

/// The fitted estimator of the contact condition, as the tap bank holds it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactModel {
    /// Shortest and longest wavelength of the features' band \[m\].
    pub band: [f64; 2],
    /// Memory of the running moments \[m\].
    pub memory: f64,
    /// The lowest and highest Kalker-coefficient scale trained on: the estimate's range.
    pub range: [f64; 2],
    /// Per bank speed, the coefficients of the features and the constant last.
    #[serde(rename = "at")]
    pub speeds: Vec<SpeedModel>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedModel {
    pub speed: f64,
    pub coefficients: Vec<f64>,
    /// Root-mean-square error of the estimate on the validation seeds after 200 m.
    pub rms_error: f64,
}

impl ContactModel {
    /// The consistency the runtime relies on.
    pub fn check(&self) -> Result<(), String> {
        let [short, long] = self.band;
        if !(short.is_finite() && short > 0.0 && long > short && long.is_finite()) {
            return Err(format!("contact band {short}-{long} m"));
        }
        if !(self.memory.is_finite() && self.memory > 0.0) {
            return Err(format!("contact memory {} m", self.memory));
        }
        let [lo, hi] = self.range;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo) {
            return Err(format!("contact range {lo}-{hi}"));
        }
        if self.speeds.is_empty() {
            return Err("a contact model without speeds".into());
        }
        for s in &self.speeds {
            if s.coefficients.len() != FEATURES + 1 || s.coefficients.iter().any(|c| !c.is_finite())
            {
                return Err(format!(
                    "contact model at {} m/s: {} coefficients (want {} finite ones)",
                    s.speed,
                    s.coefficients.len(),
                    FEATURES + 1
                ));
            }
        }
        if self.speeds.windows(2).any(|w| !(w[1].speed > w[0].speed)) {
            return Err("contact model speeds not increasing".into());
        }
        Ok(())
    }

    /// The Kalker-coefficient scale the features `f` indicate at `speed` (coefficients blended
    /// linearly between the bank speeds around it, the end ones beyond), clamped to the range.
    pub fn estimate(&self, f: &[f64; FEATURES], speed: f64) -> f64 {
        let s = &self.speeds;
        let at = |m: &SpeedModel| {
            let c = &m.coefficients;
            f.iter().zip(c).map(|(x, c)| x * c).sum::<f64>() + c[FEATURES]
        };
        let i = s.partition_point(|m| m.speed <= speed);
        let v = if i == 0 {
            at(&s[0])
        } else if i == s.len() {
            at(&s[s.len() - 1])
        } else {
            let a = (speed - s[i - 1].speed) / (s[i].speed - s[i - 1].speed);
            (1.0 - a) * at(&s[i - 1]) + a * at(&s[i])
        };
        if v.is_finite() {
            v.clamp(self.range[0], self.range[1])
        } else {
            self.range[1]
        }
    }
}

/// The running moments of the band-passed channels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    filters: Vec<[Biquad; 2]>,
    m: [[f64; 3]; 3],
    n: f64,
    memory_points: f64,
}

impl Moments {
    pub fn new(ds: f64, band: [f64; 2], memory: f64) -> Moments {
        Moments {
            filters: (0..CHANNELS.len())
                .map(|_| [Biquad::highpass(ds, band[1]), Biquad::lowpass(ds, band[0])])
                .collect(),
            m: [[0.0; 3]; 3],
            n: 0.0,
            memory_points: (memory / ds).max(1.0),
        }
    }

    /// One closed cell (channels in [`super::grid::CHANNELS`] order).
    pub fn push(&mut self, cell: &[f64; 5]) {
        let x: [f64; 3] = std::array::from_fn(|i| {
            let [hp, lp] = &mut self.filters[i];
            lp.step(hp.step(cell[CHANNELS[i]]))
        });
        if x.iter().any(|v| !v.is_finite()) {
            return;
        }
        self.n += 1.0;
        let a = 1.0 / self.n.min(self.memory_points);
        for (i, row) in self.m.iter_mut().enumerate() {
            for (j, m) in row.iter_mut().enumerate() {
                *m += a * (x[i] * x[j] - *m);
            }
        }
    }

    /// The features ([module docs](self)); `None` while a channel has no variance yet.
    pub fn features(&self) -> Option<[f64; FEATURES]> {
        let m = &self.m;
        let (v0, v1, v2) = (m[0][0], m[1][1], m[2][2]);
        if !(v0 > 0.0 && v1 > 0.0 && v2 > 0.0) {
            return None;
        }
        let f = [
            (v1 / v0).ln(),
            (v2 / v0).ln(),
            m[0][1] / (v0 * v1).sqrt(),
            m[0][2] / (v0 * v2).sqrt(),
            m[1][2] / (v1 * v2).sqrt(),
        ];
        f.iter().all(|v| v.is_finite()).then_some(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn features_are_scale_free_and_see_correlation() {
        // Channel 1 = 3 x channel 0 (perfectly correlated), channel 2 independent noise.
        let mut a = Moments::new(0.2, [3.0, 25.0], 200.0);
        let mut b = Moments::new(0.2, [3.0, 25.0], 200.0);
        let mut seed = 1u64;
        let mut noise = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..20_000 {
            let (u, w) = (noise(), noise());
            a.push(&[u, 3.0 * u, w, 0.0, 0.0]);
            // The same signals 1000 times larger: features unchanged.
            b.push(&[1e3 * u, 3e3 * u, 1e3 * w, 0.0, 0.0]);
        }
        let (fa, fb) = (a.features().unwrap(), b.features().unwrap());
        for (x, y) in fa.iter().zip(&fb) {
            assert!((x - y).abs() < 1e-9, "{fa:?} {fb:?}");
        }
        assert!((fa[0] - 9f64.ln()).abs() < 1e-9, "{fa:?}");
        assert!((fa[2] - 1.0).abs() < 1e-9, "{fa:?}");
        // Independent noise: correlation near 0 (memory of 1000 cells: sd about 0.03).
        assert!(fa[3].abs() < 0.15, "{fa:?}");
    }

    #[test]
    fn the_estimate_blends_in_speed_and_stays_in_range() {
        let m = ContactModel {
            band: [3.0, 25.0],
            memory: 200.0,
            range: [0.5, 1.0],
            speeds: vec![
                SpeedModel {
                    speed: 10.0,
                    coefficients: vec![0.1, 0.0, 0.0, 0.0, 0.0, 0.5],
                    rms_error: 0.1,
                },
                SpeedModel {
                    speed: 20.0,
                    coefficients: vec![0.2, 0.0, 0.0, 0.0, 0.0, 0.5],
                    rms_error: 0.1,
                },
            ],
        };
        m.check().unwrap();
        let f = [2.0, 0.0, 0.0, 0.0, 0.0];
        assert!((m.estimate(&f, 10.0) - 0.7).abs() < 1e-12);
        assert!((m.estimate(&f, 15.0) - 0.8).abs() < 1e-12);
        assert!((m.estimate(&f, 5.0) - 0.7).abs() < 1e-12);
        assert_eq!(m.estimate(&f, 25.0), 0.9);
        assert_eq!(m.estimate(&[10.0, 0.0, 0.0, 0.0, 0.0], 20.0), 1.0);
        assert_eq!(m.estimate(&[-10.0, 0.0, 0.0, 0.0, 0.0], 20.0), 0.5);
        let mut bad = m.clone();
        bad.speeds[0].coefficients.pop();
        assert!(bad.check().unwrap_err().contains("coefficients"));
    }
}
