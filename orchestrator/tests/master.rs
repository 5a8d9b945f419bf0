//! The master against analytic results, with the trivial test FMUs: Dahlquist (x' = -k x,
//! exact per step, no feedthrough) feeding Feedthrough (y = gain * u, direct feedthrough).

mod common;

use common::rows;

use orchestrator::master::{Algorithm, Cosimulation, Progress, RunError, RunOptions};
use orchestrator::system::{Component, Connection, Endpoint, Experiment, System, Value};

fn chain(gain: f64, fail_at: Option<f64>) -> System {
    let mut feed = vec![("gain".to_string(), Value::Real(gain))];
    if let Some(t) = fail_at {
        feed.push(("fail_at".into(), Value::Real(t)));
    }
    System {
        name: "chain".into(),
        components: vec![
            // Listed consumer first: the master must still step the producer first.
            Component {
                name: "feed".into(),
                source: common::fmu("Feedthrough"),
                parameters: feed,
            },
            Component {
                name: "dq".into(),
                source: common::fmu("Dahlquist"),
                parameters: vec![("k".into(), Value::Real(1.0))],
            },
        ],
        connections: vec![Connection {
            from: Endpoint::new("dq", "x"),
            to: Endpoint::new("feed", "u"),
            transform: None,
        }],
        experiment: Experiment::default(),
    }
}

fn options(dir: &std::path::Path, stop: f64, step: f64, algorithm: Algorithm) -> RunOptions {
    RunOptions {
        algorithm,
        out_dir: Some(dir.to_path_buf()),
        record: Some(vec![
            Endpoint::new("dq", "x"),
            Endpoint::new("feed", "y"),
            Endpoint::new("feed", "steps"),
        ]),
        ..RunOptions::new(0.0, stop, step)
    }
}

#[test]
fn gauss_seidel_passes_the_end_of_step_value_and_jacobi_the_start_of_step_value() {
    let cosim = Cosimulation::load(chain(2.0, None)).unwrap();
    assert_eq!(cosim.plan().order, vec![1, 0], "producer first");
    let h = 0.01;
    for (algorithm, lag) in [(Algorithm::GaussSeidel, 0.0), (Algorithm::Jacobi, h)] {
        let dir = tempfile::tempdir().unwrap();
        let summary = cosim.run(&options(dir.path(), 1.0, h, algorithm)).unwrap();
        assert_eq!(summary.steps, 100);
        let r = rows(&dir.path().join("results.csv"));
        assert_eq!(r.len(), 101);
        for (k, row) in r.iter().enumerate().skip(1) {
            let t = k as f64 * h;
            assert_eq!(row[0], t, "time column from integer ticks");
            assert!((row[1] - (-t).exp()).abs() < 1e-14, "x({t})");
            // y = 2 u, u = x at the end of the step (GS) or at its start (Jacobi).
            assert!(
                (row[2] - 2.0 * (-(t - lag)).exp()).abs() < 1e-14,
                "{algorithm:?}: y({t}) = {}",
                row[2]
            );
            assert_eq!(row[3], k as f64, "integer output recorded");
        }
    }
}

#[test]
fn initial_values_propagate_through_connections() {
    // Feedthrough's y is "calculated" in initialization mode from u, which the master sets
    // from Dahlquist's initial x = 1 (x0) before exiting initialization: y(0) = gain * 1.
    let cosim = Cosimulation::load(chain(3.0, None)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    cosim
        .run(&options(dir.path(), 0.1, 0.1, Algorithm::GaussSeidel))
        .unwrap();
    let r = rows(&dir.path().join("results.csv"));
    assert_eq!(r[0][0], 0.0);
    assert_eq!(r[0][2], 3.0);
}

#[test]
fn communication_points_do_not_drift_over_a_long_run() {
    let cosim = Cosimulation::load(chain(1.0, None)).unwrap();
    let mut opts = options(
        std::path::Path::new("/nonexistent"),
        1000.0,
        0.1,
        Algorithm::GaussSeidel,
    );
    opts.out_dir = None;
    let summary = cosim.run(&opts).unwrap();
    assert_eq!(summary.steps, 10_000);
    assert_eq!(summary.final_time, 1000.0);
}

#[test]
fn an_fmu_error_stops_the_run_and_keeps_the_results() {
    let cosim = Cosimulation::load(chain(1.0, Some(0.5))).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let err = cosim
        .run(&options(dir.path(), 1.0, 0.1, Algorithm::GaussSeidel))
        .unwrap_err();
    assert_eq!(err.exit_code(), 3);
    let text = err.to_string();
    assert!(
        text.contains("fmi2DoStep")
            && text.contains("'feed'")
            && text.contains("0.5")
            && text.contains("failing on purpose"),
        "{text}"
    );
    assert!(text.contains("results recorded until then"), "{text}");
    let r = rows(&dir.path().join("results.csv"));
    assert_eq!(r.last().unwrap()[0], 0.5, "rows up to the failure are kept");
}

/// The progress a run of `chain(1.0, fail_at)` for 2.5 s at 2^-10 s reports.
fn progress_of(fail_at: Option<f64>, progress: bool) -> (Vec<Progress>, Result<u64, RunError>) {
    let cosim = Cosimulation::load(chain(1.0, fail_at)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut opts = options(dir.path(), 2.5, 1.0 / 1024.0, Algorithm::GaussSeidel);
    opts.progress = progress;
    let mut seen = vec![];
    let summary = cosim.runner(&opts).progress(&mut |p| seen.push(p)).run();
    (seen, summary.map(|s| s.steps))
}

#[test]
fn progress_is_reported_in_order_up_to_the_stop_time_and_only_when_asked() {
    let (seen, steps) = progress_of(None, true);
    assert_eq!(steps.unwrap(), 2560);
    assert_eq!(
        seen,
        [
            Progress::Start { total: 2560 },
            Progress::Step { done: 1000 },
            Progress::Step { done: 2000 },
            Progress::End { done: 2560 },
        ]
    );
    let (seen, steps) = progress_of(None, false);
    assert_eq!(steps.unwrap(), 2560);
    assert_eq!(seen, [], "RunOptions::progress false: no report");
}

#[test]
fn progress_ends_where_a_failing_run_stopped() {
    // The step from t = 1.5 s (step 1536) fails.
    let (seen, result) = progress_of(Some(1.5), true);
    assert_eq!(result.unwrap_err().exit_code(), 3);
    assert_eq!(
        seen,
        [
            Progress::Start { total: 2560 },
            Progress::Step { done: 1000 },
            Progress::End { done: 1536 },
        ]
    );
}

#[test]
fn bad_systems_are_refused_before_running() {
    let loops = System {
        name: "ring".into(),
        components: vec![
            Component {
                name: "a".into(),
                source: common::fmu("Feedthrough"),
                parameters: vec![],
            },
            Component {
                name: "b".into(),
                source: common::fmu("Feedthrough"),
                parameters: vec![],
            },
        ],
        connections: vec![
            Connection {
                from: Endpoint::new("a", "y"),
                to: Endpoint::new("b", "u"),
                transform: None,
            },
            Connection {
                from: Endpoint::new("b", "y"),
                to: Endpoint::new("a", "u"),
                transform: None,
            },
        ],
        experiment: Experiment::default(),
    };
    let err = Cosimulation::load(loops).err().unwrap();
    assert_eq!(err.exit_code(), 2);
    let text = err.to_string();
    assert!(
        text.contains("algebraic loop") && text.contains("a.y") && text.contains("b.u"),
        "{text}"
    );

    let mut bad = chain(1.0, None);
    bad.connections[0].from = Endpoint::new("dq", "nope");
    let text = Cosimulation::load(bad).err().unwrap().to_string();
    assert!(
        text.contains("'dq'") && text.contains("'nope'") && text.contains("Dahlquist.fmu"),
        "{text}"
    );

    let mut cosim = Cosimulation::load(chain(1.0, None)).unwrap();
    assert!(matches!(
        cosim.set(&Endpoint::new("feed", "gain"), "abc"),
        Err(RunError::Resolve(_))
    ));
    assert!(
        cosim
            .set(&Endpoint::new("feed", "nothing"), "1")
            .unwrap_err()
            .to_string()
            .contains("'nothing'")
    );

    let dir = tempfile::tempdir().unwrap();
    let corrupt = dir.path().join("corrupt.fmu");
    std::fs::write(&corrupt, b"this is not a zip file").unwrap();
    let mut sys = chain(1.0, None);
    sys.components[0].source = corrupt.clone();
    let err = Cosimulation::load(sys).err().unwrap();
    assert_eq!(err.exit_code(), 2);
    assert!(err.to_string().contains("corrupt.fmu"), "{err}");

    let cosim = Cosimulation::load(chain(1.0, None)).unwrap();
    let err = cosim
        .run(&options(dir.path(), 1.0, 0.3, Algorithm::GaussSeidel))
        .unwrap_err();
    assert!(err.to_string().contains("whole number"), "{err}");
}
