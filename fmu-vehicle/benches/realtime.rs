//! Real-time factor of the standard 20 s run (20 m/s, German low-disturbance track, noise on,
//! 1 ms communication steps) on one core: `cargo bench -p fmu-vehicle --bench realtime`.
//! Prints the wall time of each of 5 runs and the median real-time factor.

use fmi_abi::{InstantiateContext, Logger, Model, Values};
use fmu_vehicle::fmu::{RailVehicle, VARIABLES, build_simulation};
use std::time::Instant;

fn main() {
    let simulated = 20.0;
    let h = 1e-3;
    let mut walls = vec![];
    for _ in 0..5 {
        let start = Instant::now();
        let values = Values::from_table(VARIABLES);
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
            "20 s standard run (incl. initialization): {wall:.4} s wall, {} internal steps (checksum {check:.6e})",
            sim.substeps
        );
        walls.push(wall);
    }
    walls.sort_by(f64::total_cmp);
    let median = walls[2];
    println!(
        "median real-time factor: {:.0}x real time ({:.3} us per communication step)",
        simulated / median,
        median / (simulated / h) * 1e6
    );
}
