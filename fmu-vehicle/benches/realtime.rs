//! Real-time factor of the standard 20 s run (20 m/s, German low-disturbance track, noise on,
//! 1 ms communication steps) on one core, and of the same run on a curve (radius 500 m, 60 m
//! transitions, 60 mm cant, from 20 m on): `cargo bench -p fmu-vehicle --bench realtime`.
//! Prints the wall time of each of 5 runs of each, their median real-time factors and the
//! curve's cost relative to the straight run (same process, interleaved).

use fmi_abi::{InstantiateContext, Logger, Model, Values};
use fmu_vehicle::fmu::{RailVehicle, VARIABLES, build_simulation, vr};
use std::time::Instant;

/// Wall time of one 20 s run with `edit` applied to the parameters.
fn one_run(name: &str, edit: &dyn Fn(&mut Values)) -> f64 {
    let (simulated, h) = (20.0, 1e-3);
    let start = Instant::now();
    let mut values = Values::from_table(VARIABLES);
    edit(&mut values);
    let model =
        RailVehicle::instantiate(&InstantiateContext::default(), &Logger::silent()).unwrap();
    let mut sim = build_simulation(&model, &values, &Logger::silent()).unwrap();
    let n = (simulated / h) as usize;
    let mut check = 0.0;
    for _ in 0..n {
        sim.step(h, 20.0);
        check += sim.outputs.ws_acc_y;
    }
    let wall = start.elapsed().as_secs_f64();
    println!(
        "20 s {name} run (incl. initialization): {wall:.4} s wall, {} internal steps (checksum {check:.6e})",
        sim.substeps
    );
    wall
}

fn main() {
    let straight = |_: &mut Values| {};
    let curved = |v: &mut Values| {
        v.real[vr::CURVE_RADIUS as usize] = 500.0;
        v.real[vr::CURVE_CANT as usize] = 0.06;
        v.real[vr::CURVE_START as usize] = 20.0;
        v.real[vr::CURVE_LENGTH as usize] = 1000.0;
    };
    let (mut a, mut b) = (vec![], vec![]);
    for _ in 0..5 {
        a.push(one_run("standard", &straight));
        b.push(one_run("curved", &curved));
    }
    let median = |w: &mut Vec<f64>| {
        w.sort_by(f64::total_cmp);
        w[2]
    };
    let (ma, mb) = (median(&mut a), median(&mut b));
    for (name, m) in [("standard", ma), ("curved", mb)] {
        println!(
            "{name}: median real-time factor {:.0}x real time ({:.3} us per communication step)",
            20.0 / m,
            m / 20e3 * 1e6
        );
    }
    println!(
        "the curve costs {:+.0} % of the straight run's time",
        (mb / ma - 1.0) * 100.0
    );
}
