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

/// The step the Kalman filter runs at with the diagonal model \[s\]: its sensor sigmas are
/// per sample at 1 kHz.
pub const DIAGONAL_MODEL_STEP: f64 = 1e-3;

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
    /// Prior standard deviations of the four sensors' biases (`bias_sigma_*`; 0: not
    /// estimated), [`crate::bias`].
    pub bias_sigma: [f64; 4],
    /// The vehicle's design-response model (`design_response_file`; `None`: empty name),
    /// [`crate::design`].
    pub design: Option<std::sync::Arc<crate::design::DesignModel>>,
    /// The design line `line_file` gives, and the line's distance at the run's start
    /// (`line_start`); `None`: the design comes from the inputs.
    pub line: Option<(std::sync::Arc<design_line::DesignLine>, f64)>,
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

/// Where a file the user names (`calibration_file`, `tap_file`) is: an absolute path as it
/// is; a relative one in the FMU's resources (the shipped files) if it is there, else relative
/// to the process's working directory (a file the user fitted, named as on their command
/// line), else where the resources would hold it (for the error). `None`: relative, with no
/// resources directory and not in the working directory.
pub fn user_file(name: &str, resources: Option<&Path>) -> Option<PathBuf> {
    let path = Path::new(name);
    if path.is_absolute() {
        return Some(path.to_path_buf());
    }
    let shipped = resources.map(|d| d.join(path));
    if shipped.as_ref().is_some_and(|p| p.exists()) {
        return shipped;
    }
    match std::path::absolute(path) {
        Ok(here) if here.is_file() => Some(here),
        _ => shipped,
    }
}

/// The design-response model `design_response_file` names: the shipped one built in when it is
/// named and not in the resources, else the file ([`user_file`]).
fn design_model(
    v: &Values,
    resources: Option<&Path>,
) -> Result<Option<std::sync::Arc<crate::design::DesignModel>>, Error> {
    let name = v.string[vr::DESIGN_RESPONSE_FILE as usize].trim();
    if name.is_empty() {
        return Ok(None);
    }
    let in_resources = resources.is_some_and(|d| d.join(name).is_file());
    let model = if name == crate::design::SHIPPED_NAME && !in_resources {
        crate::design::DesignModel::shipped_shared()
    } else {
        let path = user_file(name, resources).ok_or_else(|| {
            Error::DesignFile(format!(
                "design_response_file '{name}': not found (relative names are looked up in the FMU's resources, then in the working directory)"
            ))
        })?;
        crate::design::DesignModel::read_shared(&path)
    };
    model.map(Some).map_err(Error::DesignFile)
}

/// The design line `line_file` names ([`user_file`]), rounded as `line_rounding` says, with
/// `line_start`; `None` when the name is empty. The settings are checked before the file is
/// read, and a line without a design response (`has_model`) is refused before either.
fn design_line_file(
    v: &Values,
    resources: Option<&Path>,
    has_model: bool,
) -> Result<Option<(std::sync::Arc<design_line::DesignLine>, f64)>, Error> {
    let name = v.string[vr::LINE_FILE as usize].trim();
    if name.is_empty() {
        return Ok(None);
    }
    if !has_model {
        return Err(Error::LineFile(format!(
            "line_file '{name}' needs design_response_file (it is empty): without the vehicle's response to the design there is nothing to remove"
        )));
    }
    let rounding = v.real[vr::LINE_ROUNDING as usize];
    if !(design_line::MIN_ROUNDING..=design_line::MAX_ROUNDING).contains(&rounding) {
        return Err(SettingError::LineRounding(rounding).into());
    }
    let start = v.real[vr::LINE_START as usize];
    if !start.is_finite() {
        return Err(SettingError::LineStart(start).into());
    }
    let not_found = || {
        Error::LineFile(format!(
            "line_file '{name}': not found (relative names are looked up in the FMU's resources, then in the working directory)"
        ))
    };
    let path = user_file(name, resources).ok_or_else(not_found)?;
    if !path.is_file() {
        return Err(not_found());
    }
    let line = design_line::DesignLine::from_csv(&path, rounding).map_err(Error::LineFile)?;
    Ok(Some((std::sync::Arc::new(line), start)))
}

/// Where the calibration file named by the parameters is, if anywhere.
pub(crate) fn calibration_path(v: &Values, resources: Option<&Path>) -> Option<PathBuf> {
    user_file(&v.string[vr::CALIBRATION_FILE as usize], resources)
}

/// The values with a calibration file's `[parameters]` (the model its Q and R were computed
/// with) taken over where the FMU's value is still its default, so that naming another vehicle's
/// file is enough; and the parameters the user set to something else, as
/// `name = file (here current)`, which keep the user's value (Q and R then meet another model
/// than theirs, which the caller warns of).
pub fn adopt_file_parameters(
    v: &Values,
    file: &BTreeMap<String, f64>,
) -> (Values, Vec<String>, Vec<String>) {
    let mut out = v.clone();
    let (mut adopted, mut differ) = (vec![], vec![]);
    for (name, &value) in file {
        let Some(spec) = crate::variables::VARIABLES
            .iter()
            .find(|s| s.name == name && s.base() == fmi_abi::variables::Base::Real)
        else {
            continue;
        };
        let here = v.real[spec.vr as usize];
        if (here - value).abs() <= 1e-9 * value.abs() {
            continue;
        }
        match spec.start {
            fmi_abi::variables::Start::Real(default) if here == default => {
                out.real[spec.vr as usize] = value;
                adopted.push(format!("{name} = {value}"));
            }
            _ => differ.push(format!("{name} = {value} (here {here})")),
        }
    }
    (out, adopted, differ)
}

/// The calibration file the values name, loaded, with where it was, if they ask for one
/// (`use_calibration_file`); what was found goes into `notes`.
fn calibration_of(
    v: &Values,
    resources: Option<&Path>,
    notes: &mut Vec<Note>,
) -> Result<Option<(PathBuf, Calibration)>, Error> {
    if !v.boolean[vr::USE_CALIBRATION_FILE as usize] {
        return Ok(None);
    }
    match calibration_path(v, resources) {
        Some(path) if path.exists() => match calibration::load(&path)? {
            Some(c) => {
                notes.push(Note::Info(format!(
                    "Q and R from {} ({})",
                    path.display(),
                    c.status
                )));
                Ok(Some((path, c)))
            }
            None => {
                notes.push(Note::Info(format!(
                    "{} holds no matrices: using the diagonal noise model",
                    path.display()
                )));
                Ok(None)
            }
        },
        // A file the user named must exist: running on without it would give results
        // for a calibration they did not ask for.
        Some(path) if v.string[vr::CALIBRATION_FILE as usize] != DEFAULT_CALIBRATION_FILE => {
            Err(SettingError::CalibrationMissing {
                name: v.string[vr::CALIBRATION_FILE as usize].clone(),
                path,
            }
            .into())
        }
        Some(path) => {
            notes.push(Note::Warning(format!(
                "calibration file {} not found: using the diagonal noise model from the FMI parameters",
                path.display()
            )));
            Ok(None)
        }
        None => {
            notes.push(Note::Warning(
                "no resources directory: using the diagonal noise model from the FMI parameters"
                    .into(),
            ));
            Ok(None)
        }
    }
}

/// The values with the calibration's parameters adopted ([`adopt_file_parameters`]), the
/// adoption and any conflict noted.
pub(crate) fn with_file_parameters(
    v: &Values,
    c: &Calibration,
    what: &str,
    notes: &mut Vec<Note>,
) -> Values {
    let (adopted, taken, differ) = adopt_file_parameters(v, &c.parameters);
    if !taken.is_empty() {
        notes.push(Note::Info(format!(
            "model parameters from {what} (left at their defaults here): {}",
            taken.join(", ")
        )));
    }
    if !differ.is_empty() {
        notes.push(Note::Warning(format!(
            "calibration {what} was made with other model parameters than those set here ({}): its Q and R meet another model",
            differ.join(", ")
        )));
    }
    adopted
}

impl Config {
    /// The configuration from the FMI values; `resources` is the FMU's resources directory.
    pub fn from_values(v: &Values, resources: Option<&Path>) -> Result<(Config, Vec<Note>), Error> {
        let mut notes = Vec::new();
        let found = calibration_of(v, resources, &mut notes)?;
        let adopted = found
            .as_ref()
            .map(|(path, c)| with_file_parameters(v, c, &path.display().to_string(), &mut notes));
        let v = adopted.as_ref().unwrap_or(v);
        let calibrated = found.map(|(_, c)| c);
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
        let design = design_model(v, resources)?;
        let line = design_line_file(v, resources, design.is_some())?;
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
            bias_sigma: [
                r(vr::BIAS_SIGMA_WS_ACC_Y),
                r(vr::BIAS_SIGMA_WS_YAW_RATE),
                r(vr::BIAS_SIGMA_FRAME_ACC_Y),
                r(vr::BIAS_SIGMA_WS_ROLL_RATE),
            ],
            design,
            line,
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

    /// The step the Kalman filter runs at whatever the sample step ([`Engine::step`]): the
    /// calibration file's, or 1 ms for the diagonal model, whose sigmas are per sample at
    /// 1 kHz (the paper's sensors).
    pub fn model_step(&self) -> f64 {
        match self.body_noise {
            BodyNoise::Calibrated { step_size, .. } => step_size,
            BodyNoise::Rate(_) => DIAGONAL_MODEL_STEP,
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
                e.model_step = Some(self.model_step());
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
                e.model_step = Some(self.model_step());
                e.stationary_start = self.p0_stationary;
                Core::Eight(e)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The configuration and notes with the calibration file `calibration_text`, the wheelset
    /// mass set to `m` first if given.
    fn with_file(calibration_text: &str, m: Option<f64>) -> (Config, Vec<Note>) {
        let path = calibration::tests::write("config", calibration_text);
        let mut v = Values::from_table(crate::variables::VARIABLES);
        v.string[vr::CALIBRATION_FILE as usize] = path.to_str().unwrap().into();
        if let Some(m) = m {
            v.real[vr::M as usize] = m;
        }
        Config::from_values(&v, None).unwrap()
    }

    fn warnings(notes: &[Note]) -> Vec<String> {
        notes
            .iter()
            .filter_map(|n| match n {
                Note::Warning(m) => Some(m.clone()),
                Note::Info(_) => None,
            })
            .collect()
    }

    #[test]
    fn a_calibration_made_for_other_parameters_brings_them_unless_the_user_set_them() {
        // Oracle: the shipped file was made with this build's defaults, so it agrees.
        let (shipped, notes) = with_file(calibration::SHIPPED, None);
        assert!(warnings(&notes).is_empty());
        assert_eq!(shipped.params.m, 1109.0);
        // The same Q and R with another wheelset mass in [parameters], as a file made for
        // another vehicle has: naming the file is enough, the FMU takes its m.
        let other = calibration::SHIPPED.replacen("m = 1.109e3", "m = 1.813e3", 1);
        assert_ne!(other, calibration::SHIPPED);
        let (taken, notes) = with_file(&other, None);
        assert_eq!(taken.params.m, 1813.0);
        assert!(warnings(&notes).is_empty(), "{notes:?}");
        assert!(
            notes
                .iter()
                .any(|n| matches!(n, Note::Info(m) if m.contains("m = 1813"))),
            "{notes:?}"
        );
        // The user's own m stays, and the mismatch is said.
        let (kept, notes) = with_file(&other, Some(1500.0));
        assert_eq!(kept.params.m, 1500.0);
        let w = warnings(&notes);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("m = 1813 (here 1500)"), "{}", w[0]);
    }

    #[test]
    fn a_relative_file_is_looked_for_in_the_resources_then_the_working_directory() {
        let resources = tempfile::tempdir().unwrap();
        std::fs::write(resources.path().join("mine.taps"), "x").unwrap();
        // In the resources: there.
        assert_eq!(
            user_file("mine.taps", Some(resources.path())),
            Some(resources.path().join("mine.taps"))
        );
        // Not there but in the working directory (cargo runs the tests in the crate's):
        // there, made absolute.
        let here = std::path::absolute("resources/learned.taps").unwrap();
        assert!(here.is_file());
        assert_eq!(
            user_file("resources/learned.taps", Some(resources.path())),
            Some(here)
        );
        // Nowhere: where the resources would hold it, so the error names that; without
        // resources, none.
        assert_eq!(
            user_file("absent.taps", Some(resources.path())),
            Some(resources.path().join("absent.taps"))
        );
        assert_eq!(user_file("absent.taps", None), None);
        // Absolute: as given.
        assert_eq!(
            user_file("/x/y.taps", None),
            Some(PathBuf::from("/x/y.taps"))
        );
    }
}
