//! The Parquet results writer: the table the CSV writer writes, as one `DOUBLE` column per
//! variable with the units and the run's manifest in the file's metadata ([`crate::parquet`]).
//!
//! Rows are gathered in columns and written a row group at a time, so a long run streams out
//! in bounded memory: [`ROW_GROUP`] rows, or fewer for a wide table, at most [`GROUP_BYTES`]
//! (16 MiB) of values, at least 1024 rows. The file's header is only written with the first row
//! group: a full disk shows then, not before the run (the CSV writer's header probe). Parquet's index (the footer) is written
//! last, by [`ParquetRecorder::finish`]: a run stopped by an FMU error or an interrupt still
//! finishes the file, while a write that fails mid-run leaves a partial file no reader opens.

use crate::parquet::{ParquetWriter, ROW_GROUP};
use std::io;
use std::path::{Path, PathBuf};

/// The most memory a row group's values take before they are written.
pub const GROUP_BYTES: usize = 16 << 20;

/// An open Parquet results file: created by [`ParquetRecorder::create`], rows gathered by
/// [`ParquetRecorder::row`] and written a row group at a time, the footer written and the file
/// renamed into place by [`ParquetRecorder::finish`].
pub struct ParquetRecorder {
    /// `None` once finished.
    writer: Option<ParquetWriter>,
    /// The rows not yet written, by column, time first.
    pending: Vec<Vec<f64>>,
    /// Rows per row group.
    group_rows: usize,
    partial: PathBuf,
    path: PathBuf,
    /// Rows taken so far, written or still pending.
    pub rows: u64,
}

/// Dropped unfinished with no row (the run failed before it started): nothing to keep.
impl Drop for ParquetRecorder {
    fn drop(&mut self) {
        if self.writer.is_some() && self.rows == 0 {
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}

impl ParquetRecorder {
    /// Creates `dir/NAME.partial` with its schema (`time` in s, then `columns` in `units`) and
    /// `provenance` (JSON) in the metadata. Errors name the directory or file.
    pub fn create(
        dir: &Path,
        name: &str,
        columns: &[String],
        units: &[String],
        provenance: &str,
    ) -> io::Result<ParquetRecorder> {
        std::fs::create_dir_all(dir).map_err(|e| {
            io::Error::new(
                e.kind(),
                format!("cannot create the directory {}: {e}", dir.display()),
            )
        })?;
        let path = dir.join(name);
        let partial = super::partial(&path);
        let names: Vec<String> = std::iter::once("time".to_string())
            .chain(columns.iter().cloned())
            .collect();
        let units: Vec<String> = std::iter::once("s".to_string())
            .chain(units.iter().cloned())
            .collect();
        let writer = ParquetWriter::create(&partial, &names, &units, provenance)
            .map_err(|e| io::Error::other(format!("cannot create {e}")))?;
        let group_rows = (GROUP_BYTES / (8 * names.len())).clamp(1024, ROW_GROUP);
        Ok(ParquetRecorder {
            writer: Some(writer),
            pending: vec![Vec::with_capacity(group_rows); names.len()],
            group_rows,
            partial,
            path,
            rows: 0,
        })
    }

    /// Takes one row: time, then `values` (as many as columns); writes a row group when one
    /// is full, so an I/O error shows here, naming the file.
    #[inline]
    pub fn row(&mut self, time: f64, values: &[f64]) -> io::Result<()> {
        debug_assert_eq!(values.len() + 1, self.pending.len());
        self.pending[0].push(time);
        for (col, &v) in self.pending[1..].iter_mut().zip(values) {
            col.push(v);
        }
        self.rows += 1;
        if self.pending[0].len() == self.group_rows {
            self.write_pending()?;
        }
        Ok(())
    }

    fn write_pending(&mut self) -> io::Result<()> {
        if self.pending[0].is_empty() {
            return Ok(());
        }
        let writer = self.writer.as_mut().expect("an unfinished recorder");
        let group: Vec<&[f64]> = self.pending.iter().map(Vec::as_slice).collect();
        writer
            .row_group(&group)
            .map_err(|e| io::Error::other(format!("cannot write {e}")))?;
        for c in &mut self.pending {
            c.clear();
        }
        Ok(())
    }

    /// The file being written (`NAME.partial`).
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    /// Writes the last rows and the footer, syncs ([`ParquetWriter::finish`]) and renames to
    /// `NAME`; returns its path.
    pub fn finish(mut self) -> io::Result<PathBuf> {
        self.write_pending()?;
        let writer = self.writer.take().expect("an unfinished recorder");
        writer
            .finish()
            .map_err(|e| io::Error::other(format!("cannot write {e}")))?;
        super::rename_into_place(&self.partial, &self.path)?;
        Ok(self.path.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// More rows than a row group, values no text format keeps (NaN payloads aside): read
    /// back bit for bit, with the units and provenance, and only under the final name.
    #[test]
    fn rows_round_trip_bit_for_bit_across_row_groups() {
        let dir = tempfile::tempdir().unwrap();
        let cols = ["a.x".to_string(), "b.flag".to_string()];
        let mut r = ParquetRecorder::create(
            dir.path(),
            "results.parquet",
            &cols,
            &["m".into(), "".into()],
            r#"{"program":"test"}"#,
        )
        .unwrap();
        let n = ROW_GROUP + 17;
        let special = [f64::MIN_POSITIVE / 3.0, -0.0, f64::INFINITY, 1.0 / 3.0];
        let x = |k: usize| special[k % 4] * (k as f64 + 1.0);
        for k in 0..n {
            r.row(k as f64 * 1e-3, &[x(k), (k % 2) as f64]).unwrap();
        }
        assert!(!dir.path().join("results.parquet").exists());
        let path = r.finish().unwrap();
        assert!(!dir.path().join("results.parquet.partial").exists());
        let t = crate::parquet::read(&path).unwrap();
        assert_eq!(t.names, ["time", "a.x", "b.flag"]);
        assert_eq!(t.units, ["s", "m", ""]);
        assert_eq!(t.metadata["provenance"], r#"{"program":"test"}"#);
        for k in [0, 1, 2, 3, ROW_GROUP - 1, ROW_GROUP, n - 1] {
            assert_eq!(t.columns[0][k].to_bits(), (k as f64 * 1e-3).to_bits());
            assert_eq!(t.columns[1][k].to_bits(), x(k).to_bits(), "row {k}");
            assert_eq!(t.columns[2][k], (k % 2) as f64);
        }
        assert_eq!(t.columns[0].len(), n);
    }

    #[test]
    fn a_recorder_dropped_before_any_row_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let r = ParquetRecorder::create(dir.path(), "r.parquet", &["a".into()], &["".into()], "{}")
            .unwrap();
        assert!(dir.path().join("r.parquet.partial").exists());
        drop(r);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
