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
//! conditions differ most), then is divided by the speed to the power the kinematics give it
//! ([`CONTACT_SPEED_POWER`]: `V^2` for the accelerations, `V` for the yaw rate). Running second
//! moments `M_ij` of these are kept per speed of the model: a cell counts towards the two model
//! speeds around its own, in the linear-interpolation shares, each set exponentially weighted
//! with a memory of `memory` metres of its own cells (weight `w / min(n, memory / ds)` for a
//! share `w`, `n` the set's shares so far, so the first cells are a plain mean). The features
//! of a set are scale-free, so the track's roughness cancels:
//!
//! | feature | meaning |
//! |---|---|
//! | `ln(M_11 / M_00)` | yaw rate against wheelset acceleration |
//! | `ln(M_22 / M_00)` | frame against wheelset acceleration |
//! | `M_01 / sqrt(M_00 M_11)` | correlation of wheelset acceleration and yaw rate |
//! | `M_02 / sqrt(M_00 M_22)` | correlation of wheelset and frame accelerations |
//! | `M_12 / sqrt(M_11 M_22)` | correlation of yaw rate and frame acceleration |
//!
//! # The octaves of D1
//! The features are also taken in D1's octaves, 3-6, 6-12 and 12-25 m: 20 features, all of
//! which the Kalker scale is a linear function of. Over the memory's 200 m a track's own
//! spectrum tilts within D1 from one stretch to the next, and the whole band's ratios and
//! correlations move with it; per octave they follow the vehicle's transfer functions more
//! than the track (20 m/s, validation seeds 102-106, rms error after 200 m: ML95 0.078 from the
//! band alone, 0.029 with its octaves; the Manchester vehicle fitted by `alignment-studies
//! fit`, 0.093 and 0.040).
//!
//! # Conicity (a bank fitted over conicities)
//! The features are taken in three more bands, the octaves 5-10, 10-20 and 20-40 m around the
//! wheelset's kinematic wavelength `2 pi sqrt(r0 l / conicity)` (13 m for the ML95 at 0.1),
//! where a conicity shows: 35 features. `ln(conicity)` is a linear function of all of them
//! ([`ConicityModel`]); the Kalker scale, one model per bank conicity, of D1's and its
//! octaves' 20 ([`NodeModel`], which reads as many of the first bands as its coefficients
//! give: banks before 2026-11-27 read D1's five), blended at the conicity. The `novelty` checks
//! all of them against a model of what the training runs showed ([`ConicityModel`]).
//!
//! From 30 m into a run the runtime averages this linear model's `ln(conicity)` with the
//! maximum of Whittle's likelihood of the sensors' cross-spectra ([`super::spectral`], where
//! the bank holds model spectra: both shipped banks), which reads it about twice as well.
//!
//! A memory not yet full has its own conicity models ([`YoungModel`], fitted on memories of 5 to
//! 150 m started along the training runs, each half its own least squares and half the full
//! memory's model), interpolated by the track the memory holds: a run's first 150 m read the
//! conicity from the features of so short a memory, whose scatter and bias the full memory's
//! model was not fitted for.
//!
//! # Estimate
//! At each model speed the Kalker-coefficient scale is a linear function of the features,
//! fitted by least squares on the training runs of every trained condition at that constant
//! speed (`alignment-studies taps`). Each set is judged by its own speed's model, and the
//! estimates are averaged with weights of how much of the last `memory` metres each set holds
//! over that model's squared validation error, then clamped to the trained range. On the
//! validation seeds (`learned.taps`, a scale of 1.0, 0.75 or 0.5) it reaches about +-0.03 rms
//! after 200 m of track at every bank speed.
//!
//! Out of its training: on a track without cross-level (a simulation's; every training run has
//! it) the 3-6 m octave's features read the nominal contact as the lowest trained scale.
//!
//! Why sets per speed: with one set of moments for all speeds (until 2026-11-25), a run that
//! starts slowly kept its slow cells in the memory while it accelerated, and the model of the
//! current speed, applied to features of other speeds, read the nominal vehicle as worn (0.6
//! instead of 1.0 at 15-20 m/s on the variable-speed profile, validation seed 103); the blended
//! taps then lost D1 (0.28 against the nominal taps' 0.17). With the speed quotients but one set,
//! the nominal vehicle was read right and the worn one wrong (0.6-0.8 for 0.5).

use super::error::ContactProblem;
use super::grid::Biquad;
use serde::{Deserialize, Serialize};

/// The least rms error a speed's model is weighted by (Kalker scale): a model that happened to fit
/// its training runs perfectly must not take all the weight (the shipped banks' fitted errors are
/// 0.02-0.13).
pub const MIN_MODEL_ERROR: f64 = 1e-3;

/// The channels the features read ([`super::grid::CHANNELS`] indices).
pub const CHANNELS: [usize; 3] = [0, 1, 2];
/// Number of features per band.
pub const FEATURES: usize = 5;
/// The power of the speed each channel is divided by before its moments are taken: a wheelset
/// following a track wave `y(s)` has `y'' V^2` of lateral acceleration and `psi' V` of yaw rate,
/// so the quotients keep the cells of one set (speeds up to one bank step apart) on one scale.
pub const CONTACT_SPEED_POWER: [i32; 3] = [2, 1, 2];
/// The smallest speed the quotients divide by \[m/s\] (cells below the model's lowest speed
/// are left out of the moments anyway).
pub const MIN_SPEED: f64 = 1.0;

/// The fitted estimator of the contact condition, as the tap bank holds it. Its optional
/// fields (absent in banks before format 4) are never skipped when written: the FMU's state
/// serializes it with postcard, which reads fields by position (a skipped one made every
/// genuine state of a bank without conicities undecodable).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactModel {
    /// Shortest and longest wavelength of the features' band \[m\].
    pub band: [f64; 2],
    /// Further bands whose features join the first band's (shortest and longest wavelength
    /// \[m\]): D1's octaves, where the contact shows, and in a bank fitted over conicities the
    /// octaves around the kinematic wavelength, where the conicity does ([module docs](self)).
    #[serde(default)]
    pub extra_bands: Vec<[f64; 2]>,
    /// Memory of the running moments \[m\].
    pub memory: f64,
    /// The lowest and highest Kalker-coefficient scale trained on: the estimate's range.
    pub range: [f64; 2],
    /// Per bank speed, the coefficients of the features and the constant last.
    #[serde(rename = "at")]
    pub speeds: Vec<SpeedModel>,
    /// The lowest and highest equivalent conicity trained on, in a bank fitted over conicities
    /// (every speed then has a [`ConicityModel`]): the conicity estimate's range.
    #[serde(default)]
    pub conicity_range: Option<[f64; 2]>,
}

/// The condition the features indicate ([`ContactModel::estimate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Condition {
    /// The Kalker-coefficient scale, within the trained range.
    pub kalker: f64,
    /// The equivalent conicity (the one told, or estimated within the trained range); `None`
    /// in a bank without conicity conditions.
    pub conicity: Option<f64>,
    /// How far the features lie from what the training runs showed at that condition, in units
    /// of the level exceeded on [`LEVEL_SHARE`] of the validation cells; `None` in a bank
    /// without conicity conditions.
    pub novelty: Option<f64>,
}

/// The share of the validation cells (after the memory filled) whose novelty exceeds 1: what
/// the level is set by, so that `outside_training` false alarms stay under 1 % of the distance
/// on trained conditions.
pub const LEVEL_SHARE: f64 = 0.002;

/// The novelty above which `outside_training` sets: the level itself (the novelty's unit).
pub const NOVELTY_LEVEL: f64 = 1.0;

/// The share of a set's memory its cells must fill before its novelty counts (0.25: 50 m of
/// the 200 m memory). Before it the young features' scatter sets `outside_training` at the start
/// of runs on trained conditions: from 0-2 m on every one (10 km runs, seeds 1-2) with no wait;
/// from 20 m (0.1) on 9 of the 15 validation runs (seeds 102-106, conicity 0.1 at Kalker 100, 75
/// and 50 %, the default bank: novelty up to 2.3 over 20-50 m, at most 0.66 from 50 m on).
pub const NOVELTY_FROM: f64 = 0.25;

/// How many closed cells apart the runtime judges the novelty (5: every metre of the 0.2 m
/// grid). Its 200 m memory moves little in a metre, and judged at every cell it cost the
/// default a quarter of its time per sample (bindings, 20 m/s: 0.52 against 0.42 µs without it).
pub const NOVELTY_EVERY: usize = 5;

/// Terms of the forward model of a feature in the condition (`x` ln conicity, `y` Kalker scale).
pub const FORWARD_TERMS: usize = 6;

/// The forward model's terms: `[1, x, y, x^2, x y, y^2]`.
pub fn forward_terms(x: f64, y: f64) -> [f64; FORWARD_TERMS] {
    [1.0, x, y, x * x, x * y, y * y]
}

/// One bank speed's estimator of the wheels' equivalent conicity, and the model of the features
/// it checks them against (the novelty): in a bank fitted over conicities.
///
/// # Why the novelty
/// The training runs' features lie near a surface in feature space, parametrised by the two
/// conditions the bank was fitted over (conicity and Kalker scale). A vehicle or wheel state
/// the taps were not fitted for gives features off that surface, or on it beyond the trained
/// range: the forward model at the estimated (clamped) condition misses them. The squared
/// Mahalanobis distance of the miss, with the training cells' residual covariance, divided by
/// the level that [`LEVEL_SHARE`] of the validation cells exceed, is the novelty: above 1,
/// the sensors say something the taps have not seen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConicityModel {
    /// One coefficient of `ln(conicity)` per feature, then the constant.
    pub coefficients: Vec<f64>,
    /// Root-mean-square error of `ln(conicity)` on the validation runs after the memory filled
    /// (0.1: about 10 %).
    pub rms_error: f64,
    /// Per feature, the coefficients of [`forward_terms`]: the features the training runs show
    /// at a condition.
    pub forward: Vec<Vec<f64>>,
    /// The inverse covariance of the training cells' features about the forward model at their
    /// own condition, row after row (features squared).
    pub precision: Vec<f64>,
    /// The squared Mahalanobis distance exceeded on [`LEVEL_SHARE`] of the validation cells.
    pub level: f64,
    /// Estimators of `ln(conicity)` for a memory not yet full, by how much track it holds
    /// (ascending, each short of the memory). Empty in banks made before them (2026-11-27),
    /// which apply [`Self::coefficients`] from the first cell.
    #[serde(default)]
    pub young: Vec<YoungModel>,
}

/// An estimator of `ln(conicity)` fitted on the features of memories holding `fill` metres
/// ([`ConicityModel::young`]).
///
/// Why: the features of a young memory are ratios and correlations of a few wavelengths'
/// moments, noisier and biased against a full memory's (a log of a ratio of sums, a
/// correlation of band-passed signals with the filters' start in them). The full memory's
/// model, applied to them, read `ln(conicity)` 0.16-0.35 rms off at 50-100 m into a run
/// (0.05-0.1 after 200 m), and most of the bank's loss told nothing against told the conicity
/// was there (docs/learned-filter.md). Fitted on young memories' own features, a model
/// weighs each feature by what it is worth at that fill.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct YoungModel {
    /// The track the memory holds \[m\].
    pub fill: f64,
    /// One coefficient per feature, then the constant.
    pub coefficients: Vec<f64>,
    /// Root-mean-square error of `ln(conicity)` on the validation runs' memories at that fill.
    pub rms_error: f64,
}

impl ConicityModel {
    /// The squared Mahalanobis distance of features `f` from the forward model at (`x` ln
    /// conicity, `y` Kalker scale), over the level.
    pub fn novelty(&self, f: &[f64], x: f64, y: f64) -> f64 {
        let t = forward_terms(x, y);
        let n = f.len();
        let r: Vec<f64> = f
            .iter()
            .zip(&self.forward)
            .map(|(f, row)| f - row.iter().zip(&t).map(|(a, b)| a * b).sum::<f64>())
            .collect();
        let mut d2 = 0.0;
        for (i, ri) in r.iter().enumerate() {
            let row = &self.precision[i * n..(i + 1) * n];
            d2 += ri * row.iter().zip(&r).map(|(p, rj)| p * rj).sum::<f64>();
        }
        d2 / self.level
    }

    /// `ln(conicity)` from features `f` of a memory holding `fill` metres of its `memory`, and
    /// the model's rms error there: the young models around `fill` (and the full memory's at
    /// `memory`) interpolated linearly in the fill, the first young model below its own fill.
    pub fn ln_conicity(&self, f: &[f64], fill: f64, memory: f64) -> (f64, f64) {
        // The nodes: the young models, then the full memory's model at `memory`.
        let node = |i: usize| match self.young.get(i) {
            Some(y) => (y.fill, &y.coefficients, y.rms_error),
            None => (memory, &self.coefficients, self.rms_error),
        };
        let next = self
            .young
            .iter()
            .position(|y| y.fill > fill)
            .unwrap_or(self.young.len());
        let (f1, c1, r1) = node(next);
        let Some(prev) = next.checked_sub(1) else {
            return (linear(c1, f), r1);
        };
        let (f0, c0, r0) = node(prev);
        if fill >= f1 {
            return (linear(c1, f), r1);
        }
        let a = ((fill - f0) / (f1 - f0)).clamp(0.0, 1.0);
        let (x0, x1) = (linear(c0, f), linear(c1, f));
        (x0 + a * (x1 - x0), r0 + a * (r1 - r0))
    }

    fn check(&self, speed: f64, features: usize, memory: f64) -> Result<(), ContactProblem> {
        let bad = || ContactProblem::Conicity { speed };
        let finite = |v: &[f64]| v.iter().all(|c| c.is_finite());
        let sound = |y: &YoungModel| {
            y.coefficients.len() == features + 1
                && finite(&y.coefficients)
                && y.fill > 0.0
                && y.fill < memory
                && y.rms_error.is_finite()
                && y.rms_error >= 0.0
        };
        if !self.young.iter().all(sound) || self.young.windows(2).any(|w| !(w[1].fill > w[0].fill))
        {
            return Err(bad());
        }
        if self.coefficients.len() != features + 1
            || !finite(&self.coefficients)
            || self.forward.len() != features
            || self
                .forward
                .iter()
                .any(|r| r.len() != FORWARD_TERMS || !finite(r))
            || self.precision.len() != features * features
            || !finite(&self.precision)
            || !(self.level.is_finite() && self.level > 0.0)
            || !(self.rms_error.is_finite() && self.rms_error >= 0.0)
        {
            return Err(bad());
        }
        Ok(())
    }
}

/// One bank speed's linear estimator of the Kalker-coefficient scale from the features.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedModel {
    /// The constant speed of the runs it was fitted on \[m/s\]: cells count towards it by
    /// their speed's interpolation share.
    pub speed: f64,
    /// One coefficient per feature ([`FEATURES`] per band, every band), then the constant.
    pub coefficients: Vec<f64>,
    /// Root-mean-square error of the estimate on the validation seeds after 200 m.
    pub rms_error: f64,
    /// The conicity's estimator and the features' model, in a bank fitted over conicities.
    #[serde(default)]
    pub conicity: Option<ConicityModel>,
    /// In a bank fitted over conicities: per bank conicity, the Kalker scale from the first
    /// bands' features ([`NodeModel::coefficients`]), fitted on that conicity's runs alone; the
    /// estimate blends them at the conicity (linearly in its logarithm) instead of using
    /// [`Self::coefficients`].
    #[serde(default)]
    pub kalker_by_conicity: Vec<NodeModel>,
    /// In a bank fitted over conicities (since 2026-11-28): the model cross-spectra of the
    /// trained conditions, from which the conicity is estimated by Whittle's likelihood
    /// ([`super::spectral`]) in place of [`Self::conicity`]'s linear model once a window is
    /// full enough. Absent in older banks: the linear model alone, as before.
    #[serde(default)]
    pub spectra: Option<super::spectral::Spectra>,
}

/// The Kalker-scale estimator at one bank conicity ([`SpeedModel::kalker_by_conicity`]).
///
/// Why per conicity: one linear model over every conicity and Kalker scale reads the contact
/// of the nominal ML95 about 0.1 low, and the blended taps lose D1 (20 m/s, validation seeds
/// 102-104, conicity told 0.1: D1 0.34); the model fitted on the nominal conicity's runs
/// alone, as the bank over Kalker scales had it, gives 0.13.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NodeModel {
    /// The bank conicity.
    pub conicity: f64,
    /// One coefficient per feature of the first bands, then the constant: as many bands as the
    /// coefficients give ([`FEATURES`] each; banks before 2026-11-27 read the first band only).
    /// The bands come in [`ContactModel::bands`] order, so a model reads a prefix of them.
    pub coefficients: Vec<f64>,
    /// Root-mean-square error on that conicity's validation runs after the memory filled.
    pub rms_error: f64,
}

/// A linear model's value at features `f`: the coefficients, then the constant.
pub fn linear(c: &[f64], f: &[f64]) -> f64 {
    f.iter().zip(c).map(|(x, c)| x * c).sum::<f64>() + c[f.len()]
}

impl ContactModel {
    /// Every band the features are taken in: [`Self::band`] first, then the extra ones.
    pub fn bands(&self) -> Vec<[f64; 2]> {
        std::iter::once(self.band)
            .chain(self.extra_bands.iter().copied())
            .collect()
    }

    /// How many features the models read ([`FEATURES`] per band).
    pub fn features(&self) -> usize {
        FEATURES * (1 + self.extra_bands.len())
    }

    /// The consistency the runtime relies on.
    pub fn check(&self, grid: f64) -> Result<(), ContactProblem> {
        for s in &self.speeds {
            if let Some(sp) = &s.spectra {
                sp.check(grid).map_err(|problem| ContactProblem::Spectra {
                    speed: s.speed,
                    problem,
                })?;
                if self.conicity_range.is_none() {
                    return Err(ContactProblem::Spectra {
                        speed: s.speed,
                        problem: "spectra without a conicity range".into(),
                    });
                }
            }
        }
        if self.speeds.iter().any(|s| s.spectra.is_some())
            && self.speeds.iter().any(|s| s.spectra.is_none())
        {
            return Err(ContactProblem::Spectra {
                speed: self.speeds[0].speed,
                problem: "spectra at some speeds only".into(),
            });
        }
        for [short, long] in self.bands() {
            if !(short.is_finite() && short > 0.0 && long > short && long.is_finite()) {
                return Err(ContactProblem::Band { short, long });
            }
        }
        let features = self.features();
        if !(self.memory.is_finite() && self.memory > 0.0) {
            return Err(ContactProblem::Memory(self.memory));
        }
        let [lo, hi] = self.range;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo) {
            return Err(ContactProblem::Range { lo, hi });
        }
        if self.speeds.is_empty() {
            return Err(ContactProblem::NoSpeeds);
        }
        for s in &self.speeds {
            let bad_node = |n: &NodeModel| {
                let read = n.coefficients.len().saturating_sub(1);
                read == 0
                    || !read.is_multiple_of(FEATURES)
                    || read > features
                    || n.coefficients.iter().any(|c| !c.is_finite())
                    || !(n.conicity > 0.0 && n.rms_error.is_finite())
            };
            if s.kalker_by_conicity.iter().any(bad_node)
                || s.kalker_by_conicity
                    .windows(2)
                    .any(|w| !(w[1].conicity > w[0].conicity))
            {
                return Err(ContactProblem::Conicity { speed: s.speed });
            }
            if s.coefficients.len() != features + 1 || s.coefficients.iter().any(|c| !c.is_finite())
            {
                return Err(ContactProblem::Coefficients {
                    speed: s.speed,
                    count: s.coefficients.len(),
                    want: features + 1,
                });
            }
        }
        if self.speeds.windows(2).any(|w| !(w[1].speed > w[0].speed)) {
            return Err(ContactProblem::SpeedsNotIncreasing);
        }
        if let Some([lo, hi]) = self.conicity_range {
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo) {
                return Err(ContactProblem::ConicityRange { lo, hi });
            }
            for s in &self.speeds {
                s.conicity
                    .as_ref()
                    .ok_or(ContactProblem::Conicity { speed: s.speed })?
                    .check(s.speed, features, self.memory)?;
            }
        } else if let Some(s) = self.speeds.iter().find(|s| s.conicity.is_some()) {
            return Err(ContactProblem::Conicity { speed: s.speed });
        }
        Ok(())
    }

    /// The condition the moments indicate: each speed's models applied to the features of the
    /// cells near that speed, the estimates averaged with weights of how much recent track each
    /// set holds, times how full its memory is, over the model's squared error there. Cells
    /// are never judged by another speed's model, so a run's slow start does not bias the
    /// estimate while the train accelerates. `told`: the conicity given by the user (then not
    /// estimated; the novelty is judged at it). `None` before any set has features. `moments`
    /// must have been made with this model's speeds ([`Self::moments`]).
    ///
    /// The conicity is estimated as `ln(conicity)` (a wheel's kinematic wavelength goes as
    /// `conicity^-1/2`, so equal ratios matter alike), clamped to the trained range per set.
    /// A young set's novelty is scaled by how full its memory is: the features' scatter about
    /// the training surface shrinks as the memory fills, and the level was set on full ones.
    pub fn estimate(&self, moments: &Moments, told: Option<f64>) -> Option<Condition> {
        self.estimate_told(moments, told, None, None, true)
    }

    /// [`Self::estimate`] with the Kalker scale told too (`kalker_scale` parameter): the
    /// condition's Kalker scale is then the one told (clamped to the trained range), and the
    /// novelty is judged at it. `taps`: the lowest and highest conicity of the taps the
    /// estimate serves, where they cover less than the model's range (the default bank's taps
    /// hold the ML95's conicity only, its contact model the bank over conicities'): the Kalker
    /// scale is read at the conicity clamped to them, the one the taps are blended at, so that
    /// taps fitted at one conicity get the contact estimate fitted on their own runs (on the
    /// nominal vehicle exactly what a bank without conicities reads). The conicity estimate
    /// still sees the whole range: it is what says the taps no longer fit. The novelty is
    /// judged at the estimated conicity and that Kalker scale (its level was set with the
    /// Kalker scale read at the estimated conicity; the held-out envelope measures the pair as
    /// it runs: docs/accuracy.md).
    /// `novelty`: whether to judge the novelty (its quadratic form over every feature is half
    /// the contact model's cost; the runtime judges it every [`NOVELTY_EVERY`] cells); without
    /// it the condition's `novelty` is `None`.
    pub fn estimate_told(
        &self,
        moments: &Moments,
        told: Option<f64>,
        told_kalker: Option<f64>,
        taps: Option<[f64; 2]>,
        novelty: bool,
    ) -> Option<Condition> {
        let ln_range = self.conicity_range.map(|[lo, hi]| [lo.ln(), hi.ln()]);
        let ln_taps = taps.map(|[lo, hi]| [lo.ln(), hi.ln()]);
        let (mut k_sum, mut k_weight) = (0.0, 0.0);
        let (mut c_sum, mut c_weight) = (0.0, 0.0);
        let (mut n_sum, mut n_weight) = (0.0, 0.0);
        for (i, m) in self.speeds.iter().enumerate() {
            let Some(f) = moments.features(i) else {
                continue;
            };
            let set = &moments.sets[i];
            let full = set.n.min(moments.memory_points) / moments.memory_points;
            // This set's conicity (told, or estimated, with its model's error at this fill),
            // where the bank has conicities.
            let x = match (&m.conicity, ln_range) {
                (Some(cm), Some([lo, hi])) => Some(match told {
                    Some(c) => (c.ln().clamp(lo, hi), cm.rms_error),
                    None => {
                        let (x, rms) = cm.ln_conicity(f, full * self.memory, self.memory);
                        (x.clamp(lo, hi), rms)
                    }
                }),
                _ => None,
            };
            let (x, x_rms) = x.unzip();
            // The conicity the Kalker scale is read at: the taps' where they cover less.
            let at = x.map(|x| ln_taps.map_or(x, |[lo, hi]| x.clamp(lo, hi)));
            let (k, rms) = match (at, m.kalker_by_conicity.is_empty()) {
                (Some(at), false) => {
                    let (mut stack, mut heap) = ([0.0; STACK_NODES], Vec::new());
                    let ln = scratch(&mut stack, &mut heap, m.kalker_by_conicity.len());
                    for (l, n) in ln.iter_mut().zip(&m.kalker_by_conicity) {
                        *l = n.conicity.ln();
                    }
                    super::weights(ln, at)
                        .iter()
                        .fold((0.0, 0.0), |(k, r), (j, a)| {
                            let n = &m.kalker_by_conicity[*j];
                            // `check` bounds the features read by the model's; a restored
                            // state's moments are not checked against it, so a short feature
                            // vector gives no estimate (NaN: the set is skipped), not a panic.
                            let e = f
                                .get(..n.coefficients.len().saturating_sub(1))
                                .map_or(f64::NAN, |f| linear(&n.coefficients, f))
                                .clamp(self.range[0], self.range[1]);
                            (k + a * e, r + a * n.rms_error)
                        })
                }
                _ => (linear(&m.coefficients, f), m.rms_error),
            };
            let k = told_kalker.unwrap_or(k);
            if !k.is_finite() {
                continue;
            }
            let k = k.clamp(self.range[0], self.range[1]);
            // A young set's features are far noisier than the model's error (fitted after a
            // full memory): its weight grows with its cells until the memory is full.
            let w = set.recent * full;
            let wk = w / rms.max(MIN_MODEL_ERROR).powi(2);
            k_sum += wk * k;
            k_weight += wk;
            if let (Some(cm), Some(x), Some(x_rms)) = (&m.conicity, x, x_rms)
                && x.is_finite()
            {
                let wc = w / x_rms.max(MIN_MODEL_ERROR).powi(2);
                c_sum += wc * x;
                c_weight += wc;
                // Sets holding less than a cell of the recent track hardly count: their
                // novelty (a quadratic form over every feature) is not worth its cost. The
                // first cells' features are too wild to judge (their ratios of tiny
                // moments): novelty from NOVELTY_FROM of a memory on.
                if novelty && set.recent >= 1.0 && full >= NOVELTY_FROM {
                    let n = cm.novelty(f, x, k) * full;
                    if n.is_finite() {
                        n_sum += w * n;
                        n_weight += w;
                    }
                }
            }
        }
        if k_weight <= 0.0 {
            return None;
        }
        let kalker = k_sum / k_weight;
        let ln_c = (c_weight > 0.0).then(|| c_sum / c_weight);
        Some(Condition {
            kalker: kalker.clamp(self.range[0], self.range[1]),
            conicity: match (told, self.conicity_range) {
                (Some(c), Some(_)) => Some(c),
                (None, Some([lo, hi])) => ln_c.map(|x| x.exp().clamp(lo, hi)),
                _ => None,
            },
            novelty: (n_weight > 0.0).then(|| n_sum / n_weight),
        })
    }

    /// Empty moments for this model's speeds on a grid of `ds` metres.
    pub fn moments(&self, ds: f64) -> Moments {
        let speeds: Vec<f64> = self.speeds.iter().map(|m| m.speed).collect();
        Moments::new(ds, &self.bands(), self.memory, &speeds)
    }
}

/// The most bands whose filtered channels [`Moments::push`] keeps on the stack (the shipped
/// banks with a contact model have seven: D1, its three octaves and three more); a bank with
/// more takes one more allocation per cell, nothing else.
const STACK_BANDS: usize = 8;

/// The most conicity nodes of a Kalker model whose logarithms [`ContactModel::estimate_told`]
/// keeps on the stack (the shipped banks have seven).
const STACK_NODES: usize = 16;

/// `n` zeroed values of scratch for work done at every cell: in `stack` where it holds them,
/// else in `heap` (one allocation).
fn scratch<'a, T: Copy + Default, const S: usize>(
    stack: &'a mut [T; S],
    heap: &'a mut Vec<T>,
    n: usize,
) -> &'a mut [T] {
    if n <= S {
        &mut stack[..n]
    } else {
        heap.resize(n, T::default());
        heap
    }
}

/// The running moments of the band-passed channels, one set per speed of the contact model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    /// Per band, per channel: the high-pass and the low-pass.
    filters: Vec<Vec<[Biquad; 2]>>,
    /// The speeds of the sets \[m/s\], ascending (the contact model's).
    speeds: Vec<f64>,
    sets: Vec<MomentSet>,
    memory_points: f64,
}

/// The moments of the cells near one speed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct MomentSet {
    /// Per band, the channels' second moments.
    m: Vec<[[f64; 3]; 3]>,
    /// The cells' weight summed (each cell's share of this speed).
    n: f64,
    /// How much of the last `memory` metres of track this set holds (decays with distance).
    recent: f64,
    /// The features of `m`, updated when a cell changes it: every closed cell reads every
    /// set's features, but changes at most two sets. [`FEATURES`] per band, band after band.
    features: Option<Vec<f64>>,
}

impl Moments {
    /// Moments on a grid of `ds` metres in each of `bands`, per speed of `speeds` (ascending).
    pub fn new(ds: f64, bands: &[[f64; 2]], memory: f64, speeds: &[f64]) -> Moments {
        Moments {
            filters: bands
                .iter()
                .map(|band| {
                    (0..CHANNELS.len())
                        .map(|_| [Biquad::highpass(ds, band[1]), Biquad::lowpass(ds, band[0])])
                        .collect()
                })
                .collect(),
            speeds: speeds.to_vec(),
            sets: speeds
                .iter()
                .map(|_| MomentSet {
                    m: vec![[[0.0; 3]; 3]; bands.len()],
                    n: 0.0,
                    recent: 0.0,
                    features: None,
                })
                .collect(),
            memory_points: (memory / ds).max(1.0),
        }
    }

    /// One closed cell (channels in [`super::grid::CHANNELS`] order) at `speed`: its moments go
    /// to the sets of the two speeds around it, in the linear-interpolation shares.
    ///
    /// The filters see every cell; the moments only those within the model's speeds (where the
    /// taps are used; below the lowest, the quotients by a small speed would let a standing
    /// start dominate the lowest set).
    pub fn push(&mut self, cell: &[f64; 5], speed: f64) {
        let v = speed.max(MIN_SPEED);
        // The bands' filtered channels, on the stack for any bank's band count up to
        // `STACK_BANDS` (every cell closes here).
        let (mut stack, mut heap) = ([[0.0; 3]; STACK_BANDS], Vec::new());
        let xs = scratch(&mut stack, &mut heap, self.filters.len());
        for (x, band) in xs.iter_mut().zip(&mut self.filters) {
            *x = std::array::from_fn(|i| {
                let [hp, lp] = &mut band[i];
                lp.step(hp.step(cell[CHANNELS[i]])) / v.powi(CONTACT_SPEED_POWER[i])
            });
        }
        let (Some(lo), Some(hi)) = (self.speeds.first(), self.speeds.last()) else {
            return;
        };
        if xs.iter().flatten().any(|v| !v.is_finite()) || !(speed >= *lo && speed <= *hi) {
            return;
        }
        let decay = 1.0 - 1.0 / self.memory_points;
        for set in &mut self.sets {
            set.recent *= decay;
        }
        for (i, w) in super::weights(&self.speeds, speed) {
            let set = &mut self.sets[i];
            set.n += w;
            set.recent += w;
            let a = w / set.n.min(self.memory_points);
            for (m, x) in set.m.iter_mut().zip(xs.iter()) {
                for (r, row) in m.iter_mut().enumerate() {
                    for (c, m) in row.iter_mut().enumerate() {
                        *m += a * (x[r] * x[c] - *m);
                    }
                }
            }
            // Written over the last features' buffer: none while a band has no variance yet.
            let mut f = set.features.take().unwrap_or_default();
            f.clear();
            let complete = set
                .m
                .iter()
                .all(|m| features_of(m).map(|b| f.extend_from_slice(&b)).is_some());
            set.features = complete.then_some(f);
        }
    }

    /// The features ([module docs](self)) of the set of speed index `i`; `None` while a channel
    /// has no variance there yet.
    pub fn features(&self, i: usize) -> Option<&[f64]> {
        self.sets.get(i)?.features.as_deref()
    }
}

/// The features of the moments `m` ([module docs](self)); `None` while a channel has no
/// variance.
fn features_of(m: &[[f64; 3]; 3]) -> Option<[f64; FEATURES]> {
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Uniform noise in [-0.5, 0.5) from a 64-bit linear congruential generator (the learned
    /// filter's tests' repeatable noise).
    pub(crate) fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    #[test]
    fn features_are_scale_free_and_see_correlation() {
        // Channel 1 = 3 x channel 0 (perfectly correlated), channel 2 independent noise.
        let mut a = Moments::new(0.2, &[[3.0, 25.0]], 200.0, &[1.0]);
        let mut b = Moments::new(0.2, &[[3.0, 25.0]], 200.0, &[1.0]);
        let mut noise = uniform(1);
        // At 1 m/s the speed quotients (CONTACT_SPEED_POWER) leave the channels as they are.
        for _ in 0..20_000 {
            let (u, w) = (noise(), noise());
            a.push(&[u, 3.0 * u, w, 0.0, 0.0], 1.0);
            // The same signals 1000 times larger: features unchanged.
            b.push(&[1e3 * u, 3e3 * u, 1e3 * w, 0.0, 0.0], 1.0);
        }
        let (fa, fb) = (a.features(0).unwrap(), b.features(0).unwrap());
        for (x, y) in fa.iter().zip(fb) {
            assert!((x - y).abs() < 1e-9, "{fa:?} {fb:?}");
        }
        assert!((fa[0] - 9f64.ln()).abs() < 1e-9, "{fa:?}");
        assert!((fa[2] - 1.0).abs() < 1e-9, "{fa:?}");
        // Independent noise: correlation near 0 (memory of 1000 cells: sd about 0.03).
        assert!(fa[3].abs() < 0.15, "{fa:?}");
    }

    fn model() -> ContactModel {
        ContactModel {
            band: [3.0, 25.0],
            extra_bands: vec![],
            memory: 200.0,
            range: [0.5, 1.0],
            speeds: vec![
                SpeedModel {
                    speed: 10.0,
                    coefficients: vec![0.1, 0.0, 0.0, 0.0, 0.0, 0.5],
                    rms_error: 0.1,
                    conicity: None,
                    kalker_by_conicity: vec![],
                    spectra: None,
                },
                SpeedModel {
                    speed: 20.0,
                    coefficients: vec![0.2, 0.0, 0.0, 0.0, 0.0, 0.5],
                    rms_error: 0.1,
                    conicity: None,
                    kalker_by_conicity: vec![],
                    spectra: None,
                },
            ],
            conicity_range: None,
        }
    }

    #[test]
    fn each_speed_judges_its_own_cells_and_the_estimates_are_weighted_by_recent_track() {
        let m = model();
        m.check(0.2).unwrap();
        let mut moments = m.moments(0.2);
        assert_eq!(m.estimate(&moments, None).map(|c| c.kalker), None);
        // Outside the model's speeds (and at no speed) the cells are not counted.
        let mut outside = m.moments(0.2);
        for v in [5.0, 25.0, f64::NAN, -10.0] {
            for k in 0..100 {
                outside.push(&[k as f64, 2.0, 3.0 * k as f64, 0.0, 0.0], v);
            }
        }
        assert_eq!(m.estimate(&outside, None).map(|c| c.kalker), None);
        let mut noise = uniform(7);
        // Yaw rate 3 (at 10 m/s) and 2 (at 20 m/s) times the wheelset acceleration, each
        // scaled as the speed scales them (CONTACT_SPEED_POWER): ln(M11/M00) = ln 9, then ln 4.
        let n = 2000;
        for (v, ratio) in [(10.0, 3.0), (20.0, 2.0)] {
            for _ in 0..n {
                let (u, w) = (noise(), noise());
                moments.push(&[v * v * u, ratio * v * u, w, 0.0, 0.0], v);
            }
        }
        // Up to the band-pass's transient where the speed steps (the filters run before the
        // quotient); a set mixing the other's cells would be far off (ln 9 = 2.20, ln 4 = 1.39).
        let f0 = |i: usize| moments.features(i).unwrap()[0];
        assert!((f0(0) - 9f64.ln()).abs() < 1e-9, "{}", f0(0));
        assert!((f0(1) - 4f64.ln()).abs() < 0.05, "{}", f0(1));
        // Recent track: the 20 m/s set's cells are newer.
        let d: f64 = 1.0 - 0.2 / 200.0;
        let r20: f64 = (0..n).map(|k| d.powi(k)).sum();
        let r10 = r20 * d.powi(n);
        let (e10, e20) = (0.1 * f0(0) + 0.5, 0.2 * f0(1) + 0.5);
        let want = (r10 * e10 + r20 * e20) / (r10 + r20);
        let got = m.estimate(&moments, None).map(|c| c.kalker).unwrap();
        assert!((got - want).abs() < 1e-9, "{got} {want}");
        // Clamped to the trained range.
        let mut high = m.clone();
        high.speeds[1].coefficients[FEATURES] = 5.0;
        high.speeds[0].coefficients[FEATURES] = 5.0;
        assert_eq!(high.estimate(&moments, None).map(|c| c.kalker), Some(1.0));
        let mut bad = m.clone();
        bad.speeds[0].coefficients.pop();
        assert!(
            bad.check(0.2)
                .unwrap_err()
                .to_string()
                .contains("coefficients")
        );
    }

    /// A bank over conicities whose per-conicity Kalker models read the first band, or the
    /// first two: each reads the prefix of the features its coefficients give, and nothing
    /// else is accepted.
    #[test]
    fn a_conicity_s_kalker_model_reads_the_bands_its_coefficients_give() {
        let n = 2 * FEATURES;
        let node = |conicity: f64, read: usize, slope: f64| NodeModel {
            conicity,
            // The last feature read gets `slope`; the constant 0.75.
            coefficients: (0..read)
                .map(|i| if i + 1 == read { slope } else { 0.0 })
                .chain([0.75])
                .collect(),
            rms_error: 0.05,
        };
        let conicity = ConicityModel {
            // ln(conicity) = ln(0.1), whatever the features.
            coefficients: (0..n).map(|_| 0.0).chain([0.1f64.ln()]).collect(),
            rms_error: 0.1,
            forward: vec![vec![0.0; FORWARD_TERMS]; n],
            precision: (0..n * n)
                .map(|i| f64::from(u8::from(i % (n + 1) == 0)))
                .collect(),
            level: 1.0,
            young: vec![],
        };
        let mut m = ContactModel {
            band: [3.0, 25.0],
            extra_bands: vec![[6.0, 12.0]],
            memory: 200.0,
            range: [0.5, 1.0],
            speeds: vec![SpeedModel {
                speed: 20.0,
                coefficients: vec![0.0; n + 1],
                rms_error: 0.1,
                conicity: Some(conicity),
                // Told 0.1: the first node alone decides.
                kalker_by_conicity: vec![node(0.1, n, 0.01), node(0.2, FEATURES, 0.0)],
                spectra: None,
            }],
            conicity_range: Some([0.1, 0.2]),
        };
        m.check(0.2).unwrap();
        let mut moments = m.moments(0.2);
        let mut noise = uniform(3);
        for _ in 0..3000 {
            let (u, w, z) = (noise(), noise(), noise());
            moments.push(&[400.0 * u, 20.0 * (u + w), 400.0 * z, 0.0, 0.0], 20.0);
        }
        let f = moments.features(0).unwrap().to_vec();
        let got = m.estimate(&moments, Some(0.1)).unwrap().kalker;
        let want = (0.75 + 0.01 * f[n - 1]).clamp(0.5, 1.0);
        assert!((got - want).abs() < 1e-12, "{got} {want}");
        // Reading the first band only, the same slope sees the first band's last feature.
        m.speeds[0].kalker_by_conicity[0] = node(0.1, FEATURES, 0.01);
        let got = m.estimate(&moments, Some(0.1)).unwrap().kalker;
        let want = (0.75 + 0.01 * f[FEATURES - 1]).clamp(0.5, 1.0);
        assert!((got - want).abs() < 1e-12, "{got} {want}");
        // Between the bank conicities both nodes count, each reading its own prefix (linear in
        // ln conicity: 0.14 lies at w of the way from 0.1 to 0.2).
        m.speeds[0].kalker_by_conicity = vec![node(0.1, n, 0.01), node(0.2, FEATURES, 0.02)];
        let w = (0.14f64.ln() - 0.1f64.ln()) / (0.2f64.ln() - 0.1f64.ln());
        let got = m.estimate(&moments, Some(0.14)).unwrap().kalker;
        let want = (1.0 - w) * (0.75 + 0.01 * f[n - 1]).clamp(0.5, 1.0)
            + w * (0.75 + 0.02 * f[FEATURES - 1]).clamp(0.5, 1.0);
        assert!((got - want).abs() < 1e-12, "{got} {want}");
        // Taps at conicity 0.1 alone (the default bank's): told (or estimating) 0.14, the
        // Kalker scale is read at 0.1, where the taps are blended; the conicity stays 0.14.
        let at = |told| {
            m.estimate_told(&moments, told, None, Some([0.1, 0.1]), true)
                .unwrap()
        };
        let pinned = (0.75 + 0.01 * f[n - 1]).clamp(0.5, 1.0);
        assert!((at(Some(0.14)).kalker - pinned).abs() < 1e-12);
        assert_eq!(at(Some(0.14)).conicity, Some(0.14));
        // Estimated (the model says 0.1 whatever the features): the same reading.
        assert!((at(None).kalker - pinned).abs() < 1e-12);
        // Not asked to judge the novelty (the runtime asks every NOVELTY_EVERY cells): none.
        let quiet = m
            .estimate_told(&moments, Some(0.14), None, None, false)
            .unwrap();
        assert_eq!(quiet.novelty, None);
        assert!(m.estimate(&moments, Some(0.14)).unwrap().novelty.is_some());
        // Taps covering the model's range read where the estimate is, as without `taps`.
        let wide = m.estimate_told(&moments, Some(0.14), None, Some([0.1, 0.2]), true);
        assert_eq!(wide.map(|c| c.kalker), Some(got));
        // No feature, part of a band, or more features than the bands hold: refused.
        for read in [0, FEATURES + 2, n + FEATURES] {
            m.speeds[0].kalker_by_conicity[0] = node(0.1, read, 0.01);
            assert!(m.check(0.2).is_err(), "{read} features read");
        }
        m.speeds[0].kalker_by_conicity[0].coefficients.clear();
        assert!(m.check(0.2).is_err(), "no coefficients");
    }

    /// The young memories' conicity models: each applies at its own fill, linear in the fill
    /// between them and up to the full memory's model at the memory, the first one below its
    /// fill; in a run, a memory's estimate follows them as it fills.
    #[test]
    fn young_conicity_models_take_over_by_the_memory_s_fill() {
        let n = FEATURES;
        // Models that say one conicity whatever the features: constants only.
        let constant = |ln: f64| (0..n).map(|_| 0.0).chain([ln]).collect::<Vec<f64>>();
        let young = |fill: f64, ln: f64, rms: f64| YoungModel {
            fill,
            coefficients: constant(ln),
            rms_error: rms,
        };
        let mut cm = ConicityModel {
            coefficients: constant(-2.0),
            rms_error: 0.1,
            forward: vec![vec![0.0; FORWARD_TERMS]; n],
            precision: (0..n * n)
                .map(|i| f64::from(u8::from(i % (n + 1) == 0)))
                .collect(),
            level: 1.0,
            young: vec![young(10.0, -1.0, 0.5), young(50.0, -3.0, 0.3)],
        };
        let f = [0.3; FEATURES];
        let at = |cm: &ConicityModel, fill: f64| cm.ln_conicity(&f, fill, 200.0);
        let close = |(x, r): (f64, f64), (wx, wr): (f64, f64)| {
            assert!((x - wx).abs() < 1e-12 && (r - wr).abs() < 1e-12, "{x} {r}");
        };
        close(at(&cm, 2.0), (-1.0, 0.5));
        close(at(&cm, 10.0), (-1.0, 0.5));
        close(at(&cm, 20.0), (-1.5, 0.45));
        close(at(&cm, 50.0), (-3.0, 0.3));
        close(at(&cm, 125.0), (-2.5, 0.2));
        close(at(&cm, 200.0), (-2.0, 0.1));
        close(at(&cm, 1e6), (-2.0, 0.1));
        // Without young models (banks before them), the full memory's from the first cell.
        let old = ConicityModel {
            young: vec![],
            ..cm.clone()
        };
        close(at(&old, 2.0), (-2.0, 0.1));
        // Fills out of order, or not short of the memory: refused.
        cm.young.swap(0, 1);
        assert!(cm.check(20.0, n, 200.0).is_err());
        cm.young = vec![young(200.0, -1.0, 0.5)];
        assert!(cm.check(20.0, n, 200.0).is_err());
        cm.young = vec![young(10.0, -1.0, 0.5)];
        cm.check(20.0, n, 200.0).unwrap();
        // In a run at one speed: the estimate is the young model's while the memory is young.
        let model = ContactModel {
            band: [3.0, 25.0],
            extra_bands: vec![],
            memory: 200.0,
            range: [0.5, 1.0],
            speeds: vec![SpeedModel {
                speed: 20.0,
                coefficients: constant(0.75),
                rms_error: 0.1,
                conicity: Some(cm),
                kalker_by_conicity: vec![],
                spectra: None,
            }],
            conicity_range: Some([0.05, 0.4]),
        };
        model.check(0.2).unwrap();
        let mut moments = model.moments(0.2);
        let mut noise = uniform(5);
        let mut run = |cells: usize| {
            for _ in 0..cells {
                let (u, w, z) = (noise(), noise(), noise());
                moments.push(&[u, u + w, z, 0.0, 0.0], 20.0);
            }
            model.estimate(&moments, None).unwrap().conicity.unwrap()
        };
        // 10 m of cells (0.2 m each): the first young model's ln -1.
        assert!((run(50) - (-1.0f64).exp()).abs() < 1e-12);
        // At 105 m: half way from -1 (10 m) to -2 (200 m).
        let want = (-1.5f64).exp();
        assert!((run(475) - want).abs() < 1e-12);
        // A full memory: the full model's -2.
        assert!((run(1000) - (-2.0f64).exp()).abs() < 1e-12);
    }
}
