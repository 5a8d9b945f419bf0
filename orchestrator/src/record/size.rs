//! A run's recorded size, estimated before it starts, so a typo such as `--stop 1e12` is
//! refused at once instead of filling the disk.
//!
//! | format | bytes per value (estimate) | why |
//! |---|---|---|
//! | CSV | 20 | the shortest round-trip form of a measured double (17 significant digits, a sign, a point, an exponent) and its separator |
//! | Parquet | 8 | one `DOUBLE` before compression (the writer's Snappy gains little on noisy signals) |
//!
//! Estimate = rows (the start, then one per recording interval) x columns (time and each
//! recorded variable) x bytes per value. A run is refused when the estimate exceeds the free
//! space of the output directory's file system, or the limit ([`DEFAULT_LIMIT`], changed by
//! `--max-output-size`).

use crate::master::RunError;
use std::path::Path;

/// The largest results file a run writes without `--max-output-size`: 10 GB, a thousand times
/// the standard case at full resolution.
pub const DEFAULT_LIMIT: u64 = 10_000_000_000;

/// The estimated size in bytes of `rows` rows of `columns` values (time included).
pub fn estimate(rows: u64, columns: usize, parquet: bool) -> f64 {
    let per_value = if parquet { 8.0 } else { 20.0 };
    rows as f64 * columns as f64 * per_value
}

/// `bytes` for a person: `76.0 GB`, `12.3 MB`.
pub fn human(bytes: f64) -> String {
    const UNITS: [&str; 6] = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = bytes;
    let mut u = 0;
    while v >= 1000.0 && u < UNITS.len() - 1 {
        v /= 1000.0;
        u += 1;
    }
    if u == 0 {
        format!("{v:.0} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// A size as given on the command line: a number of bytes, optionally with a decimal suffix
/// k, M, G, T (powers of 1000, an optional trailing B): `500M`, `50G`, `2TB`.
pub fn parse(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let t = t
        .strip_suffix(['B', 'b'])
        .filter(|r| r.ends_with(|c: char| c.is_ascii_alphabetic()))
        .unwrap_or(t);
    let (num, scale) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let scale = match c.to_ascii_uppercase() {
                'K' => 1e3,
                'M' => 1e6,
                'G' => 1e9,
                'T' => 1e12,
                'P' => 1e15,
                _ => return Err(format!("{s:?}: expected a size such as 500M, 50G or 2T")),
            };
            (&t[..i], scale)
        }
        _ => (t, 1.0),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v * scale < u64::MAX as f64 => Ok((v * scale) as u64),
        _ => Err(format!(
            "{s:?}: expected a positive size such as 500M, 50G or 2T"
        )),
    }
}

/// The bytes free to an unprivileged writer on the file system holding `dir`, if known.
pub fn free_space(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
        let mut st = std::mem::MaybeUninit::<libc::statvfs>::uninit();
        // SAFETY: `c` is a NUL-terminated path and `st` a buffer statvfs fills on success.
        let rc = unsafe { libc::statvfs(c.as_ptr(), st.as_mut_ptr()) };
        if rc != 0 {
            return None;
        }
        // SAFETY: statvfs returned 0, so it filled `st`.
        let st = unsafe { st.assume_init() };
        #[allow(clippy::unnecessary_cast)]
        Some((st.f_bavail as u64).saturating_mul(st.f_frsize as u64))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

/// An error naming the estimate unless a results file of `rows` x `columns` fits the `limit`
/// and the free space `free` (unknown: not checked): over the free space is an I/O error (exit
/// 1, the results cannot be written), over the limit bad input (exit 2, checked first: a typo
/// in `--stop` is usually over both).
pub fn check(
    file: &str,
    rows: u64,
    columns: usize,
    parquet: bool,
    limit: u64,
    free: Option<u64>,
) -> Result<(), RunError> {
    let bytes = estimate(rows, columns, parquet);
    let what = format!(
        "the results file {file} would be about {} ({rows} rows x {columns} columns)",
        human(bytes)
    );
    if bytes > limit as f64 {
        return Err(RunError::Config(format!(
            "{what}, over the {} limit: nothing was run; check --stop and --step, record less (--record, --interval), or allow it with --max-output-size",
            human(limit as f64)
        )));
    }
    if let Some(free) = free
        && bytes > free as f64
    {
        return Err(RunError::Io(format!(
            "{what}, more than the {} free on its disk: nothing was run; shorten the run (--stop), record less (--record, --interval) or write elsewhere (--out)",
            human(free as f64)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_decimal_suffixes() {
        assert_eq!(parse("500M").unwrap(), 500_000_000);
        assert_eq!(parse("50G").unwrap(), 50_000_000_000);
        assert_eq!(parse("2TB").unwrap(), 2_000_000_000_000);
        assert_eq!(parse("1.5k").unwrap(), 1500);
        assert_eq!(parse("123").unwrap(), 123);
        for bad in ["", "-1G", "0", "abc", "5X", "nan", "inf"] {
            assert!(parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_typo_run_is_refused_with_its_size_and_the_standard_case_passes() {
        // `--stop 1e12` at 1 ms, the standard case's 31 columns.
        let e = check(
            "results.csv",
            1_000_000_000_000_001,
            31,
            false,
            DEFAULT_LIMIT,
            None,
        )
        .unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let e = e.to_string();
        assert!(
            e.contains("620.0 PB") && e.contains("--max-output-size"),
            "{e}"
        );
        check("results.csv", 20_001, 31, false, DEFAULT_LIMIT, None).unwrap();
        // Allowed by a larger limit, refused by the free space.
        check("r.parquet", 1_000_000_000, 31, true, u64::MAX, None).unwrap();
        let e = check(
            "r.parquet",
            1_000_000_000,
            31,
            true,
            u64::MAX,
            Some(1 << 30),
        )
        .unwrap_err();
        assert_eq!(e.exit_code(), 1);
        let e = e.to_string();
        assert!(e.contains("248.0 GB") && e.contains("free"), "{e}");
    }

    #[test]
    fn free_space_is_known_for_a_directory_that_exists() {
        let d = tempfile::tempdir().unwrap();
        if cfg!(unix) {
            assert!(free_space(d.path()).is_some_and(|b| b > 0));
        }
        assert!(free_space(&d.path().join("absent")).is_none());
    }
}
