//! Vehicle parameter sets, read from TOML files in the FMU's resources. Every value in those
//! files carries its source in a comment (`resources/ml95.toml`, `resources/manchester.toml`).
//! The files are also compiled into the library so that tests and tools work without the FMU's
//! resources directory.

use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wheelset {
    pub mass: f64,
    pub yaw_inertia: f64,
    pub roll_inertia: f64,
    pub spin_inertia: f64,
    pub half_gauge: f64,
    pub rolling_radius: f64,
    pub conicity: f64,
    pub rail_crown_radius: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bogie {
    pub mass: f64,
    pub roll_inertia: f64,
    pub pitch_inertia: f64,
    pub yaw_inertia: f64,
    pub semi_wheelbase: f64,
    pub cg_height: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CarBody {
    pub mass: f64,
    pub roll_inertia: f64,
    pub pitch_inertia: f64,
    pub yaw_inertia: f64,
    pub semi_bogie_distance: f64,
    pub cg_height: f64,
}

/// A suspension stage: one element per side (primary: per axle box), stiffness and damping in
/// the track's x, y, z directions, at lateral +/- `semi_spacing` and `height` above the rail.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stage {
    pub kx: f64,
    pub ky: f64,
    pub kz: f64,
    pub cx: f64,
    pub cy: f64,
    pub cz: f64,
    pub semi_spacing: f64,
    pub height: f64,
    /// Secondary only: rotational yaw stiffness per side [N m/rad].
    #[serde(default)]
    pub yaw_stiffness: f64,
    /// Secondary only: anti-roll bar per bogie [N m/rad].
    #[serde(default)]
    pub anti_roll: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleParams {
    pub name: String,
    pub wheelset: Wheelset,
    pub bogie: Bogie,
    pub car_body: CarBody,
    pub primary: Stage,
    pub secondary: Stage,
}

pub const ML95_TOML: &str = include_str!("../resources/ml95.toml");
pub const MANCHESTER_TOML: &str = include_str!("../resources/manchester.toml");

impl VehicleParams {
    pub fn ml95() -> VehicleParams {
        Self::parse(ML95_TOML, "ml95.toml").expect("the built-in ML95 file is valid")
    }

    pub fn manchester() -> VehicleParams {
        Self::parse(MANCHESTER_TOML, "manchester.toml")
            .expect("the built-in Manchester file is valid")
    }

    pub fn parse(text: &str, origin: &str) -> Result<VehicleParams, String> {
        let p: VehicleParams =
            toml::from_str(text).map_err(|e| format!("vehicle file {origin}: {e}"))?;
        p.check()
            .map_err(|e| format!("vehicle file {origin}: {e}"))?;
        Ok(p)
    }

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
