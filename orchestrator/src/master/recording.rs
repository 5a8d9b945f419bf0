//! Recording as an observer of the run ([`Observer`], as libcosim's file observer is one): it
//! reads the values at the start, after every step and at the time an FMU ended the run; it
//! owns what is recorded, the results file and the table in memory, and decides which steps
//! make a row.
//!
//! It is created before any FMU is instantiated, because creating it creates the results file
//! (and, for CSV, flushes its header): an unwritable destination stops the run before it
//! starts, and for CSV a full disk too.

use super::grid::Grid;
use super::{Flow, ObserveError, Observer, RunError, RunOptions, Table, Values};
use crate::record::Recorder;
use crate::system::{Endpoint, System};
use fmi_import::FmiError;
use model_description::{BaseType, Causality, ModelDescription, VariableKind};
use std::path::PathBuf;

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
                    let (c, v) =
                        crate::resolve::find(system, mds, e, &format!("recorded variable {e}"))?;
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

    fn sample(&mut self, values: &mut Values<'_>) -> Result<(), FmiError> {
        for c in 0..values.len() {
            let (vr, cols) = &self.real[c];
            if !vr.is_empty() {
                values.get_real(c, vr, &mut self.buf_r[..vr.len()])?;
                for (i, &col) in cols.iter().enumerate() {
                    self.row[col] = self.buf_r[i];
                }
            }
            let (vr, cols) = &self.integer[c];
            if !vr.is_empty() {
                values.get_integer(c, vr, &mut self.buf_i[..vr.len()])?;
                for (i, &col) in cols.iter().enumerate() {
                    self.row[col] = self.buf_i[i] as f64;
                }
            }
            let (vr, cols) = &self.boolean[c];
            if !vr.is_empty() {
                values.get_boolean(c, vr, &mut self.buf_b[..vr.len()])?;
                for (i, &col) in cols.iter().enumerate() {
                    self.row[col] = if self.buf_b[i] { 1.0 } else { 0.0 };
                }
            }
        }
        Ok(())
    }
}

/// The recording observer.
pub(super) struct Results {
    recording: Recording,
    recorder: Option<Recorder>,
    table: Option<Table>,
    /// A row every this many steps.
    every: u64,
}

impl Results {
    /// The observer the options ask for (`None`: nothing is recorded), with the results file
    /// created.
    pub fn new(
        system: &System,
        mds: &[&ModelDescription],
        opts: &RunOptions,
        grid: &Grid,
    ) -> Result<Option<Results>, RunError> {
        if opts.out_dir.is_none() && !opts.collect {
            return Ok(None);
        }
        let rec = Recording::new(system, mds, opts.record.as_deref())?;
        let recorder = match &opts.out_dir {
            Some(dir) => {
                let rows = grid.steps / grid.every + 1;
                crate::record::size::check(
                    opts.results.name(),
                    rows,
                    rec.columns.len() + 1,
                    opts.results.is_parquet(),
                    opts.max_output,
                    crate::record::size::free_space(dir),
                )?;
                let mut r = Recorder::create(dir, &opts.results, &rec.columns, &rec.units)
                    .map_err(|e| {
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
                Vec::with_capacity(grid.steps.min(1 << 20) as usize + 1);
                rec.columns.len() + 1
            ],
        });
        Ok(Some(Results {
            recording: rec,
            recorder,
            table,
            every: grid.every,
        }))
    }

    /// Records a row at time `t`.
    fn observe(&mut self, t: f64, values: &mut Values<'_>) -> Result<(), ObserveError> {
        self.recording.sample(values)?;
        self.keep(t).map_err(ObserveError::Run)
    }

    fn keep(&mut self, t: f64) -> Result<(), RunError> {
        let row = &self.recording.row;
        if let Some(r) = self.recorder.as_mut() {
            r.row(t, row).map_err(|e| {
                // A write failing mid-run: say where the run stopped and what is left on disk.
                RunError::Io(format!(
                    "{e}; the run stopped at t = {t} s; {}",
                    r.left_behind()
                ))
            })?;
        }
        if let Some(tb) = self.table.as_mut() {
            tb.data[0].push(t);
            for (col, v) in tb.data[1..].iter_mut().zip(row) {
                col.push(*v);
            }
        }
        Ok(())
    }

    /// Closes the results file (renamed from its partial name): the rows recorded, its path
    /// and the table.
    pub fn finish(self) -> Result<(u64, Option<PathBuf>, Option<Table>), RunError> {
        let io = |e: std::io::Error| RunError::Io(e.to_string());
        let rows = self.table.as_ref().map_or(0, |t| t.data[0].len() as u64);
        match self.recorder {
            Some(r) => {
                let rows = r.rows();
                Ok((rows, Some(r.finish().map_err(io)?), self.table))
            }
            None => Ok((rows, None, self.table)),
        }
    }
}

impl Observer for Results {
    fn initialized(&mut self, t: f64, values: &mut Values<'_>) -> Result<Flow, ObserveError> {
        self.observe(t, values).map(|()| Flow::Continue)
    }

    /// A row when the step count is a multiple of the recording interval.
    #[inline]
    fn stepped(&mut self, k: u64, t: f64, values: &mut Values<'_>) -> Result<Flow, ObserveError> {
        if k.is_multiple_of(self.every) {
            self.observe(t, values)?;
        }
        Ok(Flow::Continue)
    }

    fn ended_at(&mut self, t: f64, values: &mut Values<'_>) -> Result<(), ObserveError> {
        self.observe(t, values)
    }
}
