//! Everything the user chose, read once from the FMI parameters (and the calibration file) at
//! the end of initialization. The FMU and the offline processor ([`crate::offline`]) build the
//! filter from the same `Config`, so a recorded run smoothed offline uses exactly the filter the
//! FMU ran.

use crate::calibration::{self, Calibration};
use crate::core::Core;
use crate::discretize::Scheme;
use crate::engine::{Engine, Gain};
use crate::error::{Error, SettingError};
use crate::filter::{Mat4, Vec4, Vec7};
use crate::params::Params;
use crate::prior::{AlignmentModel, Spectrum};
use crate::statespace::{BodyNoise, StateSpace};
use crate::variables::vr;
use fmi_abi::Values;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A message for the FMU's logger (or the offline caller).
#[derive(Debug, Clone, PartialEq)]
pub enum Note {
    /// What the configuration chose (e.g. the calibration file used), logged at fmi2OK.
    Info(String),
    /// A fallback the user may not expect (e.g. no calibration file found: the diagonal noise
    /// model), logged at fmi2Warning.
    Warning(String),
}

/// The Kalman filter's configuration, checked, from the FMI parameters and the calibration
/// file: everything [`Config::core`] needs to build the filter, so that the FMU and the offline
/// path build the same one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Config {
    /// The simplified model's parameters (Table 2 defaults, the FMI parameters over them).
    pub params: Params,
    /// The discretization (`discretization`).
    pub scheme: Scheme,
    /// The alignment prior (`alignment_model`), which sets the state dimension (7 or 8).
    pub model: AlignmentModel,
    /// The gain of the Kalman filter when it is the learned filter's channel (`gain` 0 resolved
    /// for that use).
    pub gain: Gain,
    /// The gain when the Kalman filter is the estimate itself, not the learned filter's
    /// channel (`gain` 0 resolves differently: [`Gain::from_fmi`]); what
    /// [`crate::offline::process`] (and its smoother) runs. With the learned filter
    /// ([`crate::offline::process_learned`], the FMU) the Kalman filter, its fallback output and
    /// a smoother over it run `gain`.
    pub gain_alone: Gain,
    /// The process noise on the bodies: the calibration file's Q, or the diagonal model's
    /// intensities.
    pub body_noise: BodyNoise,
    /// Measurement noise of the three sensors and of the virtual measurement (paper's model).
    pub r: Mat4,
    /// Sigma of the virtual measurement for the 8-state priors; `<= 0`: none.
    pub prior_sigma_xi: f64,
    /// Initial standard deviation of the alignment estimate \[m\] (`p0_xi`), where the filter
    /// does not start from the stationary covariance.
    pub p0_xi: f64,
    /// Start from the stationary covariance (`p0_stationary`).
    pub p0_stationary: bool,
    /// Below this speed \[m/s\] the estimate is held (`min_speed`): the creep terms divide by
    /// the speed.
    pub min_speed: f64,
    /// `> 0`: build the matrices once for this speed (the paper's constant-speed filter).
    pub design_speed: f64,
    /// The calibration file's status line when its matrices are used.
    pub calibration: Option<String>,
}

/// Reads the `Params` from the FMI values.
pub fn params_from(v: &Values) -> Params {
    let r = |i: u32| v.real[i as usize];
    Params {
        m: r(vr::M),
        i: r(vr::I),
        l: r(vr::L),
        l_s: r(vr::L_S),
        alpha: r(vr::ALPHA),
        r_0: r(vr::R_0),
        m_f: r(vr::M_F),
        f11: r(vr::F11),
        f22: r(vr::F22),
        f23: r(vr::F23),
        f33: r(vr::F33),
        kx: r(vr::KX),
        cx: r(vr::CX),
        ky: r(vr::KY),
        cy: r(vr::CY),
        g: r(vr::G),
    }
}

pub use crate::variables::DEFAULT_CALIBRATION_FILE;

/// Where the calibration file named by the parameters is, if anywhere.
fn calibration_path(v: &Values, resources: Option<&Path>) -> Option<PathBuf> {
    let name = PathBuf::from(&v.string[vr::CALIBRATION_FILE as usize]);
    if name.is_absolute() {
        Some(name)
    } else {
        resources.map(|d| d.join(&name))
    }
}

/// The parameters whose value in a calibration file's `[parameters]` (the model its Q and R were
/// computed with) differs from the FMU's current value, as `name = file (here current)`. The FMU
/// reads only Q and R from the file at run time (the parameters are its build-time defaults),
/// so Q and R from a file made for another vehicle would otherwise meet this build's model
/// silently.
pub fn parameter_mismatches(v: &Values, file: &BTreeMap<String, f64>) -> Vec<String> {
    let mut differ = vec![];
    for (name, &value) in file {
        let Some(spec) = crate::variables::VARIABLES
            .iter()
            .find(|s| s.name == name && s.base() == fmi_abi::variables::Base::Real)
        else {
            continue;
        };
        let here = v.real[spec.vr as usize];
        if (here - value).abs() > 1e-9 * value.abs() {
            differ.push(format!("{name} = {value} (here {here})"));
        }
    }
    differ
}

impl Config {
    /// The configuration from the FMI values; `resources` is the FMU's resources directory.
    pub fn from_values(v: &Values, resources: Option<&Path>) -> Result<(Config, Vec<Note>), Error> {
        let mut notes = Vec::new();
        let params = params_from(v);
        params.check()?;
        let r = |i: u32| v.real[i as usize];
        let scheme = Scheme::from_fmi(v.integer[vr::DISCRETIZATION as usize])?;
        let spectrum = Spectrum {
            a: r(vr::PRIOR_A),
            omega_r: r(vr::PRIOR_OMEGA_R),
            omega_c: r(vr::PRIOR_OMEGA_C),
        };
        let model = AlignmentModel::from_fmi(v.integer[vr::ALIGNMENT_MODEL as usize], spectrum)?;
        let gain = Gain::from_fmi(
            v.integer[vr::GAIN as usize],
            v.integer[vr::ESTIMATOR as usize] == 2,
        )?;
        let gain_alone = Gain::from_fmi(v.integer[vr::GAIN as usize], false)?;
        let sig = [
            r(vr::SIGMA_ACC_WS),
            r(vr::SIGMA_YAW_RATE),
            r(vr::SIGMA_ACC_FRAME),
            r(vr::SIGMA_XI),
        ];
        let rm = Mat4::from_diagonal(&Vec4::from_fn(|i, _| sig[i] * sig[i]));
        let q = [
            0.0,
            0.0,
            0.0,
            r(vr::Q_ACC_WS),
            r(vr::Q_YAW_ACC),
            r(vr::Q_ACC_FRAME),
            r(vr::Q_XI),
        ];
        let body_noise = BodyNoise::Rate(SMatrix::from_diagonal(&Vec7::from_fn(|i, _| q[i])));
        let mut calibrated: Option<Calibration> = None;
        if v.boolean[vr::USE_CALIBRATION_FILE as usize] {
            match calibration_path(v, resources) {
                Some(path) if path.exists() => match calibration::load(&path)? {
                    Some(c) => {
                        notes.push(Note::Info(format!("Q and R from {} ({})", path.display(), c.status)));
                        let differ = parameter_mismatches(v, &c.parameters);
                        if !differ.is_empty() {
                            notes.push(Note::Warning(format!(
                                "calibration file {} was made with other model parameters ({}): the FMU takes only Q and R from it at run time, so set those parameters to the file's values if it is meant for them",
                                path.display(),
                                differ.join(", ")
                            )));
                        }
                        calibrated = Some(c);
                    }
                    None => notes.push(Note::Info(format!(
                        "{} holds no matrices: using the diagonal noise model",
                        path.display()
                    ))),
                },
                // A file the user named must exist: running on without it would give results
                // for a calibration they did not ask for.
                Some(path) if v.string[vr::CALIBRATION_FILE as usize] != DEFAULT_CALIBRATION_FILE => {
                    return Err(SettingError::CalibrationMissing {
                        name: v.string[vr::CALIBRATION_FILE as usize].clone(),
                        path,
                    }
                    .into());
                }
                Some(path) => notes.push(Note::Warning(format!(
                    "calibration file {} not found: using the diagonal noise model from the FMI parameters",
                    path.display()
                ))),
                None => notes.push(Note::Warning(
                    "no resources directory: using the diagonal noise model from the FMI parameters".into(),
                )),
            }
        }
        if calibrated.is_none() && sig.iter().any(|s| !(*s > 0.0)) {
            return Err(SettingError::Sigmas.into());
        }
        let design_speed = r(vr::DESIGN_SPEED);
        if !(design_speed >= 0.0 && design_speed.is_finite()) {
            return Err(SettingError::DesignSpeed(design_speed).into());
        }
        let prior_sigma_xi = r(vr::PRIOR_SIGMA_XI);
        if prior_sigma_xi.is_nan() {
            return Err(SettingError::PriorSigmaNan.into());
        }
        let config = Config {
            params,
            scheme,
            model,
            gain,
            gain_alone,
            body_noise,
            r: rm,
            prior_sigma_xi,
            p0_xi: r(vr::P0_XI),
            p0_stationary: v.boolean[vr::P0_STATIONARY as usize],
            min_speed: r(vr::MIN_SPEED),
            design_speed,
            calibration: None,
        };
        Ok((
            match calibrated {
                Some(c) => config.with_calibration(c),
                None => config,
            },
            notes,
        ))
    }

    /// This configuration with the noise matrices of a calibration file.
    pub fn with_calibration(self, c: Calibration) -> Config {
        let (body_noise, r) = c.noise();
        Config {
            body_noise,
            r,
            calibration: Some(c.status),
            ..self
        }
    }

    /// A fresh filter for this configuration.
    pub fn core(&self) -> Core {
        // Initial covariance: the alignment from `p0_xi`, the body states from typical
        // amplitudes (5 mm, 1 mrad, 5 mm; 0.05 m/s, 0.01 rad/s, 0.05 m/s) of a wheelset running
        // at speed; the alignment's rate (8 states) from the prior's slope, 1e-3 * 20 m/s.
        let s = [5e-3, 1e-3, 5e-3, 5e-2, 1e-2, 5e-2, self.p0_xi, 2e-2];
        match self.model {
            AlignmentModel::RandomWalk => {
                let p0 = SMatrix::<f64, 7, 7>::from_diagonal(&SVector::from_fn(|i, _| s[i] * s[i]));
                let space = StateSpace::paper(&self.params, self.body_noise.clone(), true);
                let mut e = Engine::new(space, self.scheme, self.gain, self.r, p0);
                e.stationary_start = self.p0_stationary;
                Core::Seven(e)
            }
            model => {
                let p0 = SMatrix::<f64, 8, 8>::from_diagonal(&SVector::from_fn(|i, _| s[i] * s[i]));
                let virtual_measurement = self.prior_sigma_xi > 0.0;
                let space = StateSpace::with_prior(
                    &self.params,
                    &model,
                    self.body_noise.clone(),
                    virtual_measurement,
                );
                // The sensors' block of R is kept; the virtual measurement is the prior's own,
                // uncorrelated with the sensors.
                let mut r = self.r;
                for k in 0..4 {
                    r[(3, k)] = 0.0;
                    r[(k, 3)] = 0.0;
                }
                r[(3, 3)] = if virtual_measurement {
                    self.prior_sigma_xi * self.prior_sigma_xi
                } else {
                    1.0
                };
                let mut e = Engine::new(space, self.scheme, self.gain, r, p0);
                e.stationary_start = self.p0_stationary;
                Core::Eight(e)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warnings(calibration_text: &str) -> Vec<String> {
        let path = calibration::tests::write("config", calibration_text);
        let mut v = Values::from_table(crate::variables::VARIABLES);
        v.string[vr::CALIBRATION_FILE as usize] = path.to_str().unwrap().into();
        let (_, notes) = Config::from_values(&v, None).unwrap();
        notes
            .into_iter()
            .filter_map(|n| match n {
                Note::Warning(m) => Some(m),
                Note::Info(_) => None,
            })
            .collect()
    }

    #[test]
    fn a_calibration_made_for_other_parameters_is_flagged() {
        // Oracle: the shipped file was made with this build's defaults, so it agrees.
        assert!(warnings(calibration::SHIPPED).is_empty());
        // The same Q and R with another wheelset mass in [parameters], as a file made for
        // another vehicle would have: the FMU keeps its own m, and says so.
        let other = calibration::SHIPPED.replacen("m = 1.109e3", "m = 1.813e3", 1);
        assert_ne!(other, calibration::SHIPPED);
        let w = warnings(&other);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("m = 1813 (here 1109)"), "{}", w[0]);
    }
}
