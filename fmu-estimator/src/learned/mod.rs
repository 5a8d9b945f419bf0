//! The learned estimator: a multichannel FIR filter on a distance grid, whose taps were fitted
//! by least squares on vehicle runs in the bands the accuracy is measured in, with the paper's
//! Kalman filter as one of its channels.
//!
//! - [`grid`]: the causal block mean onto the distance grid, the Kalman channel's high-pass;
//! - [`bank`]: the tap bank file (format, provenance, checks);
//! - [`contract`]: what a bank requires of the runtime (constants, filter designs, the Kalman
//!   channel), written by the fit and checked at initialization;
//! - [`window`]: one window of taps and which one a history gets, shared with the tap fit;
//! - [`error`]: a bank that cannot be read or used, and a bank without taps for what the
//!   parameters choose;
//! - [`stream`]: the run-time filter, per sample, of the parts below;
//! - `history`, `selection`, `blend`, `track`, `delay`: the channels' ring buffer, the entries
//!   the FMU's parameters choose, their blend in speed and contact, the extrapolation between
//!   grid points, the fixed-lag output's delay line.
//!
//! How the taps are fitted (`alignment-studies taps`, `studies/src/study/learned/`) and
//! what they reach is in `docs/learned-filter.md` and `docs/accuracy.md`.

pub mod bank;
mod blend;
pub mod contact;
pub mod contract;
mod delay;
pub mod error;
pub mod grid;
mod history;
mod selection;
pub mod spectral;
pub mod stage;
pub mod stream;
mod track;
pub mod window;

pub use bank::Bank;
pub use error::{BankError, LearnedError};
pub use stream::{Choice, Learned};

/// The default tap bank (`tap_file`'s default).
pub const DEFAULT_BANK: &str = "learned.taps";

/// The tap banks shipped in the FMU's resources, by file name:
///
/// | file | trained on | use |
/// |---|---|---|
/// | `learned.taps` | conicity 0.1, Kalker 100, 75 and 50 %, taps per condition; the contact model of `learned-conicity.taps` (`alignment-studies taps --contact-from`) | the default: blended by the contact estimated from the sensors; `outside_training` says when the wheels' conicity is not 0.1 (beyond 15 %) or the sensors are unlike the training |
/// | `learned-nominal.taps` | conicity 0.1, Kalker 100 % only | a vehicle whose wheels are known to be the ML95's nominal ones |
/// | `learned-conicity.taps` | conicity 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4, each at Kalker 100, 75 and 50 %, taps per condition (four-sensor taps at conicity 0.1 only) | wheels of any conicity 0.05-0.4: blended by the conicity and contact estimated from the sensors (or the `conicity` given); `novelty` and `outside_training` say when the sensors are unlike the training. Not the default: on the nominal ML95 told nothing it loses to `learned.taps` (docs/accuracy.md) |
pub const SHIPPED: [&str; 3] = [
    DEFAULT_BANK,
    "learned-nominal.taps",
    "learned-conicity.taps",
];

/// Linear interpolation weights of `v` on the ascending `xs`: one or two (index, weight) pairs,
/// zero weights left out; the end points beyond the ends. The taps are blended by it in speed
/// and contact condition, and a cell's contact moments shared between the speeds around it.
pub(crate) fn weights(xs: &[f64], v: f64) -> Vec<(usize, f64)> {
    if xs.len() == 1 {
        return vec![(0, 1.0)];
    }
    let i = xs.partition_point(|x| *x <= v).clamp(1, xs.len() - 1);
    let a = ((v - xs[i - 1]) / (xs[i] - xs[i - 1])).clamp(0.0, 1.0);
    [(i - 1, 1.0 - a), (i, a)]
        .into_iter()
        .filter(|(_, w)| *w > 0.0)
        .collect()
}

/// A tap bank shipped in the FMU's resources ([`SHIPPED`]), as built into this library
/// (offline processing without an unpacked FMU); `None` for any other name, and for every name
/// in a build without the `builtin-banks` feature (the FMU's shared library, which reads its
/// resources).
pub fn shipped_named(name: &str) -> Option<Result<Bank, BankError>> {
    let bytes = builtin(name)?;
    Some(bytes.and_then(|b| Bank::parse(b, &builtin_path(name))))
}

/// [`shipped_named`], parsed once per process for every instance that reads it
/// ([`crate::parsed`]).
pub fn shared_named(name: &str) -> Option<Result<std::sync::Arc<Bank>, BankError>> {
    let bytes = builtin(name)?;
    Some(bytes.and_then(|b| Bank::parse_shared(b, &builtin_path(name))))
}

/// How a built-in bank is named in errors (and keyed in the cache of parsed banks).
fn builtin_path(name: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(format!("{name} (built in)"))
}

/// The bytes of the shipped bank `name` built into this library; `None` for another name.
#[cfg(feature = "builtin-banks")]
fn builtin(name: &str) -> Option<Result<&'static [u8], BankError>> {
    let bytes: &'static [u8] = match name {
        "learned.taps" => include_bytes!(concat!(env!("OUT_DIR"), "/learned.taps")),
        "learned-nominal.taps" => include_bytes!(concat!(env!("OUT_DIR"), "/learned-nominal.taps")),
        "learned-conicity.taps" => {
            include_bytes!(concat!(env!("OUT_DIR"), "/learned-conicity.taps"))
        }
        _ => return None,
    };
    if bytes.is_empty() {
        return Some(Err(BankError::NotBuilt(name.to_string())));
    }
    Some(Ok(bytes))
}

/// Without the `builtin-banks` feature no bank is built in.
#[cfg(not(feature = "builtin-banks"))]
fn builtin(_name: &str) -> Option<Result<&'static [u8], BankError>> {
    None
}

/// The default tap bank (`learned.taps`), as built into this library.
#[cfg(feature = "builtin-banks")]
pub fn shipped() -> Result<Bank, BankError> {
    shipped_named(SHIPPED[0]).expect("a shipped name")
}

/// One sample's channels in [`grid::CHANNELS`] order: the sensors, then the Kalman filter's
/// alignment estimate `kalman`.
pub fn channels(s: &crate::offline::Sample, kalman: f64) -> [f64; 5] {
    [
        s.ws_acc_y,
        s.ws_yaw_rate,
        s.frame_acc_y,
        s.ws_roll_rate,
        kalman,
    ]
}

/// `active_estimator` when the `alignment` output carries the paper's Kalman filter's
/// estimate: no learned estimate exists yet (too little history) or the speed is outside the
/// taps' range. The values are the FMU's `estimator` parameter's.
pub const ACTIVE_PAPER: i32 = 1;
/// `active_estimator` when the `alignment` output carries the learned filter's estimate.
pub const ACTIVE_LEARNED: i32 = 2;

/// The outputs of one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The best causal estimate at the current position, and its standard deviation \[m\].
    pub alignment: f64,
    /// The standard deviation of `alignment` \[m\]: the blended windows' validation rms error,
    /// or the Kalman filter's where `alignment` is its estimate.
    pub std: f64,
    /// The fixed-lag estimate for the position `lag` metres behind, and its standard deviation.
    pub lagged: f64,
    /// The standard deviation of `lagged` \[m\], as `std`.
    pub lagged_std: f64,
    /// [`ACTIVE_PAPER`] or [`ACTIVE_LEARNED`].
    pub active: i32,
}

/// The Kalman filter's share of the learned outputs by the novelty ([`Learned::novelty`]):
/// `[from, full, share]`: none up to a novelty of `from`, rising linearly to `share` at `full`
/// (the level `outside_training` sets at), held above.
///
/// Why: on a vehicle whose sensors are unlike the training's the taps' error grows faster than
/// the Kalman filter's, and the two errors are far from fully correlated, so an average beats
/// either. On eight random ML95 variants (`studies/src/study/vehicles.rs`' family, drawn with
/// another seed: every mass, stiffness, damping and length within +-40 %, the wheel radius
/// +-15 %; validation seeds 102-104, 400 m at 20 m/s, told nothing) the mean whole Jrel of the
/// default goes 0.281 -> 0.235 (the bank over conicities 0.334 -> 0.280); per variant the taps
/// alone give 0.19-0.40, the Kalman filter alone 0.37-0.44, a fixed share of 0.25 everywhere
/// 0.16-0.34. On the ML95 at its trained conditions (novelty about
/// 0.05 over most cells) the default is unchanged, the bank over conicities loses 0.0007 on the
/// mean. Chosen from `from` 0.3-1, `full` 1-3, `share` 0.3-0.6 (the optimum is flat: 0.232-0.240
/// over a third of them); the evaluation vehicles were not looked at. The Kalman filter reads
/// the conicity it is given (`alpha`), so the share does not answer a conicity beyond the taps'
/// (the judged conicity's growth of `alignment_std` does): at conicity 0.05-0.15 it is worse
/// than the default's taps.
pub const FALLBACK: [f64; 3] = [0.5, 1.0, 0.4];

/// The Kalman filter's share of the outputs at novelty `novelty` ([`FALLBACK`]).
pub fn fallback_share(novelty: f64) -> f64 {
    let [from, full, share] = FALLBACK;
    share * ((novelty - from) / (full - from)).clamp(0.0, 1.0)
}

/// The learned estimate `learned` averaged with the Kalman filter's `kalman` at its share `w`.
///
/// The standard deviation stays the learned one (grown outside the training): the Kalman
/// filter's own `sqrt(P[7,7])` is its model's variance of the alignment state, not its error,
/// and would swamp it (on the Manchester vehicle, held-out seeds 1-5, rms over each record past
/// 100 m: the paper's filter's deviation 59 mm against its error of 3.3 mm; the average's error
/// 3.1 mm, the learned deviation grown by the novelty 24 mm). The average's error is at most the
/// larger of the two errors.
fn mix(learned: f64, kalman: f64, w: f64) -> f64 {
    // No share: the learned estimate itself, bit for bit.
    if w == 0.0 {
        return learned;
    }
    learned + w * (kalman - learned)
}

impl Learned {
    /// The outputs at `distance`: the learned estimates where they exist, averaged with the
    /// Kalman filter's (`kalman`: its alignment and standard deviation) by the novelty
    /// ([`FALLBACK`]; the standard deviations stay the learned ones, why in `mix`), else the
    /// Kalman filter's alone, flagged by `active`.
    pub fn estimate(&self, distance: f64, kalman: (f64, f64)) -> Estimate {
        // Outside the training the validation rms errors understate the error: grown with the
        // Mahalanobis distance (the novelty's square root, above 1), or with the judged
        // conicity's distance from the taps' (`CONICITY_ERROR_SCALE`), whichever says more.
        let grow = self.novelty().max(1.0).sqrt().max(self.conicity_growth());
        let w = fallback_share(self.novelty());
        let (alignment, std, active) = match self.causal(distance) {
            Some((a, s)) => (mix(a, kalman.0, w), s * grow, ACTIVE_LEARNED),
            None => (kalman.0, kalman.1, ACTIVE_PAPER),
        };
        let (lagged, lagged_std) = self
            .lagged(distance)
            .map(|(a, s)| {
                let k = self.kalman_lagged(distance).unwrap_or(kalman.0);
                (mix(a, k, w), s * grow)
            })
            .unwrap_or((alignment, std));
        Estimate {
            alignment,
            std,
            lagged,
            lagged_std,
            active,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{fallback_share, mix, weights};

    /// The Kalman filter's share: none up to novelty 0.5, linear to 0.4 at 1, held above; no
    /// share leaves the learned estimate as it is, even beside a Kalman estimate that is not a
    /// number.
    #[test]
    fn the_kalman_share_rises_with_the_novelty_between_its_nodes() {
        for (novelty, share) in [(0.0, 0.0), (0.5, 0.0), (0.75, 0.2), (1.0, 0.4), (9.0, 0.4)] {
            assert!((fallback_share(novelty) - share).abs() < 1e-15, "{novelty}");
        }
        assert_eq!(mix(1.0, f64::NAN, 0.0), 1.0);
        assert_eq!(mix(1.0, 3.0, 0.25), 1.5);
    }

    #[test]
    fn interpolation_weights_share_between_the_two_nodes_around_and_hold_the_ends() {
        let s = [10.0, 20.0];
        assert_eq!(weights(&s, 15.0), vec![(0, 0.5), (1, 0.5)]);
        assert_eq!(weights(&s, 12.5), vec![(0, 0.75), (1, 0.25)]);
        assert_eq!(weights(&s, 10.0), vec![(0, 1.0)]);
        assert_eq!(weights(&s, 5.0), vec![(0, 1.0)]);
        assert_eq!(weights(&s, 25.0), vec![(1, 1.0)]);
        assert_eq!(weights(&s, 20.0), vec![(1, 1.0)]);
        assert_eq!(weights(&[7.0], 3.0), vec![(0, 1.0)]);
    }
}
