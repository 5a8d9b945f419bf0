//! The design fit's cost against the record's length: `cargo bench -p design-line --bench fit`.
//! Synthetic records (no FMU): a line with a curve every 500 m (radius 600-1200 m, 60 m
//! transitions, 40-100 mm cant), the sensors of a body following it at 18 m/s and 1 ms with a
//! deterministic noise, 2, 5 and 10 km long. Printed: the median of 3 fits, its time per km and
//! the ratio to the 2 km record's per km (1: linear in the length).

use design_line::DesignLine;
use design_line::fit::{fit, synthetic};
use std::time::Instant;

const V: f64 = 18.0;
const H: f64 = 1e-3;

fn line(length: f64) -> DesignLine {
    let mut rows = vec![(0.0, 0.0, 0.0)];
    let mut s = 150.0;
    let mut i = 0;
    while s + 450.0 < length {
        let k = [1.0 / 600.0, -1.0 / 900.0, 1.0 / 1200.0][i % 3];
        let c = [0.1, -0.06, 0.04][i % 3];
        rows.extend([
            (s, 0.0, 0.0),
            (s + 60.0, k, c),
            (s + 260.0, k, c),
            (s + 320.0, 0.0, 0.0),
        ]);
        s += 500.0;
        i += 1;
    }
    rows.push((length, 0.0, 0.0));
    DesignLine::new(&rows, 10.0, |i| format!("row {i}")).expect("a valid line")
}

fn record(length: f64) -> [Vec<f64>; 4] {
    synthetic::record(&line(length), V, H, length, 0.75, synthetic::noise)
}

fn main() {
    let mut per_km_2 = None;
    println!("| record | transitions | fit, median of 3 | per km | per km against 2 km |");
    println!("|---|---|---|---|---|");
    for km in [2.0, 5.0, 10.0] {
        let r = record(km * 1000.0);
        let rec = synthetic::view(&r, H);
        let mut times = Vec::new();
        let mut found = 0;
        for _ in 0..3 {
            let t = Instant::now();
            found = fit(&rec, 0.75, 9.81, 10.0).expect("fits").transitions.len();
            times.push(t.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        let per_km = times[1] / km;
        let base = *per_km_2.get_or_insert(per_km);
        println!(
            "| {km} km | {found} | {:.2} s | {:.3} s | {:.2} |",
            times[1],
            per_km,
            per_km / base
        );
    }
}
