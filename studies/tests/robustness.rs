//! The paper's robustness and resonance cases run through the packaged FMUs for both estimators:
//! every case the demo's `alignment-studies all` runs must initialize, including those that tell
//! the learned filter's Kalman channel a wrong conicity (an approximate use the case asks for,
//! `allow_other_kalman`), and the wrong conicity must reach the filter.

mod common;

use alignment_studies::study::cases;

#[test]
fn every_robustness_case_runs_with_both_estimators_and_the_told_conicity_reaches_them() {
    let fmus = common::fmus();
    let seed = 1; // a held-out seed; nothing is chosen here
    let stop = 6.0; // 120 m at 20 m/s: past the learned filter's start-up, enough to differ
    let all = cases::with_learned(cases::robustness(0.1));
    let standard: Vec<_> = all
        .iter()
        .filter(|c| c.name.starts_with("standard"))
        .map(|c| cases::run_seed_until(&fmus, c, seed, stop).unwrap())
        .collect();
    assert_eq!(standard.len(), 2, "the standard case and its learned twin");
    let told: Vec<_> = all
        .iter()
        .filter(|c| c.name.starts_with("conicity -10 % in the filter"))
        .filter(|c| !c.name.contains("no vertical"))
        .collect();
    assert_eq!(told.len(), 2, "the paper's filter and the learned one");
    for (case, standard) in told.iter().zip(&standard) {
        let m = cases::run_seed_until(&fmus, case, seed, stop)
            .unwrap_or_else(|e| panic!("{}: {e}", case.name));
        assert!(m.whole.jrel.is_finite(), "{}: {:?}", case.name, m.whole);
        assert!(
            (m.whole.jrel - standard.whole.jrel).abs() > 1e-6,
            "{}: whole Jrel {} as in the standard case: the told conicity did not reach the filter",
            case.name,
            m.whole.jrel
        );
    }
}

#[test]
fn the_conicity_sweep_runs_the_learned_filter_told_a_worn_wheel_s_conicity() {
    // The learned filter told the conicity (its `conicity` parameter) blends the taps at it
    // instead of at the one it estimates: it must initialize, and telling it must change its
    // estimate.
    let fmus = common::fmus();
    let bank = cases::conicity_bank().unwrap();
    let sweep = cases::conicity_sweep(&bank);
    let at = |name: &str| sweep.iter().find(|c| c.name == name).unwrap();
    let told = cases::run_seed_until(
        &fmus,
        at("conicity 0.3, Kalker 100 %, learned filter told it"),
        1,
        6.0,
    )
    .unwrap();
    let blind = cases::run_seed_until(
        &fmus,
        at("conicity 0.3, Kalker 100 %, learned filter told nothing"),
        1,
        6.0,
    )
    .unwrap();
    assert!(told.whole.jrel.is_finite() && blind.whole.jrel.is_finite());
    assert!(
        (told.whole.jrel - blind.whole.jrel).abs() > 1e-6,
        "told {} and told nothing {} alike",
        told.whole.jrel,
        blind.whole.jrel
    );
}
