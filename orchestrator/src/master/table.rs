//! Recorded columns kept in memory, for callers that evaluate a run without reading its
//! results.csv back (the studies, `run` of the standard case).

/// Recorded columns kept in memory: `time` first, then `component.variable`.
#[derive(Debug, Clone, Default)]
pub struct Table {
    /// The column names: `time`, then `component.variable` in the results' order.
    pub columns: Vec<String>,
    /// One vector per column, in the order of `columns`, each one value per recorded row.
    pub data: Vec<Vec<f64>>,
}

impl Table {
    /// The column `name` (e.g. `vehicle.speed`), if recorded.
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
