//! The bank's contract: what the runtime must do exactly as the fit did for the taps to mean
//! what they were fitted to mean, written into the bank by the fit and checked by the FMU at
//! initialization.
//!
//! The taps are fitted on cells the estimator's own code made (grid, high-pass, Kalman
//! channel), so a bank is only right for a runtime that makes the same cells: a changed
//! constant or filter design, or a Kalman channel with other matrices, gives other cells, and
//! the taps then estimate something else, silently. One function ([`Contract::expected`])
//! states the contract from the constants and the Kalman builder this library uses; the fit
//! (`alignment-studies taps`) writes its result, the FMU compares the bank's with its own.
//!
//! | field | what |
//! |---|---|
//! | `tap_speed_power` | [`super::stream::TAP_SPEED_POWER`]: the history's speed quotients |
//! | `grid_edge` | [`super::grid::EDGE`]: where a cell closes |
//! | `contact_speed_power`, `contact_min_speed`, `contact_min_model_error` | the contact model's quotients, speed floor and weight floor ([`super::contact`]) |
//! | `kalman_highpass_design` | the Kalman channel's causal high-pass, as its coefficients `[b0, b1, b2, a1, a2]` at the bank's grid and cut-off |
//! | `kalman_shelf_design` | the shelf after it, as `[b0, b1, a1]` (absent without a shelf) |
//! | `contact_band_design` | the contact features' high-pass and low-pass, the same way (absent without a contact model) |
//! | `[contract.kalman]` | the Kalman channel: its states, `design_speed`, `min_speed`, and FNV-1a 64 hashes of its discrete `F`, `H`, `Q`, `R` at `reference_speed` and `reference_step` |
//!
//! The matrices are hashed after rounding each entry to 9 significant digits (`{:.8e}`): the
//! discretization's last bits may differ between platforms' `exp`, a Kalman channel that
//! differs in anything the user can set does not. The `gain` (time-varying or steady-state)
//! is not part of the contract: the fit runs the time-varying filter, the FMU by default the
//! steady-state one, equal once the start-up has passed (`engine::Gain::from_fmi`).
//!
//! A runtime constant or filter design that differs is always an error: no parameter changes
//! them, so a bank that disagrees was made by another build. A Kalman channel that differs (other
//! model parameters, another calibration, `alignment_model`, `design_speed`, `min_speed`) is an
//! error unless the FMU parameter `allow_other_kalman` is true, which makes it a warning: the
//! taps then run on a channel they were not fitted for, an approximate use the user asked for.

use super::contact::{CONTACT_SPEED_POWER, MIN_MODEL_ERROR, MIN_SPEED};
use super::grid::{Biquad, EDGE};
use super::stream::TAP_SPEED_POWER;
use crate::config::Config;
use crate::core::Core;
use crate::engine::Engine;
use serde::{Deserialize, Serialize};

/// The speed the Kalman channel's matrices are hashed at \[m/s\]: the standard case's.
pub const REFERENCE_SPEED: f64 = 20.0;

/// Significant digits the matrices' entries keep before they are hashed.
const HASH_DIGITS: usize = 9;

/// How far (relative) two floating-point constants of the contract may differ and still agree:
/// the designs' coefficients come from `sin` and `cos`, whose last bit may differ between
/// platforms; any deliberate change is far larger.
const SAME: f64 = 1e-12;

/// The runtime's side of a bank: see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contract {
    /// [`TAP_SPEED_POWER`]: the power of the speed each channel's history is divided by.
    pub tap_speed_power: [f64; 5],
    /// [`EDGE`]: how far before its end a sample closes a cell \[m\].
    pub grid_edge: f64,
    /// [`CONTACT_SPEED_POWER`]: the contact features' speed quotients.
    pub contact_speed_power: [i32; 3],
    /// [`MIN_SPEED`]: the smallest speed the contact quotients divide by \[m/s\].
    pub contact_min_speed: f64,
    /// [`MIN_MODEL_ERROR`]: the floor of a contact model's error in its weight.
    pub contact_min_model_error: f64,
    /// The Kalman channel's high-pass as `[b0, b1, b2, a1, a2]` at the bank's grid and cut-off.
    pub kalman_highpass_design: [f64; 5],
    /// The shelf after the high-pass as `[b0, b1, a1]`; absent without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kalman_shelf_design: Option<[f64; 3]>,
    /// The contact features' high-pass and low-pass, the same way; absent without a contact
    /// model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact_band_design: Option<[[f64; 5]; 2]>,
    /// The Kalman channel the taps were fitted with.
    pub kalman: KalmanChannel,
}

/// The Kalman channel the taps were fitted with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KalmanChannel {
    /// 7: the paper's random-walk alignment (`alignment_model` 1); 8: a prior with the
    /// alignment's rate in the state.
    pub states: usize,
    /// `design_speed` (0: the matrices follow the speed).
    pub design_speed: f64,
    /// `min_speed`: below it the filter holds \[m/s\].
    pub min_speed: f64,
    /// The speed the matrices are hashed at \[m/s\] ([`REFERENCE_SPEED`]): with
    /// `design_speed` 0 they depend on the speed, so both sides must take them at one.
    pub reference_speed: f64,
    /// The step the matrices are discretized for \[s\] (the bank's sample step).
    pub reference_step: f64,
    /// FNV-1a 64 (hex) of each matrix's entries, column by column, rounded to 9 significant
    /// digits: here the discrete state transition `F` (model parameters, discretization,
    /// alignment prior).
    pub f: String,
    /// The hash of the measurement matrix `H`, as [`Self::f`].
    pub h: String,
    /// The hash of the discrete process noise `Q` (calibration file or process noise
    /// parameters), as [`Self::f`].
    pub q: String,
    /// The hash of the measurement noise `R` (calibration file, sensor sigmas,
    /// `prior_sigma_xi`), as [`Self::f`].
    pub r: String,
}

impl Contract {
    /// The contract of this library's runtime for a bank of grid step `grid`, Kalman high-pass
    /// `kalman_highpass`, shelf `kalman_shelf` and contact band `contact_band` (if it has a
    /// contact model), with the Kalman channel `config` sampled every `step` seconds.
    pub fn expected(
        config: &Config,
        grid: f64,
        kalman_highpass: f64,
        kalman_shelf: Option<f64>,
        contact_band: Option<[f64; 2]>,
        step: f64,
    ) -> Contract {
        Contract {
            tap_speed_power: TAP_SPEED_POWER,
            grid_edge: EDGE,
            contact_speed_power: CONTACT_SPEED_POWER,
            contact_min_speed: MIN_SPEED,
            contact_min_model_error: MIN_MODEL_ERROR,
            kalman_highpass_design: Biquad::highpass(grid, kalman_highpass).coefficients(),
            kalman_shelf_design: kalman_shelf.map(|beta| {
                let [b0, b1, _, a1, _] = Biquad::shelf(grid, kalman_highpass, beta).coefficients();
                [b0, b1, a1]
            }),
            contact_band_design: contact_band.map(|[short, long]| {
                [
                    Biquad::highpass(grid, long).coefficients(),
                    Biquad::lowpass(grid, short).coefficients(),
                ]
            }),
            kalman: KalmanChannel::of(config, step),
        }
    }

    /// Compares a bank's contract (`self`) with the runtime's (`here`): the runtime constants
    /// and designs that differ (each named with both values), then the Kalman channel's.
    pub fn differences(&self, here: &Contract) -> (Vec<String>, Vec<String>) {
        let (bank, ours) = (self.runtime_values(), here.runtime_values());
        let runtime = bank
            .iter()
            .zip(&ours)
            .filter(|((_, a), (_, b))| !close(a, b))
            .map(|((name, a), (_, b))| {
                format!(
                    "{name}: the bank's {}, this estimator's {}",
                    shown(a),
                    shown(b)
                )
            })
            .collect();
        (runtime, self.kalman.differences(&here.kalman))
    }

    /// The runtime constants and designs, each named as the runtime's source names it.
    fn runtime_values(&self) -> [(&'static str, Vec<f64>); 8] {
        [
            (
                "TAP_SPEED_POWER (learned/stream.rs)",
                self.tap_speed_power.to_vec(),
            ),
            ("the grid's EDGE (learned/grid.rs)", vec![self.grid_edge]),
            (
                "CONTACT_SPEED_POWER (learned/contact.rs)",
                self.contact_speed_power.iter().map(|p| *p as f64).collect(),
            ),
            (
                "the contact model's MIN_SPEED (learned/contact.rs)",
                vec![self.contact_min_speed],
            ),
            (
                "the contact model's MIN_MODEL_ERROR (learned/contact.rs)",
                vec![self.contact_min_model_error],
            ),
            (
                "the Kalman channel's high-pass design (coefficients b0 b1 b2 a1 a2)",
                self.kalman_highpass_design.to_vec(),
            ),
            (
                "the Kalman channel's shelf design (coefficients b0 b1 a1)",
                self.kalman_shelf_design
                    .map(|d| d.to_vec())
                    .unwrap_or_default(),
            ),
            (
                "the contact features' band-pass design (high-pass, low-pass coefficients)",
                self.contact_band_design
                    .map(|d| d.concat())
                    .unwrap_or_default(),
            ),
        ]
    }
}

impl KalmanChannel {
    /// The Kalman channel `config` builds ([`Config::core`], as the FMU and the fit do), at
    /// [`REFERENCE_SPEED`] and `step`.
    pub fn of(config: &Config, step: f64) -> KalmanChannel {
        fn hashes<const N: usize>(e: &Engine<N>, speed: f64, h: f64) -> (usize, [String; 4]) {
            let d = e.space.discrete(speed, h, e.scheme);
            (
                N,
                [
                    hash(d.f.iter()),
                    hash(d.hm.iter()),
                    hash(d.q.iter()),
                    hash(e.r.iter()),
                ],
            )
        }
        let (states, [f, h, q, r]) = match config.core() {
            Core::Seven(e) => hashes(&e, REFERENCE_SPEED, step),
            Core::Eight(e) => hashes(&e, REFERENCE_SPEED, step),
        };
        KalmanChannel {
            states,
            design_speed: config.design_speed,
            min_speed: config.min_speed,
            reference_speed: REFERENCE_SPEED,
            reference_step: step,
            f,
            h,
            q,
            r,
        }
    }

    /// What differs from `here`, each named with both values (the matrices by what sets them).
    pub fn differences(&self, here: &KalmanChannel) -> Vec<String> {
        let mut d = vec![];
        if self.states != here.states {
            d.push(format!(
                "{} states in the bank's Kalman channel, {} here (alignment_model: 1 has 7)",
                self.states, here.states
            ));
        }
        if self.design_speed != here.design_speed {
            d.push(format!(
                "design_speed {} m/s in the bank's, {} here",
                self.design_speed, here.design_speed
            ));
        }
        if self.min_speed != here.min_speed {
            d.push(format!(
                "min_speed {} m/s in the bank's, {} here",
                self.min_speed, here.min_speed
            ));
        }
        if self.reference_speed != here.reference_speed
            || self.reference_step != here.reference_step
        {
            d.push(format!(
                "its matrices hashed at {} m/s and {} s in the bank, at {} m/s and {} s here",
                self.reference_speed,
                self.reference_step,
                here.reference_speed,
                here.reference_step
            ));
        } else if self.states == here.states {
            let differ: Vec<&str> = [
                (
                    &self.f,
                    &here.f,
                    "F (model parameters, discretization, alignment prior)",
                ),
                (&self.h, &here.h, "H (model parameters)"),
                (
                    &self.q,
                    &here.q,
                    "Q (calibration file or process noise parameters)",
                ),
                (
                    &self.r,
                    &here.r,
                    "R (calibration file, sensor sigmas or prior_sigma_xi)",
                ),
            ]
            .iter()
            .filter(|(a, b, _)| a != b)
            .map(|(_, _, what)| *what)
            .collect();
            if !differ.is_empty() {
                d.push(format!(
                    "its discrete {} at {} m/s differ from the bank's",
                    differ.join(", "),
                    self.reference_speed
                ));
            }
        }
        d
    }
}

/// FNV-1a 64 (hex) of the values rounded to [`HASH_DIGITS`] significant digits.
fn hash<'a>(values: impl Iterator<Item = &'a f64>) -> String {
    let text: String = values
        .map(|v| format!("{:.*e};", HASH_DIGITS - 1, v + 0.0))
        .collect();
    format!("{:016x}", super::bank::fnv1a(text.as_bytes()))
}

/// A constant for a message: a number alone, a list in brackets, `none` for no values.
fn shown(v: &[f64]) -> String {
    match v {
        [] => "none".into(),
        [x] => format!("{x:?}"),
        _ => format!("{v:?}"),
    }
}

/// Whether `a` and `b` agree within [`SAME`] (relative to the larger magnitude).
fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= SAME * x.abs().max(y.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(overrides: &[(&str, &str)]) -> Config {
        let o: Vec<(String, String)> = overrides
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let values = crate::offline::settings(&o).unwrap();
        crate::offline::config(&values, None).unwrap().0
    }

    fn expected(overrides: &[(&str, &str)]) -> Contract {
        Contract::expected(
            &config(overrides),
            0.2,
            1000.0,
            Some(1.0),
            Some([3.0, 25.0]),
            1e-3,
        )
    }

    #[test]
    fn the_same_runtime_agrees_with_itself() {
        let a = expected(&[]);
        assert_eq!(a.differences(&expected(&[])), (vec![], vec![]));
    }

    /// A bank fitted with another shelf (or none) feeds its taps another Kalman channel: an
    /// error naming the shelf, whatever the Kalman matrices say.
    #[test]
    fn another_shelf_is_a_runtime_difference() {
        let shelved = expected(&[]);
        let plain = Contract::expected(&config(&[]), 0.2, 1000.0, None, Some([3.0, 25.0]), 1e-3);
        let (runtime, kalman) = plain.differences(&shelved);
        assert_eq!(runtime.len(), 1, "{runtime:?}");
        assert!(runtime[0].contains("shelf"), "{runtime:?}");
        assert!(kalman.is_empty());
        // Another pole is another design, named the same way.
        let other = Contract::expected(
            &config(&[]),
            0.2,
            1000.0,
            Some(2.0),
            Some([3.0, 25.0]),
            1e-3,
        );
        let (runtime, _) = other.differences(&shelved);
        assert_eq!(runtime.len(), 1, "{runtime:?}");
        assert!(runtime[0].contains("shelf"), "{runtime:?}");
    }

    /// Oracle: each setting changes the matrix its own equations put it in (the wheelset mass
    /// enters F, not R; a sensor's sigma R only, with no calibration file).
    #[test]
    fn each_kalman_setting_is_named_by_the_matrix_it_changes() {
        let base = expected(&[]);
        let kalman = |o: &[(&str, &str)]| base.kalman.differences(&expected(o).kalman).join("; ");
        let m = kalman(&[("m", "1500")]);
        assert!(m.contains("F (") && !m.contains("R ("), "{m}");
        let plain = expected(&[("use_calibration_file", "false")]);
        let sigma = plain.kalman.differences(
            &expected(&[("use_calibration_file", "false"), ("sigma_acc_ws", "0.5")]).kalman,
        );
        assert_eq!(sigma.len(), 1, "{sigma:?}");
        assert!(
            sigma[0].contains("R (") && !sigma[0].contains("F ("),
            "{sigma:?}"
        );
        let calibration = kalman(&[("use_calibration_file", "false")]);
        assert!(
            calibration.contains("Q (") && calibration.contains("R ("),
            "{calibration}"
        );
        let model = kalman(&[("alignment_model", "2"), ("prior_sigma_xi", "0.01")]);
        assert!(model.contains("8 here"), "{model}");
        assert!(
            kalman(&[("design_speed", "20")]).contains("design_speed 0 m/s in the bank's, 20 here")
        );
        // The gain is not part of the contract (see the module docs).
        assert_eq!(kalman(&[("gain", "1")]), "");
    }
}
