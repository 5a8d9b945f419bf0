//! The shipped tap bank is what `alignment-studies taps` makes: the 20 m/s entries regenerated
//! here (training and validation runs of the packaged vehicle FMU, the fit) equal the shipped
//! file's, byte for byte. The whole bank (eleven speeds) takes minutes; one speed exercises every
//! step of the fit.

mod common;

use alignment_studies::study::learned::taps::{Options, fit};
use alignment_studies::study::runs::Fmus;
use fmu_estimator::learned::bank::Bank;
use std::path::Path;

#[test]
fn the_shipped_taps_are_regenerated_byte_for_byte() {
    let fmus = Fmus::new(
        common::fmu("RailVehicle"),
        common::fmu("AlignmentEstimator"),
    );
    let shipped = Bank::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../fmu-estimator/resources/learned.taps"),
    )
    .unwrap();
    let mut o = Options::shipped();
    o.speeds = vec![20.0];
    let mut made = fit(&fmus, &o, &|_| {}).unwrap();
    let mut want = shipped.clone();
    want.entries.retain(|e| e.speed == 20.0);
    if let Some(c) = want.contact.as_mut() {
        c.speeds.retain(|m| m.speed == 20.0);
    }
    assert!(!want.entries.is_empty());
    made.provenance.command = want.provenance.command.clone();
    assert_eq!(made.to_bytes(), want.to_bytes());
}
