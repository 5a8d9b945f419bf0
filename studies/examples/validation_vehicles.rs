#![allow(clippy::result_large_err)]
//! The vehicle files the estimator's gates on other vehicles were chosen on (the conicity
//! likelihood's share: `fmu-estimator/src/learned/spectral.rs`): the ML95 changed in one kind
//! (`VALIDATION_VARIANTS`) and a random family (`VALIDATION_FAMILY`), none an evaluation
//! vehicle.
//!
//! `cargo run --release -p alignment-studies --example validation_vehicles -- DIR` writes
//! `DIR/kind*.toml` and `DIR/family*.toml` into a new or empty `DIR`, and prints each file with
//! its vehicle's name. `tests/conicity_estimate_probe.py --vehicles DIR` runs them.

use alignment_studies::study::vehicles::{
    VALIDATION_FAMILY, VALIDATION_VARIANTS, family, variant, write,
};
use fmu_vehicle::params::VehicleParams;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().ok_or("usage: validation_vehicles DIR")?);
    if args.next().is_some() {
        return Err("usage: validation_vehicles DIR (one argument)".into());
    }
    // Files this program did not write are never replaced.
    let named = |e: std::io::Error| format!("{}: {e}", dir.display());
    if dir.exists() && std::fs::read_dir(&dir).map_err(named)?.next().is_some() {
        return Err(format!(
            "{}: not empty; give a new or empty directory",
            dir.display()
        )
        .into());
    }
    std::fs::create_dir_all(&dir).map_err(named)?;
    let kinds: Vec<VehicleParams> = VALIDATION_VARIANTS.iter().map(variant).collect();
    let (seed, n) = VALIDATION_FAMILY;
    let members = family(&VehicleParams::ml95(), seed, n);
    for (vehicles, stem) in [(&kinds, "kind"), (&members, "family")] {
        for (p, file) in vehicles.iter().zip(write(vehicles, &dir, stem)?) {
            println!("{file}\t{}", p.name);
        }
    }
    Ok(())
}
