//! Property tests of the orchestrator's readers against hostile input: SSP text (.ssd) and
//! archives (.ssp), and the input-signal CSV of `simulate`. The properties: no panic; an error
//! inside a document points into it (line and column inside the text, shown in the message);
//! an error about a file names the file; valid input still reads.
//!
//! Case counts are small by default (CI); `PROPTEST_CASES=100000 cargo test -p orchestrator
//! --test fuzz` runs a larger campaign.

use orchestrator::simulate::Signals;
use orchestrator::ssp::{self, SspError};
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn config(default_cases: u32) -> Config {
    let mut c = Config::default();
    if std::env::var_os("PROPTEST_CASES").is_none() {
        c.cases = default_cases;
    }
    c
}

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/ssp")
        .join(name)
}

/// A fake FMU: a zip holding only a modelDescription.xml declaring `variables` (all Real).
fn fake_fmu(path: &Path, name: &str, variables: &[(&str, &str)]) {
    fs::create_dir_all(path.parent().unwrap()).unwrap();
    let mut xml = format!(
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{name}\" guid=\"g\"><CoSimulation modelIdentifier=\"{name}\"/><ModelVariables>"
    );
    for (i, (var, causality)) in variables.iter().enumerate() {
        xml.push_str(&format!(
            "<ScalarVariable name=\"{var}\" valueReference=\"{i}\" causality=\"{causality}\"><Real/></ScalarVariable>"
        ));
    }
    xml.push_str("</ModelVariables><ModelStructure/></fmiModelDescription>");
    let mut zip = zip::ZipWriter::new(fs::File::create(path).unwrap());
    zip.start_file(
        "modelDescription.xml",
        zip::write::SimpleFileOptions::default(),
    )
    .unwrap();
    zip.write_all(xml.as_bytes()).unwrap();
    zip.finish().unwrap();
}

/// One directory (per test binary) with the SSP fixtures and fake FMUs they refer to.
fn workspace() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        for f in ["two_fmus.ssd", "features.ssd", "plant.ssv", "system.ssv"] {
            fs::copy(data(f), dir.path().join(f)).unwrap();
        }
        let vars = [
            ("x", "output"),
            ("w", "input"),
            ("u", "input"),
            ("y", "output"),
        ];
        for f in ["Plant", "Observer", "Sensor Unit"] {
            fake_fmu(&dir.path().join(format!("resources/{f}.fmu")), f, &vars);
        }
        dir
    })
    .path()
}

fn seeds() -> Vec<String> {
    ["two_fmus.ssd", "features.ssd"]
        .iter()
        .map(|f| fs::read_to_string(data(f)).unwrap())
        .collect()
}

/// The line and column of an error inside `text` lie inside it and appear in the message.
/// Errors inside an .ssv file (InFile) point into that file, which is named instead.
fn check_ssd(
    text: &str,
    result: Result<orchestrator::system::System, SspError>,
) -> Result<(), TestCaseError> {
    let Err(e) = result else { return Ok(()) };
    let message = e.to_string();
    prop_assert!(!message.is_empty());
    if let SspError::InFile { path, .. } = &e {
        prop_assert!(message.contains(&path.display().to_string()));
        return Ok(());
    }
    let (line, column) = e
        .line_column()
        .ok_or_else(|| TestCaseError::fail(format!("no line and column: {message}")))?;
    let lines: Vec<&str> = text.split('\n').collect();
    prop_assert!(
        line >= 1 && line <= lines.len(),
        "line {} of {}: {}",
        line,
        lines.len(),
        message
    );
    prop_assert!(
        column >= 1 && column <= lines[line - 1].chars().count() + 1,
        "column {} of line {}: {}",
        column,
        line,
        message
    );
    let at = format!("line {line}, column {column}");
    prop_assert!(message.contains(&at), "'{}' not in: {}", at, message);
    Ok(())
}

#[derive(Debug, Clone)]
enum Mutation {
    Truncate(prop::sample::Index),
    Flip(prop::sample::Index, u8),
    Delete(prop::sample::Index, usize),
    Duplicate(prop::sample::Index, usize),
    Insert(prop::sample::Index, String),
}

fn token() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("<".to_string()),
        Just(">".to_string()),
        Just("/>".to_string()),
        Just("\"".to_string()),
        Just("&".to_string()),
        Just("&lol;".to_string()),
        Just("<!--".to_string()),
        Just("<ssd:System name=\"sub\">".to_string()),
        Just("<ssd:Component name=\"plant\" source=\"resources/Plant.fmu\"/>".to_string()),
        Just("<ssd:Connection startElement=\"plant\" startConnector=\"x\" endElement=\"nope\" endConnector=\"u\"/>".to_string()),
        Just("<ssc:LinearTransformation factor=\"INF\" offset=\"NaN\"/>".to_string()),
        Just(" source=\"../../../etc/passwd\"".to_string()),
        Just(" source=\"file://host/x.fmu\"".to_string()),
        Just(" source=\"%zz\"".to_string()),
        Just(" source=\"http://example.invalid/x.fmu\"".to_string()),
        Just(" stopTime=\"1e999\"".to_string()),
        Just(" prefix=\"plant.\"".to_string()),
        Just("<ssv:Real value=\"1e\"/>".to_string()),
        Just("<ssv:Integer value=\"99999999999\"/>".to_string()),
        Just("\u{feff}".to_string()),
        "\\PC{1,6}",
        "[a-zA-Z0-9=\" ]{1,8}",
    ]
}

fn mutation() -> impl Strategy<Value = Mutation> {
    use prop::sample::Index;
    prop_oneof![
        any::<Index>().prop_map(Mutation::Truncate),
        (any::<Index>(), 1u8..=127).prop_map(|(i, x)| Mutation::Flip(i, x)),
        (any::<Index>(), 1usize..64).prop_map(|(i, n)| Mutation::Delete(i, n)),
        (any::<Index>(), 1usize..400).prop_map(|(i, n)| Mutation::Duplicate(i, n)),
        (any::<Index>(), token()).prop_map(|(i, t)| Mutation::Insert(i, t)),
    ]
}

/// Applies a mutation to text, keeping it UTF-8 (byte positions are moved back to a character
/// boundary; flips only touch ASCII bytes and keep them ASCII).
fn mutate(text: &mut String, m: &Mutation) {
    if text.is_empty() {
        return;
    }
    let boundary = |t: &String, mut i: usize| {
        while !t.is_char_boundary(i) {
            i -= 1;
        }
        i
    };
    match m {
        Mutation::Truncate(i) => {
            let i = boundary(text, i.index(text.len()));
            text.truncate(i);
        }
        Mutation::Flip(i, x) => {
            let i = i.index(text.len());
            let b = text.as_bytes()[i];
            if b.is_ascii() {
                let flipped = (b ^ x) & 0x7f;
                text.replace_range(i..i + 1, &(flipped as char).to_string());
            }
        }
        Mutation::Delete(i, n) => {
            let i = boundary(text, i.index(text.len()));
            let end = boundary(text, (i + n).min(text.len()));
            text.replace_range(i..end, "");
        }
        Mutation::Duplicate(i, n) => {
            let i = boundary(text, i.index(text.len()));
            let end = boundary(text, (i + n).min(text.len()));
            let copy = text[i..end].to_string();
            text.insert_str(end, &copy);
        }
        Mutation::Insert(i, t) => {
            let i = boundary(text, i.index(text.len() + 1));
            text.insert_str(i, t);
        }
    }
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn mutated_ssd_never_panics(seed in 0usize..2, mutations in prop::collection::vec(mutation(), 1..5)) {
        let mut text = seeds()[seed].clone();
        for m in &mutations {
            mutate(&mut text, m);
        }
        check_ssd(&text, ssp::parse_ssd(&text, workspace()))?;
    }

    #[test]
    fn random_text_never_panics(text in "\\PC{0,300}", tokens in prop::collection::vec(token(), 0..40)) {
        check_ssd(&text, ssp::parse_ssd(&text, workspace()))?;
        let soup = tokens.concat();
        let doc = format!("<ssd:SystemStructureDescription xmlns:ssd=\"u\" version=\"1.0\" name=\"n\"><ssd:System name=\"s\"><ssd:Elements>{soup}</ssd:Elements></ssd:System></ssd:SystemStructureDescription>");
        check_ssd(&doc, ssp::parse_ssd(&doc, workspace()))?;
    }
}

// ---- .ssp archives ---------------------------------------------------------------------------

fn ssp_seed(path: &Path) {
    let mut zip = zip::ZipWriter::new(fs::File::create(path).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    zip.start_file("SystemStructure.ssd", opts).unwrap();
    zip.write_all(&fs::read(data("two_fmus.ssd")).unwrap())
        .unwrap();
    for f in ["Plant", "Observer"] {
        zip.start_file(format!("resources/{f}.fmu"), opts).unwrap();
        zip.write_all(&fs::read(workspace().join(format!("resources/{f}.fmu"))).unwrap())
            .unwrap();
    }
    zip.finish().unwrap();
}

proptest! {
    #![proptest_config(config(64))]

    #[test]
    fn mutated_ssp_archives_are_refused_by_name(
        flips in prop::collection::vec((any::<prop::sample::Index>(), 1u8..=255), 0..4),
        cut in prop::option::of(any::<prop::sample::Index>()),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mutated.ssp");
        ssp_seed(&path);
        let mut bytes = fs::read(&path).unwrap();
        for (i, x) in &flips {
            let i = i.index(bytes.len());
            bytes[i] ^= x;
        }
        if let Some(c) = cut {
            bytes.truncate(c.index(bytes.len()));
        }
        fs::write(&path, &bytes).unwrap();
        if let Err(e) = ssp::read(&path) {
            let text = e.to_string();
            prop_assert!(text.contains(&path.display().to_string()), "{}", text);
        }
        // Nothing was written beside the archive.
        prop_assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}

#[test]
fn the_ssp_seed_reads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("seed.ssp");
    ssp_seed(&path);
    let loaded = ssp::read(&path).unwrap();
    assert_eq!(loaded.system.components.len(), 2);
    for s in seeds() {
        ssp::parse_ssd(&s, workspace()).unwrap();
    }
}

// ---- the input CSV of `simulate` -------------------------------------------------------------

fn cell() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|x| x.to_string()),
        (-1e3f64..1e3).prop_map(|x| format!("{x:e}")),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just("1e999".to_string()),
        Just(String::new()),
        Just(" 1 ".to_string()),
        Just("\"1\"".to_string()),
        Just("time".to_string()),
        "\\PC{0,5}",
    ]
}

fn csv_line() -> impl Strategy<Value = String> {
    prop_oneof![
        8 => prop::collection::vec(cell(), 1..5).prop_map(|c| c.join(",")),
        1 => Just("# comment".to_string()),
        1 => Just(String::new()),
        1 => Just("time,u,v".to_string()),
        1 => Just("\u{feff}\"time\",\"c.u\",v".to_string()),
        1 => Just("time,u,u".to_string()),
        1 => Just("0,\"1,5\",\"2".to_string()),
        1 => "\\PC{0,20}",
    ]
}

proptest! {
    #![proptest_config(config(512))]

    /// Never panics; an error names a line (and it is a line of the text); accepted signals
    /// have finite, non-decreasing times and interpolate without panicking anywhere.
    #[test]
    fn signals_never_panic(
        header in prop_oneof![Just("time,u,v".to_string()), Just("time".to_string()), "\\PC{0,12}"],
        lines in prop::collection::vec(csv_line(), 0..20),
        probes in prop::collection::vec(any::<f64>(), 0..8),
    ) {
        let text = std::iter::once(header).chain(lines).collect::<Vec<_>>().join("\n");
        match Signals::parse(&text) {
            Ok(s) => {
                prop_assert!(!s.time.is_empty());
                prop_assert!(s.time.iter().all(|t| t.is_finite()));
                prop_assert!(s.time.windows(2).all(|w| w[0] <= w[1]));
                for c in 0..s.names.len() {
                    prop_assert_eq!(s.columns[c].len(), s.time.len());
                    for &t in probes.iter().chain(&s.time) {
                        let _ = s.at(c, t);
                    }
                }
            }
            Err(e) => {
                prop_assert!(!e.is_empty());
                if let Some(rest) = e.strip_prefix("line ") {
                    let n: usize = rest
                        .split(|c: char| !c.is_ascii_digit())
                        .next()
                        .unwrap()
                        .parse()
                        .unwrap();
                    prop_assert!(n >= 1 && n <= text.lines().count(), "{}", e);
                } else {
                    prop_assert!(e == "the file is empty" || e == "no data rows", "{}", e);
                }
            }
        }
    }
}

/// Random bytes through the file reader: the error names the file.
#[test]
fn signal_files_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("signals.csv");
    fs::write(&path, b"time,u\n0,\xff\n").unwrap();
    let e = Signals::read(&path).unwrap_err();
    assert!(
        e.starts_with(&format!("cannot read input file {}", path.display())) && e.contains("UTF-8"),
        "{e}"
    );
    // A device is refused before it is read (it would be read until memory ran out).
    let e = Signals::read(std::path::Path::new("/dev/zero")).unwrap_err();
    assert_eq!(e, "cannot read input file /dev/zero: not a regular file");
}
