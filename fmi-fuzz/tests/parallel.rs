//! Many instances of each FMU stepping in parallel threads give bit-identical outputs to the
//! same runs done one after another: instances share no mutable state, and nothing in the
//! FMUs depends on thread timing.

mod common;

use common::fmu;
use fmi_import::{Fmu, LogConfig};
use model_description::{Causality, VariableKind};
use std::sync::Barrier;

const THREADS: usize = 8;

/// Every Real output after every step, as bits.
type Trace = Vec<u64>;

fn real_outputs(f: &Fmu) -> Vec<u32> {
    f.model_description()
        .model_variables
        .iter()
        .filter(|v| v.causality == Causality::Output && matches!(v.kind, VariableKind::Real(_)))
        .map(|v| v.value_reference)
        .collect()
}

fn vr(f: &Fmu, name: &str) -> u32 {
    f.value_reference(name).unwrap().1
}

/// SplitMix64, for reproducible sensor signals.
fn noise(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

/// Run `k` of the vehicle: its own track and noise seeds and speed, 1000 steps of 1 ms.
fn vehicle_run(f: &Fmu, k: usize, barrier: Option<&Barrier>) -> Trace {
    let outs = real_outputs(f);
    let mut inst = f
        .instantiate(&format!("vehicle{k}"), LogConfig::default())
        .unwrap();
    inst.setup_experiment(0.0, None, None).unwrap();
    inst.set_integer(
        &[vr(f, "track_seed"), vr(f, "noise_seed")],
        &[k as i32 + 1, 100 + k as i32],
    )
    .unwrap();
    inst.set_real(&[vr(f, "speed")], &[15.0 + k as f64])
        .unwrap();
    if let Some(b) = barrier {
        b.wait();
    }
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    let mut y = vec![0.0; outs.len()];
    let mut trace = Vec::new();
    for n in 0..1000 {
        inst.do_step(n as f64 * 1e-3, 1e-3).unwrap();
        inst.get_real(&outs, &mut y).unwrap();
        trace.extend(y.iter().map(|x| x.to_bits()));
    }
    trace
}

/// Run `k` of the estimator: sensor signals from seed `k`, 3000 steps of 1 ms.
fn estimator_run(f: &Fmu, k: usize, barrier: Option<&Barrier>) -> Trace {
    let outs = real_outputs(f);
    let ins = [
        vr(f, "ws_acc_y"),
        vr(f, "ws_yaw_rate"),
        vr(f, "frame_acc_y"),
        vr(f, "speed"),
    ];
    let mut inst = f
        .instantiate(&format!("estimator{k}"), LogConfig::default())
        .unwrap();
    inst.setup_experiment(0.0, None, None).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    if let Some(b) = barrier {
        b.wait();
    }
    let mut state = k as u64 * 7919 + 1;
    let mut y = vec![0.0; outs.len()];
    let mut trace = Vec::new();
    for n in 0..3000 {
        let t = n as f64 * 1e-3;
        let w = 2.0 + k as f64;
        let u = [
            0.3 * (w * t).sin() + 0.05 * noise(&mut state),
            0.01 * (w * t).cos() + 0.001 * noise(&mut state),
            0.1 * (0.5 * w * t).sin() + 0.02 * noise(&mut state),
            20.0 + k as f64,
        ];
        inst.set_real(&ins, &u).unwrap();
        inst.do_step(t, 1e-3).unwrap();
        inst.get_real(&outs, &mut y).unwrap();
        trace.extend(y.iter().map(|x| x.to_bits()));
    }
    trace
}

fn check(name: &str, run: fn(&Fmu, usize, Option<&Barrier>) -> Trace) {
    let f = Fmu::open(&fmu(name)).unwrap();
    let sequential: Vec<Trace> = (0..THREADS).map(|k| run(&f, k, None)).collect();
    let barrier = Barrier::new(THREADS);
    let parallel: Vec<Trace> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..THREADS)
            .map(|k| {
                let (f, b) = (&f, &barrier);
                s.spawn(move || run(f, k, Some(b)))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for k in 0..THREADS {
        assert!(!sequential[k].is_empty());
        assert!(
            sequential[k] == parallel[k],
            "{name}: run {k} in a thread differs from the same run done alone (first difference at value {})",
            sequential[k]
                .iter()
                .zip(&parallel[k])
                .position(|(a, b)| a != b)
                .unwrap_or(sequential[k].len().min(parallel[k].len()))
        );
    }
    // The runs differ from each other, so the comparison above is not between constants.
    for k in 1..THREADS {
        assert_ne!(
            sequential[0], sequential[k],
            "{name}: runs 0 and {k} are identical"
        );
    }
}

#[test]
fn eight_vehicles_in_parallel_threads_match_sequential_runs() {
    check("RailVehicle", vehicle_run);
}

#[test]
fn eight_estimators_in_parallel_threads_match_sequential_runs() {
    check("AlignmentEstimator", estimator_run);
}
