//! What the filter assumes about the alignment before it sees a measurement: its *prior*.
//!
//! # The three models (FMI parameter `alignment_model`)
//! 1. **Random walk** (the paper): `xi` is a state of its own with `xidot = 0 + w`, pulled toward
//!    zero by the virtual measurement `0 = xi + v`. Seven states. Nothing in it knows that the
//!    alignment is smooth along the track, so the filter lets the sensors' high-frequency errors
//!    into the estimate and the virtual measurement pulls the long waves toward zero.
//! 2. **Integrated random walk**: the alignment's rate is a state too, `x = [.., xi, xidot]`, and
//!    the random input drives its curvature, `xi'' = w(s)` along the track. Eight states. The
//!    spectrum of this prior is `q / (pi Omega^4)` (one-sided, in angular wavenumber), the
//!    short-wave asymptote of the measured track spectra: the prior says *how smooth* the
//!    alignment is, not how large. Its variance grows without bound, so the virtual measurement
//!    (`prior_sigma_xi`) keeps it finite.
//! 3. **Spectrum shaping filter**: the German alignment spectrum of docs/references.md section 3,
//!    `S(Omega) = A Oc^2 / ((Omega^2 + Or^2)(Omega^2 + Oc^2))` (one-sided, m^2/(rad/m)), is
//!    exactly the output spectrum of the second-order filter
//!    `xi'' + (Or + Oc) xi' + Or Oc xi = w(s)` driven by white noise `w` along the track:
//!    `|1 / ((j Omega + Or)(j Omega + Oc))|^2 = 1 / ((Omega^2 + Or^2)(Omega^2 + Oc^2))`.
//!    With `E[w(s) w(s')] = q delta(s - s')` the two-sided output spectrum is
//!    `q / (2 pi) |H|^2`, so one-sided `q / pi |H|^2`, and matching `S` gives
//!    **`q = pi A Oc^2`**. Check: the variance of the filter's output,
//!    `q / (2 (Or + Oc) Or Oc)`, equals `integral_0^inf S dOmega = pi A Oc / (2 Or (Or + Oc))`
//!    (a unit test). Eight states; a proper stationary prior (3.97 mm rms for the low-disturbance
//!    spectrum), so no virtual measurement is needed, though one may still be given.
//!
//! Model 2 is model 3 with `Or = Oc = 0` and the same `q`, which has the same short-wave
//! asymptote `A Oc^2 / Omega^4`; so both take their intensity from `prior_a` and `prior_omega_c`.
//!
//! # From distance to time
//! The filter runs in time at speed `V`. With `s = V t`, `d/ds = (1/V) d/dt`, so
//! `xi_tt + V (Or + Oc) xi_t + V^2 Or Oc xi = V^2 w(s(t))`, and white noise along the track of
//! intensity `q` [m^2 / m^3] is white noise in time of intensity `q / V`
//! (`delta(s - s') = delta(t - t') / V`); the time-domain input `V^2 w` has intensity
//! **`q_t = q V^3`** [m^2/s^3]. The matrix entries therefore scale with `V` and `V^2` and the
//! noise with `V^3`, which is how the filter follows a changing speed (see [`crate::statespace`]).
//!
//! Over one step `h` the alignment block's process noise is that of white noise on `xi_tt`
//! (the damping terms change it by `O(V Oc h)`, 1.6 % at 20 m/s and 1 ms):
//! `Q = q_t [h^3/3, h^2/2; h^2/2, h]`.
//!
//! # Sources
//! `A = 2.119e-7 m rad`, `Or = 0.0206 rad/m`, `Oc = 0.8246 rad/m`: the low-disturbance German
//! alignment spectrum, docs/references.md section 3 (the same constants in four public codes). The
//! vehicle FMU's default track uses the same spectrum; a track of another quality calls for the
//! matching `prior_a` (high disturbance: 6.125e-7).

use crate::error::SettingError;
use serde::{Deserialize, Serialize};

/// The alignment prior (FMI parameter `alignment_model`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum AlignmentModel {
    /// 1: the paper's random walk (7 states).
    RandomWalk,
    /// 2: integrated random walk, `xi'' = w(s)` (8 states).
    IntegratedRandomWalk(Spectrum),
    /// 3: the shaping filter of the German spectrum (8 states).
    Shaping(Spectrum),
}

/// The alignment spectrum's constants (docs/references.md section 3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spectrum {
    /// Amplitude `A` [m rad].
    pub a: f64,
    /// Lower corner `Or` [rad/m].
    pub omega_r: f64,
    /// Upper corner `Oc` [rad/m].
    pub omega_c: f64,
}

impl Spectrum {
    /// The low-disturbance German alignment spectrum.
    pub const GERMAN_LOW: Spectrum = Spectrum {
        a: 2.119e-7,
        omega_r: 0.0206,
        omega_c: 0.8246,
    };

    /// White-noise intensity along the track, `q = pi A Oc^2` [m^2/m^3].
    pub fn intensity(&self) -> f64 {
        std::f64::consts::PI * self.a * self.omega_c * self.omega_c
    }

    /// One-sided spectral density at `omega` [m^2/(rad/m)].
    pub fn density(&self, omega: f64) -> f64 {
        let (o2, r2, c2) = (
            omega * omega,
            self.omega_r * self.omega_r,
            self.omega_c * self.omega_c,
        );
        self.a * c2 / ((o2 + r2) * (o2 + c2))
    }

    /// Refuses constants the priors cannot use: `a` and `omega_c` must be positive and finite,
    /// `omega_r` finite and not negative (0 is the integrated random walk's limit).
    pub fn check(&self) -> Result<(), SettingError> {
        let ok = |x: f64| x.is_finite() && x > 0.0;
        if !(ok(self.a) && ok(self.omega_c) && self.omega_r.is_finite() && self.omega_r >= 0.0) {
            return Err(SettingError::Prior {
                a: self.a,
                omega_r: self.omega_r,
                omega_c: self.omega_c,
            });
        }
        Ok(())
    }
}

impl AlignmentModel {
    /// The prior of the FMI parameter `alignment_model` (1, 2 or 3); the 8-state priors take
    /// `spectrum` (the `prior_*` parameters), checked. Another code is refused.
    pub fn from_fmi(code: i32, spectrum: Spectrum) -> Result<AlignmentModel, SettingError> {
        match code {
            1 => Ok(AlignmentModel::RandomWalk),
            2 | 3 => {
                spectrum.check()?;
                Ok(if code == 2 {
                    AlignmentModel::IntegratedRandomWalk(spectrum)
                } else {
                    AlignmentModel::Shaping(spectrum)
                })
            }
            other => Err(SettingError::AlignmentModel(other)),
        }
    }

    /// `(a1, a0, q)` of `xi'' + a1 xi' + a0 xi = w(s)`, `E[w w] = q delta`; `None` for the
    /// random walk.
    pub fn second_order(&self) -> Option<(f64, f64, f64)> {
        match self {
            AlignmentModel::RandomWalk => None,
            AlignmentModel::IntegratedRandomWalk(s) => Some((0.0, 0.0, s.intensity())),
            AlignmentModel::Shaping(s) => {
                Some((s.omega_r + s.omega_c, s.omega_r * s.omega_c, s.intensity()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shaping filter's stationary variance equals the integral of the spectrum
    /// (trapezoidal quadrature on a log grid, an independent computation).
    #[test]
    fn shaping_filter_variance_matches_the_spectrum_integral() {
        let s = Spectrum::GERMAN_LOW;
        let (a1, a0, q) = AlignmentModel::Shaping(s).second_order().unwrap();
        let filter_variance = q / (2.0 * a1 * a0);
        let n = 200_000;
        let (lo, hi) = (1e-6f64.ln(), 1e4f64.ln());
        let mut integral = 0.0;
        let mut prev: Option<(f64, f64)> = None;
        for k in 0..=n {
            let o = (lo + (hi - lo) * k as f64 / n as f64).exp();
            let f = s.density(o);
            if let Some((po, pf)) = prev {
                integral += 0.5 * (f + pf) * (o - po);
            }
            prev = Some((o, f));
        }
        assert!(
            (filter_variance / integral - 1.0).abs() < 1e-4,
            "{filter_variance} vs {integral}"
        );
        // 3.97 mm rms for the low-disturbance spectrum.
        assert!((filter_variance.sqrt() - 3.97e-3).abs() < 0.01e-3);
    }

    /// The filter's output spectrum `q / pi |H|^2` equals `S` at every wavenumber.
    #[test]
    fn shaping_filter_spectrum_matches_at_every_wavenumber() {
        let s = Spectrum::GERMAN_LOW;
        let (a1, a0, q) = AlignmentModel::Shaping(s).second_order().unwrap();
        for o in [1e-3, 0.02, 0.3, 0.8246, 2.0, 20.0] {
            // |(j o)^2 + a1 j o + a0|^2
            let re = a0 - o * o;
            let im = a1 * o;
            let out = q / std::f64::consts::PI / (re * re + im * im);
            assert!((out / s.density(o) - 1.0).abs() < 1e-12, "{o}");
        }
    }

    #[test]
    fn bad_codes_and_spectra_are_refused_by_name() {
        let e = AlignmentModel::from_fmi(4, Spectrum::GERMAN_LOW).unwrap_err();
        assert_eq!(e, crate::error::SettingError::AlignmentModel(4));
        assert!(e.to_string().contains("alignment_model"), "{e}");
        let bad = Spectrum {
            a: f64::NAN,
            ..Spectrum::GERMAN_LOW
        };
        assert!(
            AlignmentModel::from_fmi(3, bad)
                .unwrap_err()
                .to_string()
                .contains("prior_a")
        );
        assert_eq!(
            AlignmentModel::from_fmi(1, bad).unwrap(),
            AlignmentModel::RandomWalk
        );
    }
}
