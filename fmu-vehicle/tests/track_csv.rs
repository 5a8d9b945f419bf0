//! Measured profiles from CSV: a good file round-trips; bad files are rejected with the file,
//! line and column in the message.

use fmu_vehicle::track::Track;
use std::f64::consts::TAU;
use std::path::PathBuf;

/// Writes `text` to a fresh file in the temporary directory.
fn write(name: &str, text: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!("track_csv_{}_{name}.csv", std::process::id()));
    std::fs::write(&path, text).expect("write temp file");
    path
}

/// Smooth test channels [m].
fn channels(s: f64) -> [f64; 3] {
    [
        1.5e-3 * (TAU * s / 23.0).sin() + 0.4e-3 * (TAU * s / 7.3 + 1.0).cos(),
        -2.0e-3 * (TAU * s / 41.0 + 0.3).cos(),
        0.8e-3 * (TAU * s / 13.0).sin(),
    ]
}

/// Non-uniform distances, a comment block, a blank line, columns in another order and an extra
/// column: every data point comes back from `at` (the natural spline interpolates the data; at
/// the knots only the grid's quintic Hermite error of the spline is left), the curve in between
/// follows the sampled function, the range is the file's, and beyond the ends the end values
/// are held with zero derivatives.
#[test]
fn good_file_round_trips() {
    let mut text = String::from(
        "# measured on track 2, 2024\n# units: m\n\ncross_level,distance,gauge,alignment,vertical\n",
    );
    let mut data = Vec::new();
    let mut s = -12.0;
    for i in 0..700 {
        let [a, v, c] = channels(s);
        text.push_str(&format!("{c:e},{s},1.435,{a:e},{v:e}\n"));
        data.push((s, a, v, c));
        s += 0.2 + 0.1 * ((i * 7) % 5) as f64 / 4.0; // 0.2 .. 0.3 m
    }
    let path = write("good", &text);
    let track = Track::from_csv(&path).expect("good file");
    let (first, last) = (data[0].0, data.last().unwrap().0);
    let (lo, hi) = track.range();
    assert!(
        (lo - first).abs() < 1e-12 && (hi - last).abs() < 1e-9,
        "{lo} {hi}"
    );
    assert!(track.step() <= 0.05);
    let mut worst = 0.0f64;
    for &(s, a, v, c) in &data {
        let irr = track.at(s);
        for (got, want) in [(irr.alignment, a), (irr.vertical, v), (irr.cross_level, c)] {
            worst = worst.max((got - want).abs());
        }
    }
    eprintln!("max |at(knot) - data| = {worst:.1e} m");
    assert!(worst < 1e-9, "{worst}");
    // Between the knots (away from the natural ends) the spline follows the function.
    let (mut e0, mut e1, mut e2) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..2000 {
        let s = first + 10.0 + (last - first - 20.0) * i as f64 / 2000.0;
        let irr = track.at(s);
        let [a, _, _] = channels(s);
        let h = 1e-4;
        let (ap, am) = (channels(s + h)[0], channels(s - h)[0]);
        e0 = e0.max((irr.alignment - a).abs() / 1.9e-3);
        e1 = e1.max((irr.alignment_ds - (ap - am) / (2.0 * h)).abs() / (1.9e-3 * TAU / 7.3));
        e2 = e2.max(
            (irr.alignment_ds2 - (ap - 2.0 * a + am) / (h * h)).abs()
                / (1.9e-3 * (TAU / 7.3f64).powi(2)),
        );
    }
    eprintln!("spline vs function: value {e0:.1e}, slope {e1:.1e}, curvature {e2:.1e} (relative)");
    assert!(e0 < 1e-4 && e1 < 1e-3 && e2 < 2e-2, "{e0} {e1} {e2}");
    // Beyond the ends: held values, zero derivatives; no extension possible.
    let end = track.at(last + 5.0);
    assert_eq!(
        (end.alignment, end.vertical, end.cross_level),
        (
            data.last().unwrap().1,
            data.last().unwrap().2,
            data.last().unwrap().3
        )
    );
    assert_eq!(
        (end.alignment_ds, end.vertical_ds2, end.cross_level_ds),
        (0.0, 0.0, 0.0)
    );
    let start = track.at(first - 1.0);
    assert!((start.alignment - data[0].1).abs() < 1e-15 && start.alignment_ds == 0.0);
    let mut t = track.clone();
    assert!(!t.ensure_covers(first - 100.0, last + 100.0));
    assert_eq!(t, track);
    let _ = std::fs::remove_file(path);
}

/// A uniformly sampled pure sinusoid of 3 m wavelength at 0.01 m: value, slope and curvature
/// within 1e-3 of the analytic ones (relative to their amplitudes), through the whole path
/// (parsing, natural spline, resampling, quintic Hermite).
#[test]
fn sinusoid_3m() {
    let (amp, wl) = (1e-3, 3.0);
    let k = TAU / wl;
    let mut text = String::from("distance,alignment,vertical,cross_level\n");
    for i in 0..=6000 {
        let s = i as f64 * 0.01;
        text.push_str(&format!("{s},{:e},0,0\n", amp * (k * s).sin()));
    }
    let path = write("sine", &text);
    let track = Track::from_csv(&path).expect("sine file");
    let (mut e0, mut e1, mut e2) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..5000 {
        let s = 5.0 + 50.0 * i as f64 / 5000.0 + 0.0013;
        let irr = track.at(s);
        e0 = e0.max((irr.alignment - amp * (k * s).sin()).abs() / amp);
        e1 = e1.max((irr.alignment_ds - amp * k * (k * s).cos()).abs() / (amp * k));
        e2 = e2.max((irr.alignment_ds2 + amp * k * k * (k * s).sin()).abs() / (amp * k * k));
    }
    eprintln!(
        "3 m sinusoid from CSV at 0.01 m: value {e0:.1e}, slope {e1:.1e}, curvature {e2:.1e}"
    );
    assert!(e0 < 1e-3 && e1 < 1e-3 && e2 < 1e-3, "{e0} {e1} {e2}");
    let _ = std::fs::remove_file(path);
}

fn error_of(name: &str, text: &str) -> (String, String) {
    let path = write(name, text);
    let e = Track::from_csv(&path).expect_err("bad file accepted");
    let _ = std::fs::remove_file(&path);
    (e, path.display().to_string())
}

#[test]
fn missing_column() {
    let (e, file) = error_of(
        "missing",
        "# comment\ndistance,alignment,vertical\n0,0,0\n1,0,0\n",
    );
    eprintln!("{e}");
    assert!(
        e.contains(&file) && e.contains("line 2") && e.contains("'cross_level'"),
        "{e}"
    );
}

#[test]
fn non_numeric_cell_at_line_7() {
    let mut text = String::from("# header follows\ndistance,alignment,vertical,cross_level\n");
    for s in 0..4 {
        text.push_str(&format!("{s},0.001,0.002,0.0\n")); // lines 3..6
    }
    text.push_str("4,0.001,abc,0.0\n"); // line 7
    let (e, file) = error_of("nonnumeric", &text);
    eprintln!("{e}");
    assert!(
        e.contains(&file)
            && e.contains("line 7")
            && e.contains("column 3")
            && e.contains("'vertical'")
            && e.contains("abc"),
        "{e}"
    );
}

#[test]
fn non_increasing_distance() {
    let text = "distance,alignment,vertical,cross_level\n0,0,0,0\n0.5,0,0,0\n\n0.5,0,0,0\n";
    let (e, file) = error_of("order", text);
    eprintln!("{e}");
    assert!(
        e.contains(&file)
            && e.contains("line 5")
            && e.contains("column 1")
            && e.contains("'distance'"),
        "{e}"
    );
}

#[test]
fn other_malformed_files() {
    for (name, text, want) in [
        (
            "short_row",
            "distance,alignment,vertical,cross_level\n0,0,0,0\n1,0,0\n",
            "line 3",
        ),
        (
            "nan",
            "distance,alignment,vertical,cross_level\n0,0,0,0\n1,NaN,0,0\n",
            "line 3, column 2",
        ),
        (
            "one_row",
            "distance,alignment,vertical,cross_level\n0,0,0,0\n",
            "at least two",
        ),
        ("empty", "# nothing\n", "no header"),
    ] {
        let (e, file) = error_of(name, text);
        assert!(e.contains(&file) && e.contains(want), "{name}: {e}");
    }
    let e = Track::from_csv(std::path::Path::new("/nonexistent/track.csv")).unwrap_err();
    assert!(e.contains("/nonexistent/track.csv"), "{e}");
}
