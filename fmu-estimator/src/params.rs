//! The simplified model's parameters (the paper's Table 2) and their checks.
//!
//! Sources: every default is Table 2 of Muñoz, Ros & Escalona, "Estimation of lateral track
//! irregularity through Kalman filtering techniques" (docs/references.md), except two:
//! - `r_0 = 0.425 m`. Table 2 prints 0.85 m, which is the diameter of an ML95-family wheel
//!   (about 850 mm, `docs/references.md` section 2), not a plausible rolling radius.
//!   With 0.425 m the free-wheelset (Klingel) wavelength 2 pi sqrt(r0 l / alpha) is 11.22 m,
//!   the value docs/references.md section 5 checks. The vehicle FMU must use the same radius.
//! - `g = 9.81 m/s2`, exposed so the Klingel test can switch gravitational stiffness off.
//!
//! kx, cx, ky, cy are the paper's identified equivalents; they are re-identified against our
//! vehicle model in the calibration study (issue 5), which rewrites them.

use crate::error::SettingError;
use serde::{Deserialize, Serialize};

/// Physical parameters of the simplified model (SI units, see `model` for the meaning).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Wheelset mass \[kg\].
    pub m: f64,
    /// Wheelset yaw moment of inertia [kg m2].
    pub i: f64,
    /// Half the lateral distance between the wheel-rail contact points \[m\].
    pub l: f64,
    /// Half the lateral distance between the longitudinal primary suspension elements \[m\].
    pub l_s: f64,
    /// Tread conicity [-].
    pub alpha: f64,
    /// Rolling radius of the centred wheelset \[m\].
    pub r_0: f64,
    /// Suspended mass carried by the wheelset: a quarter car body plus half a bogie frame \[kg\].
    pub m_f: f64,
    /// Kalker longitudinal creep coefficient per wheel \[N\].
    pub f11: f64,
    /// Kalker lateral creep coefficient per wheel \[N\].
    pub f22: f64,
    /// Kalker lateral/spin creep coefficient per wheel [N m].
    pub f23: f64,
    /// Kalker spin creep coefficient per wheel [N m2].
    pub f33: f64,
    /// Longitudinal primary stiffness, one element per side at +/- l_s [N/m].
    pub kx: f64,
    /// Longitudinal primary damping, one element per side at +/- l_s [N s/m].
    pub cx: f64,
    /// Lateral primary stiffness between wheelset and frame, one equivalent element [N/m].
    pub ky: f64,
    /// Lateral primary damping between wheelset and frame, one equivalent element [N s/m].
    pub cy: f64,
    /// Gravitational acceleration [m/s2].
    pub g: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params::TABLE_2
    }
}

impl Params {
    /// The paper's Table 2 (with the rolling radius and gravity noted in the module docs): the
    /// defaults of the FMU's parameters.
    pub const TABLE_2: Params = Params {
        m: 1109.0,
        i: 606.0,
        l: 0.75,
        l_s: 0.85,
        alpha: 0.1,
        r_0: 0.425,
        m_f: 3781.0,
        f11: 5.5e6,
        f22: 5.0e6,
        f23: 9.3e3,
        f33: 15.0,
        kx: 7.95e5,
        cx: 1.47e4,
        ky: 4.12e6,
        cy: 1.41e5,
        g: 9.81,
    };

    /// Refuses values for which the model has no meaning, naming the parameter (FMI name).
    pub fn check(&self) -> Result<(), SettingError> {
        let positive = [
            ("m", self.m),
            ("I", self.i),
            ("l", self.l),
            ("r_0", self.r_0),
            ("m_f", self.m_f),
        ];
        for (name, v) in positive {
            if !(v > 0.0) || !v.is_finite() {
                return Err(SettingError::NotPositive { name, value: v });
            }
        }
        if !(self.alpha > 0.0) || !self.alpha.is_finite() {
            return Err(SettingError::Conicity(self.alpha));
        }
        let non_negative = [
            ("l_s", self.l_s),
            ("f11", self.f11),
            ("f22", self.f22),
            ("f23", self.f23),
            ("f33", self.f33),
            ("kx", self.kx),
            ("cx", self.cx),
            ("ky", self.ky),
            ("cy", self.cy),
            ("g", self.g),
        ];
        for (name, v) in non_negative {
            if !(v >= 0.0) || !v.is_finite() {
                return Err(SettingError::Negative { name, value: v });
            }
        }
        Ok(())
    }
}

include!(concat!(env!("OUT_DIR"), "/calibrated.rs"));

/// The default sigma of the 8-state priors' virtual measurement \[m\]: the calibration file's
/// `prior_sigma_xi` (tuned on the calibration seed), or 5 mm, the paper's value for its own
/// virtual measurement.
pub const PRIOR_SIGMA_XI: f64 = calibrated("prior_sigma_xi", 0.005);

/// The value `CALIBRATED` gives `name`, if any (a `const fn`, so the variable table can use it).
const fn calibrated(name: &str, default: f64) -> f64 {
    let mut i = 0;
    while i < CALIBRATED.len() {
        let (n, v) = CALIBRATED[i];
        if n.len() == name.len() {
            let (a, b) = (n.as_bytes(), name.as_bytes());
            let mut j = 0;
            let mut same = true;
            while j < a.len() {
                if a[j] != b[j] {
                    same = false;
                }
                j += 1;
            }
            if same {
                return v;
            }
        }
        i += 1;
    }
    default
}

impl Params {
    /// The FMU's parameter defaults: Table 2, overridden by the calibration file's
    /// `[parameters]` (read at build time by build.rs).
    pub const DEFAULTS: Params = {
        let t = Params::TABLE_2;
        Params {
            m: calibrated("m", t.m),
            i: calibrated("I", t.i),
            l: calibrated("l", t.l),
            l_s: calibrated("l_s", t.l_s),
            alpha: calibrated("alpha", t.alpha),
            r_0: calibrated("r_0", t.r_0),
            m_f: calibrated("m_f", t.m_f),
            f11: calibrated("f11", t.f11),
            f22: calibrated("f22", t.f22),
            f23: calibrated("f23", t.f23),
            f33: calibrated("f33", t.f33),
            kx: calibrated("kx", t.kx),
            cx: calibrated("cx", t.cx),
            ky: calibrated("ky", t.ky),
            cy: calibrated("cy", t.cy),
            g: t.g,
        }
    };
}
