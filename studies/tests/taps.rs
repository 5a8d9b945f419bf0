//! The shipped tap bank over conicities (`learned-conicity.taps`) is what `alignment-studies taps`
//! makes: the 20 m/s entries of three of
//! its conicities (the extremes and the vehicle's own, where the four-sensor taps are) at its
//! three Kalker scales (the contact model's quadratic in the conditions needs three of each),
//! regenerated here (training and validation runs of the packaged vehicle
//! FMU, the fit), equal the shipped file's, byte for byte. Each condition's taps are fitted on
//! that condition's runs alone, so a subset of the conditions regenerates its entries exactly;
//! the contact model, fitted over every condition, is left out of the comparison but for its
//! model spectra, which are each condition's own (the whole
//! bank, 21 conditions at eleven speeds, takes about half an hour; one speed and nine
//! conditions exercise every step of the fit).

mod common;

use alignment_studies::study::learned::taps::{Options, fit};
use fmu_estimator::learned::bank::Bank;
use std::path::Path;

#[test]
fn the_shipped_taps_are_regenerated_byte_for_byte() {
    let fmus = common::fmus();
    let shipped = Bank::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../fmu-estimator/resources/learned-conicity.taps"),
    )
    .unwrap();
    let mut o = Options::shipped();
    // The seeds the shipped bank was fitted and chosen on, as its command gave them.
    o.training_seed = shipped.provenance.training_seed;
    o.validation_seeds = shipped.provenance.validation_seeds.clone();
    o.contact_validation_seeds = shipped.provenance.contact_validation_seeds.clone();
    o.speeds = vec![20.0];
    o.conicities = vec![0.05, 0.1, 0.4];
    o.kalker_scales = vec![1.0, 0.75, 0.5];
    let mut made = fit(&fmus, &o, &|_| {}).unwrap();
    let mut want = shipped.clone();
    want.entries.retain(|e| {
        e.speed == 20.0
            && o.conicities.contains(&e.conicity.unwrap())
            && o.kalker_scales.contains(&e.condition.unwrap())
    });
    assert_eq!(want.entries.len(), 3 * 3 * 2 + 3 * 2, "entries compared");
    // The young memories' conicity models: one per fill, their validation error falling as the
    // memory fills, down towards the full memory's; at 50 m within 0.3 in ln(conicity) (0.23
    // here, where the full memory's model applied from the first cell is off by 0.26 on the
    // shipped bank's 21 conditions, 2.1 at 5 m).
    let model = made.contact.as_ref().unwrap().speeds[0]
        .conicity
        .clone()
        .unwrap();
    let fills: Vec<f64> = model.young.iter().map(|y| y.fill).collect();
    let memory = made.contact.as_ref().unwrap().memory;
    assert!(fills.len() >= 4 && fills[0] <= 10.0 && fills[fills.len() - 1] < memory);
    assert!(fills.windows(2).all(|w| w[1] > w[0]), "{fills:?}");
    let rms: Vec<f64> = model.young.iter().map(|y| y.rms_error).collect();
    assert!(rms.windows(2).all(|w| w[1] < w[0]), "{rms:?}");
    let at_50 = fills.iter().position(|f| *f == 50.0).unwrap();
    assert!(rms[at_50] < 0.3, "{rms:?}");
    assert!(
        rms[rms.len() - 1] > model.rms_error,
        "{rms:?} {}",
        model.rms_error
    );
    // The model spectra are each condition's own runs': those of the conditions fitted here
    // equal the shipped ones, number for number.
    let spectra = |b: &Bank| {
        b.contact
            .as_ref()
            .unwrap()
            .speeds
            .iter()
            .find(|s| s.speed == 20.0)
            .unwrap()
            .spectra
            .clone()
            .unwrap()
    };
    let (made_spectra, shipped_spectra) = (spectra(&made), spectra(&shipped));
    assert_eq!(made_spectra.conditions.len(), 9);
    let per = made_spectra.bins() * fmu_estimator::learned::spectral::PACKED;
    for (i, c) in made_spectra.conditions.iter().enumerate() {
        let j = shipped_spectra
            .conditions
            .iter()
            .position(|s| s == c)
            .unwrap();
        assert_eq!(
            made_spectra.values[i * per..(i + 1) * per],
            shipped_spectra.values[j * per..(j + 1) * per],
            "the spectra of condition {c:?}"
        );
    }
    // The parts that depend on the conditions fitted together, or on the command line.
    made.contact = None;
    want.contact = None;
    made.provenance = want.provenance.clone();
    assert_eq!(made.to_bytes(), want.to_bytes());
}
