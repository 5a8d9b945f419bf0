//! The corpus of malformed inputs (`tests/corpus/ssp/*`, `tests/corpus/csv/*`): files that once
//! broke a reader, or that stand for a class of hostile input. Each must give the exact error
//! listed here, naming the file and, inside a document, the line and column and what is wrong.

use orchestrator::simulate::Signals;
use orchestrator::ssp;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

fn corpus(kind: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/corpus")
        .join(kind)
}

/// A fake FMU: a zip holding only a modelDescription.xml.
fn fake_fmu(path: &Path, name: &str) {
    fs::create_dir_all(path.parent().unwrap()).unwrap();
    let xml = format!(
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{name}\" guid=\"g\"><CoSimulation modelIdentifier=\"{name}\"/><ModelVariables><ScalarVariable name=\"x\" valueReference=\"0\" causality=\"output\"><Real/></ScalarVariable><ScalarVariable name=\"u\" valueReference=\"1\" causality=\"input\"><Real start=\"0\"/></ScalarVariable></ModelVariables><ModelStructure/></fmiModelDescription>"
    );
    let mut zip = zip::ZipWriter::new(fs::File::create(path).unwrap());
    zip.start_file(
        "modelDescription.xml",
        zip::write::SimpleFileOptions::default(),
    )
    .unwrap();
    zip.write_all(xml.as_bytes()).unwrap();
    zip.finish().unwrap();
}

/// (file, line and column or None, substrings of the message after the file's path).
type Expected = (
    &'static str,
    Option<(usize, usize)>,
    &'static [&'static str],
);

const SSP: &[Expected] = &[
    (
        "empty.ssd",
        Some((1, 1)),
        &["malformed XML at line 1, column 1: no root element"],
    ),
    (
        "truncated.ssd",
        Some((2, 1)),
        &["<SystemStructureDescription> is never closed (the input ends first)"],
    ),
    (
        "wrong_root.ssd",
        Some((1, 1)),
        &["the root element is <SystemStructure>, expected <ssd:SystemStructureDescription>"],
    ),
    (
        "not_utf8.ssd",
        Some((2, 56)),
        &["byte 0xE9 (offset 94) is not UTF-8; SSP files must be UTF-8"],
    ),
    (
        "deep_nesting.ssd",
        Some((8, 3013)),
        &["elements are nested more than 1000 levels deep (<a> inside <a>)"],
    ),
    // Entities declared in a DOCTYPE are never expanded.
    (
        "billion_laughs.ssd",
        Some((14, 47)),
        &[
            "in attribute 'name' of <SystemStructureDescription>",
            "unrecognized entity `lol9`",
        ],
    ),
    (
        "duplicate_component.ssd",
        Some((6, 7)),
        &["a second component named 'plant'"],
    ),
    (
        "unknown_component.ssd",
        Some((9, 63)),
        &[
            "connection plant.x -> nobody.u refers to 'nobody', which is not a component of the system",
        ],
    ),
    (
        "bad_factor.ssd",
        Some((10, 35)),
        &[
            "attribute 'factor' of <LinearTransformation> (connection plant.x -> observer.u) is \"1e\", expected a floating-point number",
        ],
    ),
    (
        "infinite_stop_time.ssd",
        Some((9, 40)),
        &["attribute 'stopTime' of <DefaultExperiment> is \"1e999\", expected a finite time"],
    ),
    (
        "nan_start_time.ssd",
        Some((9, 26)),
        &["attribute 'startTime' of <DefaultExperiment> is \"NaN\", expected a finite time"],
    ),
    (
        "huge_integer.ssd",
        Some((7, 48)),
        &[
            "attribute 'value' of <Integer> (parameter 'n') is \"99999999999\", expected a 32-bit integer",
        ],
    ),
    (
        "missing_source.ssd",
        Some((5, 35)),
        &["the source of component 'plant', \"resources/Nowhere.fmu\", is not an existing file"],
    ),
    (
        "bad_percent_encoding.ssd",
        Some((5, 35)),
        &[
            "source=\"resources/%zzPlant.fmu\" of <Component> (component 'plant'): bad percent-encoding",
        ],
    ),
    (
        "remote_source.ssd",
        Some((5, 35)),
        &["the URI scheme 'http:' (relative references and file: URIs are) is not supported"],
    ),
    // The error is inside bad.ssv: both files are named, the position is in the .ssv.
    (
        "bad_ssv_reference.ssd",
        Some((4, 39)),
        &[
            "bad.ssv: line 4, column 39: attribute 'value' of <Real> (parameter 'k') is \"fast\", expected a floating-point number",
        ],
    ),
    (
        "not_a_zip.ssp",
        None,
        &["not a readable SSP archive: invalid Zip archive"],
    ),
    (
        "truncated.ssp",
        None,
        &["not a readable SSP archive: invalid Zip archive"],
    ),
    (
        "no_ssd.ssp",
        None,
        &["not a readable SSP archive: no SystemStructure.ssd at the archive root"],
    ),
    (
        "traversal.ssp",
        None,
        &[
            "archive entry '../evil.fmu' points outside the archive (absolute or '..' path); refusing the archive",
        ],
    ),
    (
        "absolute.ssp",
        None,
        &[
            "archive entry '/tmp/evil.fmu' points outside the archive (absolute or '..' path); refusing the archive",
        ],
    ),
    // A zip bomb that declares 100 bytes and inflates to 10 MB: refused at the declared size.
    (
        "lying_size.ssp",
        None,
        &[
            "not a readable SSP archive: cannot extract entry 'resources/bomb.bin': File is larger than its declared uncompressed size",
        ],
    ),
];

#[test]
fn every_ssp_corpus_file_gives_its_error() {
    // The .ssd files refer to resources/Plant.fmu and resources/Observer.fmu.
    let dir = tempfile::tempdir().unwrap();
    for entry in fs::read_dir(corpus("ssp")).unwrap() {
        let path = entry.unwrap().path();
        fs::copy(&path, dir.path().join(path.file_name().unwrap())).unwrap();
    }
    fake_fmu(&dir.path().join("resources/Plant.fmu"), "Plant");
    fake_fmu(&dir.path().join("resources/Observer.fmu"), "Observer");
    let mut report = String::new();
    let mut seen = vec![];
    for entry in fs::read_dir(dir.path()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if path.is_dir() || name.ends_with(".ssv") {
            continue;
        }
        let started = std::time::Instant::now();
        let err = match ssp::read(&path) {
            Ok(_) => panic!("{name} was accepted"),
            Err(e) => e,
        };
        assert!(
            started.elapsed().as_secs_f64() < 2.0,
            "{name}: {:?}",
            started.elapsed()
        );
        let text = err.to_string();
        report.push_str(&format!("{name}: {:?} {text}\n", err.line_column()));
        let Some((_, at, parts)) = SSP.iter().find(|(n, ..)| *n == name) else {
            continue;
        };
        seen.push(name.clone());
        assert!(
            text.starts_with(&path.display().to_string()),
            "{name}: the message does not start with the file: {text}"
        );
        assert_eq!(err.line_column(), *at, "{name}: {text}");
        if let Some((line, column)) = at {
            assert!(
                text.contains(&format!("line {line}, column {column}")),
                "{name}: {text}"
            );
        }
        for p in *parts {
            assert!(text.contains(p), "{name}: '{p}' not in: {text}");
        }
    }
    assert_eq!(
        seen.len(),
        SSP.len(),
        "files without expectations, or expectations without files:\n{report}"
    );
    // Nothing escaped the archives.
    assert!(!dir.path().parent().unwrap().join("evil.fmu").exists());
    assert!(!Path::new("/tmp/evil.fmu").exists());
}

const CSV: &[(&str, &[&str])] = &[
    ("empty.csv", &[": the file is empty"]),
    ("only_comments.csv", &[": the file is empty"]),
    ("header_only.csv", &[": no data rows"]),
    (
        "no_time_column.csv",
        &[": line 1: the first column must be 'time', found 't'"],
    ),
    (
        "header_after_comment.csv",
        &[": line 3: the first column must be 'time', found 't'"],
    ),
    (
        "nan_time.csv",
        &[": line 3, column 'time': 'nan' is not a finite time"],
    ),
    (
        "infinite_time.csv",
        &[": line 3, column 'time': 'inf' is not a finite time"],
    ),
    (
        "overflowing_time.csv",
        &[": line 3, column 'time': '1e999' is not a finite time"],
    ),
    (
        "time_backwards.csv",
        &[": line 4: time 1 goes backwards (previous 2)"],
    ),
    ("ragged_row.csv", &[": line 3: 2 fields, the header has 3"]),
    (
        "duplicate_column.csv",
        &[": line 1: column 'u' appears twice (columns 2 and 3)"],
    ),
    (
        "unclosed_quote.csv",
        &[": line 3: field 2 opens a quote it never closes"],
    ),
    (
        "not_a_number.csv",
        &[": line 3, column 'v': 'two' is not a number"],
    ),
    (
        "bad_utf8.csv",
        &[
            "cannot read input file",
            "stream did not contain valid UTF-8",
        ],
    ),
];

#[test]
fn every_csv_corpus_file_gives_its_error() {
    let mut report = String::new();
    let mut seen = vec![];
    for entry in fs::read_dir(corpus("csv")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let err = match Signals::read(&path) {
            Ok(_) => panic!("{name} was accepted"),
            Err(e) => e,
        };
        report.push_str(&format!("{name}: {err}\n"));
        let Some((_, parts)) = CSV.iter().find(|(n, ..)| *n == name) else {
            continue;
        };
        seen.push(name.clone());
        assert!(err.contains(&path.display().to_string()), "{name}: {err}");
        for p in *parts {
            assert!(err.contains(p), "{name}: '{p}' not in: {err}");
        }
    }
    assert_eq!(
        seen.len(),
        CSV.len(),
        "files without expectations, or expectations without files:\n{report}"
    );
}
