//! The robustness study's sensor table through the packaged FMUs on one held-out seed: the
//! oracle is the table's own ideal row. Told the priors, each bias and the tilt are removed at
//! the standstill to the ideal figures; told nothing they are not; the presets' errors cost the
//! 70-200 m band, where the yaw gyroscope's white noise enters.

mod common;

use alignment_studies::study::sensors::{SensorResult, run};

fn row<'a>(results: &'a [SensorResult], start: &str) -> &'a SensorResult {
    results
        .iter()
        .find(|r| r.condition.name.starts_with(start))
        .unwrap_or_else(|| panic!("no row {start}"))
}

#[test]
fn told_the_priors_the_estimator_removes_the_biases_at_the_standstill() {
    let fmus = common::fmus();
    let results = run(&fmus, &[3]).unwrap();
    let ideal = row(&results, "ideal");
    let whole = |m: &[alignment_studies::study::metrics::BandMetrics]| m[0].whole.jrel;
    for name in [
        "yaw gyro bias 1e-4",
        "yaw gyro bias 1e-3",
        "wheelset accelerometer bias",
        "both accelerometers tilted",
    ] {
        let r = row(&results, name);
        for (told, ideal) in [(&r.learned, &ideal.learned), (&r.paper, &ideal.paper)] {
            assert!(
                (whole(told) - whole(ideal)).abs() < 2e-3,
                "{name}: {} vs ideal {}",
                whole(told),
                whole(ideal)
            );
        }
    }
    let big = row(&results, "yaw gyro bias 1e-3");
    assert!(whole(&big.learned_untold) > 3.0 * whole(&ideal.learned_untold));
    let mems = row(&results, "MEMS preset (");
    assert!(mems.learned[0].d3.jrel > ideal.learned[0].d3.jrel);
    // Every learned row stays below the paper's filter in the whole band.
    for r in &results {
        assert!(whole(&r.learned) < whole(&r.paper), "{}", r.condition.name);
    }
}
