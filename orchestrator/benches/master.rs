//! The master's cost per communication step, and fmpy's on the same FMUs in the same run.
//! `cargo bench -p orchestrator --bench master` (needs target/fmu/{Dahlquist,Feedthrough}.fmu
//! from `cargo xtask fmu`, and .venv from `cargo xtask test` for the fmpy comparison).
//!
//! System: Dahlquist -> Feedthrough (one Real connection), 1e5 steps of 1e-4 s: the workload of
//! docs/references.md section 8.2. Printed, each as the median of 5 runs:
//! - a bare loop over the same two instances (doStep, getReal, setReal, doStep): the FMUs' own
//!   cost plus the FFI calls, the floor any master pays;
//! - our master without recording, and recording the two connected variables as CSV and as
//!   Parquet;
//! - the master's own cost (master minus bare loop);
//! - fmpy: a Python Gauss-Seidel loop over FMU2Slave (the loop every fmpy user writes), run by
//!   tests/bench_fmpy.py, and the ratio to ours.

use fmi_import::{Fmu, LogConfig};
use orchestrator::master::{Cosimulation, ResultsFile, RunOptions};
use orchestrator::system::{Component, Connection, Endpoint, Experiment, System};
use std::path::{Path, PathBuf};
use std::time::Instant;

const STEPS: u64 = 100_000;
const H: f64 = 1e-4;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn bare_loop(dq: &Path, feed: &Path) -> f64 {
    let (a, b) = (Fmu::open(dq).unwrap(), Fmu::open(feed).unwrap());
    let (mut x, mut y) = (
        a.instantiate("dq", LogConfig::default()).unwrap(),
        b.instantiate("feed", LogConfig::default()).unwrap(),
    );
    for i in [&mut x, &mut y] {
        i.setup_experiment(0.0, Some(STEPS as f64 * H), None)
            .unwrap();
        i.enter_initialization_mode().unwrap();
        i.exit_initialization_mode().unwrap();
    }
    let (xv, uv) = (
        a.value_reference("x").unwrap().1,
        b.value_reference("u").unwrap().1,
    );
    let mut v = [0.0];
    let start = Instant::now();
    for k in 0..STEPS {
        let t = k as f64 * H;
        x.do_step(t, H).unwrap();
        x.get_real(&[xv], &mut v).unwrap();
        y.set_real(&[uv], &v).unwrap();
        y.do_step(t, H).unwrap();
    }
    start.elapsed().as_secs_f64() / STEPS as f64 * 1e6
}

fn master(system: &System, out: Option<&Path>, results: &str) -> f64 {
    let cosim = Cosimulation::load(system.clone()).unwrap();
    let opts = RunOptions {
        out_dir: out.map(Path::to_path_buf),
        results: ResultsFile::new(results).unwrap(),
        record: Some(vec![Endpoint::new("dq", "x"), Endpoint::new("feed", "u")]),
        ..RunOptions::new(0.0, STEPS as f64 * H, H)
    };
    let start = Instant::now();
    cosim.run(&opts).unwrap();
    start.elapsed().as_secs_f64() / STEPS as f64 * 1e6
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf();
    let dir = std::env::var_os("XTASK_FMU_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/fmu"));
    let (dq, feed) = (dir.join("Dahlquist.fmu"), dir.join("Feedthrough.fmu"));
    if !dq.exists() || !feed.exists() {
        eprintln!(
            "missing {} or {}: run `cargo xtask fmu` first",
            dq.display(),
            feed.display()
        );
        std::process::exit(2);
    }
    let system = System {
        name: "bench".into(),
        components: vec![
            Component {
                name: "dq".into(),
                source: dq.clone(),
                parameters: vec![],
            },
            Component {
                name: "feed".into(),
                source: feed.clone(),
                parameters: vec![],
            },
        ],
        connections: vec![Connection {
            from: Endpoint::new("dq", "x"),
            to: Endpoint::new("feed", "u"),
            transform: None,
        }],
        experiment: Experiment::default(),
    };
    let tmp = tempfile::tempdir().unwrap();
    let bare = median((0..5).map(|_| bare_loop(&dq, &feed)).collect());
    let run = |out: Option<&Path>, results: &str| {
        median((0..5).map(|_| master(&system, out, results)).collect())
    };
    let plain = run(None, "results.csv");
    let recorded = run(Some(tmp.path()), "results.csv");
    let parquet = run(Some(tmp.path()), "results.parquet");
    println!("Dahlquist -> Feedthrough, {STEPS} steps of {H} s (median of 5):");
    println!("  bare loop (2 doStep + getReal + setReal)   {bare:.3} us/step");
    println!(
        "  orchestrator, no recording                  {plain:.3} us/step (master's own cost {:.3})",
        plain - bare
    );
    println!(
        "  orchestrator, CSV of the 2 variables        {recorded:.3} us/step (master's own cost {:.3})",
        recorded - bare
    );
    println!(
        "  orchestrator, Parquet of the 2 variables    {parquet:.3} us/step (master's own cost {:.3})",
        parquet - bare
    );

    let python = root.join(".venv/bin/python");
    if !python.exists() {
        println!("  fmpy: no .venv (run `cargo xtask test` once to create it)");
        return;
    }
    let out = std::process::Command::new(&python)
        .arg(root.join("tests/bench_fmpy.py"))
        .arg(&dq)
        .arg(&feed)
        .args(["--steps", &STEPS.to_string(), "--step", &H.to_string()])
        .output()
        .expect("running tests/bench_fmpy.py");
    let text = String::from_utf8_lossy(&out.stdout);
    match text.trim().parse::<f64>() {
        Ok(fmpy) => {
            println!("  fmpy FMU2Slave Gauss-Seidel loop            {fmpy:.3} us/step");
            println!(
                "  ratio fmpy / orchestrator: {:.0}x without recording, {:.0}x with recording",
                fmpy / plain,
                fmpy / recorded
            );
        }
        Err(_) => println!(
            "  fmpy: tests/bench_fmpy.py failed: {}{}",
            text,
            String::from_utf8_lossy(&out.stderr)
        ),
    }
}
