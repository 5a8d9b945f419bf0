//! Parquet tables of `f64` columns: the columnar alternative to CSV for recordings and results,
//! chosen by a file's `.parquet` extension, written and read with the `parquet` crate's column
//! API (no Arrow: the master stays small).
//!
//! | where | what |
//! |---|---|
//! | schema | one `DOUBLE` column per variable, `REQUIRED`, named as the CSV header would be |
//! | file key-value metadata `units` | JSON object `{column: unit}` (empty units left out) |
//! | file key-value metadata `provenance` | JSON: the run's manifest (what produced the file, with which inputs and settings) |
//! | row groups | [`ROW_GROUP`] rows each from [`write()`]; [`ParquetWriter::row_group`] writes them one at a time |
//!
//! Reading accepts what other tools write for a table of numbers: `DOUBLE`, `FLOAT`, `INT32`
//! and `INT64` columns, `REQUIRED` or `OPTIONAL` (a null is refused, naming its column and
//! row), with units from our `units` key or, where absent, none. Values round-trip bit for bit.

use parquet::basic::{Compression, Repetition, Type as PhysicalType};
use parquet::column::reader::ColumnReader;
use parquet::data_type::DoubleType;
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::Type;
use std::collections::BTreeMap;
use std::fs::File;
use std::path::Path;
use std::sync::Arc;

/// Rows per row group: 64 Ki rows of a few dozen columns is a few MB in memory.
pub const ROW_GROUP: usize = 65_536;
/// The file metadata key holding the units, a JSON object `{column: unit}`; the Python
/// package's recordings use the same key, so units survive between the two.
pub const UNITS_KEY: &str = "units";
/// The file metadata key holding the producing run's manifest, as JSON.
pub const PROVENANCE_KEY: &str = "provenance";

/// Whether `path` names a Parquet file (by its extension, case-insensitive).
pub fn is_parquet(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("parquet"))
}

/// A table read back: names, units ("" where none) and columns, with the file's metadata.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParquetTable {
    /// Column names, in the schema's order.
    pub names: Vec<String>,
    /// One unit per column, "" where the `units` key gives none (or the file has no such key).
    pub units: Vec<String>,
    /// One vector per column (integers and floats widened to `f64`), all of the same length.
    pub columns: Vec<Vec<f64>>,
    /// The file's key-value metadata, every key (a key without a value maps to "").
    pub metadata: BTreeMap<String, String>,
}

/// A Parquet file written a row group at a time, so a long table streams out.
pub struct ParquetWriter {
    writer: SerializedFileWriter<File>,
    path: std::path::PathBuf,
}

fn err(path: &Path, e: impl std::fmt::Display) -> String {
    format!("{}: {e}", path.display())
}

impl ParquetWriter {
    /// Creates `path` with `names` (and their `units`), `provenance` JSON in the metadata.
    pub fn create(
        path: &Path,
        names: &[String],
        units: &[String],
        provenance: &str,
    ) -> Result<ParquetWriter, String> {
        let fields = names
            .iter()
            .map(|n| {
                Type::primitive_type_builder(n, PhysicalType::DOUBLE)
                    .with_repetition(Repetition::REQUIRED)
                    .build()
                    .map(Arc::new)
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| err(path, e))?;
        let schema = Type::group_type_builder("schema")
            .with_fields(fields)
            .build()
            .map_err(|e| err(path, e))?;
        let units: BTreeMap<&str, &str> = names
            .iter()
            .zip(units)
            .filter(|(_, u)| !u.is_empty())
            .map(|(n, u)| (n.as_str(), u.as_str()))
            .collect();
        let units = serde_json::to_string(&units).map_err(|e| err(path, e))?;
        let props = WriterProperties::builder()
            .set_compression(Compression::SNAPPY)
            // Measured values rarely repeat: a dictionary costs time and saves nothing.
            .set_dictionary_enabled(false)
            .set_key_value_metadata(Some(vec![
                KeyValue::new(UNITS_KEY.into(), units),
                KeyValue::new(PROVENANCE_KEY.into(), provenance.to_string()),
            ]))
            .set_created_by(format!("track-alignment {}", env!("CARGO_PKG_VERSION")))
            .build();
        let file = File::create(path).map_err(|e| err(path, e))?;
        let writer = SerializedFileWriter::new(file, Arc::new(schema), Arc::new(props))
            .map_err(|e| err(path, e))?;
        Ok(ParquetWriter {
            writer,
            path: path.to_path_buf(),
        })
    }

    /// Writes one row group of `columns` (one slice per column, of equal length).
    pub fn row_group(&mut self, columns: &[&[f64]]) -> Result<(), String> {
        let path = &self.path;
        let mut rg = self.writer.next_row_group().map_err(|e| err(path, e))?;
        for c in columns {
            let mut col = rg
                .next_column()
                .map_err(|e| err(path, e))?
                .ok_or_else(|| err(path, "fewer columns than the schema"))?;
            col.typed::<DoubleType>()
                .write_batch(c, None, None)
                .map_err(|e| err(path, e))?;
            col.close().map_err(|e| err(path, e))?;
        }
        rg.close().map_err(|e| err(path, e))?;
        Ok(())
    }

    /// Writes the footer and syncs the file to disk.
    pub fn finish(self) -> Result<(), String> {
        let file = self.writer.into_inner().map_err(|e| err(&self.path, e))?;
        file.sync_all().map_err(|e| err(&self.path, e))
    }
}

/// Writes whole columns, a row group per [`ROW_GROUP`] rows straight from the slices.
pub fn write(
    path: &Path,
    names: &[String],
    units: &[String],
    columns: &[&[f64]],
    provenance: &str,
) -> Result<(), String> {
    let mut w = ParquetWriter::create(path, names, units, provenance)?;
    let n = columns.first().map_or(0, |c| c.len());
    for start in (0..n).step_by(ROW_GROUP) {
        let end = (start + ROW_GROUP).min(n);
        let group: Vec<&[f64]> = columns.iter().map(|c| &c[start..end]).collect();
        w.row_group(&group)?;
    }
    w.finish()
}

/// Reads every column as `f64`; errors name the file, and the column and row where one is bad.
pub fn read(path: &Path) -> Result<ParquetTable, String> {
    let file = File::open(path).map_err(|e| err(path, e))?;
    let reader = SerializedFileReader::new(file)
        .map_err(|e| err(path, format!("not a readable Parquet file ({e})")))?;
    let meta = reader.metadata();
    let schema = meta.file_metadata().schema_descr();
    let mut table = ParquetTable::default();
    for c in schema.columns() {
        if c.max_rep_level() > 0 {
            return Err(err(
                path,
                format!(
                    "column '{}' is repeated (a list), not a number per row",
                    c.path()
                ),
            ));
        }
        table.names.push(c.path().string());
    }
    if let Some(kv) = meta.file_metadata().key_value_metadata() {
        for k in kv {
            table
                .metadata
                .insert(k.key.clone(), k.value.clone().unwrap_or_default());
        }
    }
    let units: BTreeMap<String, String> = match table.metadata.get(UNITS_KEY) {
        Some(json) => serde_json::from_str(json).map_err(|e| {
            err(
                path,
                format!("metadata '{UNITS_KEY}' is not a JSON object of strings ({e})"),
            )
        })?,
        None => BTreeMap::new(),
    };
    table.units = table
        .names
        .iter()
        .map(|n| units.get(n).cloned().unwrap_or_default())
        .collect();
    table.columns = vec![Vec::new(); table.names.len()];
    for g in 0..reader.num_row_groups() {
        let rg = reader.get_row_group(g).map_err(|e| err(path, e))?;
        let rows = rg.metadata().num_rows() as usize;
        for (i, name) in table.names.iter().enumerate() {
            let first_row = table.columns[i].len();
            let col = rg.get_column_reader(i).map_err(|e| err(path, e))?;
            let values = read_column(col, rows, schema.column(i).max_def_level())
                .map_err(|e| err(path, format!("column '{name}': {e}")))?;
            if let Err(k) = values {
                return Err(err(
                    path,
                    format!("column '{name}' row {}: null", first_row + k + 1),
                ));
            }
            table.columns[i].extend(values.unwrap());
        }
    }
    Ok(table)
}

/// One column chunk as `f64`; `Ok(Err(k))` when row `k` is null.
fn read_column(
    col: ColumnReader,
    rows: usize,
    max_def: i16,
) -> Result<Result<Vec<f64>, usize>, String> {
    macro_rules! typed {
        ($r:expr, $conv:expr) => {{
            let mut r = $r;
            let mut values = Vec::with_capacity(rows);
            let mut defs = Vec::with_capacity(rows);
            let mut read = 0;
            while read < rows {
                let (records, _, _) = r
                    .read_records(rows - read, Some(&mut defs), None, &mut values)
                    .map_err(|e| e.to_string())?;
                if records == 0 {
                    return Err(format!("{read} of {rows} rows present"));
                }
                read += records;
            }
            if max_def > 0 {
                if let Some(k) = defs.iter().position(|&d| d < max_def) {
                    return Ok(Err(k));
                }
            }
            Ok(Ok(values.into_iter().map($conv).collect()))
        }};
    }
    match col {
        ColumnReader::DoubleColumnReader(r) => typed!(r, |x: f64| x),
        ColumnReader::FloatColumnReader(r) => typed!(r, |x: f32| x as f64),
        ColumnReader::Int32ColumnReader(r) => typed!(r, |x: i32| x as f64),
        ColumnReader::Int64ColumnReader(r) => typed!(r, |x: i64| x as f64),
        _ => Err("not a number column (DOUBLE, FLOAT, INT32 or INT64)".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_bit_exact_with_units_and_provenance() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.parquet");
        let n = ROW_GROUP * 2 + 17; // three row groups
        let a: Vec<f64> = (0..n).map(|k| (k as f64 * 0.1).sin() / 3.0).collect();
        let b: Vec<f64> = (0..n)
            .map(|k| match k % 5 {
                0 => f64::NAN,
                1 => -0.0,
                2 => f64::INFINITY,
                3 => 1e-310,
                _ => k as f64,
            })
            .collect();
        let names = vec!["time".to_string(), "vehicle.ws_acc_y".to_string()];
        let units = vec!["s".to_string(), "m/s2".to_string()];
        write(&path, &names, &units, &[&a, &b], r#"{"command":"run"}"#).unwrap();
        let t = read(&path).unwrap();
        assert_eq!(t.names, names);
        assert_eq!(t.units, units);
        assert_eq!(t.metadata[PROVENANCE_KEY], r#"{"command":"run"}"#);
        for (got, want) in t.columns.iter().zip([&a, &b]) {
            assert_eq!(got.len(), want.len());
            assert!(
                got.iter()
                    .zip(want.iter())
                    .all(|(x, y)| x.to_bits() == y.to_bits())
            );
        }
    }

    #[test]
    fn a_corrupt_file_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.parquet");
        std::fs::write(&path, b"PAR1 this is not parquet PAR1").unwrap();
        let e = read(&path).unwrap_err();
        assert!(
            e.contains("bad.parquet") && e.contains("not a readable Parquet file"),
            "{e}"
        );
    }
}
