//! The correlations the banded least squares needs, from weighted cross-spectra.
//!
//! The taps minimise the error as the metric measures it: each band's zero-phase band-pass
//! (forward and backward, so `|H_b|^2`) applied to estimate minus truth. Because the FIR and
//! the band-pass are both linear and time-invariant they commute: band-passing the regressors
//! and the target with the same zero-phase filter and fitting on those is the same least
//! squares. Its normal equations need the correlations of the filtered signals,
//! `rho_cd(tau) = (1/N) sum_n (G x_c)[n] (G x_d)[n + tau]` with `G = |H_b|^2`; in the frequency
//! domain that is the inverse transform of `|H_b|^4 conj(X_c) X_d`, and a weighted sum over
//! bands is one weight `W = sum_b w_b |H_b|^4` (zero-padded FFTs: linear, biased correlations,
//! which keep the normal matrix positive semi-definite; the filters' start and end transients,
//! a few hundred points in hundreds of thousands, are left out).

use crate::Error;
use crate::study::metrics::{Band, ORDER, butter};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex64;
use sci_rs::signal::filter::design::FilterBandType;

/// `|H(f)|^2` of the metric's Butterworth band-pass for `band` on a grid of step `ds`, at
/// frequency `f` cycles per metre (the same design the metric filters with).
pub fn band_power(band: &Band, ds: f64) -> Result<impl Fn(f64) -> f64, Error> {
    let sos = butter(
        ORDER,
        vec![1.0 / band.long, 1.0 / band.short],
        FilterBandType::Bandpass,
        1.0 / ds,
    )?;
    let sections: Vec<([f64; 3], [f64; 3])> = sos.iter().map(|s| (s.b, s.a)).collect();
    Ok(move |f: f64| {
        let w = std::f64::consts::TAU * f * ds;
        let z1 = Complex64::from_polar(1.0, -w);
        let z2 = z1 * z1;
        sections
            .iter()
            .map(|(b, a)| {
                let num = b[0] + b[1] * z1 + b[2] * z2;
                let den = a[0] + a[1] * z1 + a[2] * z2;
                (num / den).norm_sqr()
            })
            .product()
    })
}

/// Weighted correlations accumulated over several records (runs).
pub struct Correlations {
    span: usize,
    channels: usize,
    /// `cc[c][d][tau + span]` and `ct[c][tau + span]`, sums over records (not yet divided).
    cc: Vec<Vec<Vec<f64>>>,
    ct: Vec<Vec<f64>>,
    count: usize,
    /// `sum_n (G t)[n]^2` for each weight given to [`Self::add`] as `extra`.
    pub extra: Vec<f64>,
}

impl Correlations {
    /// Empty sums for `channels` regressors at lags up to `span` each way, and `extra` weighted
    /// target powers ([`Self::extra`]).
    pub fn new(channels: usize, span: usize, extra: usize) -> Correlations {
        Correlations {
            span,
            channels,
            cc: vec![vec![vec![0.0; 2 * span + 1]; channels]; channels],
            ct: vec![vec![0.0; 2 * span + 1]; channels],
            count: 0,
            extra: vec![0.0; extra],
        }
    }

    /// Adds one record: channels `x` (equal lengths), target `t`, the weight `weight(f)` and
    /// further weights `extra` whose weighted target power is accumulated (band variances).
    pub fn add(
        &mut self,
        x: &[Vec<f64>],
        t: &[f64],
        weight: &dyn Fn(f64) -> f64,
        extra: &[&dyn Fn(f64) -> f64],
        ds: f64,
    ) {
        let n = t.len();
        let nfft = (n + self.span + 1).next_power_of_two();
        let mut planner = FftPlanner::<f64>::new();
        let fwd = planner.plan_fft_forward(nfft);
        let inv = planner.plan_fft_inverse(nfft);
        let spectrum = |v: &[f64]| {
            let mut b: Vec<Complex64> = v.iter().map(|x| Complex64::new(*x, 0.0)).collect();
            b.resize(nfft, Complex64::new(0.0, 0.0));
            fwd.process(&mut b);
            b
        };
        let freq = |k: usize| {
            let k = if k <= nfft / 2 { k } else { nfft - k };
            k as f64 / (nfft as f64 * ds)
        };
        let w: Vec<f64> = (0..nfft).map(|k| weight(freq(k))).collect();
        let xs: Vec<Vec<Complex64>> = x.iter().map(|c| spectrum(c)).collect();
        let ts = spectrum(t);
        let span = self.span as isize;
        let lagged = |a: &[Complex64], b: &[Complex64], out: &mut [f64]| {
            let mut p: Vec<Complex64> = (0..nfft).map(|k| a[k].conj() * b[k] * w[k]).collect();
            inv.process(&mut p);
            for tau in -span..=span {
                let k = if tau >= 0 {
                    tau as usize
                } else {
                    nfft - (-tau) as usize
                };
                out[(tau + span) as usize] += p[k].re / nfft as f64;
            }
        };
        for c in 0..self.channels {
            for d in c..self.channels {
                let mut r = vec![0.0; 2 * self.span + 1];
                lagged(&xs[c], &xs[d], &mut r);
                for (i, v) in r.iter().enumerate() {
                    self.cc[c][d][i] += v;
                    if d != c {
                        // rho_dc(tau) = rho_cd(-tau)
                        self.cc[d][c][2 * self.span - i] += v;
                    }
                }
            }
            let mut r = vec![0.0; 2 * self.span + 1];
            lagged(&xs[c], &ts, &mut r);
            for (i, v) in r.iter().enumerate() {
                self.ct[c][i] += v;
            }
        }
        for (acc, g) in self.extra.iter_mut().zip(extra) {
            *acc += (0..nfft)
                .map(|k| g(freq(k)) * ts[k].norm_sqr())
                .sum::<f64>()
                / nfft as f64;
        }
        self.count += n;
    }

    /// `rho_cd(tau)`, `|tau| <= span`.
    pub fn cc(&self, c: usize, d: usize, tau: isize) -> f64 {
        self.cc[c][d][(tau + self.span as isize) as usize] / self.count as f64
    }

    /// `rho_ct(tau) = (1/N) sum_n x_c[n] t[n + tau]`.
    pub fn ct(&self, c: usize, tau: isize) -> f64 {
        self.ct[c][(tau + self.span as isize) as usize] / self.count as f64
    }

    /// Samples added over all records: the `N` the correlations are divided by.
    pub fn count(&self) -> usize {
        self.count
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::learned::synthetic::noise;
    use crate::study::metrics::{BANDS, bandpass};

    #[test]
    fn weighted_correlations_are_those_of_the_band_passed_signals() {
        // Oracle: the time-domain definition on signals filtered by the metric's own zero-phase
        // band-pass (sci-rs sosfiltfilt). Away from the record's ends the two agree; the ends'
        // transients are O(filter length / N).
        let n = 40_000;
        let a = noise(n, 1);
        let b: Vec<f64> = noise(n, 2)
            .iter()
            .zip(&a)
            .map(|(x, y)| x + 0.5 * y)
            .collect();
        let ds = 0.2;
        let band = BANDS[1];
        let g = band_power(&band, ds).unwrap();
        let weight = |f: f64| g(f) * g(f);
        let mut c = Correlations::new(1, 20, 0);
        c.add(std::slice::from_ref(&a), &b, &weight, &[], ds);
        let (fa, fb) = (
            bandpass(&a, ds, &band).unwrap(),
            bandpass(&b, ds, &band).unwrap(),
        );
        for tau in [-7isize, 0, 3, 20] {
            let direct: f64 = (0..n)
                .filter_map(|i| {
                    let j = i as isize + tau;
                    (j >= 0 && (j as usize) < n).then(|| fa[i] * fb[j as usize])
                })
                .sum::<f64>()
                / n as f64;
            let spectral = c.ct(0, tau);
            assert!(
                (spectral - direct).abs() < 0.01 * direct.abs().max(1e-3),
                "tau {tau}: {spectral} vs {direct}"
            );
        }
    }
}
