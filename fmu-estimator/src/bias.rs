//! The sensors' biases, estimated while the train stands still and removed from every sample.
//!
//! # Why at standstill
//! A constant yaw-rate bias `b` is, to any estimator in motion, a constant track curvature
//! `b / V` (a 1e-3 rad/s bias at 20 m/s is a 20 km radius: 4 m of parabola over 400 m); a
//! constant lateral-acceleration bias is a constant cant. On straight track their means are
//! zero, but only over long distances: on the standard case's track (seed 7, 3 km at 20 m/s,
//! no noise) the true yaw rate's mean over 200 m has an rms of 9e-5 rad/s, over 1000 m 1.9e-5;
//! the wheelset accelerometer's 2.2e-3 and 4.7e-4 m/s2. So from motion alone a 1e-4 rad/s bias
//! is not known within 200 m to better than its own size, and removing a running mean costs
//! the long waves (D3) that the yaw rate carries (docs/accuracy.md, "Real sensors"). Standing
//! still, the true rates and accelerations are zero (bar a station's cant), so each sensor's
//! mean is its bias to within its noise over the samples: this is the zero-velocity update of
//! inertial navigation, and every train run starts at a standstill.
//!
//! # Estimate
//! Per sensor `i` with a prior standard deviation `sigma_i > 0` (the parameter
//! `bias_sigma_<sensor>`, the turn-on bias the datasheet gives; 0: not estimated), over the
//! samples of one standstill (`speed` below [`STANDSTILL_SPEED`]): the mean `m` and variance
//! `s^2` of its `n` samples, and the posterior mean of a bias with prior `N(b0, sigma^2)`
//! observed through `n` samples of noise variance `s^2`,
//! `b = b0 + w (m - b0)`, `w = sigma^2 / (sigma^2 + s^2 / n)`, with `b0` the estimate the
//! standstill began with (0 at the start). A later standstill refines it the same way, so a
//! bias that wanders is followed from stop to stop. In motion it is held. With every
//! `sigma_i` 0 (the default) nothing is estimated and the samples pass unchanged.
//!
//! # In motion
//! The samples with the biases removed are integrated in motion ([`crate::integrals`]): a
//! heading or a relative velocity that straight track does not give, or a yaw-rate mean since
//! the last standstill beyond its own, is a bias the estimator was not told of or could not see
//! (no standstill).

use crate::integrals::Integrals;
use serde::{Deserialize, Serialize};

/// Below this speed \[m/s\] the train stands still: its sensors read their biases.
pub const STANDSTILL_SPEED: f64 = 0.01;

/// The sensors' biases and the current standstill's statistics. Part of the FMU state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Bias {
    /// Prior standard deviation per sensor (`ws_acc_y`, `ws_yaw_rate`, `frame_acc_y`,
    /// `ws_roll_rate`); 0: not estimated.
    pub sigma: [f64; 4],
    /// The estimated biases, subtracted from the samples.
    pub estimate: [f64; 4],
    /// The estimate the current standstill began with.
    start: [f64; 4],
    /// Whether the last sample was standing.
    standing: bool,
    /// Finite samples of each sensor in the current standstill.
    n: [u64; 4],
    /// Their running mean and sum of squared deviations (Welford).
    mean: [f64; 4],
    m2: [f64; 4],
    /// The corrected samples' integrals in motion.
    pub integrals: Integrals,
}

impl Bias {
    /// No bias known yet, with these prior standard deviations.
    pub fn new(sigma: [f64; 4]) -> Bias {
        Bias {
            sigma,
            estimate: [0.0; 4],
            start: [0.0; 4],
            standing: false,
            n: [0; 4],
            mean: [0.0; 4],
            m2: [0.0; 4],
            integrals: Integrals::default(),
        }
    }

    /// Whether any sensor's bias is estimated.
    pub fn active(&self) -> bool {
        self.sigma.iter().any(|s| *s > 0.0)
    }

    /// One sample at `speed` after a step of `h`: at a standstill it refines the estimate, in
    /// motion it ends the standstill and adds to the yaw rate's mean. Each sensor's non-finite
    /// samples (a sensor not connected, one the plausibility check replaced) are left out of
    /// that sensor's figures only.
    pub fn observe(&mut self, speed: f64, h: f64, x: &[f64; 4]) {
        let standing = speed.abs() < STANDSTILL_SPEED;
        let r = self.remove(x);
        self.integrals
            .observe(standing, speed, h, [r[0], r[1], r[2]]);
        if standing && !self.standing {
            self.start = self.estimate;
            (self.n, self.mean, self.m2) = ([0; 4], [0.0; 4], [0.0; 4]);
        }
        self.standing = standing;
        if !standing || !self.active() {
            return;
        }
        for (i, &xi) in x.iter().enumerate() {
            if self.sigma[i] <= 0.0 || !xi.is_finite() {
                continue;
            }
            self.n[i] += 1;
            let n = self.n[i] as f64;
            let d = xi - self.mean[i];
            self.mean[i] += d / n;
            self.m2[i] += d * (xi - self.mean[i]);
            if self.n[i] >= 2 {
                let var = self.m2[i] / (n - 1.0);
                let prior = self.sigma[i] * self.sigma[i];
                let w = prior / (prior + var / n);
                self.estimate[i] = self.start[i] + w * (self.mean[i] - self.start[i]);
            }
        }
    }

    /// `x` with the estimated biases removed.
    pub fn remove(&self, x: &[f64; 4]) -> [f64; 4] {
        std::array::from_fn(|i| x[i] - self.estimate[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the closed-form posterior of a constant in Gaussian noise, with the noise's
    /// variance taken from the samples (numbers from a seeded generator, summed directly).
    #[test]
    fn a_standstill_gives_the_posterior_mean_and_motion_holds_it() {
        let mut state = 7u64;
        let mut noise = || {
            // Sum of 12 uniforms minus 6: close enough to a unit normal for this check.
            (0..12)
                .map(|_| {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    (state >> 11) as f64 / (1u64 << 53) as f64
                })
                .sum::<f64>()
                - 6.0
        };
        let truth = [0.05, 1e-3, -0.02, 0.0];
        let sigma = [0.1, 2e-3, 0.0, 1e-3];
        let noise_sigma = [0.01, 5e-4, 0.01, 5e-4];
        let mut b = Bias::new(sigma);
        let samples: Vec<[f64; 4]> = (0..2000)
            .map(|_| std::array::from_fn(|i| truth[i] + noise_sigma[i] * noise()))
            .collect();
        for x in &samples {
            b.observe(0.0, 1e-3, x);
        }
        for i in 0..4 {
            let n = samples.len() as f64;
            let m = samples.iter().map(|x| x[i]).sum::<f64>() / n;
            let var = samples.iter().map(|x| (x[i] - m).powi(2)).sum::<f64>() / (n - 1.0);
            let w = if sigma[i] > 0.0 {
                sigma[i] * sigma[i] / (sigma[i] * sigma[i] + var / n)
            } else {
                0.0
            };
            assert!(
                (b.estimate[i] - w * m).abs() <= 1e-12 * m.abs().max(1e-9),
                "{i}"
            );
        }
        // Within 5 standard errors of the truth for the estimated ones; 0 for the other.
        assert!((b.estimate[1] - 1e-3).abs() < 5.0 * 5e-4 / 2000f64.sqrt());
        assert_eq!(b.estimate[2], 0.0);
        // In motion the estimate holds, and the samples are corrected by it.
        let held = b.estimate;
        b.observe(20.0, 1e-3, &[9.0; 4]);
        assert_eq!(b.estimate, held);
        assert_eq!(b.remove(&[1.0; 4])[1], 1.0 - held[1]);
        // A second standstill starts from the first's estimate: with the truth moved, the
        // estimate moves to it.
        for x in &samples {
            b.observe(0.0, 1e-3, &std::array::from_fn(|i| x[i] + 2e-4));
        }
        assert!((b.estimate[1] - 1.2e-3).abs() < 5.0 * 5e-4 / 2000f64.sqrt());
    }

    /// In motion the heading integrates the yaw rate less the bias removed: after a standstill
    /// that found a 1e-3 rad/s bias, 10 s of motion at that raw rate turn it by nothing; told
    /// no prior, by 10 mrad.
    #[test]
    fn the_heading_integrates_the_rate_with_the_bias_removed() {
        let moved = |sigma: f64| {
            let mut b = Bias::new([0.0, sigma, 0.0, 0.0]);
            for _ in 0..1000 {
                b.observe(0.0, 1e-3, &[0.0, 1e-3, 0.0, 0.0]);
            }
            for _ in 0..10_000 {
                b.observe(20.0, 1e-3, &[0.0, 1e-3, 0.0, 0.0]);
            }
            b.integrals.heading_change()
        };
        assert!(moved(2e-3).abs() < 1e-12, "{}", moved(2e-3));
        assert!((moved(0.0) - 1e-2).abs() < 1e-9, "{}", moved(0.0));
    }

    /// A sensor that is not connected (NaN) leaves the others' estimates as they would be.
    #[test]
    fn one_sensors_missing_samples_do_not_stop_the_others() {
        let mut a = Bias::new([0.1, 1e-3, 0.1, 1e-3]);
        let mut b = a.clone();
        for k in 0..100 {
            let x = [0.05 + 1e-3 * (k % 7) as f64, 2e-4, -0.01, 3e-4];
            a.observe(0.0, 1e-3, &x);
            b.observe(0.0, 1e-3, &[x[0], x[1], x[2], f64::NAN]);
        }
        assert_eq!(a.estimate[..3], b.estimate[..3]);
        assert_eq!(b.estimate[3], 0.0);
        assert!(a.estimate[3] != 0.0);
    }

    #[test]
    fn without_priors_nothing_is_estimated() {
        let mut b = Bias::new([0.0; 4]);
        for _ in 0..10 {
            b.observe(0.0, 1e-3, &[1.0, 2.0, 3.0, 4.0]);
        }
        assert_eq!(b.estimate, [0.0; 4]);
        assert!(!b.active());
    }
}
