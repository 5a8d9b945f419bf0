//! Wheel-rail contact: Hertz contact ellipse, Kalker's linear creep coefficients, their load
//! scaling, Shen-Hedrick-Elkins saturation and a dead-band flange stop.
//!
//! # What is modelled, and why this way
//!
//! The vehicle model follows the paper it reproduces (Muñoz, Ros, Escalona, *Estimation of
//! lateral track irregularity through Kalman filtering techniques*): coned wheels on
//! knife-edge rails, straight track, creep forces from Kalker's linear theory (the paper
//! cites Kalker 1982; the theory and its table: J. J. Kalker, *On the rolling contact of two
//! elastic bodies in the presence of dry friction*, thesis, TH Delft 1967, and
//! *Three-dimensional elastic bodies in rolling contact*, Kluwer 1990), with the creep
//! coefficients computed from the static wheel load. This module supplies the pieces:
//!
//! 1. **Normal contact** ([`hertz()`]): the Hertz ellipse for the principal curvatures at the
//!    contact. On straight track the principal directions of wheel and rail coincide (rolling
//!    and lateral), so `A, B` are half the curvature sums per direction; the ellipse equation
//!    is solved with complete elliptic integrals computed by the arithmetic-geometric mean
//!    ([`elliptic_k`], [`elliptic_e`]); formulas and references in the `hertz` submodule docs.
//!    Both bodies are steel of the same elastic constants ([`Material`]).
//! 2. **Kalker's coefficients** ([`kalker_c`], [`creep_coefficients`]): `f11 = G a b C11`,
//!    `f22 = G a b C22`, `f23 = G (ab)^1.5 C23`, `f33 = G (ab)^2 C33` with `G` the *shear*
//!    modulus (docs/references.md section 4; Kalker 1990). The `C`s are interpolated in Kalker's table
//!    (see below for the sources and the interpolation).
//! 3. **Load scaling** ([`CreepLaw`]): for a fixed geometry the ellipse shape does not depend
//!    on the load, and `a, b ~ N^(1/3)`; hence `f11, f22 ~ N^(2/3)`, `f23 ~ N`,
//!    `f33 ~ N^(4/3)`. The law is built once (Hertz solve + table lookup at a reference load)
//!    and evaluated in one cube root and a few multiplications inside the integrator. This is
//!    exact within Hertz + Kalker-linear, not an approximation; it assumes the contact point
//!    (so the curvatures) does not move on the profiles, which is the coned-tread,
//!    knife-edge assumption of the paper.
//! 4. **Saturation** ([`saturate`]): Shen, Hedrick & Elkins, "A comparison of alternative
//!    creep force models for rail vehicle dynamic analysis", Proc. 8th IAVSD Symposium
//!    (Cambridge MA, 1983), Swets & Zeitlinger 1984, pp. 591-605; as stated in docs/references.md
//!    section 4. The spin moment is scaled by the same factor as the forces (documented on
//!    [`saturate`]; a modelling choice).
//! 5. **Flange** ([`flange_force`]): the simplest stop, a dead band (about 9 mm) then a
//!    linear spring (10-15 MN/m) (docs/references.md section 4). The paper's estimator assumes no
//!    flange contact; the stop only keeps the simulated wheelset on the track.
//!
//! # Sign conventions
//!
//! Creepages and forces as in docs/references.md section 4: `Fx = -f11 nu_x`,
//! `Fy = -f22 nu_y - f23 phi`, `Mz = f23 nu_y - f33 phi`; the forces act on the wheel and
//! oppose the creepage. Lengths in m, forces in N.
//!
//! # Kalker's table: sources and interpolation
//!
//! - C11, C22, C23 at nu = 0, 0.25, 0.5: Kalker 1990, Table E.3, as transcribed in the
//!   open-source CONTACT program of Vollebregt & Kalker (github.com/eve70a/CONTACT,
//!   `src/m_hertz.f90`, subroutine `linrol`, Apache-2.0). A C++ port of that routine seen in
//!   another public repository has C23 = 1.15 at a/b = 0.8, nu = 0.25, a typo: the Fortran
//!   original and docs/references.md both give 1.25.
//! - C33 at nu = 0.25: docs/references.md section 4 (its rows a/b = 0.2 .. 1, b/a = 0.8 .. 0.2).
//!   C33 at nu = 0 and 0.5 and at the rows docs/references.md omits: Kalker's published table
//!   (Kalker 1967 thesis, reproduced in Kalker 1990 and in the rail-vehicle-dynamics
//!   textbooks), entered from that table; CONTACT does not carry C33 and no searchable public
//!   transcription of those entries was found, so they are the least verified numbers here.
//!   They are consistent with the worked example of docs/references.md (f33 = 34.5 N m^2 at nu = 0.3
//!   is reproduced to 0.3 %, which uses the nu = 0.5 column with weight 0.2), and every nu =
//!   0.25 entry agrees with docs/references.md.
//! - Interpolation: piecewise linear in `g = min(a/b, b/a)` on each half of the table (the
//!   variable in which the table has uniform steps; both halves share the circular row, so the
//!   result is continuous across a/b = 1), then linear in nu between the columns; rows and
//!   columns are reproduced exactly at the nodes. Outside the table (g < 0.1, nu outside
//!   [0, 0.5]) values are clamped. Details on [`kalker_c`].
//!
//! # Checks (tests in `fmu-vehicle/tests/contact*.rs`)
//!
//! - m, n = 2.731 / 0.493 at 30 deg and 1.486 / 0.717 at 60 deg;
//!   K(0.5) = 1.854074677, E(0.5) = 1.350643881.
//! - docs/references.md worked example (N 40 kN, r0 0.43 m, coned tread, crown 0.30 m, steel):
//!   a = 5.11 mm, b = 4.02 mm; f11 7.56 MN, f22 6.78 MN, f23 13.6 kN m, f33 34.5 N m^2 at
//!   nu = 0.3. This module gives a = 5.106 mm, b = 4.017 mm (a/b = 1.271), f11 = 7.612 MN
//!   (+0.7 %), f22 = 6.793 MN (+0.2 %), f23 = 13.62 kN m (+0.2 %), f33 = 34.39 N m^2 (-0.3 %).
//! - The ML95-like case of the paper (23 985 N per wheel, r0 0.425 m, coned tread, crown
//!   0.30 m, steel): a = 4.281 mm, b = 3.394 mm, f11 = 5.38e6 N, f22 = 4.80e6 N,
//!   f23 = 8.07e3 N m, f33 = 17.3 N m^2, against the paper's Table 2 5.5e6 / 5e6 / 9.3e3 / 15
//!   (see `tests/contact_report.rs`).

mod creep;
mod elliptic;
mod hertz;
mod kalker;

pub use creep::{CreepForces, Creepages, flange_force, linear_creep, saturate, she_factor};
pub use elliptic::{elliptic_e, elliptic_k};
pub use hertz::{ContactGeometry, Ellipse, Material, hertz, hertz_coefficients, try_hertz};
pub use kalker::{
    CreepCoefficients, CreepLaw, KALKER_TABLE_MIN_RATIO, creep_coefficients, kalker_c,
};

/// Invalid contact inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactError {
    /// Young's modulus not positive and finite, or Poisson's ratio outside (-1, 0.5).
    InvalidMaterial {
        /// Young's modulus \[Pa\].
        young: f64,
        /// Poisson's ratio.
        poisson: f64,
    },
    /// A curvature sum is not positive and finite: the contact is not Hertzian
    /// (conformal, concave beyond the rail crown, or a zero/NaN radius).
    InvalidGeometry {
        /// Curvature sum in the rolling direction \[1/m\].
        rolling_curvature: f64,
        /// Curvature sum in the lateral direction \[1/m\].
        lateral_curvature: f64,
    },
    /// A reference load that is not positive and finite.
    InvalidReferenceLoad(f64),
}

impl std::fmt::Display for ContactError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ContactError::InvalidMaterial { young, poisson } => write!(
                f,
                "invalid material: Young's modulus {young} Pa must be positive and finite, \
                 Poisson's ratio {poisson} must lie in (-1, 0.5)"
            ),
            ContactError::InvalidGeometry {
                rolling_curvature,
                lateral_curvature,
            } => write!(
                f,
                "non-Hertzian contact geometry: curvature sums {rolling_curvature} 1/m \
                 (rolling) and {lateral_curvature} 1/m (lateral) must both be positive and finite"
            ),
            ContactError::InvalidReferenceLoad(n) => {
                write!(f, "reference load {n} N must be positive and finite")
            }
        }
    }
}

impl std::error::Error for ContactError {}
