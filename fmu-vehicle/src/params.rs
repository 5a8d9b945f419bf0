//! Vehicle parameter sets, read from TOML files in the FMU's resources. Every value in those
//! files carries its source in a comment (`resources/ml95.toml`, `resources/manchester.toml`).
//! The files are also compiled into the library so that tests and tools work without the FMU's
//! resources directory.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// One wheelset: a rigid axle with two coned wheels (the `[wheelset]` table). SI units, as in the
/// vehicle files, which give each value's source.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wheelset {
    /// Mass of one wheelset \[kg\] (the paper's m).
    pub mass: f64,
    /// Moment of inertia about the vertical axis \[kg m2\] (the paper's I).
    pub yaw_inertia: f64,
    /// Moment of inertia about the track's longitudinal axis \[kg m2\].
    pub roll_inertia: f64,
    /// Moment of inertia about the axle \[kg m2\]: with the spin speed it gives the gyroscopic yaw
    /// moment of a rolling wheelset.
    pub spin_inertia: f64,
    /// Half the lateral distance between the two contact points \[m\] (the paper's l).
    pub half_gauge: f64,
    /// Wheel rolling radius r0 with the wheelset centred \[m\].
    pub rolling_radius: f64,
    /// Equivalent conicity \[-\] (the paper's alpha): the rolling-radius difference per metre of
    /// lateral displacement is 2 times it; with `half_gauge` and `rolling_radius` it sets Klingel's
    /// wavelength 2 pi sqrt(r0 l / conicity).
    pub conicity: f64,
    /// Transverse radius of the rail head \[m\], for the Hertz contact ellipse.
    pub rail_crown_radius: f64,
}

/// One bogie frame, carrying two wheelsets through the primary suspension (`[bogie]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bogie {
    /// Bogie frame mass \[kg\], without wheelsets.
    pub mass: f64,
    /// Frame moment of inertia about the longitudinal axis \[kg m2\].
    pub roll_inertia: f64,
    /// Frame moment of inertia about the lateral axis \[kg m2\].
    pub pitch_inertia: f64,
    /// Frame moment of inertia about the vertical axis \[kg m2\].
    pub yaw_inertia: f64,
    /// Half the distance between the bogie's two axles \[m\]; must be less than
    /// `CarBody::semi_bogie_distance`.
    pub semi_wheelbase: f64,
    /// Height of the frame's centre of gravity above the rail \[m\].
    pub cg_height: f64,
}

/// The car body, on two bogies through the secondary suspension (`[car_body]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CarBody {
    /// Car body mass \[kg\], without bogies and wheelsets.
    pub mass: f64,
    /// Body moment of inertia about the longitudinal axis \[kg m2\].
    pub roll_inertia: f64,
    /// Body moment of inertia about the lateral axis \[kg m2\].
    pub pitch_inertia: f64,
    /// Body moment of inertia about the vertical axis \[kg m2\].
    pub yaw_inertia: f64,
    /// Half the distance between the two bogie pivots \[m\].
    pub semi_bogie_distance: f64,
    /// Height of the body's centre of gravity above the rail \[m\].
    pub cg_height: f64,
}

/// A suspension stage: one element per side (primary: per axle box), stiffness and damping in
/// the track's x, y, z directions, at lateral +/- `semi_spacing` and `height` above the rail.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stage {
    /// Longitudinal stiffness of one element \[N/m\].
    pub kx: f64,
    /// Lateral stiffness of one element \[N/m\].
    pub ky: f64,
    /// Vertical stiffness of one element \[N/m\].
    pub kz: f64,
    /// Longitudinal damping of one element \[N s/m\].
    pub cx: f64,
    /// Lateral damping of one element \[N s/m\].
    pub cy: f64,
    /// Vertical damping of one element \[N s/m\].
    pub cz: f64,
    /// Lateral distance of each element from the centre line \[m\] (primary: the paper's l_s).
    pub semi_spacing: f64,
    /// Height of the elements above the rail \[m\]: where their forces act, so their lateral forces
    /// also roll the bodies.
    pub height: f64,
    /// Secondary only: rotational yaw stiffness per side [N m/rad].
    #[serde(default)]
    pub yaw_stiffness: f64,
    /// Secondary only: anti-roll bar per bogie [N m/rad].
    #[serde(default)]
    pub anti_roll: f64,
}

/// A whole vehicle file: one car with two bogies and four wheelsets. Unknown keys are refused
/// (a misspelt key would otherwise silently keep a default), and [`check`](Self::check) refuses
/// non-physical values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleParams {
    /// A label for messages and reports; not used in the equations.
    pub name: String,
    /// Each of the four wheelsets (all alike).
    pub wheelset: Wheelset,
    /// Each of the two bogie frames (alike).
    pub bogie: Bogie,
    /// The car body.
    pub car_body: CarBody,
    /// Wheelset to bogie frame, per axle box.
    pub primary: Stage,
    /// Bogie frame to car body, per bogie side.
    pub secondary: Stage,
}

/// `resources/ml95.toml`: the ML95-like metro car of the estimation study (the default).
pub const ML95_TOML: &str = include_str!("../resources/ml95.toml");
/// `resources/manchester.toml`: Manchester Benchmark vehicle 1 (Iwnicki 1998), a heavier
/// main-line car, for checking results do not hinge on one vehicle.
pub const MANCHESTER_TOML: &str = include_str!("../resources/manchester.toml");

impl VehicleParams {
    /// The built-in [`ML95_TOML`].
    pub fn ml95() -> VehicleParams {
        Self::parse(ML95_TOML, "ml95.toml").expect("the built-in ML95 file is valid")
    }

    /// The built-in [`MANCHESTER_TOML`].
    pub fn manchester() -> VehicleParams {
        Self::parse(MANCHESTER_TOML, "manchester.toml")
            .expect("the built-in Manchester file is valid")
    }

    /// Parses and [`check`](Self::check)s a vehicle file's text; errors start with `origin`
    /// (the file name) and name the offending key.
    pub fn parse(text: &str, origin: &str) -> Result<VehicleParams, String> {
        let p: VehicleParams =
            toml::from_str(text).map_err(|e| format!("vehicle file {origin}: {e}"))?;
        p.check()
            .map_err(|e| format!("vehicle file {origin}: {e}"))?;
        Ok(p)
    }

    /// Reads and [`parse`](Self::parse)s a vehicle file (at most 1 MiB).
    pub fn load(path: &Path) -> Result<VehicleParams, String> {
        // A vehicle file is a few kilobytes of TOML; 1 MiB leaves room for comments.
        let text = fmi_abi::resource::read_text(path, "vehicle file", 1 << 20)?;
        Self::parse(&text, &path.display().to_string())
    }

    /// The vehicle file the FMU's `vehicle` parameter names: an absolute path, a file in
    /// `resources` (the FMU's resources directory, if known), or one of the built-in files
    /// (`ml95.toml`, `manchester.toml`, which the FMU also ships).
    pub fn named(name: &str, resources: Option<&Path>) -> Result<VehicleParams, String> {
        let path = Path::new(name);
        if path.is_absolute() {
            return Self::load(path);
        }
        if let Some(dir) = resources {
            let p = dir.join(path);
            if p.exists() {
                return Self::load(&p);
            }
        }
        match name {
            "ml95.toml" | "ml95" => Ok(Self::ml95()),
            "manchester.toml" | "manchester" => Ok(Self::manchester()),
            other => Err(format!(
                "parameter 'vehicle': no vehicle file '{other}' in the resources (ml95.toml, manchester.toml) and not an absolute path"
            )),
        }
    }

    /// Masses, inertias and lengths must be positive; stiffness and damping non-negative.
    pub fn check(&self) -> Result<(), String> {
        let positive = [
            ("wheelset.mass", self.wheelset.mass),
            ("wheelset.yaw_inertia", self.wheelset.yaw_inertia),
            ("wheelset.roll_inertia", self.wheelset.roll_inertia),
            ("wheelset.spin_inertia", self.wheelset.spin_inertia),
            ("wheelset.half_gauge", self.wheelset.half_gauge),
            ("wheelset.rolling_radius", self.wheelset.rolling_radius),
            ("wheelset.conicity", self.wheelset.conicity),
            (
                "wheelset.rail_crown_radius",
                self.wheelset.rail_crown_radius,
            ),
            ("bogie.mass", self.bogie.mass),
            ("bogie.roll_inertia", self.bogie.roll_inertia),
            ("bogie.pitch_inertia", self.bogie.pitch_inertia),
            ("bogie.yaw_inertia", self.bogie.yaw_inertia),
            ("bogie.semi_wheelbase", self.bogie.semi_wheelbase),
            ("bogie.cg_height", self.bogie.cg_height),
            ("car_body.mass", self.car_body.mass),
            ("car_body.roll_inertia", self.car_body.roll_inertia),
            ("car_body.pitch_inertia", self.car_body.pitch_inertia),
            ("car_body.yaw_inertia", self.car_body.yaw_inertia),
            (
                "car_body.semi_bogie_distance",
                self.car_body.semi_bogie_distance,
            ),
            ("car_body.cg_height", self.car_body.cg_height),
            ("primary.semi_spacing", self.primary.semi_spacing),
            ("secondary.semi_spacing", self.secondary.semi_spacing),
        ];
        for (name, v) in positive {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("'{name}' = {v} must be a positive number"));
            }
        }
        for (stage, s) in [("primary", &self.primary), ("secondary", &self.secondary)] {
            for (name, v) in [
                ("kx", s.kx),
                ("ky", s.ky),
                ("kz", s.kz),
                ("cx", s.cx),
                ("cy", s.cy),
                ("cz", s.cz),
                ("yaw_stiffness", s.yaw_stiffness),
                ("anti_roll", s.anti_roll),
                ("height", s.height),
            ] {
                if !(v >= 0.0 && v.is_finite()) {
                    return Err(format!(
                        "'{stage}.{name}' = {v} must be a non-negative number"
                    ));
                }
            }
        }
        if self.bogie.semi_wheelbase >= self.car_body.semi_bogie_distance {
            return Err(
                "bogie.semi_wheelbase must be smaller than car_body.semi_bogie_distance".into(),
            );
        }
        Ok(())
    }

    /// The suspended mass one wheelset carries: a quarter car body plus half a bogie frame
    /// (the paper's m_f).
    pub fn suspended_mass_per_wheelset(&self) -> f64 {
        self.car_body.mass / 4.0 + self.bogie.mass / 2.0
    }

    /// The whole vehicle's mass \[kg\]: body, two bogie frames, four wheelsets.
    pub fn total_mass(&self) -> f64 {
        self.car_body.mass + 2.0 * self.bogie.mass + 4.0 * self.wheelset.mass
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ml95_is_consistent_with_the_paper_table_2() {
        let p = VehicleParams::ml95();
        assert_eq!(p.wheelset.mass, 1109.0);
        assert_eq!(p.wheelset.yaw_inertia, 606.0);
        assert_eq!(p.wheelset.half_gauge, 0.75);
        assert_eq!(p.wheelset.conicity, 0.1);
        assert_eq!(p.primary.semi_spacing, 0.85);
        assert!((p.suspended_mass_per_wheelset() - 3781.0).abs() < 1e-9);
    }

    #[test]
    fn both_sets_parse_and_bad_values_are_named() {
        assert_eq!(VehicleParams::manchester().car_body.mass, 32000.0);
        let bad = ML95_TOML.replace("mass = 2600.0", "mass = -1.0");
        let e = VehicleParams::parse(&bad, "x.toml").unwrap_err();
        assert!(e.contains("x.toml") && e.contains("bogie.mass"), "{e}");
        let unknown = ML95_TOML.replace("cg_height = 0.6", "cg_heigth = 0.6");
        assert!(
            VehicleParams::parse(&unknown, "y.toml")
                .unwrap_err()
                .contains("cg_heigth")
        );
    }
}
