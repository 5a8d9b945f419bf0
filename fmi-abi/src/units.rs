//! The units our FMUs use, with their SI base-unit exponents, so that every unit a variable
//! names is defined in UnitDefinitions (docs/references.md section 7.3).

use model_description::{BaseUnit, Unit};

/// (name, kg, m, s, rad)
const KNOWN: &[(&str, i32, i32, i32, i32)] = &[
    ("1", 0, 0, 0, 0),
    ("s", 0, 0, 1, 0),
    ("Hz", 0, 0, -1, 0),
    ("m", 0, 1, 0, 0),
    ("m/s", 0, 1, -1, 0),
    ("m/s2", 0, 1, -2, 0),
    ("m2/s", 0, 2, -1, 0),
    ("m2/s3", 0, 2, -3, 0),
    ("rad", 0, 0, 0, 1),
    ("rad/s", 0, 0, -1, 1),
    ("rad/s2", 0, 0, -2, 1),
    ("rad2/s", 0, 0, -1, 2),
    ("rad2/s3", 0, 0, -3, 2),
    ("rad/m", 0, -1, 0, 1),
    ("1/m", 0, -1, 0, 0),
    ("m.rad", 0, 1, 0, 1),
    ("kg", 1, 0, 0, 0),
    ("kg.m2", 1, 2, 0, 0),
    ("N", 1, 1, -2, 0),
    ("N.m", 1, 2, -2, 0),
    ("N.m2", 1, 3, -2, 0),
    ("N/m", 1, 0, -2, 0),
    ("N.s/m", 1, 0, -1, 0),
    ("N.m/rad", 1, 2, -2, -1),
    ("N.m.s/rad", 1, 2, -1, -1),
    ("Pa", 1, -1, -2, 0),
];

/// The UnitDefinitions entry for `name`, or `None` if it is not in our table.
pub fn unit(name: &str) -> Option<Unit> {
    let &(name, kg, m, s, rad) = KNOWN.iter().find(|u| u.0 == name)?;
    Some(Unit {
        name: name.to_string(),
        base_unit: Some(BaseUnit {
            kg,
            m,
            s,
            rad,
            ..BaseUnit::default()
        }),
        display_units: if name == "m" {
            vec![model_description::DisplayUnit {
                name: "mm".into(),
                factor: 0.001,
                offset: 0.0,
            }]
        } else {
            vec![]
        },
    })
}
