//! The CSV results writer: `results.csv` (or the name the run gives) with a `time` column first
//! and one column per recorded variable named `component.variable`, and `results.units.csv`
//! beside it with the same header and one row of units (so the data file stays a plain
//! one-header CSV that every tool reads).
//!
//! Recording costs more than stepping in every master measured (docs/references.md section
//! 8.2), so the writer formats floats with `ryu` (shortest round-trip representation) into one
//! reused line buffer and writes through a large `BufWriter`. Rows are written as they come:
//! when a run fails, everything recorded so far is flushed and kept.
//!
//! [`CsvRecorder::create`] is the probe that makes an unwritable destination fail before the
//! run starts: it creates the directory, writes the units file and the header of the partial
//! file, and flushes the header to the file at once, so a missing permission, a path through a
//! regular file or a full disk is reported then, naming the file.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The error with the file it happened on in front.
fn naming(path: &Path, action: &str) -> impl FnOnce(io::Error) -> io::Error {
    let prefix = format!("cannot {action} {}", path.display());
    move |e| io::Error::new(e.kind(), format!("{prefix}: {e}"))
}

/// An open CSV results file: created with its header by [`CsvRecorder::create`], a row per
/// [`CsvRecorder::row`], renamed into place by [`CsvRecorder::finish`].
pub struct CsvRecorder {
    out: BufWriter<File>,
    line: Vec<u8>,
    partial: PathBuf,
    path: PathBuf,
    units_path: PathBuf,
    columns: usize,
    /// Columns of Integer, Enumeration or Boolean variables: written as whole numbers.
    integral: Vec<bool>,
    /// Rows written so far (not counting the header).
    pub rows: u64,
    finished: bool,
}

/// A recorder dropped before [`CsvRecorder::finish`] with no row written (the run failed before
/// it started) removes its files: there is nothing to keep. One with rows keeps the partial
/// file (a write failed mid-run).
impl Drop for CsvRecorder {
    fn drop(&mut self) {
        if !self.finished && self.rows == 0 {
            let _ = std::fs::remove_file(&self.partial);
            let _ = std::fs::remove_file(&self.units_path);
        }
    }
}

/// Appends `x` as the results files write numbers: shortest round-trip form, `nan`, `inf`, `-inf`.
pub fn push_f64(line: &mut Vec<u8>, x: f64, buf: &mut ryu::Buffer) {
    if x.is_finite() {
        let s = buf.format_finite(x);
        // ryu writes "1e-7" style exponents and "1.0" for integers: both parse everywhere.
        line.extend_from_slice(s.as_bytes());
    } else if x.is_nan() {
        line.extend_from_slice(b"nan");
    } else if x > 0.0 {
        line.extend_from_slice(b"inf");
    } else {
        line.extend_from_slice(b"-inf");
    }
}

fn csv_field(name: &str) -> String {
    if name.contains([',', '"', '\n']) {
        format!("\"{}\"", name.replace('"', "\"\""))
    } else {
        name.to_string()
    }
}

impl CsvRecorder {
    /// Creates `dir/NAME.partial` with the header (flushed to the file at once, so that an
    /// unwritable destination fails here), and the units file `dir/STEM.units.csv`. Errors name
    /// the directory or file.
    pub fn create(
        dir: &Path,
        name: &str,
        columns: &[String],
        units: &[String],
    ) -> std::io::Result<CsvRecorder> {
        std::fs::create_dir_all(dir).map_err(naming(dir, "create the directory"))?;
        let path = dir.join(name);
        let partial = super::partial(&path);
        let file = File::create(&partial).map_err(naming(&partial, "create"))?;
        let mut out = BufWriter::with_capacity(1 << 20, file);
        let header: Vec<String> = std::iter::once("time".to_string())
            .chain(columns.iter().map(|c| csv_field(c)))
            .collect();
        // Whatever this function created is removed again when it fails.
        let undo = |e: io::Error, files: &[&Path]| {
            for f in files {
                let _ = std::fs::remove_file(f);
            }
            e
        };
        writeln!(out, "{}", header.join(","))
            .and_then(|()| out.flush())
            .map_err(naming(&partial, "write"))
            .map_err(|e| undo(e, &[&partial]))?;
        let unit_row: Vec<String> = std::iter::once("s".to_string())
            .chain(units.iter().map(|u| csv_field(u)))
            .collect();
        let units_path = dir.join(super::units_file(name));
        std::fs::write(
            &units_path,
            format!("{}\n{}\n", header.join(","), unit_row.join(",")),
        )
        .map_err(naming(&units_path, "write"))
        .map_err(|e| undo(e, &[&partial, &units_path]))?;
        Ok(CsvRecorder {
            out,
            line: Vec::with_capacity(32 * (columns.len() + 1)),
            partial,
            path,
            units_path,
            columns: columns.len(),
            integral: vec![false; columns.len()],
            rows: 0,
            finished: false,
        })
    }

    /// Marks the columns (by index, without the time column) of Integer, Enumeration and
    /// Boolean variables, written as `3` and `1` rather than `3.0` and `1.0`.
    pub fn set_integral(&mut self, columns: &[usize]) {
        for c in columns {
            if let Some(f) = self.integral.get_mut(*c) {
                *f = true;
            }
        }
    }

    /// Writes one row: time, then `values` (as many as columns).
    pub fn row(&mut self, time: f64, values: &[f64]) -> std::io::Result<()> {
        debug_assert_eq!(values.len(), self.columns);
        let mut buf = ryu::Buffer::new();
        self.line.clear();
        push_f64(&mut self.line, time, &mut buf);
        for (&v, &integral) in values.iter().zip(&self.integral) {
            self.line.push(b',');
            if integral && v.is_finite() {
                self.line
                    .extend_from_slice((v as i64).to_string().as_bytes());
            } else {
                push_f64(&mut self.line, v, &mut buf);
            }
        }
        self.line.push(b'\n');
        self.out
            .write_all(&self.line)
            .map_err(naming(&self.partial, "write"))?;
        self.rows += 1;
        Ok(())
    }

    /// The file being written (`NAME.partial`).
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    /// Flushes, syncs and renames the partial file to its name; returns its path. Errors name the file.
    pub fn finish(mut self) -> std::io::Result<PathBuf> {
        self.out.flush().map_err(naming(&self.partial, "write"))?;
        self.out
            .get_ref()
            .sync_all()
            .map_err(naming(&self.partial, "write"))?;
        super::rename_into_place(&self.partial, &self.path)?;
        self.finished = true;
        Ok(self.path.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_round_trip_exactly_and_the_file_appears_on_finish() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = CsvRecorder::create(
            dir.path(),
            "results.csv",
            &["a.x".into(), "b.y,z".into()],
            &["m".into(), "".into()],
        )
        .unwrap();
        let values = [[0.1, -1e-300], [1.0 / 3.0, 123456789.0]];
        for (k, v) in values.iter().enumerate() {
            r.row(k as f64 * 1e-3, v).unwrap();
        }
        assert!(!dir.path().join("results.csv").exists());
        let path = r.finish().unwrap();
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("time,a.x,\"b.y,z\""));
        for v in values {
            let fields: Vec<f64> = lines
                .next()
                .unwrap()
                .split(',')
                .map(|f| f.parse().unwrap())
                .collect();
            assert_eq!(fields[1..], v);
        }
        let units = std::fs::read_to_string(dir.path().join("results.units.csv")).unwrap();
        assert_eq!(units.lines().nth(1), Some("s,m,"));
    }
}
