//! Reading named columns of a CSV file, as the line files and the track profiles are read:
//! one reader, so both give the same messages for the same faults.

/// One data line of a CSV file: its line number and the named columns' values, in the order
/// asked for.
pub type Row = (usize, Vec<f64>);

/// The rows of CSV `text` (`file` names it in messages) with the columns `names`, in that
/// order: blank lines and lines starting with `#` skipped, the first other line the header
/// (other columns allowed, none twice), every value a finite number. `expected` is the header
/// the messages suggest. Errors name the file, the line and the column.
pub fn rows(file: &str, text: &str, names: &[&str], expected: &str) -> Result<Vec<Row>, String> {
    let mut header: Option<(Vec<usize>, usize)> = None; // (column index per name, width)
    let mut out = vec![];
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let Some((index, width)) = &header else {
            let mut index = Vec::with_capacity(names.len());
            for name in names {
                match cells.iter().position(|c| c == name) {
                    Some(p) => index.push(p),
                    None => {
                        return Err(format!(
                            "{file}: line {line_no}: header has no column '{name}' (found: {}); \
                             expected the header '{expected}'",
                            cells.join(",")
                        ));
                    }
                }
            }
            for (p, c) in cells.iter().enumerate() {
                if cells[..p].contains(c) {
                    return Err(format!(
                        "{file}: line {line_no}, column {}: duplicate column '{c}'",
                        p + 1
                    ));
                }
            }
            header = Some((index, cells.len()));
            continue;
        };
        if cells.len() != *width {
            return Err(format!(
                "{file}: line {line_no}: {} column(s), the header has {width}",
                cells.len()
            ));
        }
        let mut row = Vec::with_capacity(names.len());
        for (k, name) in names.iter().enumerate() {
            let col = index[k];
            let cell = cells[col];
            row.push(match cell.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                _ => {
                    return Err(format!(
                        "{file}: line {line_no}, column {} ('{name}'): '{cell}' is not a finite number",
                        col + 1
                    ));
                }
            });
        }
        out.push((line_no, row));
    }
    if header.is_none() {
        return Err(format!("{file}: no header line '{expected}'"));
    }
    Ok(out)
}
