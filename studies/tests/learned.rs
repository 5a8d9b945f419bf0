//! The learned FIR smoother on the real FMUs: fitted on the calibration seed, judged on a held-out
//! seed against the paper's D1 figure and against the Kalman smoother on the same record; saved
//! and read back.

mod common;

use alignment_studies::study::learned::{
    LearnedSmoother, Lookahead, SMOOTHER_GRID, SPLITS, default_partner, learn, training_runs,
};
use alignment_studies::study::{runs, variants};

#[test]
fn the_learned_smoother_beats_the_paper_in_d1_on_a_held_out_seed() {
    let fmus = common::fmus();
    // As the study does, with a shorter training run (200 s against 1000 s) to keep it quick.
    let smoother_partner = default_partner(Lookahead::Smoother, 1.0);
    let (runs, provenance) = training_runs(&fmus, 101, 200.0, &[1.0], None).unwrap();
    let (smoother, j) = learn(
        &runs,
        &provenance,
        Lookahead::Smoother,
        SMOOTHER_GRID,
        smoother_partner.clone(),
    )
    .unwrap();
    assert!(
        SPLITS.contains(&smoother.split) && j < 0.25,
        "split {} Jrel {j}",
        smoother.split
    );
    let held_out = variants::record(&fmus, runs::seeded(1), runs::STOP, None).unwrap();
    let (alone, hybrid) = smoother.evaluate(&held_out).unwrap();
    let rts = variants::evaluate_variant(
        &held_out,
        &variants::Variant {
            name: smoother_partner.name.clone(),
            settings: smoother_partner.settings.clone(),
            smooth: true,
            output: variants::Output::Alignment,
        },
        None,
    )
    .unwrap();
    use alignment_studies::study::metrics::BandMetrics;
    let jrel = |m: &BandMetrics, b: &str| m.get(b).unwrap().jrel;
    let below = |what: &str, m: &BandMetrics, band: &str, bound: f64| {
        let j = jrel(m, band);
        assert!(j < bound, "{what} {band} Jrel {j}, bound {bound}");
    };
    // The paper's D1 Jrel is 0.48 (docs/references.md section 1); the Kalman smoother misses it on this
    // vehicle (cross-level, docs/cross-level.md).
    below("learned", &alone, "D1", 0.48);
    below("hybrid", &hybrid, "D1", 0.48);
    below("hybrid", &hybrid, "D1", 0.5 * jrel(&rts, "D1"));
    // The hybrid keeps the Kalman smoother's long waves: D3 within 20 % of it.
    below("hybrid", &hybrid, "D3", 1.2 * jrel(&rts, "D3"));
    below("hybrid", &hybrid, "whole", jrel(&rts, "whole"));

    // The on-board variant: 20 m of look-ahead, causal filters, the paper's causal filter for
    // the long waves. Its D1 is still below the paper's; the causal split lets some of the
    // Kalman filter's D1 error through, so the hybrid's D1 is worse than the learned filter's.
    let lag = Lookahead::FixedLag(20);
    let (lagged, _) = learn(
        &runs,
        &provenance,
        lag,
        SMOOTHER_GRID,
        default_partner(lag, 1.0),
    )
    .unwrap();
    let (lag_alone, lag_hybrid) = lagged.evaluate(&held_out).unwrap();
    below("lagged", &lag_alone, "D1", 0.48);
    below("lagged hybrid", &lag_hybrid, "D1", 0.48);
    below("lagged hybrid", &lag_hybrid, "whole", 0.25);

    // Saved and read back, it gives the same estimates to the bit.
    let path = std::path::Path::new("learned.json");
    let back = LearnedSmoother::from_json(&smoother.to_json(), path).unwrap();
    let k = smoother.kalman(&held_out.samples, runs::STEP).unwrap();
    assert_eq!(
        back.apply(&held_out.samples, runs::STEP, &k).unwrap(),
        smoother.apply(&held_out.samples, runs::STEP, &k).unwrap()
    );

    // Bad training requests are refused before any run.
    let e = training_runs(&fmus, 101, 30.0, &[1.0], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("longer than 40 s"), "{e}");
    let e = training_runs(&fmus, 101, 200.0, &[], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("Kalker scales"), "{e}");
    let e = training_runs(&fmus, 101, 200.0, &[1.0, -0.5], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("-0.5"), "{e}");
    let e = training_runs(&fmus, 101, 200.0, &[1.0], Some(f64::NAN))
        .unwrap_err()
        .to_string();
    assert!(e.contains("training speed"), "{e}");
    // A record at another speed or step is refused by name.
    let mut slow = held_out.samples.clone();
    for s in &mut slow {
        s.speed = 10.0;
    }
    let e = smoother
        .apply(&slow, runs::STEP, &k)
        .unwrap_err()
        .to_string();
    assert!(e.contains("trained at 20 m/s"), "{e}");
    let e = smoother
        .apply(&held_out.samples, 2e-3, &k)
        .unwrap_err()
        .to_string();
    assert!(e.contains("step of 0.001 s"), "{e}");
}
