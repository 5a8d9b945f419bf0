//! Batches of fuzz sequences in child processes: crash and hang detection, replay of a
//! failing seed, and the summary.
//!
//! A child (`fmi-fuzz worker ...`) prints `S <seed>` before each sequence, a block
//! `F <seed>` / `| <line>`... / `E` for every sequence that violated an invariant, then one
//! `STATS` line per function and `DONE <sequences> <calls>`. A child that dies without `DONE`
//! crashed in the last sequence it started; one whose current sequence runs past the
//! timeout is killed and reported as a hang in that sequence. Either way the sequence is replayed alone with its
//! calls streamed to stderr, so the report ends with the call that crashed or hung, and the
//! rest of the batch goes on in a new child.

use crate::api::NAMES;
use crate::fuzz::{Config, SeqResult, Stats, Trace, run_range};
use anyhow::{Context, Result};
use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

/// Options of a fuzz run over one FMU.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The FMU to fuzz.
    pub fmu: PathBuf,
    /// How many sequences to run.
    pub sequences: u64,
    /// The seed of the first sequence; sequence k uses seed + k, so any failing seed replays alone.
    pub seed: u64,
    /// The longest sequence, in calls before the clean-up.
    pub max_len: usize,
    /// How long one sequence may run before it counts as hung.
    pub timeout: Duration,
    /// Child processes running at once.
    pub jobs: usize,
    /// Sequences per child process: larger batches start fewer processes, smaller ones lose less to
    /// a crash.
    pub batch: u64,
    /// `name=value` settings applied right after most instantiations.
    pub presets: Vec<(String, String)>,
    /// Percentage of instances that get the presets.
    pub preset_percent: u32,
    /// Address-space limit of each child (MiB; 0 = none), so that a runaway allocation fails
    /// in the child instead of exhausting the machine.
    pub mem_limit_mb: u64,
    /// Failure reports printed in full (all failing seeds are always listed).
    pub show: usize,
    /// Stop after this many failing sequences (0: never).
    pub max_failures: usize,
}

/// What a run found.
#[derive(Debug, Default)]
pub struct Report {
    /// Sequences run, the failing ones included.
    pub sequences: u64,
    /// FMI calls made in all.
    pub calls: u64,
    /// Wall-clock time of the run.
    pub seconds: f64,
    /// One entry per failing sequence: (seed, full report text).
    pub failures: Vec<(u64, String)>,
    /// The statuses every function returned; set at the end of a run (None until then).
    pub stats: Option<StatsTable>,
    /// The run stopped at `max_failures` before all sequences ran.
    pub stopped_early: bool,
}

/// Status counts per function, for the summary.
#[derive(Debug, Clone)]
pub struct StatsTable(pub Vec<[u64; 7]>);

impl Report {
    /// The status counts as a fixed-width table, one row per FMI function (Pending counted as
    /// "other"); empty without stats.
    pub fn render_stats(&self) -> String {
        let mut s = String::new();
        let Some(StatsTable(rows)) = &self.stats else {
            return s;
        };
        s.push_str(&format!(
            "{:<30} {:>9} {:>8} {:>8} {:>8} {:>8} {:>6} {:>6}\n",
            "function", "calls", "OK", "Warning", "Discard", "Error", "Fatal", "other"
        ));
        for (f, r) in rows.iter().enumerate() {
            let calls: u64 = r.iter().sum();
            s.push_str(&format!(
                "{:<30} {:>9} {:>8} {:>8} {:>8} {:>8} {:>6} {:>6}\n",
                NAMES[f],
                calls,
                r[0],
                r[1],
                r[2],
                r[3],
                r[4],
                r[5] + r[6]
            ));
        }
        s
    }
}

/// The worker: runs `count` sequences from `first` in this process, printing the protocol.
pub fn worker(fmu: &Path, cfg: &Config, first: u64, count: u64) -> Result<()> {
    let target = crate::api::Target::open(fmu)?;
    let out = std::io::stdout();
    let mut sequences = 0u64;
    let mut calls = 0u64;
    let stats = run_range(
        &target,
        cfg,
        first,
        count,
        |seed| {
            let mut o = out.lock();
            let _ = writeln!(o, "S {seed}");
            let _ = o.flush();
        },
        |r: &SeqResult| {
            sequences += 1;
            calls += r.calls;
            if !r.failures.is_empty() {
                let mut o = out.lock();
                let _ = writeln!(o, "F {}", r.seed);
                for f in &r.failures {
                    let _ = writeln!(o, "| failure: {f}");
                }
                let _ = writeln!(o, "| calls:");
                for l in &r.trace {
                    let _ = writeln!(o, "|   {l}");
                }
                let _ = writeln!(o, "E");
                let _ = o.flush();
            }
        },
    );
    let mut o = out.lock();
    for (f, row) in stats.counts.iter().enumerate() {
        let cols: Vec<String> = row.iter().map(u64::to_string).collect();
        writeln!(o, "STATS {f} {}", cols.join(" "))?;
    }
    writeln!(o, "DONE {sequences} {calls}")?;
    o.flush()?;
    Ok(())
}

fn worker_command(o: &RunOptions, first: u64, count: u64, stream: bool) -> Result<Command> {
    let exe = std::env::current_exe().context("cannot find the fmi-fuzz executable")?;
    let mut args: Vec<String> = vec![
        "worker".into(),
        "--fmu".into(),
        o.fmu.display().to_string(),
        "--first".into(),
        first.to_string(),
        "--count".into(),
        count.to_string(),
        "--max-len".into(),
        o.max_len.to_string(),
        "--preset-percent".into(),
        o.preset_percent.to_string(),
    ];
    for (k, v) in &o.presets {
        args.push("--preset".into());
        args.push(format!("{k}={v}"));
    }
    if stream {
        args.push("--trace".into());
    }
    let mut cmd = if o.mem_limit_mb > 0 {
        let mut c = Command::new("sh");
        c.arg("-c")
            .arg(r#"ulimit -v "$1" && shift && exec "$@""#)
            .arg("sh")
            .arg((o.mem_limit_mb * 1024).to_string())
            .arg(exe);
        c
    } else {
        Command::new(exe)
    };
    cmd.args(args);
    Ok(cmd)
}

struct Running {
    child: Child,
    lines: Receiver<String>,
    /// When the current sequence (or the worker, before its first) started.
    seq_started: Instant,
    first: u64,
    count: u64,
    last_seed: Option<u64>,
    done: Option<(u64, u64)>,
    stats: Stats,
    block: Option<(u64, String)>,
}

fn spawn(o: &RunOptions, first: u64, count: u64) -> Result<Running> {
    let mut cmd = worker_command(o, first, count, false)?;
    cmd.stdout(Stdio::piped()).stderr(Stdio::null());
    let mut child = cmd.spawn().context("cannot start a fuzz worker")?;
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    Ok(Running {
        child,
        lines: rx,
        seq_started: Instant::now(),
        first,
        count,
        last_seed: None,
        done: None,
        stats: Stats::default(),
        block: None,
    })
}

impl Running {
    fn drain(&mut self, report: &mut Report) {
        while let Ok(line) = self.lines.try_recv() {
            self.line(&line, report);
        }
    }

    fn line(&mut self, line: &str, report: &mut Report) {
        if let Some((seed, text)) = &mut self.block {
            if line == "E" {
                report.failures.push((*seed, std::mem::take(text)));
                self.block = None;
            } else if let Some(l) = line.strip_prefix("| ") {
                text.push_str(l);
                text.push('\n');
            }
            return;
        }
        let mut parts = line.split_whitespace();
        match parts.next() {
            Some("S") => {
                self.last_seed = parts.next().and_then(|s| s.parse().ok());
                self.seq_started = Instant::now();
            }
            Some("F") => {
                let seed = parts.next().and_then(|s| s.parse().ok()).unwrap_or(0);
                self.block = Some((seed, String::new()));
            }
            Some("STATS") => {
                let v: Vec<u64> = parts.filter_map(|s| s.parse().ok()).collect();
                if v.len() == 8 && (v[0] as usize) < self.stats.counts.len() {
                    self.stats.counts[v[0] as usize].copy_from_slice(&v[1..]);
                }
            }
            Some("DONE") => {
                let v: Vec<u64> = parts.filter_map(|s| s.parse().ok()).collect();
                if v.len() == 2 {
                    self.done = Some((v[0], v[1]));
                }
            }
            _ => {}
        }
    }
}

/// Replays one sequence with its calls streamed to stderr; returns the last lines of that
/// stream (the call that crashed or hung is the last one begun).
fn replay_tail(o: &RunOptions, seed: u64) -> String {
    let Ok(mut cmd) = worker_command(o, seed, 1, true) else {
        return "(cannot start the replay)".into();
    };
    cmd.stdout(Stdio::null()).stderr(Stdio::piped());
    let Ok(mut child) = cmd.spawn() else {
        return "(cannot start the replay)".into();
    };
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let start = Instant::now();
    let mut lines: VecDeque<String> = VecDeque::new();
    let mut outcome = String::new();
    loop {
        while let Ok(l) = rx.try_recv() {
            lines.push_back(l);
            if lines.len() > 60 {
                lines.pop_front();
            }
        }
        match child.try_wait() {
            Ok(Some(st)) => {
                outcome = format!("replay ended: {}", describe(st));
                break;
            }
            Ok(None) if start.elapsed() > o.timeout => {
                let _ = child.kill();
                let _ = child.wait();
                outcome = format!(
                    "replay killed after {:.0} s (still running: the last call begun hangs)",
                    o.timeout.as_secs_f64()
                );
                break;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(_) => break,
        }
    }
    std::thread::sleep(Duration::from_millis(50));
    while let Ok(l) = rx.try_recv() {
        lines.push_back(l);
        if lines.len() > 60 {
            lines.pop_front();
        }
    }
    let mut s = String::from("last calls of the replay (each printed before it is made):\n");
    for l in lines {
        s.push_str("    ");
        s.push_str(&l);
        s.push('\n');
    }
    s.push_str(&outcome);
    s.push('\n');
    s
}

fn describe(st: std::process::ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = st.signal() {
            let name = match sig {
                6 => " (SIGABRT)",
                7 => " (SIGBUS)",
                9 => " (SIGKILL)",
                11 => " (SIGSEGV)",
                4 => " (SIGILL)",
                8 => " (SIGFPE)",
                _ => "",
            };
            return format!("killed by signal {sig}{name}");
        }
    }
    format!("{st}")
}

/// Runs `o.sequences` sequences from seed `o.seed` in batches of child processes.
pub fn run(o: &RunOptions, mut progress: impl FnMut(u64, u64)) -> Result<Report> {
    // Fail early, in this process, if the FMU cannot even be opened.
    drop(crate::api::Target::open(&o.fmu)?);
    let start = Instant::now();
    let mut report = Report::default();
    let mut total = Stats::default();
    let mut queue: VecDeque<(u64, u64)> = VecDeque::new();
    let mut k = 0;
    while k < o.sequences {
        let n = o.batch.min(o.sequences - k);
        queue.push_back((o.seed.wrapping_add(k), n));
        k += n;
    }
    let mut running: Vec<Running> = Vec::new();
    let mut finished = 0u64;
    while !queue.is_empty() || !running.is_empty() {
        if o.max_failures > 0 && report.failures.len() >= o.max_failures {
            report.stopped_early = true;
            queue.clear();
            for r in &mut running {
                let _ = r.child.kill();
                let _ = r.child.wait();
            }
            running.clear();
            break;
        }
        while running.len() < o.jobs.max(1)
            && let Some((first, count)) = queue.pop_front()
        {
            running.push(spawn(o, first, count)?);
        }
        let mut i = 0;
        while i < running.len() {
            let r = &mut running[i];
            r.drain(&mut report);
            let exited = r.child.try_wait()?;
            let timed_out = exited.is_none() && r.seq_started.elapsed() > o.timeout;
            if exited.is_none() && !timed_out {
                i += 1;
                continue;
            }
            if timed_out {
                let _ = r.child.kill();
            }
            let status = r.child.wait()?;
            // Let the reader thread deliver the rest.
            let deadline = Instant::now() + Duration::from_millis(500);
            while r.done.is_none() && Instant::now() < deadline {
                match r.lines.recv_timeout(Duration::from_millis(50)) {
                    Ok(l) => r.line(&l, &mut report),
                    Err(_) => {
                        if timed_out {
                            break;
                        }
                    }
                }
            }
            r.drain(&mut report);
            let r = running.swap_remove(i);
            match r.done {
                Some((seqs, calls)) if !timed_out => {
                    report.sequences += seqs;
                    report.calls += calls;
                    total.merge(&r.stats);
                    finished += seqs;
                }
                _ => {
                    let culprit = r.last_seed.unwrap_or(r.first);
                    let done_before = culprit.wrapping_sub(r.first);
                    report.sequences += done_before + 1;
                    finished += done_before + 1;
                    let what = if timed_out {
                        format!(
                            "hang: sequence {culprit} did not finish within {:.0} s",
                            o.timeout.as_secs_f64()
                        )
                    } else {
                        format!(
                            "crash: the worker process {} during sequence {culprit}",
                            describe(status)
                        )
                    };
                    let tail = replay_tail(o, culprit);
                    report
                        .failures
                        .push((culprit, format!("failure: {what}\n{tail}")));
                    let rest = r.count - done_before - 1;
                    if rest > 0 {
                        queue.push_front((culprit.wrapping_add(1), rest));
                    }
                }
            }
            progress(finished, o.sequences);
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    report.seconds = start.elapsed().as_secs_f64();
    report.stats = Some(StatsTable(total.counts));
    report.failures.sort_by_key(|f| f.0);
    Ok(report)
}

/// Runs sequences in this process (no crash isolation): for debugging and replay.
pub fn run_in_process(o: &RunOptions, trace: Trace) -> Result<Report> {
    let target = crate::api::Target::open(&o.fmu)?;
    let cfg = Config {
        max_len: o.max_len,
        trace,
        presets: o.presets.clone(),
        preset_percent: o.preset_percent,
    };
    let start = Instant::now();
    let mut report = Report::default();
    let stats = run_range(
        &target,
        &cfg,
        o.seed,
        o.sequences,
        |_| {},
        |r| {
            report.sequences += 1;
            report.calls += r.calls;
            if !r.failures.is_empty() {
                let mut text = String::new();
                for f in &r.failures {
                    text.push_str(&format!("failure: {f}\n"));
                }
                text.push_str("calls:\n");
                for l in &r.trace {
                    text.push_str(&format!("  {l}\n"));
                }
                report.failures.push((r.seed, text));
            }
        },
    );
    report.seconds = start.elapsed().as_secs_f64();
    report.stats = Some(StatsTable(stats.counts));
    Ok(report)
}
