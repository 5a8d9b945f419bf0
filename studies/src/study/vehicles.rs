//! The vehicles table: the estimators on vehicles other than the one the shipped taps were
//! fitted on (the ML95 at conicities 0.05-0.4, Kalker 50-100 %): the Manchester Benchmark
//! vehicle, and variants of the ML95 within the +-30-40 % the issue sets. None of them is used
//! for any choice of the shipped bank; they are evaluation vehicles.
//!
//! The variants are written as vehicle files (`VehicleParams` TOML) into a directory the
//! caller owns for the runs' duration, and given to the vehicle FMU by absolute path.

use super::cases::Case;
use crate::Error;
use fmu_vehicle::params::VehicleParams;
use orchestrator::system::Value;
use std::path::Path;

/// One vehicle of the table: its name, and how it differs from the ML95.
pub struct Variant {
    /// The name in the table.
    pub name: &'static str,
    /// The change to the ML95's parameters.
    pub change: fn(&mut VehicleParams),
}

/// The ML95 variants: suspensions, masses and geometry changed by 30-40 %, one kind at a time.
pub const VARIANTS: [Variant; 5] = [
    Variant {
        name: "ML95, lateral suspension -40 % (primary and secondary ky, cy)",
        change: |p| {
            for s in [&mut p.primary, &mut p.secondary] {
                s.ky *= 0.6;
                s.cy *= 0.6;
            }
        },
    },
    Variant {
        name: "ML95, primary longitudinal stiffness -40 % (wheelset yaw)",
        change: |p| p.primary.kx *= 0.6,
    },
    Variant {
        name: "ML95, car body +40 % (load)",
        change: |p| {
            p.car_body.mass *= 1.4;
            p.car_body.roll_inertia *= 1.4;
            p.car_body.pitch_inertia *= 1.4;
            p.car_body.yaw_inertia *= 1.4;
        },
    },
    Variant {
        name: "ML95, wheelsets and bogie frames +30 % mass and inertia",
        change: |p| {
            let w = &mut p.wheelset;
            w.mass *= 1.3;
            w.yaw_inertia *= 1.3;
            w.roll_inertia *= 1.3;
            w.spin_inertia *= 1.3;
            let b = &mut p.bogie;
            b.mass *= 1.3;
            b.roll_inertia *= 1.3;
            b.pitch_inertia *= 1.3;
            b.yaw_inertia *= 1.3;
        },
    },
    Variant {
        name: "ML95, bogie wheelbase +30 %",
        change: |p| {
            p.bogie.semi_wheelbase *= 1.3;
            p.bogie.yaw_inertia *= 1.3 * 1.3;
            p.bogie.pitch_inertia *= 1.3 * 1.3;
        },
    },
];

/// The table's cases, each vehicle estimated three ways as in the conicity sweep: the paper's
/// filter told the vehicle's conicity (`alpha`; its other parameters stay the ML95
/// calibration's), the learned filter told it (`conicity`), and the learned filter told
/// nothing. The variants' files are written into `dir`.
pub fn cases(dir: &Path) -> Result<Vec<Case>, Error> {
    let mut vehicles: Vec<(String, Option<String>, f64)> = vec![
        ("ML95".into(), None, VehicleParams::ml95().wheelset.conicity),
        (
            "Manchester Benchmark vehicle".into(),
            Some("manchester.toml".into()),
            VehicleParams::manchester().wheelset.conicity,
        ),
    ];
    for (i, v) in VARIANTS.iter().enumerate() {
        let mut p = VehicleParams::ml95();
        (v.change)(&mut p);
        p.name = v.name.to_string();
        p.check().map_err(Error::Input)?;
        let file = dir.join(format!("variant{i}.toml"));
        let text = toml::to_string(&p).map_err(|e| Error::input(e.to_string()))?;
        std::fs::write(&file, text)
            .map_err(|e| Error::input(format!("{}: {e}", file.display())))?;
        vehicles.push((
            v.name.to_string(),
            Some(file.to_string_lossy().into_owned()),
            p.wheelset.conicity,
        ));
    }
    let mut out = vec![];
    for (name, file, conicity) in vehicles {
        let vehicle: Vec<(String, Value)> = file
            .map(|f| vec![("vehicle".to_string(), Value::String(f))])
            .unwrap_or_default();
        let told = |e: i32, what: &str| {
            let mut v = vec![("estimator".to_string(), Value::Integer(e))];
            if e == 2 {
                v.push((
                    "tap_file".to_string(),
                    Value::String(super::cases::CONICITY_BANK.into()),
                ));
            }
            if !what.is_empty() {
                v.push((what.to_string(), Value::Real(conicity)));
            }
            v
        };
        for (how, estimator) in [
            ("paper's filter told its conicity", told(1, "alpha")),
            ("learned filter told its conicity", told(2, "conicity")),
            ("learned filter told nothing", told(2, "")),
        ] {
            out.push(Case {
                name: format!("{name}, {how}"),
                vehicle: vehicle.clone(),
                estimator,
                paper: None,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_variant_is_written_as_a_vehicle_file_the_fmu_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let cases = cases(dir.path()).unwrap();
        assert_eq!(cases.len(), 3 * (2 + VARIANTS.len()));
        for (i, v) in VARIANTS.iter().enumerate() {
            let read = VehicleParams::named(
                dir.path()
                    .join(format!("variant{i}.toml"))
                    .to_str()
                    .unwrap(),
                None,
            )
            .unwrap();
            let mut want = VehicleParams::ml95();
            (v.change)(&mut want);
            want.name = v.name.to_string();
            assert_eq!(read, want);
            // Each variant changes the vehicle beyond its name.
            let mut ml95 = VehicleParams::ml95();
            ml95.name = want.name.clone();
            assert_ne!(read, ml95, "{}", v.name);
        }
        // The Manchester vehicle is named by its file; the paper's filter is told its conicity.
        let m = &cases[3];
        assert!(m.name.starts_with("Manchester"));
        assert_eq!(
            m.estimator[1],
            (
                "alpha".to_string(),
                Value::Real(VehicleParams::manchester().wheelset.conicity)
            )
        );
    }
}
