//! The master's pluggable seams, against the trivial test FMUs (Dahlquist: x' = -k x, exact
//! per step; Feedthrough: y = gain * u, and n_in, flag_in passed to n_out, flag_out at each
//! step): observers, external inputs addressed by component, the per-run stop token, and the
//! system and plan kept in step.

// RunError is large (it carries the FMU's messages), as in the library; a test returns it once.
#![allow(clippy::result_large_err)]

mod common;

use common::rows;

use orchestrator::master::{
    Address, Cosimulation, End, Flow, ObserveError, Observer, RunError, RunOptions, StopToken,
    Values,
};
use orchestrator::system::{Component, Connection, Endpoint, Experiment, System, Value};
use std::sync::mpsc;
use std::time::Duration;

const H: f64 = 0.01;

fn dq(k: f64) -> Component {
    Component {
        name: "dq".into(),
        source: common::fmu("Dahlquist"),
        parameters: vec![("k".into(), Value::Real(k))],
    }
}

fn feed(gain: f64) -> Component {
    Component {
        name: "feed".into(),
        source: common::fmu("Feedthrough"),
        parameters: vec![("gain".into(), Value::Real(gain))],
    }
}

/// Dahlquist feeding Feedthrough's `u`.
fn chain() -> System {
    System {
        name: "chain".into(),
        components: vec![dq(1.0), feed(2.0)],
        connections: vec![Connection {
            from: Endpoint::new("dq", "x"),
            to: Endpoint::new("feed", "u"),
            transform: None,
        }],
        experiment: Experiment::default(),
    }
}

/// The two side by side, unconnected: Feedthrough (the second component) is driven only by
/// external inputs.
fn apart() -> System {
    System {
        connections: vec![],
        ..chain()
    }
}

fn recorded(dir: &std::path::Path, stop: f64, vars: &[(&str, &str)]) -> RunOptions {
    RunOptions {
        out_dir: Some(dir.to_path_buf()),
        record: Some(vars.iter().map(|(c, v)| Endpoint::new(c, v)).collect()),
        ..RunOptions::new(0.0, stop, H)
    }
}

/// An observer made of a function of (step, time, values), step 0 being the start; it
/// remembers how the run ended.
struct Watch<F> {
    at: F,
    finished: Vec<(u64, f64, End)>,
}

fn watch<F: FnMut(u64, f64, &mut Values<'_>) -> Flow>(at: F) -> Watch<F> {
    Watch {
        at,
        finished: vec![],
    }
}

impl<F: FnMut(u64, f64, &mut Values<'_>) -> Flow> Observer for Watch<F> {
    fn initialized(&mut self, t: f64, values: &mut Values<'_>) -> Result<Flow, ObserveError> {
        Ok((self.at)(0, t, values))
    }
    fn stepped(&mut self, k: u64, t: f64, values: &mut Values<'_>) -> Result<Flow, ObserveError> {
        Ok((self.at)(k, t, values))
    }
    fn finished(&mut self, steps: u64, time: f64, end: &End) {
        self.finished.push((steps, time, end.clone()));
    }
}

#[test]
fn an_observer_reads_the_values_at_the_start_and_after_every_step_and_hears_the_end() {
    let cosim = Cosimulation::load(chain()).unwrap();
    let x = cosim.address(&Endpoint::new("dq", "x")).unwrap();
    let n = cosim.address(&Endpoint::new("feed", "steps")).unwrap();
    let mut seen: Vec<(u64, f64, f64, f64)> = vec![];
    let mut w = watch(|k, t, v| {
        seen.push((k, t, v.value(&x).unwrap(), v.value(&n).unwrap()));
        Flow::Continue
    });
    let summary = cosim
        .runner(&RunOptions::new(0.0, 1.0, H))
        .observe(&mut w)
        .run()
        .unwrap();
    assert_eq!(summary.end, End::StopTime);
    assert_eq!(w.finished, [(100, 1.0, End::StopTime)]);
    assert_eq!(seen.len(), 101, "the start and 100 steps");
    for (i, &(k, t, xv, steps)) in seen.iter().enumerate() {
        assert_eq!(k, i as u64);
        assert_eq!(
            t,
            k as f64 * H,
            "the communication point from the step count"
        );
        assert!((xv - (-t).exp()).abs() < 1e-14, "x({t}) = {xv}");
        assert_eq!(steps, k as f64, "an Integer output read as a number");
    }
}

#[test]
fn an_observer_stops_the_run_at_its_step_keeping_that_row_and_terminating_cleanly() {
    let cosim = Cosimulation::load(chain()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let opts = recorded(dir.path(), 1.0, &[("dq", "x")]);
    let mut w = watch(|k, _, _| if k == 37 { Flow::Stop } else { Flow::Continue });
    let summary = cosim.runner(&opts).observe(&mut w).run().unwrap();
    assert_eq!(summary.end, End::Observer);
    assert_eq!(summary.steps, 37);
    assert_eq!(summary.final_time, 37.0 * H);
    assert_eq!(w.finished, [(37, 37.0 * H, End::Observer)]);
    let r = rows(&dir.path().join("results.csv"));
    assert_eq!(summary.rows, 38);
    assert_eq!(r.len(), 38, "the rows of the start and of steps 1 to 37");
    assert_eq!(r[37][0], 37.0 * H);
    assert!((r[37][1] - (-37.0 * H).exp()).abs() < 1e-14);
    let text = orchestrator::cli::summary_text(&summary);
    assert!(
        text.contains("an observer stopped the run at t = 0.37 s"),
        "{text}"
    );
    // At the start: no step at all.
    let mut w = watch(|_, _, _| Flow::Stop);
    let summary = cosim
        .runner(&RunOptions::new(0.0, 1.0, H))
        .observe(&mut w)
        .run()
        .unwrap();
    assert_eq!((summary.steps, summary.end), (0, End::Observer));
}

#[test]
fn every_observer_sees_a_point_and_the_run_stops_if_any_asked() {
    let cosim = Cosimulation::load(chain()).unwrap();
    let mut first = watch(|k, _, _| if k == 5 { Flow::Stop } else { Flow::Continue });
    let mut last_seen = 0;
    let mut second = watch(|k, _, _| {
        last_seen = k;
        Flow::Continue
    });
    let summary = cosim
        .runner(&RunOptions::new(0.0, 1.0, H))
        .observe(&mut first)
        .observe(&mut second)
        .run()
        .unwrap();
    assert_eq!((summary.steps, summary.end), (5, End::Observer));
    assert_eq!(second.finished, [(5, 5.0 * H, End::Observer)]);
    drop(second);
    assert_eq!(
        last_seen, 5,
        "the second observer saw the step the first stopped at"
    );
}

#[test]
fn two_runs_in_one_process_stop_independently() {
    let cosim = Cosimulation::load(chain()).unwrap();
    let (stopped, heard) = mpsc::channel();
    let (a_token, b_token) = (StopToken::new(), StopToken::new());
    let opts = RunOptions::new(0.0, 1.0, H);
    let (cosim_b, opts_b, token_b) = (&cosim, &opts, &b_token);
    let (a, b) = std::thread::scope(|s| {
        let a = s.spawn(|| {
            // Run a is stopped from outside after its step 50, as Ctrl-C would.
            let mut w = watch(|k, _, _| {
                if k == 50 {
                    a_token.stop();
                    stopped.send(()).unwrap();
                }
                Flow::Continue
            });
            cosim.runner(&opts).observe(&mut w).stop_on(&a_token).run()
        });
        let b = s.spawn(move || {
            // Run b is mid-run (after its step 10) when a is stopped.
            let mut w = watch(|k, _, _| {
                if k == 10 {
                    heard
                        .recv_timeout(Duration::from_secs(60))
                        .expect("run a stopped");
                }
                Flow::Continue
            });
            cosim_b
                .runner(opts_b)
                .observe(&mut w)
                .stop_on(token_b)
                .run()
        });
        (a.join().unwrap(), b.join().unwrap())
    });
    match a {
        Err(e @ RunError::Interrupted { steps: 50, .. }) => assert_eq!(e.exit_code(), 130),
        other => panic!("run a: {other:?}"),
    }
    let b = b.unwrap();
    assert_eq!((b.steps, b.end), (100, End::StopTime), "run b completes");
    assert!(a_token.is_stopped() && !b_token.is_stopped());
    // A later run has a token of its own: the earlier stop does not reach it.
    assert_eq!(cosim.run(&opts).unwrap().steps, 100);
}

#[test]
fn external_inputs_reach_the_component_they_name() {
    let cosim = Cosimulation::load(apart()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let opts = recorded(
        dir.path(),
        0.5,
        &[
            ("feed", "y"),
            ("feed", "n_out"),
            ("feed", "flag_out"),
            ("dq", "x"),
        ],
    );
    let names = [
        Endpoint::new("feed", "u"),
        Endpoint::new("feed", "n_in"),
        Endpoint::new("feed", "flag_in"),
    ];
    let k = |t: f64| (t / H).round();
    let fill = |t: f64, out: &mut [f64]| {
        out[0] = 1.0 + t;
        out[1] = k(t);
        out[2] = k(t) % 2.0;
    };
    cosim.runner(&opts).inputs(&names, &fill).run().unwrap();
    let r = rows(&dir.path().join("results.csv"));
    assert_eq!(r.len(), 51);
    // Set in initialization mode: y(0) = 2 u(0).
    assert_eq!(r[0][1], 2.0);
    for (i, row) in r.iter().enumerate().skip(1) {
        // The values set at t_{i-1} drove the step to t_i.
        let before = (i - 1) as f64;
        assert_eq!(row[1], 2.0 * (1.0 + before * H), "y at row {i}");
        assert_eq!(row[2], before, "n_out at row {i}");
        assert_eq!(row[3], before % 2.0, "flag_out at row {i}");
        assert!(
            (row[4] - (-row[0]).exp()).abs() < 1e-14,
            "dq (component 0) untouched"
        );
    }
}

/// The refusal of a run with external inputs `names`; nothing may be created.
fn refused(system: System, names: &[Endpoint]) -> String {
    let cosim = Cosimulation::load(system).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let opts = recorded(&out, 0.1, &[("dq", "x")]);
    let fill = |_: f64, out: &mut [f64]| out.fill(0.0);
    let err = cosim
        .runner(&opts)
        .inputs(names, &fill)
        .run()
        .expect_err("refused");
    assert_eq!(err.exit_code(), 2, "{err}");
    assert!(!out.exists(), "nothing created for a refused run: {err}");
    err.to_string()
}

#[test]
fn external_inputs_that_are_not_free_inputs_are_refused_by_name() {
    assert_eq!(
        refused(apart(), &[Endpoint::new("nope", "u")]),
        "external input nope.u: component 'nope' does not exist (components: dq, feed)"
    );
    let text = refused(apart(), &[Endpoint::new("feed", "v")]);
    assert!(
        text.starts_with("external input feed.v: component 'feed' (")
            && text.contains("Feedthrough.fmu")
            && text.ends_with("has no variable 'v'"),
        "{text}"
    );
    assert_eq!(
        refused(apart(), &[Endpoint::new("feed", "y")]),
        "external input feed.y: 'y' is not an input (causality Output)"
    );
    assert_eq!(
        refused(apart(), &[Endpoint::new("feed", "gain")]),
        "external input feed.gain: 'gain' is not an input (causality Parameter)"
    );
    assert_eq!(
        refused(chain(), &[Endpoint::new("feed", "u")]),
        "external input feed.u: the connection dq.x -> feed.u already feeds it"
    );
    assert_eq!(
        refused(
            apart(),
            &[Endpoint::new("feed", "u"), Endpoint::new("feed", "u")]
        ),
        "external input feed.u: named twice"
    );
}

#[test]
fn an_address_names_what_is_missing() {
    let cosim = Cosimulation::load(chain()).unwrap();
    assert_eq!(
        cosim.address(&Endpoint::new("feed", "n_out")).unwrap(),
        Address {
            component: 1,
            base: model_description::BaseType::Integer,
            vr: 2
        }
    );
    let e = cosim.address(&Endpoint::new("vehicle", "x")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "variable vehicle.x: component 'vehicle' does not exist (components: dq, feed)"
    );
    assert_eq!(e.exit_code(), 2);
}

#[test]
fn a_setting_changes_the_system_and_the_plan_together() {
    let mut cosim = Cosimulation::load(chain()).unwrap();
    cosim.set(&Endpoint::new("dq", "k"), "3").unwrap();
    assert_eq!(
        cosim.system().components[0].parameters.last(),
        Some(&("k".to_string(), Value::String("3".into())))
    );
    // The plan is the system's: resolving the system again gives the same settings, per
    // component in the same order (settings of different components do not interact).
    let again =
        orchestrator::resolve::resolve(cosim.system(), &cosim.model_descriptions()).unwrap();
    for c in 0..2 {
        let of = |p: &orchestrator::resolve::Plan| {
            p.settings
                .iter()
                .filter(|s| s.component == c)
                .cloned()
                .collect::<Vec<_>>()
        };
        assert_eq!(of(&again), of(cosim.plan()), "component {c}");
    }
    assert_eq!(again.links, cosim.plan().links);
    assert_eq!(again.order, cosim.plan().order);
    // And the run follows it: x = exp(-3 t).
    let x = cosim.address(&Endpoint::new("dq", "x")).unwrap();
    let mut last = f64::NAN;
    let mut w = watch(|_, _, v| {
        last = v.value(&x).unwrap();
        Flow::Continue
    });
    cosim
        .runner(&RunOptions::new(0.0, 1.0, H))
        .observe(&mut w)
        .run()
        .unwrap();
    drop(w);
    assert!((last - (-3.0_f64).exp()).abs() < 1e-14, "{last}");
}
