//! The virtual sensors' errors: what turns the true specific force or rate at a sensor into
//! the sample a real inertial sensor gives.
//!
//! # The chain, per sensor
//! With `u` the true quantity along the sensor's nominal axis and `c` the one its mounting
//! misalignment couples in (below):
//!
//! 1. **misalignment** `m` \[rad\]: the sensitive axis turned by `m` toward the coupled axis,
//!    `u' = u cos m + c sin m`. Coupled axes, the ones that carry a signal in this model:
//!    - accelerometers (lateral axis `y`): turned toward the vertical, so `c = g + z''`, the
//!      vertical specific force: gravity enters through a tilt (0.3 deg: 0.05 m/s2). `z''` is
//!      `V^2 z_v''(s)` (the vertical profile's curvature) at the axle box and the frame point's
//!      `z_b'' - a theta_b''` (bounce and pitch, nose down positive) on the frame;
//!    - yaw gyroscope (axis `z`): turned toward the longitudinal axis, so `c` is the roll rate
//!      `phi_w'`;
//!    - roll gyroscope (axis `x`): turned toward the vertical, so `c` is the yaw rate `psi_w'`.
//!
//!    The longitudinal specific force is not modelled (the speed is held over each step).
//! 2. **anti-alias filter**: a second-order Butterworth low-pass of cut-off `bandwidth` \[Hz\]
//!    (0: none; at most 2 kHz) on `u'`, evaluated at every Runge-Kutta substep (the internal
//!    step is then at most `1 / (4 bandwidth)`, so at most 8 per millisecond; standing, at
//!    substeps of that size too) and discretized by the bilinear transform with the cut-off
//!    prewarped, so the sample is the filter's output at the communication point, as a MEMS
//!    part's internal digital low-pass before its output data rate;
//! 3. **scale factor error** `k`: `(1 + k) u'`;
//! 4. **bias**: the turn-on bias `b0` (constant) plus a first-order Gauss-Markov bias of
//!    stationary standard deviation `sigma_b` and correlation time `tau` \[s\]:
//!    `b' = -b / tau + w`, `w` white of power spectral density `2 sigma_b^2 / tau` (two-sided),
//!    so `b` has the PSD `4 sigma_b^2 tau / (1 + (2 pi f tau)^2)` (one-sided, per Hz: it
//!    integrates to `sigma_b^2` over `f` from 0 to infinity) and the
//!    exact discrete update over a step `h`:
//!    `b_(k+1) = e^(-h / tau) b_k + sigma_b sqrt(1 - e^(-2 h / tau)) n_k`, `n_k` standard
//!    normal. It starts at a draw from its stationary distribution. `tau` to infinity with
//!    `sigma_b^2 / tau` fixed is the random-walk bias of rate `sqrt(2 sigma_b^2 / tau)`;
//! 5. **white noise**: per sample, `sigma` (`sigma_acc`, `sigma_gyro`, `sigma_roll_gyro`), or
//!    from a noise density `N` (one-sided, per square-root hertz, as datasheets give it) when
//!    the FMU parameter `<sensor>_noise_psd` (`N^2`, so that its unit has integer SI exponents,
//!    m2/s3 or rad2/s) is set: `sigma = N sqrt(B)`, `B` the noise bandwidth: the Nyquist
//!    frequency `1 / (2 h)` of the communication step `h`, or the anti-alias filter's
//!    equivalent noise bandwidth (`1.11 bandwidth` for a second-order Butterworth) when that is
//!    lower. So rates compare at equal in-band noise;
//! 6. **range** `r` (0: none): saturation at `+-r`;
//! 7. **quantization** `q` (0: none): rounded to the nearest multiple of `q` (one LSB).
//!
//! The sample rate is the communication step: every communication point is one sample.
//! Every error is 0 by default, so the sensors are the paper's (white noise only).
//!
//! # Presets (`sensor_grade`)
//! `sensor_grade` 1 (tactical) or 2 (industrial MEMS) gives every error parameter left at 0
//! the preset's value (a parameter set explicitly, to anything other than 0, wins); the noise
//! density replaces the per-sample sigmas. Turn-on biases are the datasheet's 1-sigma figures
//! applied with a positive sign. Sources:
//!
//! | quantity | tactical (1): Honeywell HG1700 | industrial MEMS (2): Xsens MTi-1 class |
//! |---|---|---|
//! | accelerometer bias | 1 mg = 9.81e-3 m/s2 (HG1700 spec sheet, as NavToolkit's `hg1700_model`) | 1 mg turn-on (commercial grade 100-1000 ug: El-Sheimy and Youssef 2020, Satellite Navigation 1:2, Table 1); instability 0.03 mg, tau 100 s (MTi-1 "zero offset instability") |
//! | accelerometer noise density | 0.065 ft/s/sqrt(h) = 3.3e-4 m/s2/sqrt(Hz) | 120 ug/sqrt(Hz) = 1.18e-3 m/s2/sqrt(Hz) (MTi-1) |
//! | gyroscope bias | 1 deg/h = 4.85e-6 rad/s | 0.1 deg/s = 1.75e-3 rad/s turn-on (commercial grade, El-Sheimy and Youssef); instability 10 deg/h = 4.85e-5 rad/s, tau 100 s (MTi-1) |
//! | gyroscope noise density | 0.125 deg/sqrt(h) = 3.64e-5 rad/s/sqrt(Hz) | 0.007 deg/s/sqrt(Hz) = 1.22e-4 rad/s/sqrt(Hz) (MTi-1) |
//! | scale factor error | 3e-4 (assumed: not on the sheet) | 5e-3 (MTi-1 class non-linearity 0.5 % FS, as an upper bound) |
//! | misalignment | 5e-4 rad (mounting, assumed) | 1.75e-3 rad (0.1 deg mounting, assumed) |
//! | bandwidth | none | 324 Hz accelerometers, 255 Hz gyroscopes (MTi-1) |
//! | range, quantization | none | +-16 g and +-2000 deg/s (MTi-1), 16 bits: 4.79e-3 m/s2, 1.07e-3 rad/s |
//!
//! The MTi-1 figures are those of the sensor table in Transport Research (reference-global.com,
//! 10.2478/tar-2023-0022); HG1700 from its spec sheet through NavToolkit (is4s.github.io).

use crate::simulation::NoiseRng;
use serde::{Deserialize, Serialize};

/// The four sensors, in this order everywhere: `ws_acc_y`, `ws_yaw_rate`, `frame_acc_y`,
/// `ws_roll_rate`.
pub const NAMES: [&str; 4] = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y", "ws_roll_rate"];

/// One sensor's errors (module docs); all 0 is the ideal sensor.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SensorSpec {
    /// Turn-on bias \[unit\].
    pub bias: f64,
    /// Gauss-Markov bias: stationary standard deviation \[unit\].
    pub bias_instability: f64,
    /// Its correlation time \[s\].
    pub bias_tau: f64,
    /// Scale factor error (0.01: reads 1 % high).
    pub scale_error: f64,
    /// Misalignment toward the coupled axis \[rad\].
    pub misalignment: f64,
    /// White-noise density \[unit/sqrt(Hz)\]; 0: the per-sample sigma.
    pub noise_density: f64,
    /// Anti-alias cut-off \[Hz\]; 0: none.
    pub bandwidth: f64,
    /// Full scale \[unit\]; 0: none.
    pub range: f64,
    /// One LSB \[unit\]; 0: none.
    pub resolution: f64,
}

/// The presets of `sensor_grade` (module docs), per sensor in [`NAMES`] order.
pub fn preset(grade: i32) -> Option<[SensorSpec; 4]> {
    let g = crate::dynamics::GRAVITY;
    let deg = std::f64::consts::PI / 180.0;
    match grade {
        0 => Some([SensorSpec::default(); 4]),
        1 => {
            let acc = SensorSpec {
                bias: 1e-3 * g,
                noise_density: 3.3e-4,
                scale_error: 3e-4,
                misalignment: 5e-4,
                ..Default::default()
            };
            let gyro = SensorSpec {
                bias: deg / 3600.0,
                noise_density: 0.125 * deg / 60.0,
                scale_error: 3e-4,
                misalignment: 5e-4,
                ..Default::default()
            };
            Some([acc, gyro, acc, gyro])
        }
        2 => {
            let acc = SensorSpec {
                bias: 1e-3 * g,
                bias_instability: 0.03e-3 * g,
                bias_tau: 100.0,
                noise_density: 120e-6 * g,
                scale_error: 5e-3,
                misalignment: 0.1 * deg,
                bandwidth: 324.0,
                range: 16.0 * g,
                resolution: 32.0 * g / 65536.0,
            };
            let gyro = SensorSpec {
                bias: 0.1 * deg,
                bias_instability: 10.0 * deg / 3600.0,
                bias_tau: 100.0,
                noise_density: 0.007 * deg,
                scale_error: 5e-3,
                misalignment: 0.1 * deg,
                bandwidth: 255.0,
                range: 2000.0 * deg,
                resolution: 4000.0 * deg / 65536.0,
            };
            Some([acc, gyro, acc, gyro])
        }
        _ => None,
    }
}

/// A second-order Butterworth low-pass, bilinear with the cut-off prewarped, for one step size
/// (rebuilt when the substep changes). Direct form I: its state is the last two inputs and
/// outputs, signals that mean the same under the new coefficients, so a change of substep (a
/// speed change, a stop) does not jump the output as a direct form II state would.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct LowPass {
    dt: f64,
    b: [f64; 3],
    a: [f64; 2],
    /// The last two inputs and outputs, newest first.
    x: [f64; 2],
    y: [f64; 2],
    started: bool,
}

impl LowPass {
    /// Valid for `fc dt < 1 / 2` (the Nyquist frequency); the callers keep `fc dt <= 1 / 4`.
    fn design(fc: f64, dt: f64) -> ([f64; 3], [f64; 2]) {
        debug_assert!(
            fc * dt < 0.5,
            "cut-off {fc} Hz at the Nyquist frequency of {dt} s"
        );
        let k = (std::f64::consts::PI * fc * dt).tan();
        let q = std::f64::consts::SQRT_2;
        let norm = 1.0 / (1.0 + q * k + k * k);
        let b0 = k * k * norm;
        (
            [b0, 2.0 * b0, b0],
            [2.0 * (k * k - 1.0) * norm, (1.0 - q * k + k * k) * norm],
        )
    }

    /// The filter's output for input `x` after a step of `dt`; the first input sets the state
    /// to its steady state (the sensor has been on for long).
    pub fn next(&mut self, fc: f64, dt: f64, x: f64) -> f64 {
        if !fmi_abi::step::same(dt, self.dt) {
            (self.b, self.a) = Self::design(fc, dt);
            self.dt = dt;
        }
        if !self.started {
            // The steady state of a constant input x (unit gain at DC: y = x).
            (self.x, self.y) = ([x; 2], [x; 2]);
            self.started = true;
        }
        let (b, a) = (self.b, self.a);
        let y =
            b[0] * x + b[1] * self.x[0] + b[2] * self.x[1] - a[0] * self.y[0] - a[1] * self.y[1];
        self.x = [x, self.x[0]];
        self.y = [y, self.y[0]];
        y
    }
}

/// The sensors' error model and its running state. Part of the FMU state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sensors {
    /// The errors per sensor ([`NAMES`] order).
    pub spec: [SensorSpec; 4],
    /// The Gauss-Markov biases now.
    pub drift: [f64; 4],
    /// The anti-alias filters.
    filters: [LowPass; 4],
    /// The filters' latest outputs (the misaligned signal, low-passed).
    filtered: [f64; 4],
    /// The Gauss-Markov biases' generator: the noise generator jumped twice, a stream no
    /// other output draws from, so turning the drift on leaves every other sample as it was.
    rng: NoiseRng,
}

impl Sensors {
    /// Sensors with these errors; `rng` seeds the drift (its stationary start drawn here).
    pub fn new(spec: [SensorSpec; 4], mut rng: NoiseRng) -> Sensors {
        let drift = std::array::from_fn(|i| {
            if spec[i].bias_instability > 0.0 {
                spec[i].bias_instability * rng.normal()
            } else {
                0.0
            }
        });
        Sensors {
            spec,
            drift,
            filters: Default::default(),
            filtered: [0.0; 4],
            rng,
        }
    }

    /// Whether every error is 0 (the paper's sensors: the samples are the truth plus the
    /// per-sample white noise, computed as before the errors existed).
    pub fn is_ideal(&self) -> bool {
        self.spec.iter().all(|s| *s == SensorSpec::default())
    }

    /// The longest substep the anti-alias filters allow \[s\]: a quarter period of the highest
    /// cut-off (module docs); `None` without a filter.
    pub fn filter_step(&self) -> Option<f64> {
        let bandwidth = self.spec.iter().map(|s| s.bandwidth).fold(0.0, f64::max);
        (bandwidth > 0.0).then(|| 0.25 / bandwidth)
    }

    /// The misaligned signals: `u cos m + c sin m` per sensor (module docs).
    pub fn sensed(&self, u: [f64; 4], c: [f64; 4]) -> [f64; 4] {
        std::array::from_fn(|i| {
            let m = self.spec[i].misalignment;
            if m == 0.0 {
                u[i]
            } else {
                u[i] * m.cos() + c[i] * m.sin()
            }
        })
    }

    /// Feeds the anti-alias filters the misaligned signals after a substep of `dt`.
    pub fn filter(&mut self, sensed: [f64; 4], dt: f64) {
        for (i, &x) in sensed.iter().enumerate() {
            let fc = self.spec[i].bandwidth;
            self.filtered[i] = if fc > 0.0 {
                self.filters[i].next(fc, dt, x)
            } else {
                x
            };
        }
    }

    /// The samples at a communication point after a step of `h`, from the misaligned signals
    /// there (`sensed`, already fed to the filters when they are on) and the white noise
    /// `noise` (standard normal deviates) with the per-sample sigmas `sigma`.
    pub fn sample(
        &mut self,
        sensed: [f64; 4],
        h: f64,
        sigma: [f64; 4],
        noise: [f64; 4],
    ) -> [f64; 4] {
        std::array::from_fn(|i| {
            let s = &self.spec[i];
            let x = if s.bandwidth > 0.0 {
                self.filtered[i]
            } else {
                sensed[i]
            };
            if s.bias_instability > 0.0 && s.bias_tau > 0.0 && h > 0.0 {
                let a = (-h / s.bias_tau).exp();
                self.drift[i] = a * self.drift[i]
                    + s.bias_instability * (1.0 - a * a).sqrt() * self.rng.normal();
            }
            let sd = if s.noise_density > 0.0 {
                let nyquist = if h > 0.0 { 0.5 / h } else { f64::INFINITY };
                let band = if s.bandwidth > 0.0 {
                    nyquist.min(1.11 * s.bandwidth)
                } else {
                    nyquist
                };
                if band.is_finite() {
                    s.noise_density * band.sqrt()
                } else {
                    0.0
                }
            } else {
                sigma[i]
            };
            let mut y = (1.0 + s.scale_error) * x + s.bias + self.drift[i] + sd * noise[i];
            if s.resolution > 0.0 {
                y = (y / s.resolution).round() * s.resolution;
            }
            // After the rounding, so that no sample lies beyond the full scale.
            if s.range > 0.0 {
                y = y.clamp(-s.range, s.range);
            }
            y
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The low-pass against the analytic Butterworth magnitude `1 / sqrt(1 + (f / fc)^4)`: a
    /// sine's steady amplitude through it at three frequencies, and unit gain at DC.
    #[test]
    fn the_anti_alias_filter_is_a_butterworth() {
        let (fc, dt) = (100.0, 1e-4);
        for f in [0.0, 30.0, 100.0, 300.0] {
            let mut lp = LowPass::default();
            let n = 200_000;
            let mut peak: f64 = 0.0;
            for k in 0..n {
                let t = k as f64 * dt;
                let x = if f == 0.0 {
                    1.0
                } else {
                    (2.0 * std::f64::consts::PI * f * t).sin()
                };
                let y = lp.next(fc, dt, x);
                if k > n / 2 {
                    peak = peak.max(y.abs());
                }
            }
            // Exact at DC and at the prewarped cut-off; the bilinear transform's frequency
            // warping is 0.5 % at 3 fc with this step.
            let want = 1.0 / (1.0 + (f / fc).powi(4)).sqrt();
            assert!(
                (peak - want).abs() < 1e-2 * want,
                "{f} Hz: {peak} vs {want}"
            );
        }
    }

    /// The Gauss-Markov bias: stationary variance and lag-one autocorrelation `e^(-h / tau)`,
    /// from a long sample.
    #[test]
    fn the_drift_is_first_order_gauss_markov() {
        let spec = SensorSpec {
            bias_instability: 2.0,
            bias_tau: 0.5,
            ..Default::default()
        };
        let mut s = Sensors::new([spec; 4], NoiseRng::new(3));
        let h = 0.01;
        let xs: Vec<f64> = (0..400_000)
            .map(|_| s.sample([0.0; 4], h, [0.0; 4], [0.0; 4])[0])
            .collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        let lag1 = xs
            .windows(2)
            .map(|w| (w[0] - mean) * (w[1] - mean))
            .sum::<f64>()
            / n
            / var;
        assert!((var.sqrt() - 2.0).abs() < 0.05, "{}", var.sqrt());
        assert!((lag1 - (-h / 0.5f64).exp()).abs() < 2e-3, "{lag1}");
    }

    /// Scale, bias, misalignment, saturation and quantization in the order of the module docs,
    /// against the values computed by hand; the noise density's sigma at two steps.
    #[test]
    fn the_deterministic_errors_compose_as_documented() {
        let spec = SensorSpec {
            bias: 0.1,
            scale_error: 0.02,
            misalignment: 0.01,
            resolution: 0.004,
            range: 2.0,
            ..Default::default()
        };
        let mut s = Sensors::new([spec; 4], NoiseRng::new(1));
        let sensed = s.sensed([0.5, 0.5, 3.0, 0.5], [9.81, 0.0, 9.81, 0.0]);
        let want = 0.5 * 0.01f64.cos() + 9.81 * 0.01f64.sin();
        assert!((sensed[0] - want).abs() < 1e-15);
        let y = s.sample(sensed, 1e-3, [0.0; 4], [0.0; 4]);
        let raw = 1.02 * want + 0.1;
        assert!((y[0] - (raw / 0.004).round() * 0.004).abs() < 1e-12);
        assert_eq!(y[2], 2.0, "saturated at the range");
        let dense = SensorSpec {
            noise_density: 1e-3,
            ..Default::default()
        };
        let mut s = Sensors::new([dense; 4], NoiseRng::new(1));
        let one = s.sample([0.0; 4], 1e-3, [9.0; 4], [1.0; 4])[0];
        let two = s.sample([0.0; 4], 2e-3, [9.0; 4], [1.0; 4])[0];
        assert!((one - 1e-3 * 500f64.sqrt()).abs() < 1e-15);
        assert!((two - 1e-3 * 250f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn grade_zero_is_ideal_and_others_are_refused() {
        assert_eq!(preset(0), Some([SensorSpec::default(); 4]));
        assert!(preset(1).is_some() && preset(2).is_some());
        assert_eq!(preset(3), None);
    }
}
