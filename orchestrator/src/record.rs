//! The results writer: `results.csv` with a `time` column first and one column per recorded
//! variable named `component.variable`, and `results.units.csv` beside it with the same header
//! and one row of units (so the data file stays a plain one-header CSV that every tool reads).
//!
//! Recording costs more than stepping in every master measured (masters.md section 2), so the
//! writer formats floats with `ryu` (shortest round-trip representation) into one reused line
//! buffer and writes through a large `BufWriter`. Rows are written as they come: when a run
//! fails, everything recorded so far is flushed and kept. The file is written as
//! `results.csv.partial` and renamed to `results.csv` when the run is finished (or stopped by an
//! error), so a reader never sees a half-written file under the final name.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub struct Recorder {
    out: BufWriter<File>,
    line: Vec<u8>,
    partial: PathBuf,
    path: PathBuf,
    columns: usize,
    pub rows: u64,
}

fn push_f64(line: &mut Vec<u8>, x: f64, buf: &mut ryu::Buffer) {
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

impl Recorder {
    /// Creates `dir/results.csv.partial` with the header, and `dir/results.units.csv`.
    pub fn create(dir: &Path, columns: &[String], units: &[String]) -> std::io::Result<Recorder> {
        std::fs::create_dir_all(dir)?;
        let path = dir.join("results.csv");
        let partial = dir.join("results.csv.partial");
        let mut out = BufWriter::with_capacity(1 << 20, File::create(&partial)?);
        let header: Vec<String> = std::iter::once("time".to_string())
            .chain(columns.iter().map(|c| csv_field(c)))
            .collect();
        writeln!(out, "{}", header.join(","))?;
        let unit_row: Vec<String> = std::iter::once("s".to_string())
            .chain(units.iter().map(|u| csv_field(u)))
            .collect();
        std::fs::write(
            dir.join("results.units.csv"),
            format!("{}\n{}\n", header.join(","), unit_row.join(",")),
        )?;
        Ok(Recorder {
            out,
            line: Vec::with_capacity(32 * (columns.len() + 1)),
            partial,
            path,
            columns: columns.len(),
            rows: 0,
        })
    }

    /// Writes one row: time, then `values` (as many as columns).
    pub fn row(&mut self, time: f64, values: &[f64]) -> std::io::Result<()> {
        debug_assert_eq!(values.len(), self.columns);
        let mut buf = ryu::Buffer::new();
        self.line.clear();
        push_f64(&mut self.line, time, &mut buf);
        for &v in values {
            self.line.push(b',');
            push_f64(&mut self.line, v, &mut buf);
        }
        self.line.push(b'\n');
        self.rows += 1;
        self.out.write_all(&self.line)
    }

    /// Flushes and renames to `results.csv`; returns its path.
    pub fn finish(mut self) -> std::io::Result<PathBuf> {
        self.out.flush()?;
        self.out.get_ref().sync_all()?;
        std::fs::rename(&self.partial, &self.path)?;
        Ok(self.path.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_round_trip_exactly_and_the_file_appears_on_finish() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = Recorder::create(
            dir.path(),
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
