//! The learned FIR smoother on the real FMUs: fitted on the calibration seed, judged on a held-out
//! seed against the paper's D1 figure and against the Kalman smoother on the same record.

mod common;

use orchestrator::study::learned::{LearnedSmoother, Lookahead, SPLITS, kalman_estimate};
use orchestrator::study::{runs, variants};

#[test]
fn the_learned_smoother_beats_the_paper_in_d1_on_a_held_out_seed() {
    let fmus = runs::Fmus {
        vehicle: common::fmu("RailVehicle"),
        estimator: common::fmu("AlignmentEstimator"),
    };
    // A shorter training run than the study's (200 s against 1000 s) keeps the test quick.
    // As the study does: taps fitted after the first 20 s, the split chosen on those 20 s.
    let training = variants::record(&fmus, runs::seeded(101), 200.0, None).unwrap();
    let fit_part = training.tail((runs::STOP / runs::STEP) as usize);
    let validation = variants::record(&fmus, runs::seeded(101), runs::STOP, None).unwrap();
    let mut smoother = LearnedSmoother::train(&fit_part, Lookahead::Smoother).unwrap();
    let shaping = [("alignment_model".to_string(), "3".to_string())];
    let on_validation = kalman_estimate(&validation, &shaping, true).unwrap();
    let j = smoother.tune_split(&validation, &on_validation).unwrap();
    assert!(
        SPLITS.contains(&smoother.split) && j < 0.25,
        "split {} Jrel {j}",
        smoother.split
    );
    let held_out = variants::record(&fmus, runs::seeded(1), runs::STOP, None).unwrap();
    let kalman = kalman_estimate(&held_out, &shaping, true).unwrap();
    let (alone, hybrid) = smoother.evaluate(&held_out, &kalman).unwrap();
    let rts = variants::evaluate_variant(
        &held_out,
        &variants::Variant {
            name: "shaping RTS".into(),
            settings: shaping.to_vec(),
            smooth: true,
        },
        None,
    )
    .unwrap();
    let jrel = |m: &orchestrator::study::metrics::BandMetrics, b: &str| m.get(b).unwrap().jrel;
    // The paper's D1 Jrel is 0.48 (railway.md section 1); the Kalman smoother misses it on this
    // vehicle (cross-level, docs/cross-level.md).
    assert!(
        jrel(&alone, "D1") < 0.48,
        "learned D1 {}",
        jrel(&alone, "D1")
    );
    assert!(
        jrel(&hybrid, "D1") < 0.48,
        "hybrid D1 {}",
        jrel(&hybrid, "D1")
    );
    assert!(
        jrel(&hybrid, "D1") < 0.5 * jrel(&rts, "D1"),
        "hybrid D1 {} against the Kalman smoother's {}",
        jrel(&hybrid, "D1"),
        jrel(&rts, "D1")
    );
    // The hybrid keeps the Kalman smoother's long waves: D3 within 20 % of it.
    assert!(
        jrel(&hybrid, "D3") < 1.2 * jrel(&rts, "D3"),
        "hybrid D3 {} against {}",
        jrel(&hybrid, "D3"),
        jrel(&rts, "D3")
    );
    assert!(jrel(&hybrid, "whole") < jrel(&rts, "whole"));
    // The on-board variant: 20 m of look-ahead, causal filters, the paper's causal filter below
    // 40 m. Its D1 is still below the paper's; the causal split lets some of the Kalman
    // filter's D1 error through, so the hybrid's D1 is worse than the learned filter's alone.
    let lagged = LearnedSmoother::train(&fit_part, Lookahead::FixedLag(20)).unwrap();
    let paper = [("alignment_model".to_string(), "1".to_string())];
    let causal = kalman_estimate(&held_out, &paper, false).unwrap();
    let (lag_alone, lag_hybrid) = lagged.evaluate(&held_out, &causal).unwrap();
    assert!(
        jrel(&lag_alone, "D1") < 0.48,
        "lagged D1 {}",
        jrel(&lag_alone, "D1")
    );
    assert!(
        jrel(&lag_hybrid, "D1") < 0.48,
        "lagged hybrid D1 {}",
        jrel(&lag_hybrid, "D1")
    );
    assert!(
        jrel(&lag_hybrid, "whole") < 0.25,
        "lagged hybrid whole {}",
        jrel(&lag_hybrid, "whole")
    );
    // A record at another speed is refused by name.
    let mut slow = held_out.clone();
    for s in &mut slow.samples {
        s.speed = 10.0;
    }
    let e = smoother.estimate(&slow).unwrap_err();
    assert!(e.contains("trained at 20 m/s"), "{e}");
}
