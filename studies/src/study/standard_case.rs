//! The paper's standard case as a system: the shipped `standard.ssd` (vehicle -> estimator,
//! 20 s at 1 ms), read by the master's SSP reader with the studies' FMUs in place of its
//! sources. The file is compiled in, so the studies do not depend on where they are run from.

use crate::Error;
use orchestrator::ssp::{Sources, parse_ssd_with};
use orchestrator::system::System;
use std::path::Path;

/// The text of `studies/standard.ssd`.
pub const SSD: &str = include_str!("../../standard.ssd");

/// The standard case with these FMUs; components `vehicle` then `estimator`. The roll-rate
/// gyroscope's connection is dropped unless both FMUs have `ws_roll_rate`, so an older vehicle
/// or estimator without it still runs the paper's three sensors.
pub fn system(vehicle: &Path, estimator: &Path) -> Result<System, Error> {
    let sources = Sources::from([
        ("vehicle".to_string(), vehicle.to_path_buf()),
        ("estimator".to_string(), estimator.to_path_buf()),
    ]);
    let base = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut system = parse_ssd_with(SSD, base, &sources)
        .map_err(|e| Error::Input(format!("the standard case (standard.ssd): {e}")))?;
    if !both_have(vehicle, estimator, "ws_roll_rate") {
        system
            .connections
            .retain(|c| c.from.variable != "ws_roll_rate");
    }
    Ok(system)
}

/// Whether both FMUs declare a variable `name` (from their model descriptions only). An archive
/// that cannot be read counts as having it: loading the system then reports what is wrong.
fn both_have(a: &Path, b: &Path, name: &str) -> bool {
    [a, b]
        .iter()
        .all(|p| match orchestrator::info::read_archive(p) {
            Ok(archive) => archive.model_description.variable(name).is_some(),
            Err(_) => true,
        })
}
