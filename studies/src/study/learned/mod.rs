//! The learned filters: the estimator FMU's default and the offline studies' smoother.
//!
//! | what | where | used by |
//! |---|---|---|
//! | the tap bank the estimator FMU runs by default (`estimator` 2): causal and fixed-lag taps per speed, sensor set and contact condition, fitted in the metric's bands, with the bank's contract | [`taps`] (`alignment-studies taps`); run-time side `fmu_estimator::learned` | `fmu-estimator/resources/learned*.taps`, the FMU, `smooth --learned`, the Python bindings |
//! | the contact condition's estimator stored in that bank | `contact` | [`taps`] |
//! | the band-limited correlations the bank's fit solves | [`spectra`] | [`taps`] |
//! | the offline learned smoother below (two-sided FIR + Kalman RTS hybrid) | this module, [`Fir`] | `alignment-studies learn` and `variants` |
//!
//! The rest of these docs describe the offline smoother: the alignment estimated from the three
//! sensors by a multichannel, two-sided FIR (Wiener) filter whose taps are fitted on the
//! calibration seed's run, and its combination with the Kalman (RTS) smoother, which keeps the
//! long waves. The shipped bank's method is in [`taps`] and docs/learned-filter.md.
//!
//! # Why
//! `docs/cross-level.md`: the Kalman filter's D1 error on our vehicle comes from the track's
//! cross-level, whose effect on the axle box and on the car body the paper's three-mass model
//! cannot represent. A linear estimator that is not bound to that model measures how much of the
//! alignment the three sensors carry; fitted on one seed and judged on others, it is also an
//! offline estimator in its own right. It is a black box of the vehicle it was trained on, at
//! the speed it was trained at: it needs a training run of that vehicle (here, the vehicle FMU on
//! the calibration seed), which the model-based filter does not.
//!
//! # Method
//! 1. Grid: the sensors are low-passed (Butterworth, order 8, zero phase, cut-off at 0.4 of the
//!    decimated sampling rate, i.e. a 2.5 m wavelength at the default 1 m grid) and every `D`-th
//!    sample is kept, `D = round(ds / (V h))`, so the samples are `ds` apart along the track.
//!    The window is [`SMOOTHER_WINDOW`] each way whatever `ds`, i.e. `P = SMOOTHER_WINDOW / ds` points.
//!    Each channel is scaled to unit variance on the training run (conditioning only).
//! 2. Estimate at grid point `m`: `e[m] = sum_c sum_{l = -f}^{p} w[c, l] x_c[m - l]`, a window of
//!    up to `P` points behind (`l > 0`) and ahead (`l < 0`).
//! 3. Taps: least squares against the target `t` (the true alignment band-passed to
//!    [`TARGET`], the band the window can resolve). With the correlations
//!    `rho_cd(tau) = (1/N) sum_n x_c[n] x_d[n + tau]` (biased, so the matrix below is a Gram
//!    matrix and positive semi-definite), `E[x_c[n - l] x_d[n - k]] = rho_cd(l - k)` and
//!    `E[x_c[n - l] t[n]] = rho_ct(l)`: the Wiener-Hopf equations `R w = r`, solved by
//!    Cholesky with a ridge of `RIDGE` times the mean diagonal.
//! 4. Edges: where the window would leave the record, it is cut to the samples that exist and
//!    the taps for the cut window solve the same equations restricted to its lags (the best
//!    linear estimate from the data there, not the full filter with zeros). The first and last
//!    `P` points use such one-sided windows.
//! 5. Hybrid: `e_h = k + HP(e - k)`, `k` the Kalman smoother's estimate on the same grid and
//!    `HP` a zero-phase Butterworth high-pass (order 4) at the split wavelength: the learned
//!    filter for the waves shorter than the split, the Kalman smoother for the longer ones (the
//!    complementary low-pass is `1 - HP` exactly, since both act on the difference).
//! 6. Honest evaluation: the taps are fitted on the calibration seed's run after its first 20 s;
//!    the split is then chosen from [`SPLITS`] by whole-band Jrel on those first 20 s (the
//!    standard case's calibration record, a stretch of track the taps have not seen); the
//!    evaluation seeds play no part in either ([`LearnedSmoother::tune_split`]).
//!
//! # On board: a fixed lag
//! [`Lookahead::FixedLag`] keeps the window's look-ahead to a few grid points (the study uses
//! 20 m, 1 s at 20 m/s: the estimate of a position is final once the train is 20 m past it) and
//! makes every filter causal: the anti-alias filter runs forward only (the taps learn to undo its
//! delay), the partner is the paper's causal Kalman filter, and the split is a causal high-pass
//! of order 2 ([`causal_hybrid`]), whose complement falls only as `1 / frequency`, so part of the
//! Kalman filter's D1 error comes through.
//!
//! # Measured
//! The figures (`alignment-studies variants`, held-out seeds) are in docs/learned-filter.md
//! and in the variants report.

pub(crate) mod contact;
mod fir;
pub mod recorded;
pub mod spectra;
mod split;
pub mod stage;
pub mod taps;
mod training;

pub use fir::Fir;
pub use split::{causal_hybrid, highpass, hybrid};
pub use training::{kalker_label, learn, provenance, training_runs, validation};

use super::metrics::{BandMetrics, bandpass, butter, evaluate, filtfilt};
use super::records::{Record, estimate};
use super::runs::STEP;
use super::standard::{DS, TRIM};
use crate::Error;
use fmu_estimator::offline::Sample;
use sci_rs::signal::filter::design::FilterBandType;
use sci_rs::signal::filter::sosfilt_dyn;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The anti-alias low-pass's cut-off, as a fraction of the decimated sampling rate: 0.4 of it
/// (0.8 of the decimated Nyquist frequency) leaves the order-8 Butterworth room to fall before
/// the folding frequency.
const ANTI_ALIAS_CUTOFF: f64 = 0.4;

/// How much the speed may vary (relative) over a record the smoother is applied to: it is fitted
/// at one constant speed.
const SPEED_TOLERANCE: f64 = 0.01;

/// The default grid step along the track \[m\] (20 Hz at 20 m/s).
pub const SMOOTHER_GRID: f64 = 1.0;
/// Half window \[m\]: `P = SMOOTHER_WINDOW / grid` points each way.
pub const SMOOTHER_WINDOW: f64 = 60.0;
/// The band the taps are fitted to: D1 and D2, which a 120 m window resolves.
pub const TARGET: super::metrics::Band = super::metrics::Band {
    name: "3-70 m",
    short: 3.0,
    long: 70.0,
};
/// The split wavelengths \[m\] tried: above the split the hybrid takes the Kalman estimate.
pub const SPLITS: [f64; 6] = [20.0, 30.0, 40.0, 50.0, 70.0, 100.0];
/// Ridge, relative to the mean diagonal of the normal equations.
pub const RIDGE: f64 = 1e-6;
/// Training samples skipped at the start of the run (the vehicle's start transient) \[s\].
const SKIP: f64 = 2.0;

/// How far ahead of the estimated position the learned filter may look.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Lookahead {
    /// [`SMOOTHER_WINDOW`] each way, zero-phase anti-alias filter and split: offline.
    Smoother,
    /// At most this many grid points ahead (0: causal), with a causal anti-alias filter and a causal split
    /// (the estimate for a position is complete once the train is that far past it): on board.
    FixedLag(usize),
}

/// The Kalman estimate the hybrid takes the long waves from: estimator parameters and whether
/// the RTS smoother's estimate is used (else the causal filter's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Partner {
    /// The partner in words, for the reports (not read back).
    pub name: String,
    /// The estimator's parameters by FMI name and value, as `--set` gives them; the rest at
    /// their defaults.
    pub settings: Vec<(String, String)>,
    /// The RTS smoother's estimate (offline, two-sided) rather than the causal filter's.
    pub smooth: bool,
}

/// The learned smoother of a vehicle at one speed and step: grid, anti-alias filter, taps, and
/// the hybrid's split and Kalman partner. Saved as JSON by `alignment-studies learn`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LearnedSmoother {
    /// Format of the saved file; [`FORMAT`].
    pub format: u32,
    /// How it was made (vehicle, seed, run length).
    pub provenance: String,
    /// The constant speed it was trained at \[m/s\]: records at another speed (by more than
    /// 1 %) are refused, the taps holding the vehicle's dynamics at this one.
    pub speed: f64,
    /// The sample step it was trained with \[s\]: records with another step are refused.
    pub step: f64,
    /// Samples per grid point: the grid step is `speed * step * decimation`.
    pub decimation: usize,
    /// Two-sided offline smoother or on-board fixed lag; decides whether the anti-alias filter
    /// and the split run causally.
    pub lookahead: Lookahead,
    /// The hybrid's split wavelength \[m\] ([`Self::tune_split`]; 40 m until tuned).
    pub split: f64,
    /// The Kalman estimate the hybrid takes the waves longer than `split` from.
    pub partner: Partner,
    fir: Fir,
}

/// The saved file's format number.
pub const FORMAT: u32 = 1;

/// The sensor channels of `samples` low-passed and decimated by `decimation`.
fn channels(
    samples: &[Sample],
    step: f64,
    decimation: usize,
    causal: bool,
) -> Result<Vec<Vec<f64>>, Error> {
    let cols: [fn(&Sample) -> f64; 3] = [|s| s.ws_acc_y, |s| s.ws_yaw_rate, |s| s.frame_acc_y];
    cols.iter()
        .map(|f| {
            let x: Vec<f64> = samples.iter().map(f).collect();
            decimate(&x, step, decimation, causal)
        })
        .collect()
}

/// Anti-alias low-pass (module docs, step 1), forward only when `causal`, and every
/// `decimation`-th sample.
fn decimate(x: &[f64], step: f64, decimation: usize, causal: bool) -> Result<Vec<f64>, Error> {
    let fs = 1.0 / step;
    let mut sos = butter(
        8,
        vec![ANTI_ALIAS_CUTOFF * fs / decimation as f64],
        FilterBandType::Lowpass,
        fs,
    )?;
    let y = if causal {
        sosfilt_dyn(x.iter(), &mut sos)
    } else {
        filtfilt(x, &sos, "anti-alias filter")?
    };
    Ok(y.into_iter().step_by(decimation).collect())
}

/// The decimation that puts samples `grid` metres apart at `speed` (rounded to whole samples
/// of the study's step); refuses a grid finer than one sample or coarser than half the window.
pub fn decimation(speed: f64, grid: f64) -> Result<usize, Error> {
    let sample = speed * STEP;
    if !(grid.is_finite() && grid >= 0.5 * sample && grid <= 0.5 * SMOOTHER_WINDOW) {
        return Err(Error::input(format!(
            "the grid step must lie between one sample at {speed} m/s ({sample} m) and half the window ({} m), not {grid} m",
            0.5 * SMOOTHER_WINDOW
        )));
    }
    Ok(((grid / sample).round() as usize).max(1))
}

/// The partner the study uses for `lookahead`: the shaping filter's RTS smoother with the
/// virtual measurement's sigma `shaping_sigma_xi` offline, the paper's causal filter on board.
pub fn default_partner(lookahead: Lookahead, shaping_sigma_xi: f64) -> Partner {
    match lookahead {
        Lookahead::Smoother => Partner {
            name: "shaping filter, RTS smoother".into(),
            settings: vec![
                ("alignment_model".into(), "3".into()),
                ("prior_sigma_xi".into(), shaping_sigma_xi.to_string()),
            ],
            smooth: true,
        },
        Lookahead::FixedLag(_) => Partner {
            name: "paper (random walk)".into(),
            settings: vec![("alignment_model".into(), "1".into())],
            smooth: false,
        },
    }
}

impl LearnedSmoother {
    /// Fits the taps on a constant-speed run `rec` with its true alignment; the hybrid will
    /// use `partner` with a 40 m split until [`Self::tune_split`].
    /// `grid` is the step along the track \[m\] the sensors are decimated to (rounded to a
    /// whole number of samples at the run's speed).
    pub fn train(
        rec: &Record,
        lookahead: Lookahead,
        grid: f64,
        partner: Partner,
        provenance: &str,
    ) -> Result<LearnedSmoother, Error> {
        let speed = constant_speed(&rec.samples, None)?;
        let decimation = decimation(speed, grid)?;
        let half_window = (SMOOTHER_WINDOW / (speed * STEP * decimation as f64)).round() as usize;
        if let Lookahead::FixedLag(n) = lookahead
            && n > half_window
        {
            return Err(Error::input(format!(
                "a look-ahead of {n} grid points is beyond the window ({half_window} points, {SMOOTHER_WINDOW} m)"
            )));
        }
        let skip = (SKIP / STEP) as usize;
        if rec.samples.len() <= skip {
            return Err(Error::input(
                "the training run is shorter than its start transient",
            ));
        }
        let (future, causal) = match lookahead {
            Lookahead::Smoother => (half_window, false),
            Lookahead::FixedLag(n) => (n, true),
        };
        let x = channels(&rec.samples[skip..], STEP, decimation, causal)?;
        let truth: Vec<f64> = rec.alignment[skip..]
            .iter()
            .step_by(decimation)
            .copied()
            .collect();
        let target = bandpass(&truth, speed * STEP * decimation as f64, &TARGET)?;
        Ok(LearnedSmoother {
            format: FORMAT,
            provenance: provenance.into(),
            speed,
            step: STEP,
            decimation,
            lookahead,
            split: 40.0,
            partner,
            fir: Fir::fit(&x, &target, half_window, future, RIDGE)?,
        })
    }

    fn causal(&self) -> bool {
        matches!(self.lookahead, Lookahead::FixedLag(_))
    }

    /// The grid step along the track \[m\].
    pub fn grid(&self) -> f64 {
        self.speed * self.step * self.decimation as f64
    }

    /// The learned and the hybrid estimates of `samples` (step `h`) on the grid (sample
    /// `m * decimation`), the hybrid with the partner's estimate `kalman` (one per sample).
    pub fn apply(
        &self,
        samples: &[Sample],
        h: f64,
        kalman: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), Error> {
        if (h - self.step).abs() > 1e-9 * self.step {
            return Err(Error::input(format!(
                "the learned smoother was trained with a step of {} s; the record's step is {h} s",
                self.step
            )));
        }
        if kalman.len() != samples.len() {
            return Err(Error::input(format!(
                "{} Kalman estimates for {} samples",
                kalman.len(),
                samples.len()
            )));
        }
        constant_speed(samples, Some(self.speed))?;
        let est = self
            .fir
            .apply(&channels(samples, h, self.decimation, self.causal())?)?;
        // A causal anti-alias filter would delay the Kalman estimate (the learned taps undo the
        // delay of the sensors' one, not this); the estimate has little content near the
        // decimated Nyquist rate, so it is sampled as it is.
        let k: Vec<f64> = if self.causal() {
            kalman.iter().step_by(self.decimation).copied().collect()
        } else {
            decimate(kalman, h, self.decimation, false)?
        };
        let hybrid = if self.causal() {
            causal_hybrid(&est, &k, self.grid(), self.split)?
        } else {
            hybrid(&est, &k, self.grid(), self.split)?
        };
        Ok((est, hybrid))
    }

    /// The partner's Kalman estimate of `samples` (step `h`), one per sample.
    pub fn kalman(&self, samples: &[Sample], h: f64) -> Result<Vec<f64>, Error> {
        let p = &self.partner;
        Ok(estimate(samples, h, &p.settings, None, p.smooth)?.1)
    }

    /// The learned estimate and the hybrid on `rec`, each evaluated against the truth.
    pub fn evaluate(&self, rec: &Record) -> Result<(BandMetrics, BandMetrics), Error> {
        let kalman = self.kalman(&rec.samples, STEP)?;
        self.evaluate_with(rec, &kalman)
    }

    fn evaluate_with(
        &self,
        rec: &Record,
        kalman: &[f64],
    ) -> Result<(BandMetrics, BandMetrics), Error> {
        let (est, hybrid) = self.apply(&rec.samples, STEP, kalman)?;
        let distance: Vec<f64> = rec
            .distance
            .iter()
            .step_by(self.decimation)
            .copied()
            .collect();
        Ok((
            evaluate(&distance, &est, &rec.distance, &rec.alignment, DS, TRIM)?,
            evaluate(&distance, &hybrid, &rec.distance, &rec.alignment, DS, TRIM)?,
        ))
    }

    /// Chooses the split from [`SPLITS`] by the hybrid's mean whole-band Jrel on `validation`
    /// (records the taps were not fitted on); returns that Jrel.
    pub fn tune_split(&mut self, validation: &[Record]) -> Result<f64, Error> {
        let kalman: Vec<Vec<f64>> = validation
            .iter()
            .map(|r| self.kalman(&r.samples, STEP))
            .collect::<Result<_, _>>()?;
        let mut best = (self.split, f64::INFINITY);
        for split in SPLITS {
            self.split = split;
            let mut sum = 0.0;
            for (r, k) in validation.iter().zip(&kalman) {
                sum += self.evaluate_with(r, k)?.1.whole.jrel;
            }
            let j = sum / validation.len() as f64;
            if j < best.1 {
                best = (split, j);
            }
        }
        if !best.1.is_finite() {
            return Err(Error::input(
                "no split gave a finite accuracy on the validation records",
            ));
        }
        self.split = best.0;
        Ok(best.1)
    }

    /// The saved form.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("plain numbers and strings")
    }

    /// Reads a saved smoother, checking its format and that its taps fit its windows.
    pub fn from_json(text: &str, file: &Path) -> Result<LearnedSmoother, Error> {
        let l: LearnedSmoother = serde_json::from_str(text).map_err(|e| {
            Error::input(format!(
                "{}: not a learned smoother file: {e}",
                file.display()
            ))
        })?;
        if l.format != FORMAT {
            return Err(Error::input(format!(
                "{}: format {} (this orchestrator reads format {FORMAT})",
                file.display(),
                l.format
            )));
        }
        let finite = [l.speed, l.step, l.split]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        if !finite || l.decimation == 0 {
            return Err(Error::input(format!(
                "{}: speed, step, split and decimation must be positive",
                file.display()
            )));
        }
        l.fir.check().map_err(|e| e.context(file.display()))?;
        Ok(l)
    }
}

/// The record's speed, refusing records whose speed varies by more than 1 % or differs from
/// `expected` by more than 1 %: the taps hold the vehicle's dynamics at one speed.
fn constant_speed(samples: &[Sample], expected: Option<f64>) -> Result<f64, Error> {
    let (lo, hi) = samples
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s.speed), hi.max(s.speed))
        });
    if !(lo > 0.0 && hi.is_finite() && hi <= (1.0 + SPEED_TOLERANCE) * lo) {
        return Err(Error::input(format!(
            "the learned smoother needs a constant speed; the record's speed ranges from {lo} to {hi} m/s"
        )));
    }
    let v = 0.5 * (lo + hi);
    if let Some(e) = expected
        && (v - e).abs() > 0.01 * e
    {
        return Err(Error::input(format!(
            "the learned smoother was trained at {e} m/s; the record runs at {v} m/s"
        )));
    }
    Ok(v)
}

/// Reproducible synthetic signals for the tests and the benchmark: the learned filter's cost and
/// its structural properties (causality, exact inverses) do not depend on the values.
pub mod synthetic {
    use super::Record;
    use crate::study::runs::STEP;
    use fmu_estimator::offline::Sample;

    /// Reproducible uniform noise in [-0.5, 0.5) (an LCG).
    pub fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut state = seed
            .wrapping_mul(2862933555777941757)
            .wrapping_add(3037000493);
        (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    /// A constant-speed record of noise (20 m/s, the study's step): sensors from seeds `seed`
    /// to `seed + 2`, the alignment from `seed + 3`.
    pub fn noise_record(seconds: f64, seed: u64) -> Record {
        let n = (seconds / STEP) as usize;
        Record {
            samples: Sample::from_columns(
                &vec![20.0; n],
                &noise(n, seed),
                &noise(n, seed + 1),
                &noise(n, seed + 2),
            ),
            distance: (1..=n).map(|k| 20.0 * STEP * k as f64).collect(),
            alignment: noise(n, seed + 3),
        }
    }

    /// Root mean square.
    pub fn rms(x: &[f64]) -> f64 {
        (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::synthetic::{noise, noise_record};
    use super::*;

    #[test]
    fn the_causal_anti_alias_filter_reads_no_later_sample() {
        // Oracle: causality. A change at sample 3000 reaches the decimated sample 60 and no
        // earlier one.
        let raw = noise(5000, 8);
        let mut changed = raw.clone();
        changed[3000] += 1.0;
        let (d0, d1) = (
            decimate(&raw, STEP, 50, true).unwrap(),
            decimate(&changed, STEP, 50, true).unwrap(),
        );
        assert_eq!(d0[..60], d1[..60]);
        assert_ne!(d0[60], d1[60]);
    }

    #[test]
    fn the_on_board_pipeline_is_causal_up_to_its_lag() {
        // Oracle: causality. The whole fixed-lag path (anti-alias filter, taps, the Kalman
        // estimate's sampling, the causal split) must give the same estimates before the
        // position a change reaches minus the look-ahead: for the study's 20 m on the 1 m grid
        // and for its causal and 3 m forms on the 0.2 m grid.
        for (lag, grid) in [(20, SMOOTHER_GRID), (0, 0.2), (15, 0.2)] {
            let partner = default_partner(Lookahead::FixedLag(lag), 1.0);
            let l = LearnedSmoother::train(
                &noise_record(60.0, 1),
                Lookahead::FixedLag(lag),
                grid,
                partner,
                "test",
            )
            .unwrap();
            assert!((l.grid() - grid).abs() < 1e-12, "grid {}", l.grid());
            let rec = noise_record(20.0, 9);
            let kalman = noise(rec.samples.len(), 13);
            let (est, hybrid) = l.apply(&rec.samples, STEP, &kalman).unwrap();
            let k = 12_345;
            let mut samples = rec.samples.clone();
            let mut kalman2 = kalman.clone();
            for s in &mut samples[k..] {
                s.ws_acc_y += 1.0;
                s.frame_acc_y -= 1.0;
            }
            for v in &mut kalman2[k..] {
                *v += 1.0;
            }
            let (est2, hybrid2) = l.apply(&samples, STEP, &kalman2).unwrap();
            let first = k.div_ceil(l.decimation) - lag;
            assert_eq!(est[..first], est2[..first], "lag {lag}, grid {grid}");
            assert_eq!(hybrid[..first], hybrid2[..first], "lag {lag}, grid {grid}");
            assert_ne!(
                hybrid[first + lag],
                hybrid2[first + lag],
                "lag {lag}, grid {grid}"
            );
        }
    }

    #[test]
    fn records_at_another_or_a_varying_speed_are_refused() {
        let s = |v: f64| Sample::from_columns(&[v], &[0.0], &[0.0], &[0.0])[0];
        let varying = vec![s(10.0), s(20.0)];
        let e = constant_speed(&varying, None).unwrap_err();
        assert_eq!(e.exit_code(), 2, "bad input: {e}");
        let e = e.to_string();
        assert!(e.contains("from 10 to 20 m/s"), "{e}");
        let e = constant_speed(&[s(15.0)], Some(20.0))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("trained at 20 m/s") && e.contains("15 m/s"),
            "{e}"
        );
        assert_eq!(
            constant_speed(&[s(20.0), s(20.1)], Some(20.0)).unwrap(),
            20.05
        );
    }
}
