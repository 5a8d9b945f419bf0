//! The long-wave stage: a correction of the causal estimate's long waves from a longer memory
//! than the taps' 60 m window.
//!
//! # Why
//! The taps see 60 m of history. A 70-200 m wave (D3) spans more than that, and the taps take
//! its content from the Kalman channel, whose long waves are limited by the paper's model. A
//! least-squares FIR over 600 m of the same sensors, fitted to D3 alone, reaches the
//! non-causal Wiener figure there (docs/accuracy.md, "What the sensors allow"). The stage
//! is that idea as a second step after the taps: its inputs are the sensor channels and the
//! taps' own causal estimate, so it can replace the estimate's long waves, not only add to them.
//!
//! # What it computes, per closed grid cell
//! | step | rule |
//! |---|---|
//! | inputs | the history's sensor channels as the taps read them (each cell divided by its speed's [`super::stream::TAP_SPEED_POWER`]), then the taps' causal estimate (before the stage; the Kalman filter's estimate where the taps made none) |
//! | the estimate's mean | the estimate's mean since the run's start is taken from it: an untold gyroscope bias swings the taps' estimate by some 150 mm over its first 2 km (the Kalman channel's drift, high-passed), which the band-pass alone passes into the stage's memory (figures in docs/accuracy.md, "The long-wave stage"). The sensor channels are left whole: their mean taken out changed nothing |
//! | band-pass | each input through a causal Butterworth high-pass of order 2 at [`HIGHPASS`] and a low-pass of order 4 at [`LOWPASS`] (wavelengths, on the bank's grid), the estimate through one more high-pass section at [`HIGHPASS`] first ([`ESTIMATE_HIGHPASS_ORDER`]): the stage sees only the waves it may correct |
//! | FIR | `c = sum_i g_i sum_j w_ij u_i(k - j m)`: tap `j` of input `i` multiplies the band-passed input `j` spacings ([`SPACING`], `m` cells) back, `j = 0 .. LAGS - 1` (600 m); `g_i` is the current speed's `V^p` for the sensors (the taps' rescaling), 1 for the estimate |
//! | output | the causal estimate plus `c` times the stage's share, `c` blended linearly in speed between the two bank speeds around the current one, as the taps are |
//! | share | 0 over a run's first 200 m, rising to 1 at 400 m ([`START_RAMP`]: fitted on full memories, the stage corrects a cold start's partial one badly); and 1 while the fastest cell in the memory is within 10 % of the slowest, 0 from 20 % ([`SPEED_SPAN`]: fitted at constant speed) |
//!
//! Before a run has 600 m behind it the inputs before its start are zeros. The fixed-lag
//! output is left as the taps make it.
//!
//! # The fit
//! `alignment-studies stage` (`studies/src/study/learned/stage.rs`) runs the vehicle FMU on
//! five training track seeds at every bank speed and contact condition, runs this estimator
//! over the runs with [`super::Learned::log_stage`] on (the same band-pass, the same estimate
//! the FMU makes), and solves the ridge least squares of the taps' residual with the taps'
//! objective (the metric's bands, zero-phase, on the regressors and the residual alike: the
//! stage is causal, the fit minimises what the metric measures).

use super::grid::Biquad;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// Cut-off wavelength of the band-pass's high-pass \[m\]: twice the metric's longest wave,
/// so D3 passes with little phase lead.
pub const HIGHPASS: f64 = 400.0;
/// Cut-off wavelength of the band-pass's low-pass \[m\]. Order 4 rather than 2: on the
/// validation seeds 109-112 (`tests/long_stage_probe.py`, 20 m/s, three sensors) whole Jrel
/// 0.089 against 0.091, D1 0.098 against 0.101 (the stage's leak into the short waves).
pub const LOWPASS: f64 = 40.0;
/// Distance between the stage's taps \[m\]: a quarter of the low-pass's cut-off.
pub const SPACING: f64 = 10.0;
/// Taps per input: 600 m of memory.
pub const LAGS: usize = 61;

/// The stage's share of its correction against the ratio of the fastest to the slowest cell
/// in its memory: whole up to the first, none from the second, linear between. The taps were
/// fitted at constant speed; a memory recorded at other speeds than the current one feeds them
/// inputs unlike their training (the accelerations' long waves are mostly the roll's gravity,
/// which the taps' `V^1.5` rescaling does not follow). Without it, the variable-speed profile
/// (0 -> 20 -> 10 m/s, 640 m; validation seeds 102-106) went from whole Jrel 0.114 without
/// the stage to 0.151 (the first fit: whole band, seed 101, no start ramp); with it the stage
/// sits that profile out (0.114), as it does any record
/// starting from a standstill for its first 600 m at speed. The edges are a judgement (a
/// train's speed within +-5 % keeps the whole stage), not a fit.
pub const SPEED_SPAN: [f64; 2] = [1.1, 1.2];

/// The stage's share over a run's start: none over the first of these distances \[m\] of
/// its memory, whole from the second, linear between. Fitted on full memories, the stage
/// corrects a cold start's partial one badly: with the whole-band fit on seed 101, on the
/// validation seeds 102-106 (standard case, 400 m from a cold start) the stage from the first
/// cell gave whole Jrel 0.105, none 0.097,
/// this ramp 0.096; on 2 km runs of seeds 104-106 (which the ridge was not chosen on) 0.092,
/// 0.104 and 0.092 (ramps over 0-200, 0-400, 100-400, 200-600, 300-600 and 400-800 m gave
/// 0.107 / 0.099 / 0.099 / 0.096 / 0.097 / 0.097 and 0.093 / 0.092 / 0.092 / 0.093 / 0.094
/// / 0.094).
pub const START_RAMP: [f64; 2] = [200.0, 400.0];

/// The share over a run's start after `covered` metres of cells ([`START_RAMP`]).
pub fn start_share(covered: f64) -> f64 {
    let [a, b] = START_RAMP;
    ((covered - a) / (b - a)).clamp(0.0, 1.0)
}

/// The Q factors of the fourth-order Butterworth low-pass's two sections:
/// `1 / (2 cos(pi/8))` and `1 / (2 cos(3 pi/8))`.
const LOWPASS_Q: [f64; 2] = [0.541_196_100_146_197, 1.306_562_964_876_376_6];

/// The stage's band-pass on a grid of `ds` metres: the high-pass, then the low-pass's two
/// sections.
pub fn design(ds: f64) -> [Biquad; 3] {
    [
        Biquad::highpass(ds, HIGHPASS),
        Biquad::lowpass_q(ds, LOWPASS, LOWPASS_Q[0]),
        Biquad::lowpass_q(ds, LOWPASS, LOWPASS_Q[1]),
    ]
}

/// The order of the estimate's high-pass at [`HIGHPASS`]: the band-pass's section and one
/// more. An untold gyroscope bias swings the taps' estimate by some 150 mm over 2 km; order 2
/// passes 4 % of such a 2000 m wave, order 4 0.2 %.
pub const ESTIMATE_HIGHPASS_ORDER: u32 = 4;

/// The estimate's extra high-pass section (applied before [`design`]'s band-pass): with it
/// the estimate's high-pass is of [`ESTIMATE_HIGHPASS_ORDER`].
pub fn estimate_highpass(ds: f64) -> Biquad {
    Biquad::highpass(ds, HIGHPASS)
}

/// The grid cells between two taps on a grid of `ds` metres (`None` unless [`SPACING`] is a
/// whole number of cells).
pub fn every(ds: f64) -> Option<usize> {
    let m = SPACING / ds;
    let r = m.round();
    ((m - r).abs() < 1e-9 * m && r >= 1.0).then_some(r as usize)
}

/// A bank's stage: its design as fitted, and its taps per speed and sensor set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageBank {
    /// [`HIGHPASS`], [`LOWPASS`], [`SPACING`] \[m\] and [`LAGS`] as the fit had them: a build
    /// with others refuses the bank (its taps multiply other inputs).
    pub highpass: f64,
    /// See `highpass`.
    pub lowpass: f64,
    /// See `highpass`.
    pub spacing: f64,
    /// See `highpass`.
    pub lags: usize,
    /// [`ESTIMATE_HIGHPASS_ORDER`] as the fit had it (0: a stage fitted before the
    /// estimate's own treatment, refused).
    #[serde(default)]
    pub estimate_highpass_order: u32,
    /// The fit's entries.
    #[serde(rename = "entry")]
    pub entries: Vec<StageEntry>,
}

/// The stage's taps at one bank speed, for one sensor set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageEntry {
    /// Bank speed \[m/s\].
    pub speed: f64,
    /// The sensor channels ([`super::grid::CHANNELS`] names), then `estimate`.
    pub channels: Vec<String>,
    /// The ridge chosen on the validation runs (times the Gram matrix's mean diagonal).
    pub ridge: f64,
    /// The fit's objective (`sum_b w_b Jrel_b^2`) on the validation runs, without the stage
    /// and with it.
    pub validation: [f64; 2],
    /// `LAGS` taps per channel, channel after channel; within a channel, tap `j` multiplies
    /// the band-passed input `j` spacings back. Metres of alignment per unit of the input.
    pub taps: Vec<f64>,
}

/// The name of the estimate's input in a [`StageEntry`]'s channels.
pub const ESTIMATE: &str = "estimate";

impl StageBank {
    /// Whether this build applies the stage as it was fitted; the problem otherwise.
    pub fn check(&self, grid: f64) -> Result<(), String> {
        if self.estimate_highpass_order != ESTIMATE_HIGHPASS_ORDER {
            return Err(format!(
                "the stage was fitted with the estimate high-passed at order {}; this build has order {ESTIMATE_HIGHPASS_ORDER}, its mean taken out first: fit it again",
                self.estimate_highpass_order
            ));
        }
        let ours = (HIGHPASS, LOWPASS, SPACING, LAGS);
        if (self.highpass, self.lowpass, self.spacing, self.lags) != ours {
            return Err(format!(
                "the stage was fitted with a band-pass at {}-{} m and {} taps every {} m; this build has {}-{} m and {} every {} m: fit it again",
                self.lowpass,
                self.highpass,
                self.lags,
                self.spacing,
                LOWPASS,
                HIGHPASS,
                LAGS,
                SPACING
            ));
        }
        if every(grid).is_none() {
            return Err(format!(
                "its taps are {SPACING} m apart, not a whole number of {grid} m cells"
            ));
        }
        for (i, e) in self.entries.iter().enumerate() {
            let sensors = &e.channels[..e.channels.len().saturating_sub(1)];
            if e.channels.last().map(String::as_str) != Some(ESTIMATE)
                || sensors.is_empty()
                || sensors
                    .iter()
                    .any(|c| !super::grid::CHANNELS[..4].contains(&c.as_str()))
            {
                return Err(format!(
                    "stage entry {i}: channels {:?} (sensor channels, then 'estimate')",
                    e.channels
                ));
            }
            if e.taps.len() != e.channels.len() * LAGS {
                return Err(format!(
                    "stage entry {i}: {} taps for {} channels of {LAGS}",
                    e.taps.len(),
                    e.channels.len()
                ));
            }
            if !(e.speed.is_finite() && e.speed > 0.0) || e.taps.iter().any(|t| !t.is_finite()) {
                return Err(format!(
                    "stage entry {i}: speed {} or a tap not a number",
                    e.speed
                ));
            }
        }
        Ok(())
    }
}

/// The stage's taps for one sensor set, one per speed of the taps' own (ascending), so the
/// taps' blend in speed serves the stage as it is.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct StageTaps {
    /// Per speed, `LAGS` taps per input.
    pub(super) taps: Vec<Vec<f64>>,
}

impl StageTaps {
    /// The entries of `bank` for the sensor channels `sensors` (their names); `None` when it
    /// has none for them, or not one per speed of `speeds` (the taps' own).
    pub(super) fn select(bank: &StageBank, sensors: &[&str], speeds: &[f64]) -> Option<StageTaps> {
        let mut at: Vec<&StageEntry> = bank
            .entries
            .iter()
            .filter(|e| {
                e.channels.len() == sensors.len() + 1
                    && e.channels.iter().zip(sensors).all(|(a, b)| a == b)
            })
            .collect();
        at.sort_by(|a, b| a.speed.total_cmp(&b.speed));
        let found: Vec<f64> = at.iter().map(|e| e.speed).collect();
        (found == speeds).then(|| StageTaps {
            taps: at.iter().map(|e| e.taps.clone()).collect(),
        })
    }
}

/// One cell's record for the fit ([`super::Learned::log_stage`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StageRow {
    /// Where the cell closed \[m\].
    pub distance: f64,
    /// The taps' causal estimate there, before the stage (`NaN` where they made none).
    pub estimate: f64,
    /// The band-passed inputs (the sensor channels, then the estimate; unused ones 0), each
    /// times its gain at the cell's speed: what the taps multiply.
    pub inputs: [f64; 5],
}

/// The slowest and fastest cell speed over the last `span` cells: monotonic queues of
/// (cell number, speed), so each cell costs O(1) on average.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct Extremes {
    low: VecDeque<(u64, f64)>,
    high: VecDeque<(u64, f64)>,
    count: u64,
}

impl Extremes {
    fn push(&mut self, v: f64, span: u64) {
        let k = self.count;
        self.count += 1;
        while self.low.back().is_some_and(|b| b.1 >= v) {
            self.low.pop_back();
        }
        self.low.push_back((k, v));
        while self.high.back().is_some_and(|b| b.1 <= v) {
            self.high.pop_back();
        }
        self.high.push_back((k, v));
        for q in [&mut self.low, &mut self.high] {
            while q.front().is_some_and(|f| f.0 + span <= k) {
                q.pop_front();
            }
        }
    }

    /// Fastest over slowest (infinite if the slowest stood still; 1 before any cell).
    fn ratio(&self) -> f64 {
        match (self.low.front(), self.high.front()) {
            (Some(l), Some(h)) => h.1 / l.1,
            _ => 1.0,
        }
    }
}

/// The stage's share at the speed ratio `r` over its memory ([`SPEED_SPAN`]).
pub fn share(r: f64) -> f64 {
    let [a, b] = SPEED_SPAN;
    if r <= a {
        1.0
    } else if r >= b || r.is_nan() {
        0.0
    } else {
        (b - r) / (b - a)
    }
}

/// The stage's running state: each input's band-pass and the last 600 m of its output.
///
/// The memory is kept by phase: a cell's correction reads the cells a whole number of
/// spacings behind it, which all share its position within a spacing (its phase). Each
/// (input, phase) holds its last `LAGS` values contiguously, so a correction reads four short
/// runs of memory instead of 244 values spread over 100 kB. (Against one ring per input the
/// benchmark showed no difference beyond its run-to-run spread.)
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct Stage {
    filters: Vec<[Biquad; 3]>,
    /// `[input][phase][slot]`, flattened: the value of cell `k` of phase `k % every` sits in
    /// slot `(k / every) % LAGS`.
    memory: Vec<f64>,
    every: usize,
    /// The cells' speeds over the memory; its count is the cells pushed.
    speeds: Extremes,
    /// The grid step \[m\].
    ds: f64,
    /// The sum of the estimate's values since the run's start: their mean is taken from the
    /// estimate before its band-pass (module docs, "the estimate's mean").
    estimate_sum: f64,
    /// The estimate's extra high-pass section ([`estimate_highpass`]).
    estimate_filter: Biquad,
}

impl Stage {
    /// A stage over `inputs` inputs on a grid of `ds` metres (a whole number of cells per
    /// spacing: [`StageBank::check`]).
    pub(super) fn new(inputs: usize, ds: f64) -> Stage {
        let every = every(ds).unwrap_or(1);
        Stage {
            filters: vec![design(ds); inputs],
            memory: vec![0.0; inputs * every * LAGS],
            every,
            speeds: Extremes::default(),
            ds,
            estimate_sum: 0.0,
            estimate_filter: estimate_highpass(ds),
        }
    }

    /// The cells the memory spans: `LAGS - 1` spacings and the newest cell.
    fn span(&self) -> u64 {
        ((LAGS - 1) * self.every + 1) as u64
    }

    /// Where the values of `input` at the phase of cell `k` begin in `memory`, and the slot
    /// of cell `k`.
    fn at(&self, input: usize, k: u64) -> (usize, usize) {
        let every = self.every as u64;
        let phase = (k % every) as usize;
        (
            (input * self.every + phase) * LAGS,
            ((k / every) % LAGS as u64) as usize,
        )
    }

    /// Band-passes one cell's inputs, closed at `speed`, and keeps them; returns them
    /// band-passed.
    pub(super) fn push(&mut self, x: &[f64], speed: f64) -> [f64; 5] {
        let k = self.speeds.count;
        self.speeds.push(speed, self.span());
        let mut out = [0.0; 5];
        let n = self.filters.len();
        self.estimate_sum += x[n - 1];
        for i in 0..n {
            let xi = if i == n - 1 {
                self.estimate_filter
                    .step(x[i] - self.estimate_sum / (k + 1) as f64)
            } else {
                x[i]
            };
            let v = self.filters[i].iter_mut().fold(xi, |v, s| s.step(v));
            let (base, slot) = self.at(i, k);
            self.memory[base + slot] = v;
            out[i] = v;
        }
        out
    }

    /// The share of its correction the stage gives: at the speeds in its memory ([`share`])
    /// and over the run's start ([`start_share`]).
    pub(super) fn share(&self) -> f64 {
        share(self.speeds.ratio()) * start_share(self.speeds.count as f64 * self.ds)
    }

    /// The correction of the newest cell by `taps` (`LAGS` per input), each input's sum times
    /// its `gain` (before [`Self::share`]). Slots not yet written hold zeros: the lags before
    /// a run's start.
    pub(super) fn correction(&self, taps: &[f64], gain: &[f64]) -> f64 {
        let Some(newest) = self.speeds.count.checked_sub(1) else {
            return 0.0;
        };
        let mut c = 0.0;
        for (i, g) in gain.iter().enumerate().take(self.filters.len()) {
            let w = &taps[i * LAGS..(i + 1) * LAGS];
            let (base, slot) = self.at(i, newest);
            let m = &self.memory[base..base + LAGS];
            // Lag j is slot `slot - j`, wrapping: the slots up to `slot` backwards, then the
            // rest from the end backwards.
            let (recent, older) = m.split_at(slot + 1);
            let mut s = 0.0;
            for (t, v) in w.iter().zip(recent.iter().rev().chain(older.iter().rev())) {
                s += t * v;
            }
            c += g * s;
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The band-pass is scipy's `butter(2, high-pass) then butter(4, low-pass)`: its gain at
    /// the cut-offs is 1/sqrt(2) (each section pair of a Butterworth), 1 in between, and it
    /// falls as the fourth power beyond the low-pass's cut-off.
    #[test]
    fn the_band_pass_is_butterworth() {
        let ds = 0.2;
        let gain = |wavelength: f64| {
            let w = std::f64::consts::TAU * ds / wavelength;
            design(ds)
                .iter()
                .map(|b| {
                    let [b0, b1, b2, a1, a2] = b.coefficients();
                    let z = num_complex_free::polar(1.0, -w);
                    let z2 = num_complex_free::mul(z, z);
                    let n = num_complex_free::add3(
                        b0,
                        num_complex_free::scale(z, b1),
                        num_complex_free::scale(z2, b2),
                    );
                    let d = num_complex_free::add3(
                        1.0,
                        num_complex_free::scale(z, a1),
                        num_complex_free::scale(z2, a2),
                    );
                    num_complex_free::abs(n) / num_complex_free::abs(d)
                })
                .product::<f64>()
        };
        let half = std::f64::consts::FRAC_1_SQRT_2;
        // At a cut-off the other filter passes all but a little.
        assert!(
            (gain(LOWPASS) / half - 1.0).abs() < 0.01,
            "{}",
            gain(LOWPASS)
        );
        assert!(
            (gain(HIGHPASS) / half - 1.0).abs() < 0.01,
            "{}",
            gain(HIGHPASS)
        );
        assert!((gain(127.0) - 1.0).abs() < 0.03, "{}", gain(127.0));
        // An octave below the low-pass's cut-off: 1 / sqrt(1 + 2^8).
        let octave = 1.0 / (1.0f64 + 256.0).sqrt();
        assert!(
            (gain(LOWPASS / 2.0) / octave - 1.0).abs() < 0.05,
            "{}",
            gain(LOWPASS / 2.0)
        );
    }

    /// A tap `j` of an input multiplies that input's band-passed value `j` spacings back.
    #[test]
    fn a_tap_reads_its_own_lag() {
        let ds = 0.2;
        let mut s = Stage::new(2, ds);
        let every = every(ds).unwrap();
        assert_eq!(every, 50);
        let mut kept = vec![];
        for k in 0..(LAGS * every + 7) {
            let x = [((k as f64) * 0.01).sin(), ((k as f64) * 0.003).cos()];
            kept.push(s.push(&x, 20.0));
        }
        let mut taps = vec![0.0; 2 * LAGS];
        taps[3] = 2.0; // input 0, 30 m back
        taps[LAGS + 60] = -1.0; // input 1, 600 m back
        let n = kept.len() - 1;
        let want = 0.5 * 2.0 * kept[n - 3 * every][0] - 3.0 * kept[n - 60 * every][1];
        let got = s.correction(&taps, &[0.5, 3.0]);
        assert!((got - want).abs() < 1e-15, "{got} {want}");
    }

    /// The speed ratio is that of the memory's cells alone: a slow start leaves it once it
    /// is more than the memory behind.
    #[test]
    fn the_speed_ratio_covers_the_memory_alone() {
        let mut e = Extremes::default();
        let span = 100;
        for k in 0..span {
            e.push(if k < 10 { 10.0 } else { 20.0 }, span);
        }
        assert_eq!(e.ratio(), 2.0);
        for _ in 0..10 {
            e.push(20.0, span);
        }
        assert_eq!(e.ratio(), 1.0);
        e.push(21.0, span);
        assert_eq!(e.ratio(), 1.05);
        assert_eq!(share(1.05), 1.0);
        assert!((share(1.15) - 0.5).abs() < 1e-12);
        assert_eq!(share(f64::INFINITY), 0.0);
        assert_eq!(start_share(100.0), 0.0);
        assert!((start_share(300.0) - 0.5).abs() < 1e-12);
        assert_eq!(start_share(500.0), 1.0);
        // Brute force over a random walk of speeds.
        let mut e = Extremes::default();
        let mut v: Vec<f64> = vec![];
        let mut x = 15.0f64;
        for k in 0..2000u64 {
            x = (x + ((k * 7919 % 13) as f64 - 6.0) * 0.1).max(0.5);
            v.push(x);
            e.push(x, span);
            let w = &v[v.len().saturating_sub(span as usize)..];
            let (lo, hi) = w
                .iter()
                .fold((f64::MAX, 0.0f64), |(l, h), s| (l.min(*s), h.max(*s)));
            assert_eq!(e.ratio(), hi / lo, "cell {k}");
        }
    }

    /// A stage fitted with another band-pass or another treatment of the estimate, or whose
    /// taps do not match its channels, is refused with what differs.
    #[test]
    fn a_stage_is_checked_against_this_build() {
        let good = StageBank {
            highpass: HIGHPASS,
            lowpass: LOWPASS,
            spacing: SPACING,
            lags: LAGS,
            estimate_highpass_order: ESTIMATE_HIGHPASS_ORDER,
            entries: vec![StageEntry {
                speed: 20.0,
                channels: ["ws_acc_y", "ws_yaw_rate", "frame_acc_y", ESTIMATE]
                    .map(String::from)
                    .to_vec(),
                ridge: 1e-6,
                validation: [0.1, 0.09],
                taps: vec![0.0; 4 * LAGS],
            }],
        };
        assert_eq!(good.check(0.2), Ok(()));
        let mut other = good.clone();
        other.lowpass = 30.0;
        assert!(other.check(0.2).unwrap_err().contains("fit it again"));
        let mut whole = good.clone();
        whole.estimate_highpass_order = 0;
        assert!(whole.check(0.2).unwrap_err().contains("at order 0"));
        assert!(good.check(0.3).unwrap_err().contains("whole number"));
        let mut short = good.clone();
        short.entries[0].taps.pop();
        assert!(
            short
                .check(0.2)
                .unwrap_err()
                .contains("243 taps for 4 channels")
        );
        let mut named = good.clone();
        named.entries[0].channels[3] = "kalman".into();
        assert!(named.check(0.2).unwrap_err().contains("channels"));
        let mut nan = good;
        nan.entries[0].taps[7] = f64::NAN;
        assert!(nan.check(0.2).unwrap_err().contains("not a number"));
    }

    /// Small complex arithmetic for the frequency response, without a dependency.
    mod num_complex_free {
        pub fn polar(r: f64, t: f64) -> (f64, f64) {
            (r * t.cos(), r * t.sin())
        }
        pub fn mul(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
            (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
        }
        pub fn scale(a: (f64, f64), k: f64) -> (f64, f64) {
            (a.0 * k, a.1 * k)
        }
        pub fn add3(a: f64, b: (f64, f64), c: (f64, f64)) -> (f64, f64) {
            (a + b.0 + c.0, b.1 + c.1)
        }
        pub fn abs(a: (f64, f64)) -> f64 {
            a.0.hypot(a.1)
        }
    }
}
