//! The master algorithm: instantiate, initialize with values propagated through the
//! connections, then step every component with a fixed communication step.
//!
//! Time is kept as an integer tick count: the communication points are `start + k * step`, each
//! computed from `k`, so they never drift however long the run (Reference-FMUs #507). The
//! default algorithm is Gauss-Seidel: within a step, components run producers first (the order
//! of [`crate::resolve::Plan::order`]) and a consumer sees its producers' outputs at the end of
//! the step; with the vehicle stepped first the estimator receives the sensor samples at
//! `t + h`, as it expects. Jacobi (on request) sets every input from the outputs at `t`, then
//! steps every component.
//!
//! Values move through flat buffers: each component's connected outputs of one type occupy a
//! contiguous range, read with one fmi2GetXxx call per component and type; each component's
//! inputs are gathered (with their linear transformation) and written with one fmi2SetXxx call.
//! Nothing is allocated inside the stepping loop.
//!
//! Reliability: the results file is created (and its header flushed) before any FMU is
//! instantiated, so an unwritable destination or a full disk stops the run before it starts;
//! an FMU failing mid-run, or [`request_stop`] (Ctrl-C on the command line, checked once per
//! step), ends the run at a step boundary with every recorded row kept as whole lines in
//! `results.csv`; a write failing mid-run names the file and the time the run stopped at.

use crate::record::Recorder;
use crate::resolve::{Link, Plan, resolve};
use crate::system::{Endpoint, Linear, System, Value};
use fmi_import::{FmiError, Fmu, ImportError, Instance, LogConfig, fmi2Status};
use model_description::{BaseType, Causality, ModelDescription, VariableKind};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Set by [`request_stop`]; read by the stepping loop once per step.
static STOP: AtomicBool = AtomicBool::new(false);

/// Asks every run in this process to stop at its next step boundary (what the command line's
/// Ctrl-C handler calls). The run then flushes and keeps its results and returns
/// [`RunError::Interrupted`]. Returns whether this is the first request.
pub fn request_stop() -> bool {
    !STOP.swap(true, Ordering::SeqCst)
}

/// Whether [`request_stop`] has been called.
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// One value for an input of the first component: its type, value reference and value (an
/// Integer or Enumeration as a whole number, a Boolean as 0 or 1).
pub type ExternalValue = (BaseType, u32, f64);

/// Fills the buffer with the first component's input values at time `t`.
pub type ExternalInputs<'a> = dyn Fn(f64, &mut Vec<ExternalValue>) + 'a;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Algorithm {
    GaussSeidel,
    Jacobi,
}

#[derive(Clone)]
pub struct RunOptions {
    pub start: f64,
    pub stop: f64,
    pub step: f64,
    pub algorithm: Algorithm,
    /// Where results.csv goes; `None` records nothing.
    pub out_dir: Option<PathBuf>,
    /// Variables to record; `None`: every output of every component.
    pub record: Option<Vec<Endpoint>>,
    /// Recording interval [s], a whole number of steps; `None`: every step.
    pub interval: Option<f64>,
    /// Also keep the recorded rows in memory ([`RunSummary::table`]), for the studies.
    pub collect: bool,
    pub progress: bool,
    pub log: LogConfig,
}

/// Recorded columns kept in memory: `time` first, then `component.variable`.
#[derive(Debug, Clone, Default)]
pub struct Table {
    pub columns: Vec<String>,
    pub data: Vec<Vec<f64>>,
}

impl Table {
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .position(|c| c == name)
            .map(|i| self.data[i].as_slice())
    }

    /// The column `name`, or an error naming it.
    pub fn require(&self, name: &str) -> Result<&[f64], String> {
        self.column(name)
            .ok_or_else(|| format!("the results have no column '{name}'"))
    }

    /// A results.csv read back (the one CSV reader, [`crate::csv`]).
    pub fn read_csv(path: &std::path::Path) -> Result<Table, String> {
        let csv = crate::csv::Csv::read(path)?;
        Ok(Table {
            columns: csv.names,
            data: csv.columns,
        })
    }
}

#[derive(Debug, Clone)]
pub struct RunSummary {
    pub steps: u64,
    pub rows: u64,
    pub results: Option<PathBuf>,
    /// The recorded rows, when [`RunOptions::collect`] asked for them.
    pub table: Option<Table>,
    pub wall: Duration,
    pub final_time: f64,
    /// The instance that ended the run before the stop time: its fmi2DoStep returned
    /// fmi2Discard with fmi2GetBooleanStatus(fmi2Terminated) true. The run then ends cleanly,
    /// as fmpy does: the rows until the last communication point, and one at the instance's
    /// last successful time (`final_time`) when it reported one past that point.
    pub ended_by: Option<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Import(#[from] ImportError),
    #[error(transparent)]
    Resolve(#[from] crate::resolve::ResolveError),
    #[error("{0}")]
    Config(String),
    #[error("{error}{}", .results.as_ref().map(|p| format!("\nthe results recorded until then are in {}", p.display())).unwrap_or_default())]
    Fmi {
        error: FmiError,
        results: Option<PathBuf>,
    },
    #[error("{0}")]
    Io(String),
    /// The run was asked to stop ([`request_stop`], e.g. Ctrl-C) and stopped at a step boundary.
    #[error(
        "interrupted at t = {time} s, after {steps} of {total} steps{}",
        match .results {
            Some(p) => format!("; the {rows} rows recorded until then are in {}", p.display()),
            None => String::new(),
        }
    )]
    Interrupted {
        time: f64,
        steps: u64,
        total: u64,
        rows: u64,
        results: Option<PathBuf>,
    },
}

impl RunError {
    /// The process exit code: 2 for a problem with the input (files, system, parameters),
    /// 3 for an FMU that failed during the run, 1 for an I/O failure, 130 (128 + SIGINT, as
    /// shells report a process ended by Ctrl-C) for an interrupted run.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Import(_) | RunError::Resolve(_) | RunError::Config(_) => 2,
            RunError::Fmi { .. } => 3,
            RunError::Io(_) => 1,
            RunError::Interrupted { .. } => 130,
        }
    }
}

/// A value type that can cross a connection.
trait Port: Copy + Default {
    fn get(inst: &mut Instance, vr: &[u32], out: &mut [Self]) -> Result<(), FmiError>;
    fn set(inst: &mut Instance, vr: &[u32], values: &[Self]) -> Result<(), FmiError>;
    fn apply(self, t: Option<Linear>) -> Self;
}

impl Port for f64 {
    fn get(inst: &mut Instance, vr: &[u32], out: &mut [f64]) -> Result<(), FmiError> {
        inst.get_real(vr, out)
    }
    fn set(inst: &mut Instance, vr: &[u32], values: &[f64]) -> Result<(), FmiError> {
        inst.set_real(vr, values)
    }
    fn apply(self, t: Option<Linear>) -> f64 {
        match t {
            Some(l) => l.factor * self + l.offset,
            None => self,
        }
    }
}

impl Port for i32 {
    fn get(inst: &mut Instance, vr: &[u32], out: &mut [i32]) -> Result<(), FmiError> {
        inst.get_integer(vr, out)
    }
    fn set(inst: &mut Instance, vr: &[u32], values: &[i32]) -> Result<(), FmiError> {
        inst.set_integer(vr, values)
    }
    fn apply(self, _: Option<Linear>) -> i32 {
        self
    }
}

impl Port for bool {
    fn get(inst: &mut Instance, vr: &[u32], out: &mut [bool]) -> Result<(), FmiError> {
        inst.get_boolean(vr, out)
    }
    fn set(inst: &mut Instance, vr: &[u32], values: &[bool]) -> Result<(), FmiError> {
        inst.set_boolean(vr, values)
    }
    fn apply(self, _: Option<Linear>) -> bool {
        self
    }
}

/// The links of one value type, laid out for one-call-per-component transfers.
struct Transfer<T: Port> {
    /// Per component: the output value references it feeds, and where they start in `slots`.
    out_vr: Vec<Vec<u32>>,
    out_start: Vec<usize>,
    /// Per component: its connected input value references, the slot feeding each, and the
    /// transformation.
    in_vr: Vec<Vec<u32>>,
    in_slot: Vec<Vec<usize>>,
    in_transform: Vec<Vec<Option<Linear>>>,
    slots: Vec<T>,
    scratch: Vec<T>,
}

impl<T: Port> Transfer<T> {
    fn new(n: usize, links: &[&Link]) -> Transfer<T> {
        let mut out_vr: Vec<Vec<u32>> = vec![vec![]; n];
        // Each distinct (component, output) gets one slot; links sharing an output share it.
        for l in links {
            if !out_vr[l.from].contains(&l.from_vr) {
                out_vr[l.from].push(l.from_vr);
            }
        }
        let mut out_start = vec![0; n];
        let mut total = 0;
        for c in 0..n {
            out_start[c] = total;
            total += out_vr[c].len();
        }
        let mut in_vr = vec![vec![]; n];
        let mut in_slot = vec![vec![]; n];
        let mut in_transform = vec![vec![]; n];
        for l in links {
            let slot = out_start[l.from]
                + out_vr[l.from]
                    .iter()
                    .position(|&v| v == l.from_vr)
                    .expect("registered above");
            in_vr[l.to].push(l.to_vr);
            in_slot[l.to].push(slot);
            in_transform[l.to].push(l.transform);
        }
        let widest = in_vr.iter().map(Vec::len).max().unwrap_or(0);
        Transfer {
            out_vr,
            out_start,
            in_vr,
            in_slot,
            in_transform,
            slots: vec![T::default(); total],
            scratch: vec![T::default(); widest],
        }
    }

    fn read_outputs(&mut self, c: usize, inst: &mut Instance) -> Result<(), FmiError> {
        let n = self.out_vr[c].len();
        if n == 0 {
            return Ok(());
        }
        let s = self.out_start[c];
        T::get(inst, &self.out_vr[c], &mut self.slots[s..s + n])
    }

    fn write_inputs(&mut self, c: usize, inst: &mut Instance) -> Result<(), FmiError> {
        let n = self.in_vr[c].len();
        if n == 0 {
            return Ok(());
        }
        for i in 0..n {
            self.scratch[i] = self.slots[self.in_slot[c][i]].apply(self.in_transform[c][i]);
        }
        T::set(inst, &self.in_vr[c], &self.scratch[..n])
    }
}

/// What is recorded: per component and type, the value references, and their column index.
struct Recording {
    columns: Vec<String>,
    units: Vec<String>,
    real: Vec<(Vec<u32>, Vec<usize>)>,
    integer: Vec<(Vec<u32>, Vec<usize>)>,
    boolean: Vec<(Vec<u32>, Vec<usize>)>,
    row: Vec<f64>,
    buf_r: Vec<f64>,
    buf_i: Vec<i32>,
    buf_b: Vec<bool>,
}

impl Recording {
    fn new(
        system: &System,
        mds: &[&ModelDescription],
        selection: Option<&[Endpoint]>,
    ) -> Result<Recording, RunError> {
        let n = system.components.len();
        let mut chosen: Vec<(usize, &model_description::ScalarVariable)> = vec![];
        match selection {
            None => {
                for (c, md) in mds.iter().enumerate() {
                    for v in md
                        .model_variables
                        .iter()
                        .filter(|v| v.causality == Causality::Output)
                    {
                        if v.kind.base_type() != BaseType::String {
                            chosen.push((c, v));
                        }
                    }
                }
            }
            Some(list) => {
                for e in list {
                    let c = system
                        .components
                        .iter()
                        .position(|x| x.name == e.component)
                        .ok_or_else(|| {
                            RunError::Config(format!(
                                "recorded variable {e}: no component '{}'",
                                e.component
                            ))
                        })?;
                    let v = mds[c].variable(&e.variable).ok_or_else(|| {
                        RunError::Config(format!(
                            "recorded variable {e}: component '{}' ({}) has no variable '{}'",
                            e.component,
                            system.components[c].source.display(),
                            e.variable
                        ))
                    })?;
                    if v.kind.base_type() == BaseType::String {
                        return Err(RunError::Config(format!(
                            "recorded variable {e}: String variables cannot be recorded"
                        )));
                    }
                    chosen.push((c, v));
                }
            }
        }
        let mut rec = Recording {
            columns: vec![],
            units: vec![],
            real: vec![(vec![], vec![]); n],
            integer: vec![(vec![], vec![]); n],
            boolean: vec![(vec![], vec![]); n],
            row: vec![],
            buf_r: vec![],
            buf_i: vec![],
            buf_b: vec![],
        };
        for (col, (c, v)) in chosen.iter().enumerate() {
            rec.columns
                .push(format!("{}.{}", system.components[*c].name, v.name));
            rec.units.push(match &v.kind {
                VariableKind::Real(r) => r.unit.clone().unwrap_or_default(),
                _ => String::new(),
            });
            let target = match v.kind.base_type() {
                BaseType::Real => &mut rec.real[*c],
                BaseType::Integer | BaseType::Enumeration => &mut rec.integer[*c],
                _ => &mut rec.boolean[*c],
            };
            target.0.push(v.value_reference);
            target.1.push(col);
        }
        let widest =
            |l: &Vec<(Vec<u32>, Vec<usize>)>| l.iter().map(|x| x.0.len()).max().unwrap_or(0);
        rec.buf_r = vec![0.0; widest(&rec.real)];
        rec.buf_i = vec![0; widest(&rec.integer)];
        rec.buf_b = vec![false; widest(&rec.boolean)];
        rec.row = vec![0.0; rec.columns.len()];
        Ok(rec)
    }

    fn sample(&mut self, instances: &mut [Instance]) -> Result<(), FmiError> {
        for (c, inst) in instances.iter_mut().enumerate() {
            let (vr, cols) = &self.real[c];
            if !vr.is_empty() {
                inst.get_real(vr, &mut self.buf_r[..vr.len()])?;
                for (i, &col) in cols.iter().enumerate() {
                    self.row[col] = self.buf_r[i];
                }
            }
            let (vr, cols) = &self.integer[c];
            if !vr.is_empty() {
                inst.get_integer(vr, &mut self.buf_i[..vr.len()])?;
                for (i, &col) in cols.iter().enumerate() {
                    self.row[col] = self.buf_i[i] as f64;
                }
            }
            let (vr, cols) = &self.boolean[c];
            if !vr.is_empty() {
                inst.get_boolean(vr, &mut self.buf_b[..vr.len()])?;
                for (i, &col) in cols.iter().enumerate() {
                    self.row[col] = if self.buf_b[i] { 1.0 } else { 0.0 };
                }
            }
        }
        Ok(())
    }
}

/// A loaded system: its FMUs, the resolved plan, and the instances once instantiated.
pub struct Cosimulation {
    pub system: System,
    fmus: Vec<Fmu>,
    pub plan: Plan,
}

impl Cosimulation {
    /// Opens every FMU and resolves the system against their model descriptions.
    pub fn load(system: System) -> Result<Cosimulation, RunError> {
        if system.components.is_empty() {
            return Err(RunError::Config(format!(
                "system '{}' has no components",
                system.name
            )));
        }
        let mut fmus = vec![];
        for c in &system.components {
            fmus.push(Fmu::open(&c.source)?);
        }
        let mds: Vec<&ModelDescription> = fmus.iter().map(|f| f.model_description()).collect();
        let plan = resolve(&system, &mds)?;
        Ok(Cosimulation { system, fmus, plan })
    }

    pub fn model_descriptions(&self) -> Vec<&ModelDescription> {
        self.fmus.iter().map(|f| f.model_description()).collect()
    }

    /// Adds `component.variable=value` settings (command-line `--set`), checked like the
    /// system's own parameters; they are applied after those, so they win.
    pub fn set(&mut self, name: &Endpoint, text: &str) -> Result<(), RunError> {
        let c = self
            .system
            .components
            .iter()
            .position(|x| x.name == name.component)
            .ok_or_else(|| {
                RunError::Config(format!(
                    "--set {name}={text}: no component '{}'",
                    name.component
                ))
            })?;
        let md = self.fmus[c].model_description();
        let v = md.variable(&name.variable).ok_or_else(|| {
            RunError::Config(format!(
                "--set {name}={text}: component '{}' ({}) has no variable '{}'",
                name.component,
                self.fmus[c].path().display(),
                name.variable
            ))
        })?;
        let s = crate::resolve::setting(c, v, &Value::String(text.to_string()), name.clone())?;
        self.plan.settings.push(s);
        Ok(())
    }

    /// Runs the system; see the module docs.
    pub fn run(&self, opts: &RunOptions) -> Result<RunSummary, RunError> {
        self.run_with_inputs(opts, &|_, out: &mut Vec<ExternalValue>| out.clear())
    }

    /// Runs the system with external Real inputs of the first component: before the step from
    /// `t`, `external(t, buffer)` fills the buffer with (value reference, value) pairs, which are
    /// set before the component steps (and once at the start, in initialization mode).
    pub fn run_with_inputs(
        &self,
        opts: &RunOptions,
        external: &ExternalInputs<'_>,
    ) -> Result<RunSummary, RunError> {
        let started = Instant::now();
        let n = self.system.components.len();
        if !(opts.step > 0.0 && opts.step.is_finite()) {
            return Err(RunError::Config(format!(
                "step {} must be a positive number",
                opts.step
            )));
        }
        if !(opts.start.is_finite() && opts.stop.is_finite()) {
            return Err(RunError::Config(format!(
                "the start time {} s and the stop time {} s must be finite numbers",
                opts.start, opts.stop
            )));
        }
        let span = opts.stop - opts.start;
        if !(span >= 0.0) {
            return Err(RunError::Config(format!(
                "the stop time {} s is before the start time {} s",
                opts.stop, opts.start
            )));
        }
        let steps = (span / opts.step).round();
        if !(span >= 0.0) || (steps * opts.step - span).abs() > 1e-9 * span.abs().max(1.0) {
            return Err(RunError::Config(format!(
                "the run from {} s to {} s is not a whole number of {} s steps",
                opts.start, opts.stop, opts.step
            )));
        }
        // Communication points are start + k * step with k exact in an f64.
        const MAX_STEPS: f64 = (1u64 << 53) as f64;
        if steps > MAX_STEPS {
            use model_description::format_f64 as f;
            return Err(RunError::Config(format!(
                "the run from {} s to {} s has {steps:e} steps of {} s, more than 2^53",
                f(opts.start),
                f(opts.stop),
                f(opts.step)
            )));
        }
        let steps = steps as u64;
        let every = match opts.interval {
            None => 1,
            Some(i) => {
                let m = (i / opts.step).round();
                if m < 1.0 || (m * opts.step - i).abs() > 1e-9 * i.max(1.0) {
                    return Err(RunError::Config(format!(
                        "recording interval {i} s is not a whole number of {} s steps",
                        opts.step
                    )));
                }
                m as u64
            }
        };

        // The results file first: an unwritable destination stops us before any FMU runs.
        let mds = self.model_descriptions();
        let mut recording = if opts.out_dir.is_some() || opts.collect {
            let rec = Recording::new(&self.system, &mds, opts.record.as_deref())?;
            let recorder = match &opts.out_dir {
                Some(dir) => {
                    let mut r = Recorder::create(dir, &rec.columns, &rec.units).map_err(|e| {
                        RunError::Io(format!(
                            "cannot write results in {} (nothing was run): {e}",
                            dir.display()
                        ))
                    })?;
                    let integral: Vec<usize> = rec
                        .integer
                        .iter()
                        .chain(&rec.boolean)
                        .flat_map(|(_, cols)| cols.iter().copied())
                        .collect();
                    r.set_integral(&integral);
                    Some(r)
                }
                None => None,
            };
            let table = opts.collect.then(|| Table {
                columns: std::iter::once("time".to_string())
                    .chain(rec.columns.iter().cloned())
                    .collect(),
                // Reserved up to a million rows; a longer run grows the columns as it goes.
                data: vec![
                    Vec::with_capacity(steps.min(1 << 20) as usize + 1);
                    rec.columns.len() + 1
                ],
            });
            Some((rec, recorder, table))
        } else {
            None
        };
        let mut instances = Vec::with_capacity(n);
        for (c, fmu) in self.system.components.iter().zip(&self.fmus) {
            instances.push(fmu.instantiate(&c.name, opts.log.clone())?);
        }
        let fmi = |error: FmiError| RunError::Fmi {
            error,
            results: None,
        };
        for inst in instances.iter_mut() {
            inst.setup_experiment(opts.start, Some(opts.stop), None)
                .map_err(fmi)?;
        }
        for s in &self.plan.settings {
            let inst = &mut instances[s.component];
            match &s.value {
                Value::Real(x) => inst.set_real(&[s.vr], &[*x]),
                Value::Integer(x) => inst.set_integer(&[s.vr], &[*x]),
                Value::Boolean(x) => inst.set_boolean(&[s.vr], &[*x]),
                Value::String(x) => inst.set_string(&[s.vr], &[x.as_str()]),
            }
            .map_err(fmi)?;
        }
        for inst in instances.iter_mut() {
            inst.enter_initialization_mode().map_err(fmi)?;
        }
        let mut ext: Vec<ExternalValue> = Vec::new();
        let set_external =
            |inst: &mut Instance, ext: &mut Vec<ExternalValue>, t: f64| -> Result<(), FmiError> {
                external(t, ext);
                for &(base, vr, x) in ext.iter() {
                    match base {
                        BaseType::Real => inst.set_real(&[vr], &[x])?,
                        BaseType::Integer | BaseType::Enumeration => {
                            inst.set_integer(&[vr], &[x as i32])?
                        }
                        BaseType::Boolean => inst.set_boolean(&[vr], &[x != 0.0])?,
                        BaseType::String => {}
                    }
                }
                Ok(())
            };
        if n > 0 {
            set_external(&mut instances[0], &mut ext, opts.start).map_err(fmi)?;
        }

        let by_type = |b: BaseType| {
            self.plan
                .links
                .iter()
                .filter(|l| l.base == b)
                .collect::<Vec<_>>()
        };
        let mut real: Transfer<f64> = Transfer::new(n, &by_type(BaseType::Real));
        let mut integer: Transfer<i32> = Transfer::new(n, &by_type(BaseType::Integer));
        let mut boolean: Transfer<bool> = Transfer::new(n, &by_type(BaseType::Boolean));

        // Initial values through the connections: producers first, repeated once per component
        // so that values reach the end of any chain.
        for _ in 0..n {
            for &c in &self.plan.order {
                let inst = &mut instances[c];
                real.write_inputs(c, inst).map_err(fmi)?;
                integer.write_inputs(c, inst).map_err(fmi)?;
                boolean.write_inputs(c, inst).map_err(fmi)?;
                real.read_outputs(c, inst).map_err(fmi)?;
                integer.read_outputs(c, inst).map_err(fmi)?;
                boolean.read_outputs(c, inst).map_err(fmi)?;
            }
        }
        for &c in &self.plan.order {
            instances[c].exit_initialization_mode().map_err(fmi)?;
        }
        for (c, inst) in instances.iter_mut().enumerate() {
            real.read_outputs(c, inst).map_err(fmi)?;
            integer.read_outputs(c, inst).map_err(fmi)?;
            boolean.read_outputs(c, inst).map_err(fmi)?;
        }

        let io = |e: std::io::Error| RunError::Io(e.to_string());
        let keep = |t: f64,
                    row: &[f64],
                    recorder: &mut Option<Recorder>,
                    table: &mut Option<Table>|
         -> Result<(), RunError> {
            if let Some(r) = recorder.as_mut() {
                r.row(t, row).map_err(io)?;
            }
            if let Some(tb) = table.as_mut() {
                tb.data[0].push(t);
                for (col, v) in tb.data[1..].iter_mut().zip(row) {
                    col.push(*v);
                }
            }
            Ok(())
        };
        // A write failing mid-run: say where the run stopped and what is left on disk.
        let stopped = |e: RunError, t: f64, recorder: &Option<Recorder>| match (e, recorder) {
            (RunError::Io(m), Some(r)) => RunError::Io(format!(
                "{m}; the run stopped at t = {t} s; the rows written until then are in {} (the last one may be incomplete)",
                r.partial_path().display()
            )),
            (e, _) => e,
        };
        if let Some((rec, recorder, table)) = recording.as_mut() {
            rec.sample(&mut instances).map_err(fmi)?;
            keep(opts.start, &rec.row, recorder, table)
                .map_err(|e| stopped(e, opts.start, recorder))?;
        }

        let bar = if opts.progress && steps >= 10_000 {
            let bar = indicatif::ProgressBar::new(steps);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:40}] {percent:>3}% {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            Some(bar)
        } else {
            None
        };

        let order = &self.plan.order;
        let mut failure: Option<FmiError> = None;
        // The instance that ended the simulation, and its last successful time if past the
        // last communication point.
        let mut ended_by: Option<(String, Option<f64>)> = None;
        let mut interrupted = false;
        let mut k: u64 = 0;
        'steps: while k < steps {
            if stop_requested() {
                interrupted = true;
                break 'steps;
            }
            let t = opts.start + k as f64 * opts.step;
            let result: Result<(), FmiError> = (|| {
                set_external(&mut instances[0], &mut ext, t)?;
                match opts.algorithm {
                    Algorithm::GaussSeidel => {
                        for &c in order {
                            let inst = &mut instances[c];
                            real.write_inputs(c, inst)?;
                            integer.write_inputs(c, inst)?;
                            boolean.write_inputs(c, inst)?;
                            inst.do_step(t, opts.step)?;
                            real.read_outputs(c, inst)?;
                            integer.read_outputs(c, inst)?;
                            boolean.read_outputs(c, inst)?;
                        }
                    }
                    Algorithm::Jacobi => {
                        for &c in order {
                            let inst = &mut instances[c];
                            real.write_inputs(c, inst)?;
                            integer.write_inputs(c, inst)?;
                            boolean.write_inputs(c, inst)?;
                        }
                        for &c in order {
                            instances[c].do_step(t, opts.step)?;
                        }
                        for &c in order {
                            let inst = &mut instances[c];
                            real.read_outputs(c, inst)?;
                            integer.read_outputs(c, inst)?;
                            boolean.read_outputs(c, inst)?;
                        }
                    }
                }
                Ok(())
            })();
            if let Err(e) = result {
                if e.status == fmi2Status::Discard && e.terminated {
                    let at = e.last_successful_time.filter(|a| *a > t && a.is_finite());
                    ended_by = Some((e.instance, at));
                } else {
                    failure = Some(e);
                }
                break 'steps;
            }
            k += 1;
            if let Some((rec, recorder, table)) = recording.as_mut()
                && k.is_multiple_of(every)
            {
                if let Err(e) = rec.sample(&mut instances) {
                    failure = Some(e);
                    break 'steps;
                }
                let t = opts.start + k as f64 * opts.step;
                keep(t, &rec.row, recorder, table).map_err(|e| stopped(e, t, recorder))?;
            }
            if let Some(bar) = &bar
                && k.is_multiple_of(1000)
            {
                bar.set_position(k);
            }
        }
        if let Some(bar) = bar {
            bar.finish_and_clear();
        }
        let mut final_time = opts.start + k as f64 * opts.step;
        // As fmpy does: a last row at the ending FMU's last successful time, with every
        // component's outputs as they are (in a system, the others' at their last step).
        if let Some((_, Some(at))) = &ended_by {
            final_time = *at;
            if let Some((rec, recorder, table)) = recording.as_mut() {
                rec.sample(&mut instances).map_err(fmi)?;
                keep(*at, &rec.row, recorder, table).map_err(|e| stopped(e, *at, recorder))?;
            }
        }
        let (rows, results, table) = match recording {
            Some((_, recorder, table)) => {
                let rows = table.as_ref().map_or(0, |t| t.data[0].len() as u64);
                match recorder {
                    Some(r) => {
                        let rows = r.rows;
                        (rows, Some(r.finish().map_err(io)?), table)
                    }
                    None => (rows, None, table),
                }
            }
            None => (0, None, None),
        };
        if let Some(error) = failure {
            return Err(RunError::Fmi { error, results });
        }
        if interrupted {
            for inst in instances.iter_mut() {
                // Terminating is a courtesy here; the interrupt is what the caller hears of.
                let _ = inst.terminate();
            }
            return Err(RunError::Interrupted {
                time: opts.start + k as f64 * opts.step,
                steps: k,
                total: steps,
                rows,
                results,
            });
        }
        for inst in instances.iter_mut() {
            inst.terminate().map_err(|error| RunError::Fmi {
                error,
                results: results.clone(),
            })?;
        }
        Ok(RunSummary {
            steps: k,
            rows,
            results,
            table,
            wall: started.elapsed(),
            final_time,
            ended_by: ended_by.map(|(who, _)| who),
        })
    }
}
