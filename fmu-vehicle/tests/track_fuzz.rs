//! Measured-track CSV files against hostile input: random and mutated files never panic (nor
//! exhaust the memory: the grid is bounded); every error names the file; an accepted file gives a
//! finite track; and the corpus (`tests/corpus/track/*.csv`) gives the exact errors listed here.
//!
//! Case counts are small by default (CI); `PROPTEST_CASES=100000 cargo test -p fmu-vehicle --test
//! track_fuzz` runs a larger campaign.

use fmu_vehicle::track::Track;
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::path::{Path, PathBuf};

fn config(default_cases: u32) -> Config {
    let mut c = Config::default();
    if std::env::var_os("PROPTEST_CASES").is_none() {
        c.cases = default_cases;
    }
    c
}

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus/track")
}

/// (file, substrings the message must contain after the file name).
const EXPECTED: &[(&str, &[&str])] = &[
    (
        "huge_span.csv",
        &[
            "the profile spans 1e300 m (distance 0 to 1e300 m)",
            "more than the limit of 1e7",
            "split the file",
        ],
    ),
    (
        "overflowing_span.csv",
        &["the profile spans inf m", "more than the limit of 1e7"],
    ),
    (
        "long_span.csv",
        &[
            "the profile spans 1000000 m",
            "needs 2e7 nodes, more than the limit of 1e7 (500 km at 0.05 m)",
        ],
    ),
    (
        "infinite_distance.csv",
        &["line 3, column 1 ('distance'): 'inf' is not a finite number"],
    ),
    (
        "overflowing_number.csv",
        &["line 3, column 2 ('alignment'): '1e999' is not a finite number"],
    ),
    (
        "nan_distance.csv",
        &["line 3, column 1 ('distance'): 'nan' is not a finite number"],
    ),
    (
        "decreasing.csv",
        &["line 4, column 1 ('distance'): distance 1 m is not greater than 2 m on line 3"],
    ),
    (
        "duplicate_column.csv",
        &["line 1, column 5: duplicate column 'alignment'"],
    ),
    (
        "missing_column.csv",
        &["line 1: header has no column 'vertical' (found: distance,alignment,cross_level)"],
    ),
    ("ragged_row.csv", &["line 3: 5 column(s), the header has 4"]),
    (
        "header_only.csv",
        &["needs at least two data lines, found 0"],
    ),
    (
        "empty.csv",
        &["no header line 'distance,alignment,vertical,cross_level'"],
    ),
    (
        "quoted_cells.csv",
        &["line 3, column 1 ('distance'): '\"1\"' is not a finite number"],
    ),
    (
        "semicolons.csv",
        &[
            "line 1: header has no column 'distance' (found: distance;alignment;vertical;cross_level)",
        ],
    ),
    (
        "close_points_steep.csv",
        &["the spline through the 'alignment' column is not finite near distance"],
    ),
    (
        "bad_utf8.csv",
        &["cannot read the track file: stream did not contain valid UTF-8"],
    ),
];

#[test]
fn every_corpus_file_gives_its_error() {
    let mut seen = vec![];
    for entry in std::fs::read_dir(corpus()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let started = std::time::Instant::now();
        let e = match Track::from_csv(&path) {
            Ok(_) => panic!("{name}: accepted"),
            Err(e) => e,
        };
        assert!(
            started.elapsed().as_secs_f64() < 2.0,
            "{name} took {:?}",
            started.elapsed()
        );
        let (_, parts) = EXPECTED
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("{name} has no expectation: {e}"));
        assert!(
            e.starts_with(&format!("{}: ", path.display())),
            "{name}: the message does not start with the file: {e}"
        );
        for p in *parts {
            assert!(e.contains(p), "{name}: '{p}' not in: {e}");
        }
        seen.push(name);
    }
    assert_eq!(seen.len(), EXPECTED.len(), "files: {seen:?}");
}

/// A cell: mostly numbers of moderate size (so that accepted files stay small tracks), sometimes
/// the values that break parsers.
fn cell() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (-100.0f64..100.0).prop_map(|x| x.to_string()),
        1 => prop_oneof![
            Just("nan".to_string()),
            Just("inf".to_string()),
            Just("-inf".to_string()),
            Just("1e999".to_string()),
            Just("1e300".to_string()),
            Just("-1e308".to_string()),
            Just("1e-300".to_string()),
            Just(String::new()),
            Just("\"1\"".to_string()),
            Just("distance".to_string()),
            "\\PC{0,4}",
        ],
    ]
}

fn line() -> impl Strategy<Value = String> {
    prop_oneof![
        10 => prop::collection::vec(cell(), 3..6).prop_map(|c| c.join(",")),
        1 => Just("# comment".to_string()),
        1 => Just(String::new()),
        1 => Just("distance,alignment,vertical,cross_level".to_string()),
        1 => "\\PC{0,20}",
    ]
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("track_fuzz");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn random_files_never_panic(
        header in prop_oneof![
            Just("distance,alignment,vertical,cross_level".to_string()),
            Just("cross_level,distance,x,alignment,vertical".to_string()),
            "\\PC{0,30}",
        ],
        lines in prop::collection::vec(line(), 0..30),
        increasing in any::<bool>(),
    ) {
        let mut text = header + "\n";
        let mut s = -5.0;
        for (i, l) in lines.iter().enumerate() {
            if increasing && i % 2 == 0 {
                // Valid rows in between, so that the later stages are reached too.
                s += 0.3;
                text.push_str(&format!("{s},{l}\n"));
                continue;
            }
            text.push_str(l);
            text.push('\n');
        }
        let path = scratch(&format!("case_{}.csv", std::process::id()));
        std::fs::write(&path, &text).unwrap();
        match Track::from_csv(&path) {
            Ok(track) => {
                let (lo, hi) = track.range();
                prop_assert!(lo.is_finite() && hi.is_finite() && lo < hi);
                for k in 0..=20 {
                    let irr = track.at(lo + (hi - lo) * k as f64 / 20.0);
                    prop_assert!(irr.alignment.is_finite() && irr.vertical.is_finite() && irr.cross_level.is_finite());
                }
            }
            Err(e) => prop_assert!(e.starts_with(&format!("{}: ", path.display())), "{}", e),
        }
    }
}
