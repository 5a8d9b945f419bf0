//! The results writers, one per format, chosen by the results file's extension:
//!
//! | file | format | units | provenance |
//! |---|---|---|---|
//! | `results.csv` (default) | CSV, `time` then `component.variable` columns ([`csv`]) | `results.units.csv` beside it | the directory's `manifest.json` |
//! | `results.parquet` | Parquet, one `DOUBLE` column each ([`parquet`]) | file metadata `units` | file metadata `provenance`: the manifest, and `manifest.json` too |
//!
//! Both are written as `NAME.partial` and renamed to `NAME` when the run is finished (or
//! stopped by an FMU error or an interrupt), so a reader never sees a half-written file under
//! the final name. Every I/O error names the file it happened on.

pub mod csv;
pub mod parquet;
pub mod size;

pub use csv::{CsvRecorder, push_f64};
pub use parquet::ParquetRecorder;

use std::io;
use std::path::{Path, PathBuf};

/// The results file of a run: its plain name inside the output directory, whose extension
/// chooses the format, and the provenance a Parquet file carries (JSON; the run's manifest).
#[derive(Debug, Clone, PartialEq)]
pub struct ResultsFile {
    name: String,
    /// The JSON a Parquet results file carries under `provenance` (the run's manifest, set
    /// when the output directory is held); `{}` until then. Unused for CSV.
    pub provenance: String,
}

impl Default for ResultsFile {
    fn default() -> ResultsFile {
        ResultsFile {
            name: "results.csv".into(),
            provenance: "{}".into(),
        }
    }
}

impl ResultsFile {
    /// `name` must be a plain file name (no directory) ending in `.csv` or `.parquet`.
    pub fn new(name: &str) -> Result<ResultsFile, String> {
        let plain = !name.is_empty()
            && !name.starts_with('.')
            && !name.contains(['/', '\\'])
            && Path::new(name).file_name() == Some(std::ffi::OsStr::new(name));
        let ext = Path::new(name)
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("csv" | "parquet") if plain => Ok(ResultsFile {
                name: name.into(),
                ..ResultsFile::default()
            }),
            _ => Err(format!(
                "--results {name}: expected a plain file name ending in .csv or .parquet (it goes into --out)"
            )),
        }
    }

    /// The plain file name, as checked by [`ResultsFile::new`].
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Whether the results are written as Parquet (by the `.parquet` extension), else CSV.
    pub fn is_parquet(&self) -> bool {
        crate::parquet::is_parquet(Path::new(&self.name))
    }

    /// The files a run with these results writes into its output directory (for the manifest).
    pub fn files(&self) -> Vec<String> {
        if self.is_parquet() {
            vec![self.name.clone()]
        } else {
            vec![self.name.clone(), units_file(&self.name)]
        }
    }
}

/// `NAME.partial`, the name a results file has until it is finished.
pub(crate) fn partial(path: &Path) -> PathBuf {
    let mut p = path.as_os_str().to_owned();
    p.push(".partial");
    PathBuf::from(p)
}

/// The CSV units file of results `NAME`: `STEM.units.csv`.
pub(crate) fn units_file(name: &str) -> String {
    let stem = Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(name);
    format!("{stem}.units.csv")
}

/// Renames a finished `NAME.partial` to `NAME`, naming both on failure.
pub(crate) fn rename_into_place(partial: &Path, path: &Path) -> io::Result<()> {
    std::fs::rename(partial, path).map_err(|e| {
        io::Error::new(
            e.kind(),
            format!(
                "cannot rename {} to {}: {e}",
                partial.display(),
                path.display()
            ),
        )
    })
}

/// A results writer of either format.
pub enum Recorder {
    /// `NAME.csv` with `NAME.units.csv` beside it.
    Csv(CsvRecorder),
    /// `NAME.parquet`, units and provenance in its metadata.
    Parquet(ParquetRecorder),
}

impl Recorder {
    /// Creates the results file in `dir` (with its header, so an unwritable destination fails
    /// here, before the run).
    pub fn create(
        dir: &Path,
        file: &ResultsFile,
        columns: &[String],
        units: &[String],
    ) -> io::Result<Recorder> {
        Ok(if file.is_parquet() {
            Recorder::Parquet(ParquetRecorder::create(
                dir,
                file.name(),
                columns,
                units,
                &file.provenance,
            )?)
        } else {
            Recorder::Csv(CsvRecorder::create(dir, file.name(), columns, units)?)
        })
    }

    /// Marks the columns of Integer, Enumeration and Boolean variables: the CSV writes them as
    /// whole numbers; Parquet keeps every column `DOUBLE` (exact for such values).
    pub fn set_integral(&mut self, columns: &[usize]) {
        if let Recorder::Csv(r) = self {
            r.set_integral(columns);
        }
    }

    /// Writes (or, for Parquet, gathers) one row: time, then a value per column.
    #[inline]
    pub fn row(&mut self, time: f64, values: &[f64]) -> io::Result<()> {
        match self {
            Recorder::Csv(r) => r.row(time, values),
            Recorder::Parquet(r) => r.row(time, values),
        }
    }

    /// Rows taken so far.
    pub fn rows(&self) -> u64 {
        match self {
            Recorder::Csv(r) => r.rows,
            Recorder::Parquet(r) => r.rows,
        }
    }

    /// What a write failing mid-run leaves on disk, for its error message.
    pub fn left_behind(&self) -> String {
        match self {
            Recorder::Csv(r) => format!(
                "the rows written until then are in {} (the last one may be incomplete)",
                r.partial_path().display()
            ),
            Recorder::Parquet(r) => format!(
                "{} has no footer and cannot be read (Parquet's index is written last)",
                r.partial_path().display()
            ),
        }
    }

    /// Writes what is left, closes the file and renames it to its name; returns its path.
    pub fn finish(self) -> io::Result<PathBuf> {
        match self {
            Recorder::Csv(r) => r.finish(),
            Recorder::Parquet(r) => r.finish(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_names_choose_the_format_and_plain_names_only() {
        let p = ResultsFile::new("run.PARQUET").unwrap();
        assert!(p.is_parquet() && p.files() == ["run.PARQUET"]);
        let c = ResultsFile::new("a.csv").unwrap();
        assert!(!c.is_parquet() && c.files() == ["a.csv", "a.units.csv"]);
        assert_eq!(
            ResultsFile::default().files(),
            ["results.csv", "results.units.csv"]
        );
        for bad in [
            "out/a.csv",
            "a.txt",
            "a",
            ".csv",
            "",
            "..\\a.csv",
            "../a.parquet",
        ] {
            let e = ResultsFile::new(bad).unwrap_err();
            assert!(e.contains(&format!("--results {bad}:")), "{e}");
        }
    }
}
