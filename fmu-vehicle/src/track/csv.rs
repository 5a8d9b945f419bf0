//! Reading a measured profile from CSV and resampling it onto a uniform grid.

use design_line::csv::rows;
use std::path::Path;

/// The required columns, in the order of the channels.
pub(super) const COLUMNS: [&str; 4] = ["distance", "alignment", "vertical", "cross_level"];

/// A measured profile as read: strictly increasing distances and the three channels.
pub(super) struct Profile {
    pub distance: Vec<f64>,
    pub channels: [Vec<f64>; 3],
}

/// Parses the CSV text of `path` (used only in messages).
pub(super) fn parse(path: &Path, text: &str) -> Result<Profile, String> {
    let file = path.display().to_string();
    let rows = rows(&file, text, &COLUMNS, &COLUMNS.join(","))?;
    let mut prof = Profile {
        distance: Vec::with_capacity(rows.len()),
        channels: [Vec::new(), Vec::new(), Vec::new()],
    };
    let distance_column = distance_column(text);
    let mut prev_line = 0;
    for (line_no, row) in rows {
        if let Some(&last) = prof.distance.last()
            && row[0] <= last
        {
            return Err(format!(
                "{file}: line {line_no}, column {distance_column} ('distance'): distance {} m is not greater than \
                 {} m on line {prev_line}; distances must be strictly increasing",
                row[0], last
            ));
        }
        prof.distance.push(row[0]);
        for ch in 0..3 {
            prof.channels[ch].push(row[ch + 1]);
        }
        prev_line = line_no;
    }
    if prof.distance.len() < 2 {
        return Err(format!(
            "{file}: needs at least two data lines, found {}",
            prof.distance.len()
        ));
    }
    Ok(prof)
}

/// The 1-based column of `distance` in the header of `text` (which [`rows`] has accepted).
fn distance_column(text: &str) -> usize {
    text.lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .and_then(|h| h.split(',').map(str::trim).position(|c| c == "distance"))
        .map_or(1, |p| p + 1)
}

/// A natural cubic spline (zero second derivative at both ends) through `(x, y)`, `x` strictly
/// increasing, `x.len() >= 2`.
pub(super) struct Spline<'a> {
    x: &'a [f64],
    y: &'a [f64],
    m: Vec<f64>,
}

impl<'a> Spline<'a> {
    pub fn new(x: &'a [f64], y: &'a [f64]) -> Spline<'a> {
        let n = x.len();
        let mut m = vec![0.0; n];
        if n > 2 {
            // Tridiagonal system for the interior second derivatives (Thomas algorithm).
            let k = n - 2;
            let mut diag = vec![0.0; k];
            let mut rhs = vec![0.0; k];
            let mut upper = vec![0.0; k];
            for i in 1..n - 1 {
                let h0 = x[i] - x[i - 1];
                let h1 = x[i + 1] - x[i];
                diag[i - 1] = 2.0 * (h0 + h1);
                upper[i - 1] = h1;
                rhs[i - 1] = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
            }
            for j in 1..k {
                let lower = x[j + 1] - x[j]; // h of the row j+1's sub-diagonal = h0 of row j+1
                let w = lower / diag[j - 1];
                diag[j] -= w * upper[j - 1];
                rhs[j] -= w * rhs[j - 1];
            }
            m[k] = rhs[k - 1] / diag[k - 1];
            for j in (0..k - 1).rev() {
                m[j + 1] = (rhs[j] - upper[j] * m[j + 2]) / diag[j];
            }
        }
        Spline { x, y, m }
    }

    /// Value and first and second derivative at `t` in interval `i` (`x[i] <= t <= x[i + 1]`).
    pub fn eval(&self, i: usize, t: f64) -> [f64; 3] {
        let (x, y, m) = (self.x, self.y, &self.m);
        let h = x[i + 1] - x[i];
        let a = (x[i + 1] - t) / h;
        let b = (t - x[i]) / h;
        let v = a * y[i]
            + b * y[i + 1]
            + ((a * a * a - a) * m[i] + (b * b * b - b) * m[i + 1]) * h * h / 6.0;
        let d = (y[i + 1] - y[i]) / h - (3.0 * a * a - 1.0) / 6.0 * h * m[i]
            + (3.0 * b * b - 1.0) / 6.0 * h * m[i + 1];
        let dd = a * m[i] + b * m[i + 1];
        [v, d, dd]
    }
}

/// Reads and parses `path`.
pub(super) fn read(path: &Path) -> Result<Profile, String> {
    // 1 GiB holds the node cap (1e7 rows of four numbers) with room to spare.
    let text = fmi_abi::resource::read_text(path, "track file", 1 << 30)?;
    parse(path, &text)
}
