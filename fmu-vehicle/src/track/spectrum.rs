//! The irregularity spectra: German (low / high disturbance) and FRA (US) classes 5 and 6.
//!
//! All three functions return a **one-sided** power spectral density in **angular** wavenumber
//! `omega` \[rad/m\], in m^2/(rad/m), so that the variance of a channel over a band is the plain
//! integral `sigma^2 = int S(omega) d omega` over that band. The cross-level PSD is that of the
//! *height difference* `u_z^lr - u_z^rr` in metres, not of an angle (see [`psd_cross_level`]).
//! Conversion to cyclic wavenumber `f = omega / (2 pi)` \[cycles/m\]: `S_f(f) = 2 pi S(2 pi f)`.

use serde::{Deserialize, Serialize};

/// Which irregularity spectrum the synthesized track follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Spectrum {
    /// German spectrum, low disturbance (FMI code 1).
    GermanLow,
    /// German spectrum, high disturbance (FMI code 2).
    GermanHigh,
    /// FRA (US) track class 5 (FMI code 3).
    Fra5,
    /// FRA (US) track class 6, the best US class (FMI code 4).
    Fra6,
}

impl Spectrum {
    /// The spectrum for the FMI Integer parameter `spectrum`: 1 German low, 2 German high,
    /// 3 FRA class 5, 4 FRA class 6.
    pub fn from_fmi(code: i32) -> Result<Spectrum, String> {
        match code {
            1 => Ok(Spectrum::GermanLow),
            2 => Ok(Spectrum::GermanHigh),
            3 => Ok(Spectrum::Fra5),
            4 => Ok(Spectrum::Fra6),
            _ => Err(format!(
                "parameter 'spectrum' must be 1 (German low disturbance), 2 (German high \
                 disturbance), 3 (FRA class 5) or 4 (FRA class 6); got {code}"
            )),
        }
    }

    /// The FMI code of this spectrum (inverse of [`Spectrum::from_fmi`]).
    pub fn fmi_code(self) -> i32 {
        match self {
            Spectrum::GermanLow => 1,
            Spectrum::GermanHigh => 2,
            Spectrum::Fra5 => 3,
            Spectrum::Fra6 => 4,
        }
    }
}

/// Half the lateral distance between the two wheel-rail contact points \[m\], the `b` of the
/// German cross-level spectrum.
pub const HALF_CONTACT_DISTANCE: f64 = 0.75;

// German spectra (ORE B176 family as used in vehicle dynamics), docs/references.md section 3 [src]:
// one-sided, angular wavenumber, m^2/(rad/m), A in m^2 rad/m.
const GER_OC: f64 = 0.8246;
const GER_OR: f64 = 0.0206;
const GER_OS: f64 = 0.4380;

// FRA classes (Hamid & Yang 1981; Garg & Dukkipati 1984, "Dynamics of railway vehicle
// systems", table of the six classes) with k = 0.25, A in cm^2 rad/m, PSD in cm^2/(rad/m).
const FRA_K: f64 = 0.25;
const FRA_OC: f64 = 0.8245;
const CM2_TO_M2: f64 = 1e-4;

/// Spectrum constants: `(A_a, A_v, Omega_s)`; German in m^2 rad/m, FRA in cm^2 rad/m.
fn constants(spec: Spectrum) -> (f64, f64, f64) {
    match spec {
        // docs/references.md section 3 [src: four public codes]; same Os for both levels.
        Spectrum::GermanLow => (2.119e-7, 4.032e-7, GER_OS),
        Spectrum::GermanHigh => (6.125e-7, 1.080e-6, GER_OS),
        // A_a from docs/references.md [src]; A_v = 0.2095 / 0.0339 cm^2 rad/m as in the public
        // TTB-2D tool (Cantero, SoftwareX 20, 2022, profile options "FRAv2", classes 1-6:
        // 1.2107 1.0181 0.6816 0.5376 0.2095 0.0339); Omega_s = 0.8209 / 0.4380 rad/m from
        // the FRA class table [lit, not found in a public code in this session].
        Spectrum::Fra5 => (0.0762, 0.2095, 0.8209),
        Spectrum::Fra6 => (0.0339, 0.0339, 0.4380),
    }
}

fn is_german(spec: Spectrum) -> bool {
    matches!(spec, Spectrum::GermanLow | Spectrum::GermanHigh)
}

/// German profile shape `A Oc^2 / ((O^2 + Or^2)(O^2 + Oc^2))`.
fn german_profile(a: f64, omega: f64) -> f64 {
    let o2 = omega * omega;
    a * GER_OC * GER_OC / ((o2 + GER_OR * GER_OR) * (o2 + GER_OC * GER_OC))
}

/// FRA profile shape `k A Oc^2 / (O^2 (O^2 + Oc^2))`, converted from cm^2 to m^2.
fn fra_profile(a: f64, omega: f64) -> f64 {
    let o2 = omega * omega;
    CM2_TO_M2 * FRA_K * a * FRA_OC * FRA_OC / (o2 * (o2 + FRA_OC * FRA_OC))
}

/// One-sided PSD of the alignment `(u_y^lr + u_y^rr) / 2` at angular wavenumber `omega`
/// \[rad/m\], in m^2/(rad/m).
///
/// German: `A_a Oc^2 / ((O^2 + Or^2)(O^2 + Oc^2))`, `Oc = 0.8246`, `Or = 0.0206` rad/m,
/// `A_a = 2.119e-7` (low) / `6.125e-7` (high) m^2 rad/m. FRA: `0.25 A_a Oc^2 / (O^2 (O^2 +
/// Oc^2))` cm^2/(rad/m), `Oc = 0.8245`, `A_a = 0.0762` (class 5) / `0.0339` (class 6) cm^2
/// rad/m; it grows as `1/O^2` at long wavelengths (no roll-off like the German `Or`; its
/// integral diverges at `O -> 0`), so a synthesis must be band-limited.
pub fn psd_alignment(spec: Spectrum, omega: f64) -> f64 {
    let (a_a, _, _) = constants(spec);
    if is_german(spec) {
        german_profile(a_a, omega)
    } else {
        fra_profile(a_a, omega)
    }
}

/// One-sided PSD of the vertical profile `(u_z^lr + u_z^rr) / 2` at `omega` \[rad/m\], in
/// m^2/(rad/m). Same forms as [`psd_alignment`] with `A_v`: German `4.032e-7` (low) /
/// `1.080e-6` (high) m^2 rad/m; FRA `0.2095` (class 5) / `0.0339` (class 6) cm^2 rad/m.
pub fn psd_vertical(spec: Spectrum, omega: f64) -> f64 {
    let (_, a_v, _) = constants(spec);
    if is_german(spec) {
        german_profile(a_v, omega)
    } else {
        fra_profile(a_v, omega)
    }
}

/// One-sided PSD of the cross-level as a **height difference** `u_z^lr - u_z^rr` at `omega`
/// \[rad/m\], in m^2/(rad/m).
///
/// German: the published spectrum `(A_v / b^2) Oc^2 O^2 / ((O^2 + Or^2)(O^2 + Oc^2)(O^2 +
/// Os^2))` with `b = 0.75` m has units 1/(rad/m) = rad^2/(rad/m): it is the PSD of the cross-level
/// *angle* `theta = (u_z^lr - u_z^rr) / (2 b)`, `b` being half the distance between the contact
/// points. The height difference is `2 b theta`, so its PSD is `(2 b)^2` times the angle's:
/// `4 A_v Oc^2 O^2 / ((O^2 + Or^2)(O^2 + Oc^2)(O^2 + Os^2))`, `Os = 0.4380` rad/m.
///
/// FRA: `4 k A_v Oc^2 / ((O^2 + Oc^2)(O^2 + Os^2))` cm^2/(rad/m), `k = 0.25`, already a height
/// difference, `Os = 0.8209` (class 5) / `0.4380` (class 6) rad/m.
///
/// The two families then agree in structure: `S_cl / S_v = 4 O^2 / (O^2 + Os^2)`, which tends to
/// 4 at short wavelengths (the two rails' vertical irregularities uncorrelated: the difference
/// of two independent rails has four times the PSD of their mean) and to 0 at long ones (rails
/// moving together). That agreement is the check on the `(2 b)^2` reading of the German units.
pub fn psd_cross_level(spec: Spectrum, omega: f64) -> f64 {
    let (_, a_v, o_s) = constants(spec);
    let o2 = omega * omega;
    if is_german(spec) {
        4.0 * a_v * GER_OC * GER_OC * o2
            / ((o2 + GER_OR * GER_OR) * (o2 + GER_OC * GER_OC) * (o2 + o_s * o_s))
    } else {
        CM2_TO_M2 * 4.0 * FRA_K * a_v * FRA_OC * FRA_OC
            / ((o2 + FRA_OC * FRA_OC) * (o2 + o_s * o_s))
    }
}
