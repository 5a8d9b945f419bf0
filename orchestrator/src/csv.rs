//! The one reader for every CSV the orchestrator takes (`simulate --input`, `smooth`, a run's
//! `results.csv` read back), with one set of rules:
//!
//! | input | rule |
//! |---|---|
//! | a UTF-8 byte-order mark | skipped |
//! | blank lines, lines starting with `#` | skipped |
//! | quoted fields (`"a,b"`, `""` inside) | accepted, header and data alike |
//! | a duplicated column name | refused, naming it and both positions |
//! | a row with another number of fields than the header | refused, naming the line |
//! | a field that is not a number | refused, naming the line and the column; `nan`, `inf` and `true` / `false` (1 / 0) are numbers |
//! | column look-up | by exact name, else by the name after a `component.` prefix (refused if two columns match) |
//!
//! Line numbers count every line of the file from 1, the header included.

use std::path::Path;

/// A CSV file's columns as numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct Csv {
    /// The header's column names, trimmed, unique.
    pub names: Vec<String>,
    /// One vector per column, in the order of `names`, one value per data row.
    pub columns: Vec<Vec<f64>>,
    /// The file line of each data row (1-based), for messages about a row.
    pub lines: Vec<usize>,
    /// The file line of the header.
    pub header_line: usize,
}

impl Csv {
    /// Data row `k` (0-based) as a user finds it: `line N` of a CSV file (its own line number,
    /// blank and comment lines counted), `row N` of a Parquet file (read with header line 0).
    pub fn place(&self, k: usize) -> String {
        let n = self.lines.get(k).copied().unwrap_or(k + 1);
        if self.header_line == 0 {
            format!("row {n}")
        } else {
            format!("line {n}")
        }
    }

    /// Reads `path` (a regular file of at most [`crate::input::CSV_LIMIT`] bytes); errors name
    /// the file, and the line and column where the content is wrong.
    pub fn read(path: &Path) -> Result<Csv, String> {
        let text = crate::input::read_text(path, crate::input::CSV_LIMIT)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        Csv::parse(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Reads a table by its extension: `.parquet` through [`crate::parquet`] (its rows numbered
    /// from 1 in [`Csv::lines`], the header as line 0), anything else as CSV.
    pub fn read_any(path: &Path) -> Result<Csv, String> {
        if !crate::parquet::is_parquet(path) {
            return Csv::read(path);
        }
        let t = crate::parquet::read(path)?;
        let mut seen = std::collections::HashSet::new();
        if let Some(dup) = t.names.iter().find(|n| !seen.insert(n.as_str())) {
            return Err(format!("{}: column '{dup}' appears twice", path.display()));
        }
        let rows = t.columns.first().map_or(0, Vec::len);
        Ok(Csv {
            names: t.names,
            columns: t.columns,
            lines: (1..=rows).collect(),
            header_line: 0,
        })
    }

    /// Parses CSV text by the rules of the module docs; an error names the line (and column)
    /// but not the file, which the caller knows.
    pub fn parse(text: &str) -> Result<Csv, String> {
        Csv::parse_finite(text, &[])
    }

    /// [`Csv::parse`], with the columns named in `finite` refused where a value is not finite
    /// (`nan`, `inf`, an overflowing `1e999`), the message quoting the field as written.
    pub fn parse_finite(text: &str, finite: &[&str]) -> Result<Csv, String> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut rows = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l))
            .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
        let (header_line, header) = rows.next().ok_or("the file is empty")?;
        let names: Vec<String> = fields(header)
            .map_err(|e| format!("line {header_line}: {e}"))?
            .into_iter()
            .map(|s| s.trim().to_string())
            .collect();
        for (j, n) in names.iter().enumerate() {
            if n.is_empty() {
                return Err(format!("line {header_line}: column {} has no name", j + 1));
            }
            if let Some(k) = names[..j].iter().position(|m| m == n) {
                return Err(format!(
                    "line {header_line}: column '{n}' appears twice (columns {} and {})",
                    k + 1,
                    j + 1
                ));
            }
        }
        let mut columns = vec![Vec::new(); names.len()];
        let mut lines = vec![];
        for (line, row) in rows {
            let f = fields(row).map_err(|e| format!("line {line}: {e}"))?;
            if f.len() != names.len() {
                return Err(format!(
                    "line {line}: {} fields, the header has {}",
                    f.len(),
                    names.len()
                ));
            }
            for ((c, field), name) in columns.iter_mut().zip(&f).zip(&names) {
                let x = number(field).ok_or_else(|| {
                    format!(
                        "line {line}, column '{name}': '{}' is not a number",
                        field.trim()
                    )
                })?;
                if !x.is_finite() && finite.contains(&name.as_str()) {
                    return Err(format!(
                        "line {line}, column '{name}': '{}' is not a finite {name}",
                        field.trim()
                    ));
                }
                c.push(x);
            }
            lines.push(line);
        }
        Ok(Csv {
            names,
            columns,
            lines,
            header_line,
        })
    }

    /// The index of the column `name`: exact, else the one whose name after a `component.`
    /// prefix is `name`. None if there is none; an error if several prefixed columns match.
    pub fn find(&self, name: &str) -> Result<Option<usize>, String> {
        if let Some(i) = self.names.iter().position(|n| n == name) {
            return Ok(Some(i));
        }
        let matching: Vec<usize> = self
            .names
            .iter()
            .enumerate()
            .filter(|(_, n)| n.rsplit_once('.').is_some_and(|(_, bare)| bare == name))
            .map(|(i, _)| i)
            .collect();
        match matching.as_slice() {
            [] => Ok(None),
            [i] => Ok(Some(*i)),
            _ => Err(format!(
                "column '{name}' is ambiguous: {}",
                matching
                    .iter()
                    .map(|i| format!("'{}'", self.names[*i]))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }
    }

    /// The first of `names` the file has ([`Csv::find`]), or an error listing the columns.
    pub fn column(&self, names: &[&str]) -> Result<&[f64], String> {
        for n in names {
            if let Some(i) = self.find(n)? {
                return Ok(&self.columns[i]);
            }
        }
        Err(format!(
            "no column named {} (columns: {})",
            names.join(" or "),
            self.names.join(", ")
        ))
    }
}

/// A number as the results files write them, and `true` / `false` for Booleans.
fn number(field: &str) -> Option<f64> {
    let f = field.trim();
    match f {
        "true" => Some(1.0),
        "false" => Some(0.0),
        _ => f.parse().ok(),
    }
}

/// The fields of one line: comma-separated, a field in double quotes may hold commas and `""`.
fn fields(line: &str) -> Result<Vec<String>, String> {
    let mut out = vec![];
    let mut field = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    let mut was_quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                field.push('"');
            }
            (true, '"') => quoted = false,
            (true, c) => field.push(c),
            (false, '"') if field.trim().is_empty() && !was_quoted => {
                field.clear();
                quoted = true;
                was_quoted = true;
            }
            (false, ',') => {
                out.push(std::mem::take(&mut field));
                was_quoted = false;
            }
            (false, c) => field.push(c),
        }
    }
    if quoted {
        return Err(format!(
            "field {} opens a quote it never closes",
            out.len() + 1
        ));
    }
    out.push(field);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bom_quotes_comments_and_prefixes_are_accepted() {
        let c = Csv::parse(
            "\u{feff}\"time\",\"vehicle.ws_acc_y\",\"a,b\"\n# note\n\n0,1.5,nan\n1,\"2\",true\n",
        )
        .unwrap();
        assert_eq!(c.names, ["time", "vehicle.ws_acc_y", "a,b"]);
        assert_eq!(c.columns[1], [1.5, 2.0]);
        assert!(c.columns[2][0].is_nan() && c.columns[2][1] == 1.0);
        assert_eq!(c.lines, [4, 5]);
        // A row is named by the file's own line, the comment and blank lines counted.
        assert_eq!(c.place(0), "line 4");
        assert_eq!(c.column(&["ws_acc_y"]).unwrap(), [1.5, 2.0]);
        assert_eq!(c.find("time").unwrap(), Some(0));
        assert_eq!(c.find("nope").unwrap(), None);
    }

    #[test]
    fn errors_name_the_line_and_column() {
        let e = Csv::parse("time,u,u\n0,1,2\n").unwrap_err();
        assert!(
            e.contains("line 1") && e.contains("'u' appears twice"),
            "{e}"
        );
        let e = Csv::parse("time,u\n0,1\n1\n").unwrap_err();
        assert!(e.contains("line 3") && e.contains("1 fields"), "{e}");
        let e = Csv::parse("time,u\n0,1\n# c\n1,x\n").unwrap_err();
        assert!(e.contains("line 4, column 'u': 'x'"), "{e}");
        let e = Csv::parse("time,u\n0,\"1\n").unwrap_err();
        assert!(e.contains("line 2") && e.contains("quote"), "{e}");
        let e = Csv::parse("time,a.u,b.u\n0,1,2\n")
            .unwrap()
            .find("u")
            .unwrap_err();
        assert!(
            e.contains("ambiguous") && e.contains("'a.u'") && e.contains("'b.u'"),
            "{e}"
        );
        assert!(Csv::parse("").unwrap_err().contains("empty"));
    }
}
