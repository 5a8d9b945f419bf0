//! The learned FIR estimator's cost, beside the Kalman filter's on the same samples in the same
//! run: `cargo bench -p alignment-studies --bench learned`. No FMU needed: the record is synthetic
//! noise at 20 m/s and 1 ms (the cost does not depend on the values).
//!
//! Printed, each the median of 5 runs over 200 s of samples (200 000 samples, 4 000 grid points):
//! - the learned smoother (60 m each way) and the fixed-lag form (20 m ahead): anti-alias filter,
//!   decimation and taps, per input sample and per 1 m grid point, without the hybrid's Kalman
//!   part;
//! - the paper's Kalman filter over the same samples (`fmu_estimator::offline`), per sample.

use alignment_studies::study::learned::synthetic::noise_record;
use alignment_studies::study::learned::{
    LearnedSmoother, Lookahead, SMOOTHER_GRID, default_partner,
};
use alignment_studies::study::runs::STEP;
use fmu_estimator::offline;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time(mut f: impl FnMut()) -> f64 {
    median(
        (0..5)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    )
}

fn main() {
    let train = noise_record(200.0, 1);
    let rec = noise_record(200.0, 11);
    let n = rec.samples.len() as f64;
    let kalman = vec![0.0; rec.samples.len()];
    let mut costs = vec![];
    for lookahead in [Lookahead::Smoother, Lookahead::FixedLag(20)] {
        let l = LearnedSmoother::train(
            &train,
            lookahead,
            SMOOTHER_GRID,
            default_partner(lookahead, 1.0),
            "bench",
        )
        .expect("training on noise");
        let points = n / l.decimation as f64;
        let t = time(|| {
            std::hint::black_box(l.apply(&rec.samples, STEP, &kalman).expect("apply"));
        });
        println!(
            "learned FIR {lookahead:?}: {:.1} ns per sample, {:.2} us per 1 m grid point ({:.1} ms for 200 s)",
            t / n * 1e9,
            t / points * 1e6,
            t * 1e3
        );
        costs.push(t);
    }
    let values = offline::settings(&[("alignment_model".into(), "1".into())]).expect("settings");
    let (config, _) = offline::config(&values, None).expect("config");
    let t = time(|| {
        std::hint::black_box(offline::process(&config, STEP, &rec.samples, false).expect("filter"));
    });
    println!(
        "paper's Kalman filter (offline library): {:.1} ns per sample ({:.1} ms for 200 s); learned smoother / Kalman filter: {:.2}, fixed lag / Kalman filter: {:.2}",
        t / n * 1e9,
        t * 1e3,
        costs[0] / t,
        costs[1] / t
    );
}
