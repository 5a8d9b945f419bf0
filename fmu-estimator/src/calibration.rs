//! Q and R: from the calibration file in the FMU's resources when it holds them, otherwise the
//! diagonal model built from the FMI noise parameters.
//!
//! The calibration file (`resources/calibration.toml`) is written by `alignment-studies
//! calibrate` from vehicle runs, as the paper does (system error `x_k - F x_{k-1}` and measurement
//! error `z_k - H x_k`). When it holds no matrices the FMU uses the **diagonal model** below.
//! Format:
//! ```toml
//! status = "calibrated ..."      # free text, logged
//! step_size = 0.001              # [s] the step Q was computed for
//! speed = 20.0                   # [m/s] the speed Q was computed for (informative)
//! [parameters]                   # the simplified model's parameters (FMI names): they become
//! kx = 1.2e6                     # the FMU's parameter defaults at build time (build.rs), so the
//! ...                            # modelDescription.xml and the binary agree
//! [noise]
//! q = [[...7 numbers...], ...]   # 7 rows, discrete process noise covariance
//! r = [[...4 numbers...], ...]   # 4 rows, measurement noise covariance
//! ```
//! The Kalman filter runs at `step_size` whatever the sample step (`Engine::step`: samples held
//! over their step), so Q and R are used as they were computed.
//!
//! # The diagonal model
//! - `R = diag(sigma_acc_ws^2, sigma_yaw_rate^2, sigma_acc_frame^2, sigma_xi^2)`: the sensor
//!   sigmas of the paper's section 5 (0.01 m/s2, 0.0005 rad/s, 0.01 m/s2) and its 5 mm for the
//!   virtual alignment measurement.
//! - `Q = h diag(0, 0, 0, q_acc_ws, q_yaw_acc, q_acc_frame, q_xi)`: white accelerations of
//!   intensity `q_*` [m2/s3 or rad2/s3] on the three bodies and a random walk of intensity
//!   `q_xi` [m2/s] on the alignment. The `q_xi` default comes from the low-disturbance German
//!   alignment spectrum (docs/references.md section 3): alignment slope about 4.5e-4 rms, so at 20 m/s
//!   `dxi/dt` is about 9e-3 m/s rms with a correlation time of about 0.06 s (1 / (Oc V)),
//!   `q_xi = 2 sigma^2 tau`, about 1e-5 m2/s.
//! - The acceleration intensities (1e-4 for all three bodies) were chosen by a coarse sweep on
//!   data from the simplified model itself (1e-2 to 1e-6, two seeds, 20 s at 20 m/s with the
//!   paper's sensor noise and `sigma_xi = 5 mm`): whole-band Jrel fell from 1.09 at 1e-2 to 0.92
//!   at 1e-4 and 0.89 at 1e-6. On such data the long wavelengths (D3) stay poor (Jrel about 1.2)
//!   with the 5 mm virtual measurement, and much better with a weaker one (0.93 at 20 mm): the
//!   calibration study decides; these defaults only have to be sane.

use crate::error::CalibrationError;
use crate::filter::Mat4;
use crate::model::Mat7;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Matrices read from a calibration file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// The file's free-text `status` line ("unspecified" when absent), logged so a run says
    /// which calibration it used.
    pub status: String,
    /// The step Q and R were computed for \[s\], 1e-4 to 0.1: the Kalman filter runs at it
    /// ([`crate::engine::Engine::step`]).
    pub step_size: f64,
    /// The discrete process noise covariance of the paper's 7 states at `step_size`
    /// (symmetric, non-negative diagonal), as the paper's section 4.2 estimates it.
    pub q: Mat7,
    /// The measurement noise covariance of the four measurements (the three sensors and the
    /// virtual alignment measurement), positive definite.
    pub r: Mat4,
    /// The file's `[parameters]`: the simplified model Q and R were computed with (the FMU's
    /// defaults at build time; at run time only compared with the FMU's parameters).
    pub parameters: BTreeMap<String, f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    status: Option<String>,
    step_size: Option<f64>,
    #[allow(dead_code)]
    speed: Option<f64>,
    /// The FMU's defaults at build time (build.rs).
    parameters: Option<BTreeMap<String, f64>>,
    noise: Option<Noise>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Noise {
    q: Option<Vec<Vec<f64>>>,
    r: Option<Vec<Vec<f64>>>,
}

fn matrix<const N: usize>(
    rows: &[Vec<f64>],
    name: &'static str,
    file: &Path,
) -> Result<nalgebra::SMatrix<f64, N, N>, CalibrationError> {
    let file = file.to_path_buf();
    if rows.len() != N || rows.iter().any(|r| r.len() != N) {
        return Err(CalibrationError::Shape { file, name, n: N });
    }
    let m = nalgebra::SMatrix::<f64, N, N>::from_fn(|i, j| rows[i][j]);
    if m.iter().any(|x| !x.is_finite()) {
        return Err(CalibrationError::NonFinite { file, name });
    }
    if (m - m.transpose()).amax() > 1e-12 * m.amax() {
        return Err(CalibrationError::NotSymmetric { file, name });
    }
    if (0..N).any(|i| m[(i, i)] < 0.0) {
        return Err(CalibrationError::NegativeDiagonal { file, name });
    }
    Ok(m)
}

impl Calibration {
    /// The filter's body process noise and measurement noise from these matrices.
    pub fn noise(&self) -> (crate::statespace::BodyNoise, Mat4) {
        (
            crate::statespace::BodyNoise::Calibrated {
                q: self.q,
                step_size: self.step_size,
            },
            self.r,
        )
    }
}

/// The calibration file shipped in the FMU's resources, as built into this library (for
/// offline processing without an unpacked FMU).
pub const SHIPPED: &str = include_str!("../resources/calibration.toml");

/// Reads a calibration file. `Ok(None)`: the file holds no matrices (not yet calibrated).
pub fn load(path: &Path) -> Result<Option<Calibration>, CalibrationError> {
    let text = read(path)?;
    parse(&text, path)
}

/// The `[parameters]` table of the calibration file at `path`: the simplified model's
/// parameters it was made with. The FMU takes them as its defaults at build time only
/// (build.rs); a master that points `calibration_file` at another file must set them as
/// parameters too (the orchestrator's studies do).
pub fn file_parameters(path: &Path) -> Result<BTreeMap<String, f64>, CalibrationError> {
    Ok(file(&read(path)?, path)?.parameters.unwrap_or_default())
}

fn read(path: &Path) -> Result<String, CalibrationError> {
    // A calibration file is a few kilobytes of TOML.
    fmi_abi::resource::read_text(path, "calibration file", 1 << 20).map_err(CalibrationError::Read)
}

fn file(text: &str, path: &Path) -> Result<File, CalibrationError> {
    toml::from_str(text).map_err(|e| CalibrationError::Toml {
        file: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Parses a calibration file's text; `path` names it in messages.
pub fn parse(text: &str, path: &Path) -> Result<Option<Calibration>, CalibrationError> {
    let file = file(text, path)?;
    let status = file.status.unwrap_or_else(|| "unspecified".into());
    let (q, r) = file.noise.map_or((None, None), |n| (n.q, n.r));
    match (q, r) {
        (None, None) => Ok(None),
        (Some(q), Some(r)) => {
            let step_size = file
                .step_size
                // The filter runs at this step whatever the sample step: at most 1e4 filter
                // steps per sample of up to 1 s.
                .filter(|h| (1e-4..=0.1).contains(h))
                .ok_or_else(|| CalibrationError::StepSize {
                    file: path.to_path_buf(),
                })?;
            let q = matrix::<7>(&q, "q", path)?;
            let r = matrix::<4>(&r, "r", path)?;
            if r.cholesky().is_none() {
                return Err(CalibrationError::RNotPositiveDefinite {
                    file: path.to_path_buf(),
                });
            }
            Ok(Some(Calibration {
                status,
                step_size,
                q,
                r,
                parameters: file.parameters.unwrap_or_default(),
            }))
        }
        _ => Err(CalibrationError::Incomplete {
            file: path.to_path_buf(),
        }),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// `text` as `calibration.toml` in a directory of this process named `name`.
    pub(crate) fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("fmu-estimator-cal-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("calibration.toml");
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn the_shipped_file_is_readable() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("resources/calibration.toml");
        load(&p).unwrap();
    }

    #[test]
    fn a_full_calibration_is_read() {
        let q: Vec<String> = (0..7)
            .map(|i| {
                format!(
                    "[{}]",
                    (0..7)
                        .map(|j| if i == j { "1e-6" } else { "0" })
                        .collect::<Vec<_>>()
                        .join(",")
                )
            })
            .collect();
        let r: Vec<String> = (0..4)
            .map(|i| {
                format!(
                    "[{}]",
                    (0..4)
                        .map(|j| if i == j { "2e-4" } else { "0" })
                        .collect::<Vec<_>>()
                        .join(",")
                )
            })
            .collect();
        let p = write(
            "full",
            &format!(
                "status = \"test\"\nstep_size = 0.001\n[parameters]\nkx = 1.0\n[noise]\nq = [{}]\nr = [{}]\n",
                q.join(","),
                r.join(",")
            ),
        );
        let c = load(&p).unwrap().unwrap();
        assert_eq!(c.q[(6, 6)], 1e-6);
        assert_eq!(c.r[(3, 3)], 2e-4);
        assert_eq!(c.step_size, 0.001);
    }

    #[test]
    fn bad_files_are_refused_with_the_file_and_entry_named() {
        let p = write(
            "bad1",
            "step_size = 0.001\n[noise]\nq = [[1.0]]\nr = [[1.0]]\n",
        );
        let e = load(&p).unwrap_err().to_string();
        assert!(
            e.contains("calibration.toml") && e.contains("'q' must be 7 rows"),
            "{e}"
        );
        let p = write("bad2", "[noise]\nq = [[1.0]]\n");
        assert!(load(&p).unwrap_err().to_string().contains("both"));
        let p = write("bad3", "this is = not toml [");
        assert!(
            load(&p)
                .unwrap_err()
                .to_string()
                .contains("calibration.toml")
        );
        let e = load(Path::new("/nonexistent/calibration.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("/nonexistent/calibration.toml"), "{e}");
    }
}
