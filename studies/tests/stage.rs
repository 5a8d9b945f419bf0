//! The shipped default bank's long-wave stage (`learned.taps`, `[stage]`) is what
//! `alignment-studies stage` makes: its 20 m/s entries (both sensor sets), fitted again here
//! from the shipped bank's own taps (training and validation runs of the packaged vehicle FMU,
//! the estimator over them, the least squares and the ridge's choice), equal the shipped ones
//! number for number. One speed exercises every step of the fit (the whole stage, eleven
//! speeds, takes about 5.5 min on 2 cores).

mod common;

use alignment_studies::study::learned::stage::{StageOptions, fit};
use fmu_estimator::learned::bank::Bank;
use std::path::Path;

#[test]
fn the_shipped_stage_is_regenerated_number_for_number() {
    let fmus = common::fmus();
    let shipped = Bank::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../fmu-estimator/resources/learned.taps"),
    )
    .unwrap();
    let mut o = StageOptions::shipped();
    o.speeds = vec![20.0];
    let made = fit(&fmus, &o, &shipped, &|_| {}).unwrap();
    let (made, shipped) = (made.stage.unwrap(), shipped.stage.unwrap());
    let want: Vec<_> = shipped
        .entries
        .iter()
        .filter(|e| e.speed == 20.0)
        .cloned()
        .collect();
    assert_eq!(
        want.len(),
        2,
        "three sensors, and with the roll-rate gyroscope"
    );
    assert_eq!(made.entries, want);
    // The stage was kept because it helped on the validation runs.
    for e in &want {
        assert!(
            e.validation[1] < 0.97 * e.validation[0],
            "{:?}",
            e.validation
        );
    }
}
