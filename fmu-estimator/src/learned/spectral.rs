//! The wheels' conicity from the sensors' cross-spectra, by Whittle's likelihood.
//!
//! # Why
//! The contact features ([`super::contact`]) are zero-lag moments in a few bands, and a linear
//! model of them reads `ln(conicity)` to 0.086 rms after 200 m (validation seeds 102-106, 20
//! m/s). The Cramer-Rao bound for the same 200 m of the same three sensors is 0.029: the
//! conicity shows in the fine shape of the cross-spectra around the wheelset's kinematic
//! wavelength, which band moments average away (`tests/conicity_likelihood.py`,
//! docs/learned-filter.md). The blended taps leave no room for the difference: 5 % off the
//! conicity costs D1 a third of its error or more.
//!
//! # Model
//! The channels are the grid cells of `ws_acc_y`, `ws_yaw_rate` and `frame_acc_y`, each divided
//! by its own speed to the power of its kinematics ([`CONTACT_SPEED_POWER`]: `V^2`, `V`, `V^2`).
//! At constant speed on a track of stationary irregularity they are a Gaussian vector process in
//! distance, whose cross-spectral density matrix `S(f; c, K)` (per cycle/m, one-sided,
//! `S_ij = E[conj(X_i) X_j]`, scipy's `csd` convention) depends on the conicity `c`, the Kalker
//! scale `K` and the speed, and scales with the track's spectrum.
//!
//! The bank holds, per bank speed and trained condition, `S` at the frequencies `j / (N ds)`
//! (`N` = [`WINDOW`] cells of `ds` = 0.2 m: 200 m) for `j` in the stored bins, measured on the
//! condition's 10 km training run ([`welch`]: Hann windows of `N` cells, half overlapping).
//!
//! # Likelihood
//! The periodogram of the last `n` cells, Hann-windowed (`w_m = (1 - cos(2 pi m / n)) / 2`,
//! `m` = 0 the oldest), is `P_k = s conj(X_k) X_k^T` at `f_k = k / (n ds)`, with
//! `X_k = sum_m w_m x_m e^(-2 pi i k m / n)` and `s = 2 ds / sum_m w_m^2`, so that white noise of
//! density `S0` has `E[P_k] = S0`. Its expectation is the density seen through the window:
//! `E_k = sum_j H(f_k - f_j) S_j`, `H = |W|^2` normalised to sum 1 over the bins used (for
//! `n = N`, the stored `S_k` itself: the Welch estimate already is that average). Whittle's
//! negative log-likelihood of the bins in the wavelengths 3-40 m ([`WAVES`]), with the track's
//! level `a_o` free in each octave `o` (3-6, 6-12, 12-24, 24-40 m; the track's spectrum tilts
//! from one stretch to the next), is
//!
//! `sum_o sum_(k in o) [ln det(a_o E_k) + tr((a_o E_k)^-1 P_k)]`,
//!
//! minimised over `a_o` at `a_o = T_o / (3 n_o)`, `T_o = sum_(k in o) tr(E_k^-1 P_k)`, which
//! leaves `sum_o 3 n_o ln T_o + sum_k ln det E_k` (constants dropped). `P_k` has rank one, so
//! `tr(E_k^-1 P_k) = |L^-1 y|^2` with `y = sqrt(s) conj(X_k)` and `E_k = L L^H` (Cholesky).
//!
//! # Search
//! `E` between the bank's conditions is interpolated linearly in `ln c` (between the trained
//! conicities at one Kalker scale), in `K` and in speed. The likelihood is evaluated at every
//! trained condition; around the best, a golden-section search in `ln c` between that
//! condition's neighbouring conicities at its Kalker scale, and again at a Kalker scale halfway
//! to a neighbour's where that fits better at the conicity found: some 40-50 evaluations of
//! 62 bins per estimate.
//!
//! # Running
//! The cells enter a ring of [`WINDOW`] cells. For the full window a sliding DFT keeps `X_k`
//! (the bins one either side too, as the Hann window is three bins of the rectangular one:
//! `X_k^Hann = X_k / 2 - (X_(k-1) + X_(k+1)) / 4`), recomputed exactly from the ring every
//! [`WINDOW`] cells; shorter windows at the start of a run ([`LENGTHS`]) are transformed
//! directly, their mean taken out first. Every [`EVERY`] cells from the first length on
//! ([`EVERY_FULL`] once the window is full), the
//! likelihood's `ln c`, averaged with the contact features' ([`SHARE`]; less, down to none,
//! where the model spectra fit the window worse than they fit the training vehicle's,
//! `dispersion` and [`FIT_LEVEL`], or where the two estimates disagree far more than they
//! do on it, [`DISAGREEMENT`]), becomes the target, and the output moves to it linearly over
//! the next [`EVERY`] cells (from the features' estimate before the first).
//!
//! # Figures
//! Validation seeds 102-106, 400 m at 20 m/s, conicity 0.06-0.3 at Kalker 100 and 50 %, the
//! bank over conicities told nothing, `ln(conicity)` rms error after 200 m: the features'
//! 0.099, the likelihood's 0.037 (the numpy formulation of `tests/conicity_likelihood.py`,
//! its model spectra from other runs: 0.045), the two averaged 0.033, gated by the fit and the
//! disagreement ([`share`]) 0.034; after 50 m 0.257, 0.144, 0.113 and 0.097.

use super::contact::CONTACT_SPEED_POWER;
use serde::{Deserialize, Serialize};

/// Cells in the model's and the full likelihood's window (200 m at the bank's 0.2 m grid).
pub const WINDOW: usize = 1000;
/// The wavelengths the likelihood reads \[m\]: the conicity's kinematic wavelength lies within
/// them over 0.05-0.4 (6.5-18 m for the ML95's wheelset, longer for a bogie).
pub const WAVES: [f64; 2] = [3.0, 40.0];
/// The window lengths at the start of a run \[cells\] (30-200 m at 0.2 m): each estimate reads the
/// longest the ring holds.
pub const LENGTHS: [usize; 9] = [150, 200, 250, 300, 400, 500, 600, 750, 1000];
/// Cells between estimates (10 m), and over which the output moves to a new one.
pub const EVERY: usize = 50;
/// Cells between estimates once the window is full (25 m): a shift of 10 m changes a twentieth
/// of a full window's cells, and an estimate costs some 100 us (0.2 us per 1 kHz step at 20
/// m/s every 10 m, 0.08 every 25 m). Validation seeds 102-106, the 12 conditions of the module
/// docs' figures, whole Jrel mean / worst (with the share and gate of the time, 2026-11-28):
/// every 10 m 0.129 / 0.194, 25 m 0.130 / 0.198, 50 m 0.130 / 0.204.
pub const EVERY_FULL: usize = 125;
/// Bins stored below the band and above it for the short windows' kernels: the main lobe of
/// the shortest window's kernel is `2 N / LENGTHS[0]` = 13.3 fine bins wide each side.
pub const MARGIN: usize = 14;
/// The likelihood's share in the conicity estimate, against the contact features' (`ln c`
/// averaged), where its fit and the two estimates' agreement allow ([`share`]).
///
/// Why so much, from the first window: the young memories' models ([`super::contact`]) are
/// least squares on noisy features, so they shrink toward the training conditions' middle, and
/// most at the bank's edges, where the likelihood is sharpest. Mean error in `ln c` on the
/// validation seeds at 30 / 50 / 100 m, conicity 0.05 at Kalker 50 %: the likelihood's +0.02 /
/// +0.03 / +0.03, the features' +0.66 / +0.49 / +0.22; at 0.1 / 100 % both within 0.07.
/// Chosen with [`DISAGREEMENT_FULL`] and [`FIT_LEVEL`] on the validation seeds, the bank over
/// conicities told nothing, whole Jrel:
/// - the ML95 (seeds 102-106, 400 m at 20 m/s, conicity 0.05, 0.06, 0.075, 0.1, 0.15, 0.2,
///   0.3, 0.4 at Kalker 100 and 50 %; mean / worst condition, always 0.05 / 50 %);
/// - eight random ML95 variants (`VALIDATION_FAMILY` in `studies/src/study/vehicles.rs`: all
///   parameters at once; seeds 102-104, mean);
/// - eight variants changed in one kind (`VALIDATION_VARIANTS` there: car body x 0.75 and
///   x 1.2, wheelsets x 1.2, bogie frames x 0.8 in mass and inertia, secondary lateral x 1.3,
///   primary longitudinal x 1.3, primary lateral x 0.7, wheelsets x 0.85 with frames x 1.15;
///   none an evaluation vehicle's change): seeds 102-104, 400 m, mean / worst; and seeds
///   102-103, 2 km, mean.
///
/// `tests/conicity_estimate_probe.py` makes the table's figures: the ML95 with `--conicities
/// 0.05,0.06,0.075,0.1,0.15,0.2,0.3,0.4`, the vehicles with `--vehicles DIR` (the files of
/// `cargo run --release -p alignment-studies --example validation_vehicles -- DIR`).
///
/// The disagreement's bounds are in [`DISAGREEMENT`]s, at 30 m and at 200 m (linear in the
/// window's length between); the fit's in [`FIT_LEVEL`]s.
///
/// | share | disagreement, full / none | fit, full / none | ML95 | random variants | one kind, 400 m | one kind, 2 km |
/// |---|---|---|---|---|---|---|
/// | 0.5 at 30 m to 0.8 at 200 m | 2 / 3 | no gate | 0.1430 / 0.247 | 0.3103 | 0.1315 / 0.258 | 0.1645 |
/// | 0.8 | 2 / 3 | no gate | 0.1409 / 0.232 | 0.3165 | 0.1389 / 0.283 | |
/// | 0.8 | no gate | no gate | 0.1365 / 0.198 | 0.3933 | 0.1493 / 0.350 | |
/// | 0.8 | 4 / 6 | no gate | 0.1365 / 0.198 | 0.3466 | 0.1473 / 0.335 | |
/// | 0.8 | 4 / 6 | 1 / 1.5 | 0.1361 / 0.200 | 0.3107 | 0.1324 / 0.232 | |
/// | 0.8 | 3 / 4.5 | 1 / 1.5 | 0.1366 / 0.202 | 0.3101 | 0.1301 / 0.217 | 0.1664 |
/// | 0.8 | 2 / 3 | 1 / 1.5 | 0.1409 / 0.234 | 0.3080 | 0.1276 / 0.206 | 0.1623 |
/// | 0.8 | 3 / 4.5 | 0.8 / 1.2 | 0.1396 / 0.211 | 0.3067 | 0.1267 / 0.207 | |
/// | 1 at 30 m to 0.8 at 200 m | 3 / 4.5 | 1 / 1.5 | 0.1374 / 0.194 | 0.3136 | 0.1349 / 0.219 | |
/// | 0.8 | 3 / 4.5 to 2 / 3 | 1 / 1.5 | 0.1394 / 0.219 | 0.3095 | 0.1277 / 0.206 | |
/// | 0.8 | 4 / 6 to 2 / 3 | 1 / 1.5 | 0.1388 / 0.211 | 0.3087 | 0.1279 / 0.206 | 0.1624 |
/// | 0.8 | 6 / 9 to 2 / 3 | 1 / 1.5 | 0.1385 / 0.207 | 0.3087 | 0.1285 / 0.207 | 0.1626 |
/// | 0.8 | 4 / 6 to 2.5 / 3.75 | 1 / 1.5 | 0.1373 / 0.201 | 0.3089 | 0.1289 / 0.209 | 0.1647 |
///
/// Taken: 6 / 9 to 2 / 3, the most the ML95 gains with no loss on any set of vehicles. A
/// disagreement gate as wide at 200 m as at 30 m gains the ML95 a little more on 400 m, but
/// on 2 km the variants changed in one kind lose (car body x 1.2: 0.132 -> 0.142): their
/// spectra look like the ML95's at another conicity and fit as well, and over a full window
/// only the disagreement tells them. The ML95 on 2 km (seeds 102-103, the sixteen
/// conditions): 0.1279 before, 0.1271 with the row taken.
pub const SHARE: f64 = 0.8;

/// The likelihood's share ([`SHARE`]) for a window of `n` cells, where its `ln c` and the
/// features' differ by `d` and its fit's dispersion (the private function of that name) is
/// `dispersion`: the full share while `d` is within [`DISAGREEMENT_FULL`] [`DISAGREEMENT`]s at
/// that length and the dispersion within [`FIT_LEVEL`] there, none from 1.5 times either
/// bound, linear between (the two gates multiplied). A dispersion that is not a number (the
/// model spectra not positive definite at the maximum found) gives the likelihood no share.
pub fn share(n: usize, d: f64, dispersion: f64) -> f64 {
    let i = LENGTHS
        .iter()
        .position(|l| *l >= n)
        .unwrap_or(LENGTHS.len() - 1);
    let t = (n as f64 - LENGTHS[0] as f64) / (WINDOW - LENGTHS[0]) as f64;
    let [first, full] = DISAGREEMENT_FULL;
    let agree = first + (full - first) * t.clamp(0.0, 1.0);
    let gate = |x: f64, bound: f64| (3.0 - 2.0 * x / bound).clamp(0.0, 1.0);
    // The model spectra were not positive definite at the maximum: no fit, no share.
    let fit = if dispersion.is_nan() {
        0.0
    } else {
        gate(dispersion, FIT_LEVEL[i])
    };
    SHARE * gate(d.abs(), agree * DISAGREEMENT[i]) * fit
}

/// The rms difference between the likelihood's `ln c` and the features' per window length
/// ([`LENGTHS`]), on the validation runs (seeds 102-106, the ML95 at conicity 0.06-0.3, Kalker
/// 100 and 50 %, 400 m at 20 m/s; 30 m: as 40 m's). Why it gates the likelihood: its model
/// spectra are the ML95's, and on another vehicle it reads the conicity that makes the ML95's
/// spectra look most like that vehicle's, far from the truth (the Manchester vehicle, conicity
/// 0.15: 0.05; the ML95 with its car body 40 % heavier: 0.085 for 0.1), where the features' model,
/// fitted to read the conicity whatever the track, stays near it (0.19; 0.11). The two
/// disagree there by 0.3-1.3, on the ML95 by 0.08 rms after 200 m.
pub const DISAGREEMENT: [f64; 9] = [0.33, 0.33, 0.33, 0.29, 0.23, 0.195, 0.15, 0.098, 0.084];

/// How many [`DISAGREEMENT`]s the two estimates may differ by with the likelihood's full share
/// (none from 1.5 times it), at the first window length and at the full window, linear in the
/// length between. Why so wide at first: the young features' pull toward the training's middle
/// makes the ML95's own disagreement large at the bank's edges (0.05 / 50 %: 0.63 at 30 m,
/// 0.46 at 50 m), and there the likelihood's fit ([`FIT_LEVEL`]) tells most other vehicles
/// from the ML95. Why narrow at 200 m: a vehicle changed in one kind only can look like the
/// ML95 at another conicity and fit as well, and only the disagreement tells it ([`SHARE`]'s
/// table).
pub const DISAGREEMENT_FULL: [f64; 2] = [6.0, 2.0];

/// The likelihood's fit (`dispersion`) that 90 % of the ML95's validation estimates stay
/// within, per window length ([`LENGTHS`]): seeds 102-106, the sixteen conditions of
/// [`SHARE`]'s table, 80-640 estimates per length. Why it gates the likelihood: on another
/// vehicle the ML95's model spectra fit its cross-spectra worse, whatever conicity they are
/// read at. Median on the ML95 / on eight random variants ([`SHARE`]), at 30, 60, 100 and 200
/// m: 0.30 / 0.74, 0.61 / 1.26, 0.75 / 1.62, 0.84 / 2.29. It tells them apart from about
/// 60 m; shorter windows hold 10-20 bins.
pub const FIT_LEVEL: [f64; 9] = [0.61, 0.87, 0.87, 0.81, 0.92, 1.01, 1.05, 1.05, 1.29];

/// Numbers per stored matrix: the three real diagonal entries, then the real and imaginary
/// parts of `S_01`, `S_02`, `S_12`.
pub const PACKED: usize = 9;
/// Golden-section steps: the bracket (two conicity steps of the bank, up to 0.8 in `ln c`)
/// shrinks to 0.8 x 0.618^12 = 0.003.
const GOLDEN_STEPS: usize = 12;

/// One bank speed's model spectra.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spectra {
    /// Cells in the window the spectra were measured with ([`WINDOW`]).
    pub window: usize,
    /// The first stored bin (`j` at `j / (window ds)` cycles/m).
    pub first_bin: usize,
    /// The conditions, `[conicity, Kalker scale]`, in the order of `values`.
    pub conditions: Vec<[f64; 2]>,
    /// Per condition, per bin from `first_bin`, [`PACKED`] numbers: the speed-quotient channels'
    /// cross-spectral densities, as `f32` (7 digits: the likelihood's own noise is far larger).
    /// A bank keeps them in its data block ([`super::bank`]): its TOML header holds an empty
    /// string here; the FMU's state, their bytes.
    #[serde(with = "packed_f32")]
    pub values: Vec<f32>,
}

impl Spectra {
    /// Bins per condition.
    pub fn bins(&self) -> usize {
        self.values.len() / (PACKED * self.conditions.len()).max(1)
    }

    /// How many values a bank on a grid of `ds` metres stores ([`stored_bins`]); `None` if
    /// that does not fit a `usize` (a damaged header).
    pub fn stored_values(&self, ds: f64) -> Option<usize> {
        if !(ds.is_finite() && ds > 0.0) {
            return None;
        }
        let [lo, hi] = stored_bins(ds);
        (hi + 1)
            .checked_sub(lo)?
            .checked_mul(PACKED)?
            .checked_mul(self.conditions.len())
    }

    /// Whether the layout is whole and every number usable; `Err` names what is not.
    pub fn check(&self, ds: f64) -> Result<(), String> {
        if self.window != WINDOW {
            return Err(format!("window {} cells, want {WINDOW}", self.window));
        }
        if self.conditions.is_empty()
            || self
                .conditions
                .iter()
                .any(|[c, k]| !(c.is_finite() && *c > 0.0 && k.is_finite() && *k > 0.0))
        {
            return Err("conditions must be positive conicities and Kalker scales".into());
        }
        let [lo, hi] = stored_bins(ds);
        if self.values.len() != self.bins() * PACKED * self.conditions.len()
            || self.first_bin != lo
            || self.first_bin + self.bins() != hi + 1
        {
            return Err(format!(
                "{} numbers from bin {} for {} conditions: want bins {lo}-{hi}",
                self.values.len(),
                self.first_bin,
                self.conditions.len(),
            ));
        }
        if self.values.iter().any(|v| !v.is_finite()) {
            return Err("a value that is not finite".into());
        }
        for s in self.values.chunks(PACKED) {
            if !(s[0] > 0.0 && s[1] > 0.0 && s[2] > 0.0) {
                return Err("a spectral density that is not positive".into());
            }
        }
        Ok(())
    }

    fn matrix(&self, condition: usize, bin: usize) -> Option<[f64; PACKED]> {
        let j = bin.checked_sub(self.first_bin)?;
        let n = self.bins();
        (j < n).then(|| {
            let at = (condition * n + j) * PACKED;
            std::array::from_fn(|i| self.values[at + i] as f64)
        })
    }
}

/// The bins of a window of `n` cells whose wavelengths lie within [`WAVES`], first and last.
pub fn band_bins(n: usize, ds: f64) -> [usize; 2] {
    let length = n as f64 * ds;
    [
        ((length / WAVES[1]).ceil() as usize).max(1),
        (length / WAVES[0]).floor() as usize,
    ]
}

/// The bins of the [`WINDOW`] a bank stores, first and last: from the first above zero (the
/// short windows' kernels reach below the band, and mirror at zero) to [`MARGIN`] beyond the
/// bin nearest the band's shortest wave.
pub fn stored_bins(ds: f64) -> [usize; 2] {
    [1, band_bins(WINDOW, ds)[1] + MARGIN + 1]
}

/// The octave (0 the shortest waves) of bin `k` of a window `length` metres long.
fn octave(k: usize, length: f64) -> usize {
    let wave = length / k as f64;
    ((wave / WAVES[0]).log2().floor().max(0.0) as usize).min(OCTAVES - 1)
}

/// Octaves of the likelihood's band: 3-6, 6-12, 12-24, 24-40 m.
const OCTAVES: usize = 4;

/// A complex number as (re, im).
type C = [f64; 2];

fn mul(a: C, b: C) -> C {
    [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
}

/// `e^(-2 pi i m / n)` for `m` in `0..n`: a DFT of length `n` reads bin `k` at `(k m) % n`.
fn twiddles(n: usize) -> Vec<C> {
    (0..n)
        .map(|m| {
            let (sin, cos) = (-2.0 * std::f64::consts::PI * m as f64 / n as f64).sin_cos();
            [cos, sin]
        })
        .collect()
}

/// The Hann-windowed DFT of the three channels `x[m]` (`m` = 0 the oldest; their mean taken
/// out) at bins `k` of `bins`: `X_k` per channel.
fn hann_dft(x: &[[f64; 3]], bins: [usize; 2]) -> Vec<[C; 3]> {
    let n = x.len();
    let mean: [f64; 3] = std::array::from_fn(|c| x.iter().map(|v| v[c]).sum::<f64>() / n as f64);
    let table = twiddles(n);
    let w: Vec<f64> = (0..n).map(|m| 0.5 - 0.5 * table[m][0]).collect();
    (bins[0]..=bins[1])
        .map(|k| {
            let mut out = [[0.0; 2]; 3];
            for (m, v) in x.iter().enumerate() {
                let t = table[(k * m) % n];
                for c in 0..3 {
                    let a = w[m] * (v[c] - mean[c]);
                    out[c][0] += a * t[0];
                    out[c][1] += a * t[1];
                }
            }
            out
        })
        .collect()
}

/// `s conj(X_i) X_j` packed ([`PACKED`]).
fn packed(x: &[C; 3], s: f64) -> [f64; PACKED] {
    let cross = |i: usize, j: usize| mul([x[i][0], -x[i][1]], x[j]);
    let (a, b, c) = (cross(0, 1), cross(0, 2), cross(1, 2));
    [
        s * (x[0][0].powi(2) + x[0][1].powi(2)),
        s * (x[1][0].powi(2) + x[1][1].powi(2)),
        s * (x[2][0].powi(2) + x[2][1].powi(2)),
        s * a[0],
        s * a[1],
        s * b[0],
        s * b[1],
        s * c[0],
        s * c[1],
    ]
}

/// The scale of a Hann window of `n` cells' periodogram: `2 ds / sum w^2` (`sum w^2 = 3 n / 8`).
fn scale(n: usize, ds: f64) -> f64 {
    2.0 * ds / (3.0 * n as f64 / 8.0)
}

/// Welch's estimate of the cross-spectral densities of three channels (`x[m]`, along the track
/// on a grid of `ds` metres) at bins `bins` of a window of `n` cells: the mean of the
/// Hann-windowed periodograms of windows `n / 2` apart, packed ([`PACKED`]). `None` if the
/// channels are shorter than one window.
pub fn welch(x: &[[f64; 3]], n: usize, ds: f64, bins: [usize; 2]) -> Option<Vec<[f64; PACKED]>> {
    if x.len() < n || n < 2 {
        return None;
    }
    let mut sum = vec![[0.0; PACKED]; bins[1] + 1 - bins[0]];
    let mut count = 0;
    for start in (0..=x.len() - n).step_by(n / 2) {
        for (s, p) in sum.iter_mut().zip(hann_dft(&x[start..start + n], bins)) {
            for (a, b) in s.iter_mut().zip(packed(&p, scale(n, ds))) {
                *a += b;
            }
        }
        count += 1;
    }
    for s in &mut sum {
        for a in s.iter_mut() {
            *a /= count as f64;
        }
    }
    Some(sum)
}

/// `det E` and `y^H E^-1 y` for the Hermitian `E` (packed) and a vector `y`; `None` unless
/// `E` is positive definite.
fn quadratic(e: &[f64; PACKED], y: &[C; 3]) -> Option<(f64, f64)> {
    // E = L L^H, L lower triangular with a real diagonal. E_10 = conj(E_01).
    let e10 = [e[3], -e[4]];
    let e20 = [e[5], -e[6]];
    let e21 = [e[7], -e[8]];
    // The pivots' reciprocal square roots: three divisions per matrix (the likelihood's inner
    // loop), the rest products.
    if !(e[0] > 0.0) {
        return None;
    }
    let r0 = 1.0 / e[0].sqrt();
    let l10 = [e10[0] * r0, e10[1] * r0];
    let l20 = [e20[0] * r0, e20[1] * r0];
    let d1 = e[1] - (l10[0] * l10[0] + l10[1] * l10[1]);
    if !(d1 > 0.0) {
        return None;
    }
    let r1 = 1.0 / d1.sqrt();
    // l21 = (E_21 - l20 conj(l10)) / l11
    let t = mul(l20, [l10[0], -l10[1]]);
    let l21 = [(e21[0] - t[0]) * r1, (e21[1] - t[1]) * r1];
    let d2 = e[2] - (l20[0] * l20[0] + l20[1] * l20[1]) - (l21[0] * l21[0] + l21[1] * l21[1]);
    if !(d2 > 0.0) {
        return None;
    }
    let r2 = 1.0 / d2.sqrt();
    // z = L^-1 y
    let z0 = [y[0][0] * r0, y[0][1] * r0];
    let a = mul(l10, z0);
    let z1 = [(y[1][0] - a[0]) * r1, (y[1][1] - a[1]) * r1];
    let (b, c) = (mul(l20, z0), mul(l21, z1));
    let z2 = [(y[2][0] - b[0] - c[0]) * r2, (y[2][1] - b[1] - c[1]) * r2];
    let q = [z0, z1, z2].iter().map(|z| z[0] * z[0] + z[1] * z[1]).sum();
    Some((e[0] * d1 * d2, q))
}

/// The conditions of the two speed models around the current speed, as a lattice of trained
/// conicities and Kalker scales, with their expected periodograms at the current window.
#[derive(Debug, PartialEq)]
struct Lattice {
    /// `ln` of the conicities, ascending.
    ln_c: Vec<f64>,
    /// The Kalker scales, ascending.
    kalker: Vec<f64>,
    /// Per Kalker scale, per conicity: the expected periodograms at the window's bins, where
    /// the condition was trained.
    expected: Vec<Vec<Option<Vec<[f64; PACKED]>>>>,
    /// Per Kalker scale, the conicities trained there, by index.
    trained: Vec<Vec<usize>>,
}

impl Lattice {
    /// The conicities trained at Kalker index `k`, by index.
    fn at(&self, k: usize) -> impl Iterator<Item = usize> + '_ {
        self.trained[k].iter().copied()
    }

    /// The expected periodograms at `ln c` = `x` and Kalker index `k` (halfway between two
    /// trained scales: their mean), into `out`; `pair` is scratch of its size.
    fn blend(&self, k: f64, x: f64, out: &mut [[f64; PACKED]], pair: &mut [[f64; PACKED]]) {
        let k0 = k.floor() as usize;
        let u = k - k0 as f64;
        self.row(k0, x, out);
        if u > 0.0 {
            self.row(k0 + 1, x, pair);
            for (a, b) in out.iter_mut().zip(pair.iter()) {
                for i in 0..PACKED {
                    a[i] = (1.0 - u) * a[i] + u * b[i];
                }
            }
        }
    }

    /// The expected periodograms at `ln c` = `x` and Kalker index `k` (an integer: a trained
    /// scale), linear between the trained conicities there, the nearest beyond them, into `out`.
    fn row(&self, k: usize, x: f64, out: &mut [[f64; PACKED]]) {
        let trained = &self.trained[k];
        let (Some(&first), Some(&last)) = (trained.first(), trained.last()) else {
            return;
        };
        let get = |c: usize| self.expected[k][c].as_deref().unwrap_or(&[]);
        let pair = if x <= self.ln_c[first] {
            (first, first, 0.0)
        } else if x >= self.ln_c[last] {
            (last, last, 0.0)
        } else {
            let i = trained
                .windows(2)
                .position(|w| x <= self.ln_c[w[1]])
                .unwrap_or(0);
            let (a, b) = (trained[i], trained[i + 1]);
            (a, b, (x - self.ln_c[a]) / (self.ln_c[b] - self.ln_c[a]))
        };
        let (a, b, t) = pair;
        for ((o, p), q) in out.iter_mut().zip(get(a)).zip(get(b)) {
            for i in 0..PACKED {
                o[i] = (1.0 - t) * p[i] + t * q[i];
            }
        }
    }
}

/// The running likelihood: the ring of cells, the sliding DFT, the estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spectral {
    /// The grid step \[m\].
    ds: f64,
    /// The last [`WINDOW`] cells (speed quotients), oldest at `head`.
    ring: Vec<[f64; 3]>,
    head: usize,
    /// Cells pushed, up to [`WINDOW`].
    filled: usize,
    /// The rectangular window's DFT of the ring at the full window's bins and one either side.
    sliding: Vec<[C; 3]>,
    /// Cells since the last exact DFT of the ring.
    since_exact: usize,
    /// Cells since the last estimate.
    since_estimate: usize,
    /// The latest estimate of `ln c`, the value the output moves from, and the cells since.
    target: Option<f64>,
    from: f64,
    ramp: usize,
    /// The last estimate's lattice and the speed and window it was made for: at constant speed
    /// with the full window the next estimate's is the same (a fifth of an estimate's cost).
    /// Derived data: not in the FMU state, made again after a restore.
    #[serde(skip)]
    cache: Option<(f64, usize, std::sync::Arc<Lattice>)>,
}

impl Spectral {
    /// The likelihood's `ln(conicity)` as the output has moved to it; `None` before the first
    /// estimate.
    pub fn ln_conicity(&self) -> Option<f64> {
        let t = self.target?;
        Some(self.from + (t - self.from) * (self.ramp as f64 / EVERY as f64).min(1.0))
    }

    /// The likelihood on a grid of `ds` metres, before any cell.
    pub fn new(ds: f64) -> Spectral {
        let [lo, hi] = band_bins(WINDOW, ds);
        Spectral {
            ds,
            ring: vec![[0.0; 3]; WINDOW],
            head: 0,
            filled: 0,
            sliding: vec![[[0.0; 2]; 3]; hi + 3 - lo],
            since_exact: 0,
            since_estimate: 0,
            target: None,
            from: 0.0,
            ramp: 0,
            cache: None,
        }
    }

    /// One closed cell of the channels ([`super::grid::CHANNELS`] order) at `speed`; `true`
    /// when an estimate is due ([`Self::update`]): every [`EVERY`] cells from the first
    /// window on. A cell that is not finite is left out.
    pub fn push(&mut self, cell: &[f64; 5], speed: f64) -> bool {
        let v = speed.max(super::contact::MIN_SPEED);
        let x: [f64; 3] = std::array::from_fn(|i| {
            cell[super::contact::CHANNELS[i]] / v.powi(CONTACT_SPEED_POWER[i])
        });
        if x.iter().any(|v| !v.is_finite()) {
            return false;
        }
        self.ramp = self.ramp.saturating_add(1);
        let old = std::mem::replace(&mut self.ring[self.head], x);
        self.head = (self.head + 1) % WINDOW;
        self.filled = (self.filled + 1).min(WINDOW);
        self.since_exact += 1;
        if self.since_exact >= WINDOW {
            self.exact();
        } else {
            // The twiddles e^(2 pi i k / N) by recurrence from the first bin's: two sines per
            // cell instead of one per bin (their rounding, 1e-14, is reset by `exact`).
            let lo = band_bins(WINDOW, self.ds)[0] - 1;
            let angle = |k: usize| {
                let (sin, cos) = (2.0 * std::f64::consts::PI * k as f64 / WINDOW as f64).sin_cos();
                [cos, sin]
            };
            let (mut twiddle, step) = (angle(lo), angle(1));
            for s in self.sliding.iter_mut() {
                for c in 0..3 {
                    s[c] = mul([s[c][0] - old[c] + x[c], s[c][1]], twiddle);
                }
                twiddle = mul(twiddle, step);
            }
        }
        self.since_estimate += 1;
        let every = if self.filled >= WINDOW {
            EVERY_FULL
        } else {
            EVERY
        };
        self.filled >= LENGTHS[0] && self.since_estimate >= every
    }

    /// A new estimate at `speed` with the `models` (per bank speed, ascending, with their
    /// speeds); `None` if the models give none.
    pub fn update(&mut self, speed: f64, models: &[(f64, &Spectra)]) -> Option<Reading> {
        self.since_estimate = 0;
        self.estimate(speed, models)
    }

    /// Moves the output to `target` over the next [`EVERY`] cells, from where it is, or from
    /// `before` (`ln c` of the features' estimate) at the first.
    pub fn aim(&mut self, target: f64, before: f64) {
        self.from = self.ln_conicity().unwrap_or(before);
        self.target = Some(target);
        self.ramp = 0;
    }

    /// The ring's DFT at the sliding bins, from its cells.
    fn exact(&mut self) {
        self.since_exact = 0;
        let lo = band_bins(WINDOW, self.ds)[0] - 1;
        let table = twiddles(WINDOW);
        for (j, s) in self.sliding.iter_mut().enumerate() {
            let k = lo + j;
            *s = [[0.0; 2]; 3];
            for m in 0..WINDOW {
                let x = self.ring[(self.head + m) % WINDOW];
                let t = table[(k * m) % WINDOW];
                for c in 0..3 {
                    s[c][0] += x[c] * t[0];
                    s[c][1] += x[c] * t[1];
                }
            }
        }
    }

    /// The window's `y = sqrt(s) conj(X_k)` at its band's bins.
    fn periodogram(&self, n: usize) -> Vec<[C; 3]> {
        let root = scale(n, self.ds).sqrt();
        let conj = |x: [C; 3]| x.map(|c| [root * c[0], -root * c[1]]);
        if n == WINDOW {
            self.sliding
                .windows(3)
                .map(|w| {
                    conj(std::array::from_fn(|c| {
                        [
                            0.5 * w[1][c][0] - 0.25 * (w[0][c][0] + w[2][c][0]),
                            0.5 * w[1][c][1] - 0.25 * (w[0][c][1] + w[2][c][1]),
                        ]
                    }))
                })
                .collect()
        } else {
            let cells: Vec<[f64; 3]> = (WINDOW - n..WINDOW)
                .map(|m| self.ring[(self.head + m) % WINDOW])
                .collect();
            hann_dft(&cells, band_bins(n, self.ds))
                .into_iter()
                .map(conj)
                .collect()
        }
    }

    /// The likelihood's `ln c` from the longest window the ring holds; `None` if the models
    /// give none (a flat record, a model not positive definite).
    fn estimate(&mut self, speed: f64, models: &[(f64, &Spectra)]) -> Option<Reading> {
        let n = *LENGTHS.iter().rev().find(|&&n| n <= self.filled)?;
        let y = self.periodogram(n);
        let lattice = match &self.cache {
            Some((v, m, l)) if *v == speed && *m == n => l.clone(),
            _ => {
                let l = std::sync::Arc::new(lattice(models, speed, n, self.ds)?);
                self.cache = Some((speed, n, l.clone()));
                l
            }
        };
        let length = n as f64 * self.ds;
        let [lo, _] = band_bins(n, self.ds);
        let octaves: Vec<usize> = (0..y.len()).map(|i| octave(lo + i, length)).collect();
        let mut scratch = vec![[0.0; PACKED]; y.len()];
        let mut kalker_pair = vec![[0.0; PACKED]; y.len()];
        let mut nll = |k: f64, x: f64| -> f64 {
            lattice.blend(k, x, &mut scratch, &mut kalker_pair);
            whittle(&scratch, &y, &octaves)
        };
        let mut best = (f64::INFINITY, 0, 0);
        for k in 0..lattice.kalker.len() {
            for c in lattice.at(k) {
                let v = nll(k as f64, lattice.ln_c[c]);
                if v < best.0 {
                    best = (v, k, c);
                }
            }
        }
        if !best.0.is_finite() {
            return None;
        }
        let (_, k, c) = best;
        let trained: Vec<usize> = lattice.at(k).collect();
        let i = trained.iter().position(|&t| t == c)?;
        let lo = lattice.ln_c[trained[i.saturating_sub(1)]];
        let hi = lattice.ln_c[trained[(i + 1).min(trained.len() - 1)]];
        let mut kalker = k as f64;
        let (mut x, mut v) = golden(|x| nll(kalker, x), lo, hi);
        // A Kalker scale halfway to a neighbour's, where it fits better at that conicity, is
        // searched again.
        let halfway = [k as f64 - 0.5, k as f64 + 0.5]
            .into_iter()
            .filter(|kk| *kk >= 0.0 && *kk <= (lattice.kalker.len() - 1) as f64)
            .map(|kk| (kk, nll(kk, x)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((kk, at)) = halfway
            && at < v
        {
            (x, v) = golden(|x| nll(kk, x), lo, hi);
            v = v.min(at);
            kalker = kk;
        }
        if !v.is_finite() {
            return None;
        }
        lattice.blend(kalker, x, &mut scratch, &mut kalker_pair);
        Some(Reading {
            ln_c: x,
            cells: n,
            dispersion: dispersion(&scratch, &y, &octaves),
        })
    }
}

/// One estimate of the likelihood.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// The `ln c` of its maximum.
    pub ln_c: f64,
    /// The window's length in cells.
    pub cells: usize,
    /// How well the model spectra fit there (the function `dispersion`).
    pub dispersion: f64,
}

/// How far the window's bins scatter about the expected periodograms `e` (at the likelihood's
/// maximum), the level free per octave as in [`whittle`]: the mean of `(z_k - 3)^2 / 3` over
/// the bins, `z_k = tr(E_k^-1 P_k) / a_o`, `a_o` the octave's fitted level. `NaN` where `e` is
/// not positive definite.
///
/// Why: where the model is right, `y_k` is complex Gaussian with covariance `a_o E_k`, so
/// `z_k` is a sum of three unit exponentials (mean 3, variance 3) and the dispersion is near 1
/// with many bins per octave. With few it is less, as the level is fitted from the same bins
/// (an octave of one bin contributes nothing): a 30 m window holds 10 bins, 5 / 3 / 1 / 1 per
/// octave: each of an octave's `n` bins adds `(n - 1) / (n + 1/3)` on average, about 0.55 over
/// the window where the model is right; on the ML95 0.3-0.8 by the window's length, hence a
/// level per length ([`FIT_LEVEL`]). Where the vehicle is another, the ML95's spectra have the
/// wrong shape across the bins and channels at every conicity, and the bins where they fall
/// short of the sensors' power give large `z_k`. The likelihood's own value cannot tell it: its
/// level is free.
fn dispersion(e: &[[f64; PACKED]], y: &[[C; 3]], octaves: &[usize]) -> f64 {
    let mut q = Vec::with_capacity(y.len());
    let mut t = [0.0; OCTAVES];
    let mut n = [0usize; OCTAVES];
    for ((e, y), &o) in e.iter().zip(y).zip(octaves) {
        let Some((_, qk)) = quadratic(e, y) else {
            return f64::NAN;
        };
        q.push(qk);
        t[o] += qk;
        n[o] += 1;
    }
    let sum: f64 = q
        .iter()
        .zip(octaves)
        .map(|(qk, &o)| {
            let z = qk * 3.0 * n[o] as f64 / t[o];
            (z - 3.0) * (z - 3.0)
        })
        .sum();
    sum / (3.0 * q.len().max(1) as f64)
}

/// The profiled negative log-likelihood ([module docs](self)) of the window's `y` under the
/// expected periodograms `e`, the level free per octave; infinite where `e` is not positive
/// definite or an octave holds no power.
fn whittle(e: &[[f64; PACKED]], y: &[[C; 3]], octaves: &[usize]) -> f64 {
    let mut t = [0.0; OCTAVES];
    let mut n = [0usize; OCTAVES];
    // The determinants multiplied, their logarithm taken when the product nears the ends of
    // the floating-point range: a logarithm per few bins instead of one per bin (a third of
    // the likelihood's cost).
    let (mut log_det, mut product) = (0.0, 1.0);
    for ((e, y), &o) in e.iter().zip(y).zip(octaves) {
        let Some((d, q)) = quadratic(e, y) else {
            return f64::INFINITY;
        };
        product *= d;
        if !(1e-150..=1e150).contains(&product) {
            log_det += product.ln();
            product = 1.0;
        }
        t[o] += q;
        n[o] += 1;
    }
    let mut out = log_det + product.ln();
    for (t, n) in t.iter().zip(n) {
        if n > 0 {
            if !(*t > 0.0) {
                return f64::INFINITY;
            }
            out += 3.0 * n as f64 * t.ln();
        }
    }
    out
}

/// The minimum of `f` on `[lo, hi]` by golden sections ([`GOLDEN_STEPS`]), its argument and value.
fn golden(mut f: impl FnMut(f64) -> f64, lo: f64, hi: f64) -> (f64, f64) {
    const R: f64 = 0.618_033_988_749_894_9;
    let (mut a, mut b) = (lo, hi);
    let (mut c, mut d) = (b - R * (b - a), a + R * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..GOLDEN_STEPS {
        if fc <= fd {
            (b, d, fd) = (d, c, fc);
            c = b - R * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + R * (b - a);
            fd = f(d);
        }
    }
    if fc <= fd { (c, fc) } else { (d, fd) }
}

/// The lattice of conditions at `speed` for a window of `n` cells: each condition's expected
/// periodogram, interpolated linearly between the two model speeds around `speed` (a condition
/// trained at one of them only: that one's).
fn lattice(models: &[(f64, &Spectra)], speed: f64, n: usize, ds: f64) -> Option<Lattice> {
    if models.is_empty() {
        return None;
    }
    let speeds: Vec<f64> = models.iter().map(|m| m.0).collect();
    let around = super::weights(&speeds, speed);
    let mut ln_c: Vec<f64> = vec![];
    let mut kalker: Vec<f64> = vec![];
    for (i, _) in &around {
        for [c, k] in &models[*i].1.conditions {
            ln_c.push(c.ln());
            kalker.push(*k);
        }
    }
    for v in [&mut ln_c, &mut kalker] {
        v.sort_by(f64::total_cmp);
        v.dedup();
    }
    let kernel = kernel(n, ds);
    let mut expected = vec![vec![None; ln_c.len()]; kalker.len()];
    for (ki, k) in kalker.iter().enumerate() {
        for (ci, x) in ln_c.iter().enumerate() {
            let mut sum: Option<Vec<[f64; PACKED]>> = None;
            let mut weight = 0.0;
            for (i, w) in &around {
                let s = models[*i].1;
                let Some(cond) = s
                    .conditions
                    .iter()
                    .position(|[c, kk]| c.ln() == *x && kk == k)
                else {
                    continue;
                };
                let e = expect(s, cond, &kernel)?;
                weight += w;
                match &mut sum {
                    None => sum = Some(e.iter().map(|m| m.map(|v| v * w)).collect()),
                    Some(sum) => {
                        for (a, b) in sum.iter_mut().zip(&e) {
                            for i in 0..PACKED {
                                a[i] += w * b[i];
                            }
                        }
                    }
                }
            }
            expected[ki][ci] = sum.map(|mut s| {
                for m in &mut s {
                    for v in m.iter_mut() {
                        *v /= weight;
                    }
                }
                s
            });
        }
    }
    let trained = expected
        .iter()
        .map(|row| (0..row.len()).filter(|c| row[*c].is_some()).collect())
        .collect();
    Some(Lattice {
        ln_c,
        kalker,
        expected,
        trained,
    })
}

/// Per bin of a window of `n` cells' band, the fine bins (of [`WINDOW`] cells, negative for
/// the mirrored negative frequencies) and their weights in the expected periodogram: the
/// window's `|W|^2` normalised to sum 1 over them. For `n` = [`WINDOW`], the bin itself.
fn kernel(n: usize, ds: f64) -> Vec<Vec<(i64, f64)>> {
    let [lo, hi] = band_bins(n, ds);
    if n == WINDOW {
        return (lo..=hi).map(|k| vec![(k as i64, 1.0)]).collect();
    }
    let ratio = WINDOW as f64 / n as f64;
    let reach = (2.0 * ratio).ceil() as i64;
    (lo..=hi)
        .map(|k| {
            let centre = (k as f64 * ratio).round() as i64;
            let mut row: Vec<(i64, f64)> = (centre - reach..=centre + reach)
                .filter(|j| *j != 0)
                .map(|j| {
                    let theta = k as f64 / n as f64 - j as f64 / WINDOW as f64;
                    (j, hann_power(theta, n))
                })
                .collect();
            let total: f64 = row.iter().map(|r| r.1).sum();
            for r in &mut row {
                r.1 /= total;
            }
            row
        })
        .collect()
}

/// `|W(theta)|^2` of the Hann window of `n` cells at `theta` cycles per cell: its DFT is three
/// shifted Dirichlet kernels, `D(t) = sum_m e^(-2 pi i t m) = e^(-i pi t (n-1)) sin(pi t n) /
/// sin(pi t)`.
fn hann_power(theta: f64, n: usize) -> f64 {
    let d = |t: f64| -> C {
        let s = (std::f64::consts::PI * t).sin();
        let mag = if s.abs() < 1e-12 {
            n as f64
        } else {
            (std::f64::consts::PI * t * n as f64).sin() / s
        };
        let a = -std::f64::consts::PI * t * (n as f64 - 1.0);
        [mag * a.cos(), mag * a.sin()]
    };
    let step = 1.0 / n as f64;
    let (a, b, c) = (d(theta), d(theta - step), d(theta + step));
    let w = [
        0.5 * a[0] - 0.25 * (b[0] + c[0]),
        0.5 * a[1] - 0.25 * (b[1] + c[1]),
    ];
    w[0] * w[0] + w[1] * w[1]
}

/// Condition `cond`'s expected periodograms through `kernel`; `None` if a bin it needs is not
/// stored.
fn expect(s: &Spectra, cond: usize, kernel: &[Vec<(i64, f64)>]) -> Option<Vec<[f64; PACKED]>> {
    kernel
        .iter()
        .map(|row| {
            let mut out = [0.0; PACKED];
            for (j, w) in row {
                let m = s.matrix(cond, j.unsigned_abs() as usize)?;
                // S(-f) = conj(S(f)): the imaginary parts change sign.
                let sign = if *j < 0 { -1.0 } else { 1.0 };
                for i in 0..PACKED {
                    let imag = i >= 3 && (i - 3) % 2 == 1;
                    out[i] += w * m[i] * if imag { sign } else { 1.0 };
                }
            }
            Some(out)
        })
        .collect()
}

/// `f32` values as their little-endian bytes in a binary format (the FMU state's postcard); in a
/// human-readable one (the bank's TOML header) an empty string, the values being in the bank's
/// data block ([`super::bank`] reads them into place).
mod packed_f32 {
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<S: Serializer>(v: &[f32], s: S) -> Result<S::Ok, S::Error> {
        if s.is_human_readable() {
            return s.serialize_str("");
        }
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        s.serialize_bytes(&bytes)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f32>, D::Error> {
        if d.is_human_readable() {
            return match String::deserialize(d)?.as_str() {
                "" => Ok(vec![]),
                _ => Err(D::Error::custom(
                    "the model spectra's values belong in the bank's data block, not its header",
                )),
            };
        }
        let bytes = serde_bytes_vec(d)?;
        if !bytes.len().is_multiple_of(4) {
            return Err(D::Error::custom("not whole f32 values"));
        }
        Ok(bytes
            .chunks(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect())
    }

    fn serde_bytes_vec<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<u8>, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Vec<u8>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("bytes")
            }
            fn visit_bytes<E: Error>(self, v: &[u8]) -> Result<Vec<u8>, E> {
                Ok(v.to_vec())
            }
            fn visit_byte_buf<E: Error>(self, v: Vec<u8>) -> Result<Vec<u8>, E> {
                Ok(v)
            }
        }
        d.deserialize_byte_buf(V)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learned::contact::tests::uniform;

    const DS: f64 = 0.2;

    #[test]
    fn the_likelihood_s_share_fades_with_disagreement_and_misfit() {
        let sigma = DISAGREEMENT[LENGTHS.len() - 1];
        let full = DISAGREEMENT_FULL[1] * sigma;
        let level = FIT_LEVEL[LENGTHS.len() - 1];
        assert_eq!(share(WINDOW, 0.0, 0.0), SHARE);
        assert_eq!(share(LENGTHS[0], 0.0, 0.0), SHARE);
        assert_eq!(share(WINDOW, -full, level), SHARE);
        assert!((share(WINDOW, 1.25 * full, 0.0) - 0.5 * SHARE).abs() < 1e-12);
        assert_eq!(share(WINDOW, 1.5 * full, 0.0), 0.0);
        assert!((share(WINDOW, 0.0, 1.25 * level) - 0.5 * SHARE).abs() < 1e-12);
        assert_eq!(share(WINDOW, 0.0, 1.5 * level), 0.0);
        // The two gates multiply; a fit that is not a number leaves the likelihood nothing.
        assert!((share(WINDOW, 1.25 * full, 1.25 * level) - 0.25 * SHARE).abs() < 1e-12);
        assert_eq!(share(WINDOW, 0.0, f64::NAN), 0.0);
        // The shortest window's bounds are its own; between, the disagreement's bound is
        // linear in the length (halfway: the two bounds' mean, in its length's DISAGREEMENT).
        let short = DISAGREEMENT_FULL[0] * DISAGREEMENT[0];
        assert_eq!(share(LENGTHS[0], short, FIT_LEVEL[0]), SHARE);
        assert!(share(LENGTHS[0], 1.5 * short, 0.0) < 1e-12);
        assert_eq!(share(LENGTHS[0], 2.0 * short, 0.0), 0.0);
        let (n, i) = (575, 6);
        assert!(LENGTHS[i - 1] < n && n <= LENGTHS[i]);
        let mid = 0.5 * (DISAGREEMENT_FULL[0] + DISAGREEMENT_FULL[1]) * DISAGREEMENT[i];
        assert!((share(n, mid, 0.0) - SHARE).abs() < 1e-12);
        assert!((share(n, 1.25 * mid, 0.0) - 0.5 * SHARE).abs() < 1e-12);
        // The fit's level is that length's too (FIT_LEVEL is not monotone in the length).
        assert_eq!(share(n, 0.0, FIT_LEVEL[i]), SHARE);
        assert!((share(n, 0.0, 1.25 * FIT_LEVEL[i]) - 0.5 * SHARE).abs() < 1e-12);
        let (higher, level) = (FIT_LEVEL[2], FIT_LEVEL[3]);
        assert!(higher > level);
        assert_eq!(share(LENGTHS[3], 0.0, level), SHARE);
        assert!(share(LENGTHS[3], 0.0, higher) < SHARE);
    }

    /// Bins drawn complex Gaussian with the covariances `E_k` themselves (any level per
    /// octave) have a dispersion of 1 (the sum of three unit exponentials has variance 3), to
    /// the draw's scatter (`2 / sqrt(bins)`: 0.022). Drawn with the first channel's amplitude
    /// times `sqrt 2` in every other bin, a shape no level can fit, `z` there is a sum of
    /// exponentials weighted by the eigenvalues of `L^T D E^-1 D L` (0.69, 1, 2.89; `D` =
    /// diag(sqrt 2, 1, 1)), the octave's level is the two kinds' mean (`(3 + 4.59) / 2 / 3`),
    /// and `E[(z / a - 3)^2]` over both kinds gives 1.47 (a numpy draw of 20 x 8000 bins: 1.470
    /// +- 0.041).
    #[test]
    fn the_dispersion_is_one_where_the_model_is_right_and_grows_where_it_is_not() {
        // Box-Muller from two streams: consecutive draws of one linear congruential stream
        // are correlated enough to bias fourth moments (the Neave effect).
        let (mut u, mut v) = (uniform(5), uniform(91));
        let mut normal = move || {
            let (a, b) = (u() + 0.5, v() + 0.5);
            (-2.0 * a.max(1e-300).ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        };
        // E = L L^T, L lower triangular and real: E_ij = E[y_i conj(y_j)].
        let l = [[1.0, 0.0, 0.0], [0.6, 0.8, 0.0], [-0.3, 0.5, 0.4]];
        let mut e = [0.0; PACKED];
        let entry = |i: usize, j: usize| (0..3).map(|m| l[i][m] * l[j][m]).sum::<f64>();
        (e[0], e[1], e[2]) = (entry(0, 0), entry(1, 1), entry(2, 2));
        (e[3], e[5], e[7]) = (entry(0, 1), entry(0, 2), entry(1, 2));
        let bins = 8000;
        let octaves: Vec<usize> = (0..bins).map(|k| k * OCTAVES / bins).collect();
        let levels: [f64; 4] = [1.0, 3.0, 0.2, 7.0];
        let draw = |boost: &dyn Fn(usize) -> f64, normal: &mut dyn FnMut() -> f64| {
            (0..bins)
                .map(|k| {
                    let w: [C; 3] =
                        std::array::from_fn(|_| [normal() / 2f64.sqrt(), normal() / 2f64.sqrt()]);
                    let a = levels[octaves[k]].sqrt();
                    let mut y: [C; 3] = std::array::from_fn(|i| {
                        let re = (0..3).map(|m| l[i][m] * w[m][0]).sum::<f64>();
                        let im = (0..3).map(|m| l[i][m] * w[m][1]).sum::<f64>();
                        [a * re, a * im]
                    });
                    let b = boost(k).sqrt();
                    y[0] = [b * y[0][0], b * y[0][1]];
                    y
                })
                .collect::<Vec<[C; 3]>>()
        };
        let model = vec![e; bins];
        let right = dispersion(&model, &draw(&|_| 1.0, &mut normal), &octaves);
        assert!((right - 1.0).abs() < 0.07, "{right}");
        let wrong = dispersion(
            &model,
            &draw(&|k| 1.0 + (k % 2) as f64, &mut normal),
            &octaves,
        );
        assert!((wrong - 1.47).abs() < 0.15, "{wrong}");
        // A model that is not positive definite fits nothing.
        let mut bad = e;
        bad[0] = -1.0;
        assert!(dispersion(&vec![bad; bins], &draw(&|_| 1.0, &mut normal), &octaves).is_nan());
    }

    #[test]
    fn white_noise_has_its_density_in_every_window() {
        // Unit-variance-ish white noise on a 0.2 m grid: one-sided density 2 var ds.
        let mut u = uniform(7);
        let x: Vec<[f64; 3]> = (0..200_000).map(|_| [u(), 2.0 * u(), u()]).collect();
        let var = 1.0 / 12.0;
        for n in [150, 1000] {
            let bins = band_bins(n, DS);
            let w = welch(&x, n, DS, bins).unwrap();
            let mean = |i: usize| w.iter().map(|m| m[i]).sum::<f64>() / w.len() as f64;
            for (i, gain) in [(0, 1.0), (1, 4.0), (2, 1.0)] {
                let want = 2.0 * var * gain * DS;
                assert!(
                    (mean(i) / want - 1.0).abs() < 0.03,
                    "n {n}: {} against {want}",
                    mean(i)
                );
            }
            // Independent channels: no cross-spectrum.
            assert!(mean(3).abs() < 0.03 * 2.0 * var * 2.0 * DS);
        }
    }

    #[test]
    fn the_cholesky_form_is_the_inverse_s_quadratic_form() {
        // E = A A^H + I for a fixed complex A; y fixed: against the explicit inverse by
        // Cramer's rule.
        let a: [[C; 3]; 3] = [
            [[1.0, 0.2], [0.3, -0.4], [0.0, 0.5]],
            [[-0.2, 0.1], [0.8, 0.0], [0.4, 0.3]],
            [[0.5, -0.6], [0.1, 0.2], [0.9, 0.1]],
        ];
        let mut e = [[[0.0; 2]; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                for (x, y) in a[i].iter().zip(&a[j]) {
                    let p = mul(*x, [y[0], -y[1]]);
                    e[i][j][0] += p[0];
                    e[i][j][1] += p[1];
                }
                if i == j {
                    e[i][j][0] += 1.0;
                }
            }
        }
        let pk = [
            e[0][0][0], e[1][1][0], e[2][2][0], e[0][1][0], e[0][1][1], e[0][2][0], e[0][2][1],
            e[1][2][0], e[1][2][1],
        ];
        let y: [C; 3] = [[0.3, -1.0], [2.0, 0.5], [-0.7, 0.4]];
        let (det, q) = quadratic(&pk, &y).unwrap();
        // Explicit complex determinant and adjugate.
        let sub = |a: C, b: C| [a[0] - b[0], a[1] - b[1]];
        let det3 = |m: &[[C; 3]; 3]| {
            let t = |i: usize, j: usize, k: usize| {
                mul(m[0][i], sub(mul(m[1][j], m[2][k]), mul(m[1][k], m[2][j])))
            };
            let (x, y, z) = (t(0, 1, 2), t(1, 0, 2), t(2, 0, 1));
            [x[0] - y[0] + z[0], x[1] - y[1] + z[1]]
        };
        let d = det3(&e);
        assert!(d[1].abs() < 1e-12);
        assert!((det / d[0] - 1.0).abs() < 1e-12);
        // q = y^H E^-1 y with E^-1 y by Cramer's rule.
        let mut q2 = 0.0;
        for i in 0..3 {
            let mut m = e;
            for r in 0..3 {
                m[r][i] = y[r];
            }
            let xi = det3(&m);
            let xi = [xi[0] / d[0], xi[1] / d[0]];
            q2 += mul([y[i][0], -y[i][1]], xi)[0];
        }
        assert!((q - q2).abs() < 1e-12 * q2.abs(), "{q} against {q2}");
    }

    #[test]
    fn the_hann_kernel_sums_to_one_over_all_bins() {
        // Parseval: sum over the N fine bins of |W|^2 is N sum w^2 = 3 N n / 8.
        for n in [150, 400] {
            let k = 3;
            let total: f64 = (0..WINDOW)
                .map(|j| hann_power(k as f64 / n as f64 - j as f64 / WINDOW as f64, n))
                .sum();
            let want = WINDOW as f64 * 3.0 * n as f64 / 8.0;
            assert!((total / want - 1.0).abs() < 1e-9, "{total} against {want}");
        }
    }

    #[test]
    fn the_sliding_dft_equals_the_direct_one() {
        let mut s = Spectral::new(DS);
        let mut u = uniform(3);
        for _ in 0..1234 {
            s.push(&[u(), u(), u(), 0.0, 0.0], 1.0);
        }
        let mut exact = s.clone();
        exact.exact();
        for (a, b) in s.sliding.iter().zip(&exact.sliding) {
            for c in 0..3 {
                assert!((a[c][0] - b[c][0]).abs() < 1e-9 && (a[c][1] - b[c][1]).abs() < 1e-9);
            }
        }
        // And the Hann periodogram from it is the direct Hann DFT's (mean aside: the band
        // starts above the bins a mean leaks into).
        let direct: Vec<[f64; 3]> = (0..WINDOW).map(|m| s.ring[(s.head + m) % WINDOW]).collect();
        let want = hann_dft(&direct, band_bins(WINDOW, DS));
        let root = scale(WINDOW, DS).sqrt();
        for (y, x) in s.periodogram(WINDOW).iter().zip(&want) {
            for c in 0..3 {
                assert!((y[c][0] - root * x[c][0]).abs() < 1e-9);
                assert!((y[c][1] + root * x[c][1]).abs() < 1e-9);
            }
        }
    }

    /// Three channels driven by one white "track" through a resonance whose wavelength is set
    /// by `c` (a toy of the wheelset's kinematic wave), plus white noise: a process whose
    /// cross-spectra move with `c` as the vehicle's do with the conicity.
    fn toy(c: f64, len: usize, seed: u64) -> Vec<[f64; 3]> {
        let mut u = uniform(seed);
        let wave = 13.0 * (0.1 / c).sqrt();
        let w0 = 2.0 * std::f64::consts::PI * DS / wave;
        let r: f64 = 0.99;
        let (a1, a2) = (2.0 * r * w0.cos(), -r * r);
        let (mut y1, mut y2) = (0.0, 0.0);
        let mut prev = 0.0;
        (0..len)
            .map(|_| {
                let e = u();
                let y = a1 * y1 + a2 * y2 + e;
                (y2, y1) = (y1, y);
                let d = y - y2;
                let out = [
                    y + 0.05 * u(),
                    d + 0.1 * e + 0.05 * u(),
                    0.5 * prev + 0.2 * y + 0.05 * u(),
                ];
                prev = e;
                out
            })
            .collect()
    }

    #[test]
    fn the_likelihood_finds_the_toy_s_parameter() {
        // Models at five "conicities" from long toy runs; records at other ones, 200 m and
        // 60 m, each estimate within the toy's own scatter of the truth.
        let nodes = [0.05, 0.075, 0.1, 0.15, 0.2];
        let bins = stored_bins(DS);
        let mut values = vec![];
        for (i, c) in nodes.iter().enumerate() {
            let w = welch(&toy(*c, 400_000, 11 + i as u64), WINDOW, DS, bins).unwrap();
            values.extend(w.iter().flatten().map(|v| *v as f32));
        }
        let spectra = Spectra {
            window: WINDOW,
            first_bin: bins[0],
            conditions: nodes.iter().map(|c| [*c, 1.0]).collect(),
            values,
        };
        spectra.check(DS).unwrap();
        let models = [(20.0, &spectra)];
        for (truth, cells, tolerance) in [(0.09, 1000, 0.05), (0.13, 1000, 0.05), (0.09, 300, 0.06)]
        {
            let mut errors = vec![];
            for seed in 0..6 {
                let mut s = Spectral::new(DS);
                for x in toy(truth, cells, 100 + seed) {
                    // The quotient by the speed (20 m/s, powers 2, 1, 2) undone.
                    if s.push(&[x[0] * 400.0, x[1] * 20.0, x[2] * 400.0, 0.0, 0.0], 20.0)
                        && let Some(r) = s.update(20.0, &models)
                    {
                        s.aim(r.ln_c, 0.0);
                    }
                }
                errors.push(s.target.unwrap() - f64::ln(truth));
            }
            let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
            assert!(
                rms < tolerance,
                "{truth}, {cells} cells: ln c errors {errors:?}"
            );
        }
    }
}
