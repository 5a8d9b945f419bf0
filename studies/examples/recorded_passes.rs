#![allow(clippy::result_large_err)]
//! Synthetic recordings for `alignment-studies fit --recordings`: passes of the vehicle FMU
//! over one line (track seed 101) at mixed speeds, each with a start offset and a distance
//! scale error of its own, and the line's reference alignment.
//!
//! `cargo run --release -p alignment-studies --example recorded_passes -- DIR [LENGTH_M]`
//! writes `DIR/reference.csv` and `DIR/pass*.csv` (and prints each pass's true offset and
//! scale). `--set vehicle.NAME=VALUE`-like settings: the environment variable `VEHICLE`
//! (a vehicle file for the FMU's `vehicle` parameter).

use alignment_studies::study::learned::recorded::synthetic::{write_pass, write_reference};
use alignment_studies::study::records::record;
use alignment_studies::study::runs::{Fmus, seeded};
use orchestrator::system::Value;
use std::path::PathBuf;

/// Speed (m/s), start offset (m), distance scale of each pass: offsets up to 20 m and scale
/// errors of 0.5 %, as a train's odometry.
const PASSES: [(f64, f64, f64); 4] = [
    (15.0, 14.2, 1.005),
    (20.0, -18.6, 0.995),
    (20.0, 7.1, 1.003),
    (25.0, -9.4, 0.996),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().ok_or("usage: recorded_passes DIR [LENGTH_M]")?);
    let length: f64 = args
        .next()
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(5000.0);
    std::fs::create_dir_all(&dir)?;
    let mut fmus = Fmus::new(
        "target/fmu/RailVehicle.fmu".into(),
        "target/fmu/AlignmentEstimator.fmu".into(),
    );
    if let Ok(v) = std::env::var("VEHICLE") {
        fmus.set("vehicle", "vehicle", &v)?;
    }
    let run = |speed: f64, noise: i32, extra: f64| {
        let mut s = seeded(101);
        s[1].1 = Value::Integer(noise);
        let stop = ((length + extra) / speed).ceil();
        record(&fmus, s, stop, Some(&move |_| speed))
    };
    write_reference(&run(20.0, 5001, 100.0)?, None, &dir.join("reference.csv"))?;
    for (i, (speed, offset, scale)) in PASSES.iter().enumerate() {
        let file = dir.join(format!("pass{i}.csv"));
        write_pass(&run(*speed, 6000 + i as i32, 0.0)?, *offset, *scale, &file)?;
        println!(
            "{}: {speed} m/s, true position = recorded start - {offset} + (odometry from the start) / {scale}",
            file.display()
        );
    }
    Ok(())
}
