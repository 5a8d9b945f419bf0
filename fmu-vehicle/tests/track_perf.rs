//! Generation and evaluation speed of the synthesized track. The budgets are asserted only in
//! optimized builds (`cargo test --release -p fmu-vehicle --test track_perf -- --nocapture`);
//! an unoptimized build only runs the code (briefly) and prints the timings.

use fmu_vehicle::track::{Track, TrackSpec};
use std::hint::black_box;
use std::time::Instant;

/// Generating 1 km of all three channels takes less than 100 ms (release; best of 5, so that
/// other tests running at the same time do not make it flaky).
#[test]
fn generate_one_km_all_channels() {
    let spec = TrackSpec::default();
    // Unoptimized builds only check that it runs, on a shorter stretch (~1 s per km there).
    let (runs, len) = if cfg!(debug_assertions) {
        (1, 100.0)
    } else {
        (5, 1000.0)
    };
    let mut best = f64::INFINITY;
    for seed in 0..runs {
        let spec = TrackSpec {
            seed,
            ..spec.clone()
        };
        let t0 = Instant::now();
        let track = black_box(Track::generate(&spec, 0.0, len));
        best = best.min(t0.elapsed().as_secs_f64());
        let (lo, hi) = track.range();
        assert!(lo <= 0.0 && hi >= len);
    }
    eprintln!(
        "generate {len} m (3 channels, in whole blocks of 51.2 m): {:.1} ms",
        1e3 * best
    );
    if !cfg!(debug_assertions) {
        assert!(best < 0.1, "{best} s");
    }
}

/// `at` costs well under a microsecond.
#[test]
fn evaluation_is_fast() {
    let (len, n) = if cfg!(debug_assertions) {
        (10.0, 10_000)
    } else {
        (500.0, 1_000_000)
    };
    let track = Track::generate(&TrackSpec::default(), 0.0, len);
    let t0 = Instant::now();
    let mut acc = 0.0;
    for i in 0..n {
        let irr = track.at(black_box(len * (i as f64 + 0.5) / n as f64));
        acc += irr.alignment_ds2 + irr.cross_level;
    }
    black_box(acc);
    let per_call = t0.elapsed().as_secs_f64() / n as f64;
    eprintln!("Track::at: {:.1} ns per call", 1e9 * per_call);
    if !cfg!(debug_assertions) {
        assert!(per_call < 1e-6, "{per_call} s");
    }
}
