//! Kalker's linear theory: the coefficients C11, C22, C23, C33 and the creep coefficients
//! f11, f22, f23, f33, plus their load scaling ([`CreepLaw`]).

use serde::{Deserialize, Serialize};

use super::ContactError;
use super::hertz::{ContactGeometry, Ellipse, Material, try_hertz};

/// The Poisson ratios of the table columns.
const NU: [f64; 3] = [0.0, 0.25, 0.5];

/// One row of Kalker's table: `[C11, C22, C23, C33]`, each at nu = 0, 0.25, 0.5.
type Row = [[f64; 3]; 4];

/// Kalker's table for `a/b = g`, g = 0.1, 0.2, ..., 1.0 (contact ellipse shorter in the
/// rolling direction).
///
/// C11, C22, C23: Kalker (1990) Table E.3 as transcribed in the open-source CONTACT
/// (eve70a/CONTACT, `src/m_hertz.f90`, subroutine `linrol`, Apache-2.0).
/// C33: nu = 0.25 from docs/references.md section 4 (rows a/b = 0.2, 0.4, ..., 1.0 there); the other
/// entries from Kalker's published table (Kalker 1967 thesis / 1990 Table E.3) as reproduced
/// in the rail-dynamics textbooks; CONTACT's `linrol` does not carry C33, and no searchable
/// public transcription of those entries was found (see the module docs).
#[allow(clippy::approx_constant)] // 3.14 is a table entry, not pi
const A_SHORT: [Row; 10] = [
    // g = 0.1
    [
        [2.51, 3.31, 4.85],
        [2.51, 2.52, 2.53],
        [0.334, 0.473, 0.731],
        [6.42, 8.28, 11.7],
    ],
    // 0.2
    [
        [2.59, 3.37, 4.81],
        [2.59, 2.63, 2.66],
        [0.483, 0.603, 0.809],
        [3.46, 4.27, 5.66],
    ],
    // 0.3
    [
        [2.68, 3.44, 4.80],
        [2.68, 2.75, 2.81],
        [0.607, 0.715, 0.889],
        [2.49, 2.96, 3.72],
    ],
    // 0.4
    [
        [2.78, 3.53, 4.82],
        [2.78, 2.88, 2.98],
        [0.720, 0.823, 0.977],
        [2.02, 2.32, 2.77],
    ],
    // 0.5
    [
        [2.88, 3.62, 4.83],
        [2.88, 3.01, 3.14],
        [0.827, 0.929, 1.07],
        [1.74, 1.93, 2.22],
    ],
    // 0.6
    [
        [2.98, 3.72, 4.91],
        [2.98, 3.14, 3.31],
        [0.930, 1.03, 1.18],
        [1.56, 1.68, 1.86],
    ],
    // 0.7
    [
        [3.09, 3.81, 4.97],
        [3.09, 3.28, 3.48],
        [1.03, 1.14, 1.29],
        [1.43, 1.50, 1.60],
    ],
    // 0.8
    [
        [3.19, 3.91, 5.05],
        [3.19, 3.41, 3.65],
        [1.13, 1.25, 1.40],
        [1.34, 1.37, 1.42],
    ],
    // 0.9
    [
        [3.29, 4.01, 5.12],
        [3.29, 3.54, 3.82],
        [1.23, 1.36, 1.51],
        [1.27, 1.27, 1.27],
    ],
    // 1.0 (circle; shared with the other half)
    CIRCLE,
];

/// The circular contact, a/b = 1.
const CIRCLE: Row = [
    [3.40, 4.12, 5.20],
    [3.40, 3.67, 3.98],
    [1.33, 1.47, 1.63],
    [1.21, 1.19, 1.16],
];

/// Kalker's table for `b/a = g`, g = 0.1, 0.2, ..., 1.0 (contact ellipse longer in the rolling
/// direction, the usual case for a tread contact on a crowned rail head). Sources as for
/// [`A_SHORT`].
const B_SHORT: [Row; 10] = [
    // g = b/a = 0.1
    [
        [10.7, 11.7, 12.9],
        [10.7, 12.8, 16.0],
        [12.2, 14.6, 18.0],
        [0.795, 0.526, 0.228],
    ],
    // 0.2
    [
        [6.96, 7.78, 8.82],
        [6.96, 8.14, 9.79],
        [5.72, 6.63, 7.89],
        [0.828, 0.601, 0.341],
    ],
    // 0.3
    [
        [5.57, 6.34, 7.34],
        [5.57, 6.40, 7.51],
        [3.79, 4.32, 5.01],
        [0.868, 0.674, 0.446],
    ],
    // 0.4
    [
        [4.84, 5.57, 6.57],
        [4.84, 5.48, 6.31],
        [2.88, 3.24, 3.70],
        [0.912, 0.747, 0.549],
    ],
    // 0.5
    [
        [4.37, 5.10, 6.11],
        [4.37, 4.90, 5.56],
        [2.35, 2.62, 2.96],
        [0.958, 0.819, 0.650],
    ],
    // 0.6
    [
        [4.06, 4.78, 5.80],
        [4.06, 4.50, 5.04],
        [2.01, 2.23, 2.50],
        [1.01, 0.892, 0.751],
    ],
    // 0.7
    [
        [3.82, 4.54, 5.58],
        [3.82, 4.21, 4.67],
        [1.76, 1.95, 2.18],
        [1.05, 0.965, 0.852],
    ],
    // 0.8
    [
        [3.65, 4.36, 5.42],
        [3.65, 3.99, 4.39],
        [1.58, 1.75, 1.94],
        [1.10, 1.04, 0.954],
    ],
    // 0.9
    [
        [3.51, 4.22, 5.30],
        [3.51, 3.81, 4.16],
        [1.44, 1.59, 1.77],
        [1.16, 1.11, 1.06],
    ],
    // 1.0
    CIRCLE,
];

/// Smallest tabulated g = min(a/b, b/a); below it the coefficients are held at the g = 0.1
/// row (see [`kalker_c`]).
pub const KALKER_TABLE_MIN_RATIO: f64 = 0.1;

/// Kalker's linear-theory coefficients `[C11, C22, C23, C33]` for the semi-axis ratio `a/b`
/// (a in the rolling direction) and Poisson's ratio `poisson`.
///
/// Interpolation (all piecewise linear, so that the tabulated values are reproduced exactly
/// at the nodes and the result is continuous):
/// - in `g = min(a/b, b/a)` on each half of the table separately (`a/b <= 1`: the rows
///   a/b = 0.1 .. 1; `a/b > 1`: the rows b/a = 0.1 .. 1). Both halves share the circular row,
///   so the result is continuous across a/b = 1, and the table's own monotonicity in a/b is
///   preserved (C11, C22, C23 increase with a/b, C33 decreases; the one exception is C11 at
///   nu near 0.5 for a/b < 0.3, where Kalker's column itself dips by 1 %). `g` is the
///   variable the table is tabulated in with uniform steps, so linear interpolation in it is
///   the natural choice; interpolating in a/b across the whole range would stretch the
///   b/a-half over 1..10;
/// - for `g < 0.1` (a/b < 0.1 or a/b > 10) the g = 0.1 row is used (clamped; such slender
///   ellipses do not occur for tread contact, and the asymptotic formulas Kalker gives for
///   g -> 0 cover C11, C22, C23 only);
/// - linearly in `nu` between the columns nu = 0, 0.25, 0.5; `nu` outside [0, 0.5] is clamped.
///   (CONTACT interpolates a parabola in 1/C through the three columns instead; at
///   nu = 0.3 and a/b = 1.26 that gives C11 0.8 % lower and C22, C23, C33 within 0.2 %;
///   `tests/contact_report.rs` prints the comparison.)
///
/// `a_over_b` must be positive; NaN propagates.
pub fn kalker_c(a_over_b: f64, poisson: f64) -> [f64; 4] {
    if a_over_b.is_nan() || poisson.is_nan() {
        return [f64::NAN; 4];
    }
    debug_assert!(a_over_b > 0.0, "a/b = {a_over_b} must be positive");
    let (table, g) = if a_over_b <= 1.0 {
        (&A_SHORT, a_over_b)
    } else {
        (&B_SHORT, 1.0 / a_over_b)
    };
    // Rows are at x = 10 g = 1, 2, ..., 10.
    let x = (10.0 * g).clamp(1.0, 10.0);
    let i = (x.floor() as usize).clamp(1, 9); // interval [i, i + 1]
    let w = x - i as f64;
    let (lo, hi) = (&table[i - 1], &table[i]);

    let nu = poisson.clamp(NU[0], NU[2]);
    let (j, t) = if nu <= NU[1] {
        (0, (nu - NU[0]) / (NU[1] - NU[0]))
    } else {
        (1, (nu - NU[1]) / (NU[2] - NU[1]))
    };

    let mut c = [0.0; 4];
    for (q, out) in c.iter_mut().enumerate() {
        let at = |row: &Row| (1.0 - t) * row[q][j] + t * row[q][j + 1];
        *out = (1.0 - w) * at(lo) + w * at(hi);
    }
    c
}

/// Kalker's creep coefficients of one contact.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct CreepCoefficients {
    /// Longitudinal \[N\].
    pub f11: f64,
    /// Lateral \[N\].
    pub f22: f64,
    /// Lateral/spin \[N m\].
    pub f23: f64,
    /// Spin \[N m^2\].
    pub f33: f64,
}

impl CreepCoefficients {
    /// All coefficients multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> CreepCoefficients {
        CreepCoefficients {
            f11: self.f11 * factor,
            f22: self.f22 * factor,
            f23: self.f23 * factor,
            f33: self.f33 * factor,
        }
    }
}

/// f11 = G a b C11, f22 = G a b C22, f23 = G (ab)^1.5 C23, f33 = G (ab)^2 C33, with G the
/// shear modulus and the C's from [`kalker_c`] at a/b and the material's Poisson ratio.
///
/// An empty ellipse (a or b <= 0) gives zero coefficients.
pub fn creep_coefficients(ellipse: Ellipse, mat: &Material) -> CreepCoefficients {
    if ellipse.a.is_nan() || ellipse.b.is_nan() || ellipse.a <= 0.0 || ellipse.b <= 0.0 {
        return CreepCoefficients::default();
    }
    let [c11, c22, c23, c33] = kalker_c(ellipse.a / ellipse.b, mat.poisson);
    let g = mat.shear_modulus();
    let ab = ellipse.a * ellipse.b;
    let sqrt_ab = ab.sqrt();
    CreepCoefficients {
        f11: g * ab * c11,
        f22: g * ab * c22,
        f23: g * ab * sqrt_ab * c23,
        f33: g * ab * ab * c33,
    }
}

/// Creep coefficients as a function of the normal load, for a fixed geometry and material.
///
/// For a fixed geometry the Hertz ellipse keeps its shape (a/b, hence the C's) and both
/// semi-axes grow as N^(1/3), so `f11, f22 ~ N^(2/3)`, `f23 ~ N`, `f33 ~ N^(4/3)`. The law
/// stores the coefficients at one reference load and evaluates any other load with one cube
/// root and a few multiplications ([`CreepLaw::at_load`]), instead of solving the Hertz
/// equation and interpolating Kalker's table at every right-hand-side evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CreepLaw {
    reference_load: f64,
    reference: CreepCoefficients,
}

impl CreepLaw {
    /// Builds the law from the Hertz contact at `reference_load` \[N\] (any positive load gives
    /// the same law up to rounding; the static wheel load is the natural choice).
    ///
    /// # Panics
    /// On an invalid geometry, material or reference load (see [`CreepLaw::try_new`]).
    pub fn new(geom: &ContactGeometry, mat: &Material, reference_load: f64) -> CreepLaw {
        match CreepLaw::try_new(geom, mat, reference_load) {
            Ok(law) => law,
            Err(err) => panic!("CreepLaw::new: {err}"),
        }
    }

    /// [`CreepLaw::new`] returning an error instead of panicking.
    pub fn try_new(
        geom: &ContactGeometry,
        mat: &Material,
        reference_load: f64,
    ) -> Result<CreepLaw, ContactError> {
        check_load(reference_load)?;
        let ellipse = try_hertz(geom, mat, reference_load)?;
        Ok(CreepLaw {
            reference_load,
            reference: creep_coefficients(ellipse, mat),
        })
    }

    /// A law through given coefficients at a given load (e.g. a paper's table of creep
    /// coefficients at the static wheel load), scaled with the Hertz exponents.
    pub fn from_coefficients(
        reference: CreepCoefficients,
        reference_load: f64,
    ) -> Result<CreepLaw, ContactError> {
        check_load(reference_load)?;
        Ok(CreepLaw {
            reference_load,
            reference,
        })
    }

    /// The reference load \[N\].
    pub fn reference_load(&self) -> f64 {
        self.reference_load
    }

    /// The coefficients at the reference load.
    pub fn reference_coefficients(&self) -> CreepCoefficients {
        self.reference
    }

    /// The creep coefficients at `normal_load` \[N\]; zero for `normal_load <= 0` or NaN
    /// (wheel lift).
    #[inline]
    pub fn at_load(&self, normal_load: f64) -> CreepCoefficients {
        if normal_load.is_nan() || normal_load <= 0.0 {
            return CreepCoefficients::default();
        }
        let r = normal_load / self.reference_load;
        let s = r.cbrt();
        let s2 = s * s;
        CreepCoefficients {
            f11: self.reference.f11 * s2,
            f22: self.reference.f22 * s2,
            f23: self.reference.f23 * r,
            f33: self.reference.f33 * (s2 * s2),
        }
    }

    /// The same law with every coefficient multiplied by `factor` (the study's
    /// "Kalker coefficients -50 %" case is `scaled(0.5)`).
    pub fn scaled(&self, factor: f64) -> CreepLaw {
        CreepLaw {
            reference_load: self.reference_load,
            reference: self.reference.scaled(factor),
        }
    }
}

fn check_load(load: f64) -> Result<(), ContactError> {
    if load.is_finite() && load > 0.0 {
        Ok(())
    } else {
        Err(ContactError::InvalidReferenceLoad(load))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nu_zero_column_has_c11_equal_c22() {
        // At nu = 0 the longitudinal and lateral problems coincide (Kalker's table).
        for row in A_SHORT.iter().chain(B_SHORT.iter()) {
            assert_eq!(row[0][0], row[1][0]);
        }
    }

    #[test]
    fn interval_selection_at_the_nodes() {
        for (i, row) in A_SHORT.iter().enumerate() {
            let g = (i + 1) as f64 / 10.0;
            let c = kalker_c(g, 0.25);
            for q in 0..4 {
                assert!((c[q] - row[q][1]).abs() <= 1e-14 * row[q][1], "{g} {q}");
            }
        }
    }
}
